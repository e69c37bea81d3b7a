"""The quantiles of `petrinav bt analyze` against an independent method.

`bt analyze` reads the quantiles of the time to the end off a survival
function from a shift-and-invert Krylov space (petri's `survival`; the
Crank–Nicolson grid, `absorption_cdf_steps`, only where the space does
not settle). This script exports the same chain (`--net`, then
`petrinav gspn convert` to Storm's DRN), and finds each quantile again
with SciPy: `P(T ≤ t)` from the matrix exponential's action
(`scipy.sparse.linalg.expm_multiply`, Al-Mohy and Higham's method,
accurate to double precision), a root of `P(T ≤ t) = q · P(the run ends)`
by Brent's method to 1e-9 s. Neither the time stepping nor the block
solves are shared.

    python crates/bt/bench/quantiles_exact.py                 # the five largest Nav2 trees
    python crates/bt/bench/quantiles_exact.py --all --markdown
    python crates/bt/bench/quantiles_exact.py --petrinav target/release/petrinav

Needs numpy and scipy (`pip install numpy scipy`) and a built CLI (default
`target/release/petrinav`). Figures in `crates/bt/BENCHMARKS.md`.
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.optimize as so
import scipy.sparse as sp
import scipy.sparse.linalg as sl

ROOT = Path(__file__).resolve().parents[3]
NAV2 = ROOT / "models" / "bt" / "nav2"
# The five largest shipped trees (models/bt/nav2/largest.txt).
LARGEST = [
    line
    for line in (NAV2 / "largest.txt").read_text().splitlines()
    if line.strip() and not line.startswith("#")
]


def read_drn(path: Path):
    """The CTMC of a DRN file written by `petrinav gspn convert`: the
    generator `Q` (CSR), the initial distribution and the absorbing states.
    A state with exit rate 0 is probabilistic: only the initial state may
    be one (petrinav eliminates every other vanishing marking)."""
    rows, cols, vals = [], [], []
    rate, init, cur = {}, {}, None
    with open(path) as f:
        for line in f:
            if line.startswith("state "):
                parts = line.split()
                cur = int(parts[1])
                rate[cur] = float(parts[2][1:]) if parts[2].startswith("!") else 0.0
                if rate[cur] == 0.0 and "init" not in parts:
                    sys.exit(f"{path}: state {cur} is probabilistic and not the initial one")
            elif line.startswith("\t\t") and cur is not None:
                target, p = line.strip().split(" : ")
                target, p = int(target), float(p)
                if rate[cur] == 0.0:
                    init[target] = init.get(target, 0.0) + p
                elif target != cur:
                    rows.append(cur)
                    cols.append(target)
                    vals.append(p * rate[cur])
    n = max(rate) + 1
    q = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    out = np.asarray(q.sum(axis=1)).ravel()
    absorbing = out == 0.0
    p0 = np.zeros(n)
    if init:
        for s, p in init.items():
            p0[s] += p
        probabilistic = [s for s, r in rate.items() if r == 0.0]
        absorbing[probabilistic] = False
    else:
        p0[0] = 1.0
    return q - sp.diags(out), p0, absorbing


def exact_quantiles(drn: Path, qs, p_end: float, guesses):
    """Each quantile of the time to the end, of the runs that end."""
    q, p0, absorbing = read_drn(drn)
    qt = q.T.tocsr()

    def cdf(t: float) -> float:
        return float(sl.expm_multiply(qt * t, p0)[absorbing].sum()) / p_end

    out = []
    for level, guess in zip(qs, guesses):
        lo, hi = 0.5 * guess, 1.5 * guess
        while cdf(hi) < level:
            hi *= 2
        out.append(so.brentq(lambda t: cdf(t) - level, lo, hi, xtol=1e-9, rtol=1e-12))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--petrinav", default=str(ROOT / "target" / "release" / "petrinav"))
    ap.add_argument("--all", action="store_true", help="every shipped Nav2 tree, not only the five largest")
    ap.add_argument("--params", nargs="*", default=["nominal", "degraded"])
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    trees = sorted(p.name for p in NAV2.glob("*.xml") if p.name != "nav2_tree_nodes.xml") if args.all else LARGEST
    if args.markdown:
        print("| tree | set | q | bt analyze (s) | expm_multiply (s) | relative error |")
        print("|---|---|---|---|---|---|")
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for name in trees:
            for pset in args.params:
                net, drn = Path(tmp) / "net.toml", Path(tmp) / "chain.drn"
                report = json.loads(
                    subprocess.run(
                        [args.petrinav, "bt", "analyze", str(NAV2 / name), "--params",
                         str(NAV2 / f"{pset}.toml"), "--json", "--net", str(net)],
                        check=True, capture_output=True, text=True,
                    ).stdout
                )
                if report["mean_time"] <= 0.0:
                    continue
                subprocess.run([args.petrinav, "gspn", "convert", str(net), str(drn)], check=True,
                               capture_output=True)
                qs = [q for q, _ in report["quantiles"]]
                ours = [t for _, t in report["quantiles"]]
                exact = exact_quantiles(drn, qs, 1.0 - report["p_never"], ours)
                for level, a, b in zip(qs, ours, exact):
                    rel = (a - b) / b
                    worst = max(worst, abs(rel))
                    if args.markdown:
                        print(f"| `{name}` | {pset} | {level} | {a:.6g} | {b:.6g} | {rel:+.1e} |")
                    else:
                        print(f"{name:62} {pset:9} q={level:<5} ours {a:<12.6g} exact {b:<12.6g} {rel:+.1e}")
    print(f"largest relative error: {worst:.1e}")


if __name__ == "__main__":
    main()
