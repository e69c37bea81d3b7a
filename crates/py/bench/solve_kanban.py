"""`net.solve()` from Python against `petrinav gspn solve` on the same net.

    python crates/py/bench/solve_kanban.py            # Kanban N = 4 (454,475 states), 7 rounds
    python crates/py/bench/solve_kanban.py -n 3 -r 15

Each round times, one after the other on the same file (so that both meet
the same machine load):

- the command line, `petrinav gspn solve kanban4.toml --json`, as a whole
  process (start, read, generate, compile, solve, print), wall clock;
- Python, `pn.load(path).solve()` in this process (read, generate,
  compile, solve: a fresh Net each round, so nothing is cached), wall clock.

It prints the medians and their ratio (Python / command line), and checks
that both give the same numbers. The command line is `$PETRINAV_BIN`, else
`target/release/petrinav` (build it first: `cargo build --release -p
petrinav`).
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import petrinav as pn

ROOT = Path(__file__).resolve().parents[3]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=4, help="kanbans per cell (default 4)")
    parser.add_argument("-r", "--rounds", type=int, default=7)
    args = parser.parse_args()
    binary = os.environ.get("PETRINAV_BIN", str(ROOT / "target/release/petrinav"))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"kanban{args.n}.toml"
        subprocess.run([binary, "gspn", "family", "kanban", str(args.n), "-o", str(path)], check=True)
        cli_s, py_s, cli_solve_s, py_solve_s = [], [], [], []
        for r in range(args.rounds + 1):
            t0 = time.perf_counter()
            out = subprocess.run(
                [binary, "gspn", "solve", str(path), "--json"], check=True, capture_output=True, text=True
            ).stdout
            t1 = time.perf_counter()
            sol = pn.load(path).solve()
            t2 = time.perf_counter()
            expected = json.loads(out)
            assert sol.to_dict() | {"seconds": 0} == expected | {"seconds": 0}, "different numbers"
            if r == 0:
                continue  # warm-up: file cache, page faults
            cli_s.append(t1 - t0)
            py_s.append(t2 - t1)
            cli_solve_s.append(expected["seconds"])
            py_solve_s.append(sol.seconds)
            print(f"round {r}: command line {t1 - t0:.3f} s, Python {t2 - t1:.3f} s")
    cm, pm = statistics.median(cli_s), statistics.median(py_s)
    print()
    print(f"Kanban N = {args.n}: {expected['tangible_markings']:,} tangible markings, {expected['solver']}")
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    print(f"command line  gspn solve --json   median {cm:.3f} s  (min {min(cli_s):.3f}, max {max(cli_s):.3f})")
    print(f"Python        load(...).solve()   median {pm:.3f} s  (min {min(py_s):.3f}, max {max(py_s):.3f})")
    print(f"ratio Python / command line: {pm / cm:.3f}")
    print(f"solve phase alone (as each reports it): command line {statistics.median(cli_solve_s):.3f} s, "
          f"Python {statistics.median(py_solve_s):.3f} s")


if __name__ == "__main__":
    main()
