#!/usr/bin/env python3
"""Side-by-side benchmark: petrinav against Storm (stormpy) on the same PNPRO files.

For each net of the scalable families (Kanban, FMS, dining philosophers) the
script writes the PNPRO file with `petrinav gspn family NAME N -o FILE`, then

* runs `petrinav gspn solve FILE -m MEASURE --json` and times the whole
  process (reading the file, generation, elimination, solve, output);
* loads the same file in Storm through stormpy (`load_gspn_file`,
  `build_jani_model`, `build_model` (`build_sparse_model` in stormpy 1.x),
  `model_checking` of
  `S=? [ MEASURE ]` (`LRAmin=? [ MEASURE ]` for nets with immediate
  transitions, which Storm turns into Markov automata), Storm's default engine and solver settings), in a child
  process with a timeout, and times those calls (the interpreter's start and
  `import stormpy` are not counted);

and prints both times, both values, their difference and the ratio
Storm / petrinav. Nothing is estimated: a run that fails or times out prints
as such.

Usage (from the repository root, after `cargo build --release -p petrinav`):

    pip install stormpy            # wheels for CPython on Linux x86-64
    python3 crates/petri/bench/storm_compare.py                       # every default size
    python3 crates/petri/bench/storm_compare.py kanban:2-5 fms:2-6 philosophers:5-10
    python3 crates/petri/bench/storm_compare.py kanban:6 --storm-timeout 1800

Options: --petrinav PATH (default target/release/petrinav, or
$CARGO_TARGET_DIR/release/petrinav), --storm-timeout SECONDS (default 1800),
--workdir DIR (where the PNPRO files go; default a temporary directory),
--markdown (print the table as Markdown for BENCHMARKS.md), --engine
auto|explicit|structured (petrinav's `gspn solve --engine`, default auto;
the engine used is a column).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

# Family -> (measure in petrinav's syntax, the same in Storm's).
MEASURES = {
    "kanban": ("#Pm1 >= 1", "Pm1 >= 1"),
    "fms": ("#P1 >= 1", "P1 >= 1"),
    "philosophers": ("#Eat_1 >= 1", "Eat_1 >= 1"),
}
DEFAULT_RUNS = ["kanban:2-5", "fms:2-6", "philosophers:5-10"]


def storm_child(path, formula):
    """Runs in the child process: solve with Storm, print JSON."""
    t0 = time.perf_counter()
    import stormpy
    import stormpy.gspn

    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    gspn = stormpy.gspn.load_gspn_file(path)
    jani, _ = stormpy.gspn.build_jani_model(gspn)
    # A GSPN with immediate transitions becomes a Markov automaton, on which
    # Storm wants the optimisation direction stated (the weights resolve
    # every choice, so min = max).
    has_immediate = any(True for _ in gspn.get_immediate_transitions())
    text = f"LRAmin=? [ {formula} ]" if has_immediate else f"S=? [ {formula} ]"
    parse = getattr(stormpy, "parse_properties_for_jani_model", None)  # stormpy 1.x
    props = parse(text, jani) if parse else stormpy.parse_properties(text, jani)
    t_parse = time.perf_counter() - t0
    t0 = time.perf_counter()
    if hasattr(stormpy, "build_sparse_model"):  # stormpy 1.x
        model = stormpy.build_sparse_model(jani, props)
    else:  # stormpy 2.x
        model = stormpy.build_model(jani, props)
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    result = stormpy.model_checking(model, props[0])
    s0 = model.initial_states[0]
    value = result.at(s0) if hasattr(result, "at") else result.get_value(s0)
    t_check = time.perf_counter() - t0
    print(
        json.dumps(
            {
                "value": value,
                "states": model.nr_states,
                "transitions": model.nr_transitions,
                "import": t_import,
                "parse": t_parse,
                "build": t_build,
                "check": t_check,
                "seconds": t_parse + t_build + t_check,
                "version": getattr(stormpy, "__version__", "?"),
            }
        )
    )


def run_storm(path, formula, timeout):
    cmd = [sys.executable, os.path.abspath(__file__), "--storm-child", path, formula]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:.0f} s"}
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["?"])[-1]
        return {"error": f"failed: {last}"}
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_petrinav(exe, path, measure, engine):
    t0 = time.perf_counter()
    out = subprocess.run(
        [exe, "gspn", "solve", path, "-m", measure, "--engine", engine, "--json"],
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        return {"error": out.stderr.strip()[-200:]}
    j = json.loads(out.stdout)
    return {
        "value": j["measures"][measure],
        "states": j["tangible_markings"],
        "residual": j["residual"],
        "solver": j["solver"],
        "engine": j.get("engine", "explicit"),
        "seconds": wall,
    }


def parse_runs(specs):
    runs = []
    for spec in specs:
        family, _, sizes = spec.partition(":")
        if family not in MEASURES:
            sys.exit(f"unknown family {family!r} (one of {', '.join(MEASURES)})")
        lo, _, hi = sizes.partition("-")
        for n in range(int(lo), int(hi or lo) + 1):
            runs.append((family, n))
    return runs


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--storm-child":
        storm_child(sys.argv[2], sys.argv[3])
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="*", default=DEFAULT_RUNS, help="FAMILY:N or FAMILY:LO-HI")
    target = os.environ.get("CARGO_TARGET_DIR", "target")
    ap.add_argument("--petrinav", default=os.path.join(target, "release", "petrinav"))
    ap.add_argument("--storm-timeout", type=float, default=1800.0)
    ap.add_argument("--workdir")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--engine", default="auto", choices=["auto", "explicit", "structured"])
    a = ap.parse_args()
    workdir = a.workdir or tempfile.mkdtemp(prefix="storm_compare_")
    os.makedirs(workdir, exist_ok=True)
    try:
        import stormpy  # noqa: F401

        have_storm = True
    except ImportError:
        have_storm = False
        print("stormpy is not installed (pip install stormpy): Storm columns stay empty", file=sys.stderr)
    rows = []
    header = ("net", "engine", "states", "petrinav s", "Storm s", "Storm/petrinav", "petrinav value", "Storm value", "|diff|")
    if a.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
    else:
        print("  ".join(f"{h:>16}" for h in header))
    for family, n in parse_runs(a.runs):
        path = os.path.join(workdir, f"{family}-{n}.PNPRO")
        subprocess.run([a.petrinav, "gspn", "family", family, str(n), "-o", path], check=True)
        measure, formula = MEASURES[family]
        ours = run_petrinav(a.petrinav, path, measure, a.engine)
        theirs = run_storm(path, formula, a.storm_timeout) if have_storm else {"error": "no stormpy"}
        ov, tv = ours.get("value"), theirs.get("value")
        ratio = theirs["seconds"] / ours["seconds"] if "seconds" in theirs and "seconds" in ours else None
        cells = (
            f"{family} {n}",
            ours.get("engine", "-"),
            str(ours.get("states", theirs.get("states", "?"))),
            f"{ours['seconds']:.3f}" if "seconds" in ours else ours["error"],
            f"{theirs['seconds']:.3f}" if "seconds" in theirs else theirs["error"],
            f"{ratio:.1f}" if ratio else "-",
            f"{ov:.10f}" if ov is not None else "-",
            f"{tv:.10f}" if tv is not None else "-",
            f"{abs(ov - tv):.1e}" if ov is not None and tv is not None else "-",
        )
        rows.append((family, n, ours, theirs))
        if a.markdown:
            print("| " + " | ".join(cells) + " |", flush=True)
        else:
            print("  ".join(f"{c:>16}" for c in cells), flush=True)
    json.dump(
        [{"family": f, "n": n, "petrinav": o, "storm": t} for f, n, o, t in rows],
        open(os.path.join(workdir, "results.json"), "w"),
        indent=1,
    )
    print(f"(files and results.json in {workdir})", file=sys.stderr)


if __name__ == "__main__":
    main()
