"""The analysis of Nav2's five largest shipped trees (`pn.bt.load(path)
.analyze(nominal.toml)`, a release build of the package), timed by CPU and
by wall clock.

    python crates/py/bench/bt_analyze.py          # 5 rounds per tree
    python crates/py/bench/bt_analyze.py -r 9

CPU time (`time.process_time`, every thread of this process) is what the
analysis costs; on a shared, loaded box the wall clock is several times
longer and says more about the load than about the code. Prints the
fastest and the median of each; figures in `crates/bt/BENCHMARKS.md`.
"""

import argparse
import time
from pathlib import Path

import petrinav as pn

NAV2 = Path(__file__).resolve().parents[3] / "models" / "bt" / "nav2"
# The five largest shipped trees (models/bt/nav2/largest.txt).
TREES = [
    line
    for line in (NAV2 / "largest.txt").read_text().splitlines()
    if line.strip() and not line.startswith("#")
]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("-r", "--rounds", type=int, default=5)
    args = ap.parse_args()
    for name in TREES:
        tree = pn.bt.load(NAV2 / name)
        cpu, wall = [], []
        for _ in range(args.rounds):
            c0, w0 = time.process_time(), time.perf_counter()
            r = tree.analyze(NAV2 / "nominal.toml")
            cpu.append(time.process_time() - c0)
            wall.append(time.perf_counter() - w0)
        cpu.sort()
        wall.sort()
        print(
            f"{name:62} states {r['states']:6}  P(success) {r['p_success']:.5f}  "
            f"CPU fastest {cpu[0] * 1e3:7.1f} ms median {cpu[len(cpu) // 2] * 1e3:7.1f} ms  "
            f"wall fastest {wall[0] * 1e3:7.1f} ms"
        )


if __name__ == "__main__":
    main()
