#!/usr/bin/env python3
"""The structured engine against the explicit one on larger nets.

For each FAMILY:N (or a net file) the script runs
`petrinav gspn solve FILE --engine structured --json` and, unless the chain
is above --explicit-max states, the same with `--engine explicit`, and
compares every place's mean tokens and P{#p > 0} and every transition's
throughput: the largest absolute difference (relative to max(1, |value|))
must be <= --tol (default 1e-9). Both runs are timed end to end (process
start to exit) and their peak resident memory read from /usr/bin/time.

Usage (from the repository root, after `cargo build --release -p petrinav`):

    python3 crates/petri/bench/engines_compare.py kanban:1-5 fms:1-6 polling:2-5 tandem:2-6
    python3 crates/petri/bench/engines_compare.py kanban:7 --explicit-max 0   # structured only

Exit status 1 if any compared pair differs by more than --tol.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile


def run(exe, path, engine):
    cmd = ["/usr/bin/time", "-f", "%e %M", exe, "gspn", "solve", path, "--engine", engine, "--json"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        return {"error": out.stderr.strip().splitlines()[-2:]}
    wall, kb = out.stderr.strip().splitlines()[-1].split()
    j = json.loads(out.stdout)
    j["wall"], j["peak_mib"] = float(wall), int(kb) / 1024
    return j


def diff(a, b):
    worst = 0.0
    for key, fields in (("places", ("mean_tokens", "prob_nonempty")), ("transitions", ("throughput",))):
        for name, va in a[key].items():
            for f in fields:
                x, y = va[f], b[key][name][f]
                worst = max(worst, abs(x - y) / max(1.0, abs(x)))
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="FAMILY:N, FAMILY:LO-HI or a net file")
    target = os.environ.get("CARGO_TARGET_DIR", "target")
    ap.add_argument("--petrinav", default=os.path.join(target, "release", "petrinav"))
    ap.add_argument("--explicit-max", type=float, default=12e6, help="largest chain solved explicitly too")
    ap.add_argument("--tol", type=float, default=1e-9)
    a = ap.parse_args()
    workdir = tempfile.mkdtemp(prefix="engines_compare_")
    nets = []
    for spec in a.runs:
        if os.path.exists(spec):
            nets.append((spec, spec))
            continue
        family, _, sizes = spec.partition(":")
        lo, _, hi = sizes.partition("-")
        for n in range(int(lo), int(hi or lo) + 1):
            path = os.path.join(workdir, f"{family}-{n}.PNPRO")
            subprocess.run([a.petrinav, "gspn", "family", family, str(n), "-o", path], check=True)
            nets.append((f"{family} {n}", path))
    print("| net | states (tangible + vanishing) | components | structured s | structured MiB | sweeps | explicit s | explicit MiB | max diff |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    bad = False
    for name, path in nets:
        s = run(a.petrinav, path, "structured")
        if "error" in s:
            print(f"| {name} | structured: {s['error']} | | | | | | | |", flush=True)
            continue
        states = f"{s['tangible_markings']} + {s.get('vanishing_markings', 0)}"
        comps = " × ".join(str(c) for c in s.get("components", []))
        cells = [name, states, comps, f"{s['wall']:.2f}", f"{s['peak_mib']:.0f}", str(s["iterations"])]
        if s["tangible_markings"] <= a.explicit_max:
            e = run(a.petrinav, path, "explicit")
            if "error" in e:
                cells += [str(e["error"]), "", ""]
            else:
                d = diff(e, s)
                bad |= d > a.tol
                cells += [f"{e['wall']:.2f}", f"{e['peak_mib']:.0f}", f"{d:.1e}"]
        else:
            cells += ["-", "-", "not run"]
        print("| " + " | ".join(cells) + " |", flush=True)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
