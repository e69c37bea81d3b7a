"""The Kanban system with petrinav from Python: solve its steady state and
draw the marginal distribution of the first cell's places.

    pip install ./crates/py matplotlib
    python examples/python/kanban.py                 # writes docs/img/kanban_marginal.png
    python examples/python/kanban.py -n 4 -o k4.png  # N = 4: 454,475 markings, about a second

Kanban (Ciardo & Tilgner) is four manufacturing cells with N kanbans each;
in cell 1 a kanban is free (Pkan1), a part is being machined (Pm1), waits
for rework (Pback1) or is done (Pout1). The marginal distribution of a
place is P{#p = k} for every token count k, from the probabilities of the
tangible markings.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import petrinav as pn  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=3, help="kanbans per cell (default 3)")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "docs/img/kanban_marginal.png")
    args = parser.parse_args()

    # The family's net has a parameter N; a GreatSPN or PNML file loads the
    # same way: pn.load("kanban.pnpro", params={"N": args.n}).
    net = pn.family("kanban", 1, params={"N": args.n})
    sol = net.solve()
    print(f"{net.name}, N = {args.n}: {len(sol.probabilities):,} tangible markings, "
          f"{sol.solver} in {sol.iterations} iterations, residual {sol.residual:.1e}")
    print(f"throughput of the line (tout4): {sol.throughput('tout4'):.6f} parts per time unit")

    places = ["Pkan1", "Pm1", "Pback1", "Pout1"]
    k = np.arange(args.n + 1)
    fig, ax = plt.subplots(figsize=(7, 3.8), dpi=110)
    width = 0.8 / len(places)
    for i, place in enumerate(places):
        marginal = sol.marginal(place)  # P{#place = k}, k = 0 … bound
        p = np.zeros(args.n + 1)
        p[: len(marginal)] = marginal
        ax.bar(k + (i - 1.5) * width, p, width, label=f"{place}  (E = {sol.mean_tokens(place):.3f})")
        assert abs(p.sum() - 1) < 1e-9
    ax.set_xticks(k)
    ax.set_xlabel("tokens k")
    ax.set_ylabel("P{#p = k}")
    ax.set_title(f"Kanban, N = {args.n}: marginal distributions in cell 1 (steady state)")
    ax.legend(frameon=False)
    ax.set_ylim(0, 1)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    args.output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output)
    print(f"-> {args.output}")


if __name__ == "__main__":
    main()
