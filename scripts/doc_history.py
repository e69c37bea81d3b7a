#!/usr/bin/env python3
"""Share of doc-comment lines that narrate history (issue 40, outcome 2).

Usage: scripts/doc_history.py [ROOT] [--max-percent P]

The rule, mechanical so that anyone counts the same:

* A *doc line* is a line of a `.rs` file under `crates/*/src` whose first
  non-blank characters are `//!` (module docs) or `///` (item docs).
* A *paragraph* is a run of doc lines of one kind with text, ended by a
  blank doc line, a line of another kind, or a code line.
* A paragraph is *history* when it narrates a measurement or an attempt,
  that is when it holds at least one of:
  - a date (`2026-12-04`);
  - a commit id (7 to 40 hex digits, with a letter and a digit);
  - a seed or a run of seeds (`seed 4`, `seeds 1-16`);
  - a branch (`branch`, "at `main`", "on `main`");
  - one of the phrases "we / was / were / been tried", "tried and / but",
    "not kept", "measured" followed by on / with / in / and / again / a
    comma / a parenthesis / a colon (a measurement reported, not a measured
    quantity), "it / they / we / robot / tracker / which used to",
    "before →", "→ after", "before:", "| before", "we ran", "traced",
    "what remains", "was changed".
  Every line of a history paragraph is a history line.
* Exempt: the paragraphs under a `# Figures` heading of a module doc (up to
  the next heading): the figures of the design as built, one table with the
  command that re-runs it.

Prints the totals and the files with most history; with `--max-percent P`
exits 1 when history exceeds P % of the doc lines.
"""
import pathlib
import re
import sys

MARKERS = re.compile(
    r"\b\d{4}-\d{2}-\d{2}\b"
    r"|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b"
    r"|\bseeds? \d"
    r"|\bbranch\b|\b(?:at|on) `main`"
    r"|\b(?:we|was|were|been) tried\b|\btried (?:and|but)\b|\bnot kept\b|\bmeasured(?:(?: on| with| in| and| again)\b|,| \(|:)|\b(?:it|they|we|robot|tracker|which) used to\b"
    r"|before →|→ after|\bbefore:|\| before\b|\bwe ran\b|\btraced\b"
    r"|\bwhat remains\b|\bwas changed\b",
    re.IGNORECASE,
)


def doc_kind(line):
    s = line.lstrip()
    if s.startswith("//!"):
        return "//!", s[3:].strip()
    if s.startswith("///") and not s.startswith("////"):
        return "///", s[3:].strip()
    return None, None


def count(path):
    """(doc lines, history lines, module-doc lines, module-doc history lines)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    doc = hist = mdoc = mhist = 0
    para, para_kind = [], None
    figures = False

    def flush():
        nonlocal hist, mhist, para, para_kind
        if para and not (para_kind == "//!" and figures) and MARKERS.search(" ".join(para)):
            hist += len(para)
            if para_kind == "//!":
                mhist += len(para)
        para, para_kind = [], None

    for line in lines:
        kind, body = doc_kind(line)
        if kind is None:
            flush()
            continue
        doc += 1
        if kind == "//!":
            mdoc += 1
            if body.startswith("#") and not body.startswith("#["):
                flush()
                figures = body.lstrip("#").strip().lower() == "figures"
                continue
        if kind != para_kind:
            flush()
        if not body:
            flush()
            continue
        para_kind = kind
        para.append(body)
    flush()
    return doc, hist, mdoc, mhist


def main():
    args = [a for a in sys.argv[1:]]
    limit = None
    if "--max-percent" in args:
        i = args.index("--max-percent")
        limit = float(args[i + 1])
        del args[i : i + 2]
    root = pathlib.Path(args[0]) if args else pathlib.Path(__file__).resolve().parent.parent
    rows = []
    for path in sorted(root.glob("crates/*/src/**/*.rs")):
        rows.append((*count(path), path.relative_to(root)))
    doc = sum(r[0] for r in rows)
    hist = sum(r[1] for r in rows)
    mdoc = sum(r[2] for r in rows)
    mhist = sum(r[3] for r in rows)
    for r in sorted(rows, key=lambda r: -r[1])[:20]:
        if r[1]:
            print(f"{r[1]:5} of {r[0]:5} doc lines ({r[3]} of {r[2]} module-doc)  {r[4]}")
    print(f"module docs (//!): {mhist} history lines of {mdoc}: {100 * mhist / max(mdoc, 1):.1f} %")
    print(f"all docs (//! and ///): {hist} history lines of {doc}: {100 * hist / max(doc, 1):.1f} %")
    if limit is not None and 100 * hist / max(doc, 1) > limit:
        sys.exit(1)


if __name__ == "__main__":
    main()
