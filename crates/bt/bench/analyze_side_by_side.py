"""`petrinav bt analyze` end to end with two builds, run in turn.

For each of Nav2's five largest shipped trees and both parameter sets,
each round runs the "before" binary and then the "after" one (so that a
change in the box's load falls on both), and prints the fastest and the
median wall clock and the median CPU time of the child (10 ms
granularity) as a Markdown table. Figures in `crates/bt/BENCHMARKS.md`.

    python3 crates/bt/bench/analyze_side_by_side.py --before /tmp/old/petrinav --after target/release/petrinav
    python3 crates/bt/bench/analyze_side_by_side.py --before A --after B --rounds 9

Build the "before" binary from an older commit in another worktree
(`git worktree add /tmp/old <commit> && cargo build --release -p petrinav`).
"""

import argparse
import os
import statistics
import subprocess
import time
from pathlib import Path

NAV2 = Path(__file__).resolve().parents[3] / "models" / "bt" / "nav2"
# The five largest shipped trees (models/bt/nav2/largest.txt).
TREES = [
    line
    for line in (NAV2 / "largest.txt").read_text().splitlines()
    if line.strip() and not line.startswith("#")
]
SETS = ["nominal", "degraded"]


def run_once(binary: str, tree: str, pset: str) -> tuple[float, float]:
    """Wall and CPU seconds of one analysis."""
    before = os.times()
    start = time.perf_counter()
    subprocess.run(
        [binary, "bt", "analyze", str(NAV2 / tree), "--params", str(NAV2 / f"{pset}.toml")],
        check=True,
        capture_output=True,
    )
    wall = time.perf_counter() - start
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", required=True, help="the older petrinav binary")
    ap.add_argument("--after", required=True, help="the newer petrinav binary")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    times: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for tree in TREES:
        for pset in SETS:
            for _ in range(args.rounds):
                for name, binary in (("before", args.before), ("after", args.after)):
                    times.setdefault((tree, pset, name), []).append(run_once(binary, tree, pset))
    print(f"load average at the end: {' '.join(open('/proc/loadavg').read().split()[:3])}")
    print("| tree | set | before: wall fastest / median | after: wall fastest / median | before: CPU median | after: CPU median |")
    print("|---|---|---|---|---|---|")

    def wall(v):
        return f"{min(w for w, _ in v) * 1000:.0f} / {statistics.median(w for w, _ in v) * 1000:.0f} ms"

    def cpu(v):
        return f"{statistics.median(c for _, c in v) * 1000:.0f} ms"

    for tree in TREES:
        for pset in SETS:
            a, b = times[(tree, pset, "before")], times[(tree, pset, "after")]
            print(f"| `{tree}` | {pset} | {wall(a)} | {wall(b)} | {cpu(a)} | {cpu(b)} |")


if __name__ == "__main__":
    main()
