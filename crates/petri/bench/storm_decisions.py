#!/usr/bin/env python3
"""petrinav's optimiser against Storm (stormpy) on DRN files.

Three parts, each optional:

* ``agree``: random DRN files of each model type (DTMC, CTMC, MDP, Markov
  automaton; seeded, a few hundred states, a label ``goal``, a reward model
  ``cost`` with state and action rewards) written by this script, read by
  both tools; for every file the properties ``P [F "goal"]``,
  ``T [F "goal"]``, ``R{"cost"} [F "goal"]``, ``LRA ["goal"]`` and
  ``R{"cost"} [LRA]`` (min and max where the model has choices) are solved
  by ``petrinav gspn optimize FILE --objective … --json --precision 1e-9``
  and by Storm in its sound mode (``stormpy.environments.sound``, precision
  1e-6); the values must agree within Storm's precision (relative 2e-6, or
  both infinite).
* ``ours``: the DRN files petrinav writes (``gspn convert NET file.drn``)
  of the shipped supervisor net with decisions and of the ``corridors``
  family are read by Storm and solved alike (Storm reads our files).
* ``time``: end to end on a large file (``corridors N``, N = 100: 216,751
  states, a Markov automaton written by ``gspn convert``): the wall time of
  the whole ``petrinav gspn optimize`` process (reading, graph analysis,
  iteration, output) against Storm's ``build_model_from_drn`` plus
  ``model_checking`` in a child process (the interpreter's start and
  ``import stormpy`` not counted), for ``Pmax=? [F "all_working"]`` and
  ``Tmin=? [F "all_working" | "lost"]``; Storm with its default settings and
  in sound mode; each repeated (``--repeat``), the best kept.

Usage (from the repository root, after ``cargo build --release -p
petrinav``; stormpy 2.0 in a virtual environment):

    /tmp/storm/bin/python crates/petri/bench/storm_decisions.py agree ours
    /tmp/storm/bin/python crates/petri/bench/storm_decisions.py time --size 100 --repeat 3

Options: --petrinav PATH (default target/release/petrinav), --workdir DIR
(default a temporary directory), --storm-timeout SECONDS (default 1800),
--markdown (tables for BENCHMARKS.md).
"""

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time


def fmt(v):
    return repr(float(v))


def random_drn(path, kind, n, seed):
    """Writes a random model of `kind` (dtmc, ctmc, mdp, ma) with n states."""
    rng = random.Random(seed)
    markovian = [kind in ("dtmc", "ctmc", "mdp") or rng.random() < 0.6 for _ in range(n)]
    lines = []
    rows_total = 0
    goal = {s for s in range(n) if rng.random() < 0.05} | {n - 1}
    body = []
    for s in range(n):
        rows = 1 if kind in ("dtmc", "ctmc") or (kind == "ma" and markovian[s]) else rng.randint(1, 3)
        exit_rate = None
        header = f"state {s}"
        if kind in ("ctmc", "ma"):
            exit_rate = rng.uniform(0.5, 5.0) if markovian[s] else 0.0
        state_reward = round(rng.uniform(0, 2), 3)
        entries_of = []
        for _ in range(rows):
            k = rng.randint(1, 3)
            if kind == "ma" and not markovian[s]:
                # Probabilistic states go to Markovian states or to later
                # probabilistic ones: no Zeno cycle.
                choices = [t for t in range(n) if markovian[t] or t > s] or [n - 1]
            else:
                choices = list(range(n))
            targets = sorted(set(rng.choice(choices) for _ in range(k)))
            weights = [rng.uniform(0.1, 1.0) for _ in targets]
            total = sum(weights)
            probs = [w / total for w in weights]
            probs[-1] = 1.0 - sum(probs[:-1])
            entries_of.append((targets, probs, round(rng.uniform(0, 1), 3) if rng.random() < 0.5 else 0.0))
        if kind == "ctmc":
            targets, probs, a = entries_of[0]
            rates = [p * exit_rate for p in probs]
            exit_rate = sum(rates)
            entries_of = [(targets, rates, a)]
        if exit_rate is not None:
            header += f" !{fmt(exit_rate)}"
        header += f" [{fmt(state_reward)}]"
        if s == 0:
            header += " init"
        if s in goal:
            header += " goal"
        body.append(header)
        for i, (targets, values, a) in enumerate(entries_of):
            body.append(f"\taction {i} [{fmt(a)}]")
            for t, v in zip(targets, values):
                body.append(f"\t\t{t} : {fmt(v)}")
        rows_total += rows
    type_name = {"dtmc": "DTMC", "ctmc": "CTMC", "mdp": "MDP", "ma": "Markov Automaton"}[kind]
    lines = [
        f"// random {kind}, seed {seed}",
        f"@type: {type_name}",
        "@value_type: double",
        "@parameters",
        "",
        "@reward_models",
        "cost",
        "@nr_states",
        str(n),
        "@nr_choices",
        str(rows_total),
        "@model",
    ] + body
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def properties(kind):
    dirs = ["min", "max"] if kind in ("mdp", "ma") else [""]
    out = []
    for d in dirs:
        out += [
            f'P{d}=? [F "goal"]',
            f'T{d}=? [F "goal"]',
            f'R{{"cost"}}{d}=? [F "goal"]',
            f'LRA{d}=? ["goal"]',
            f'R{{"cost"}}{d}=? [LRA]',
        ]
    return out


def ours(petrinav, path, prop, precision="1e-9"):
    t0 = time.perf_counter()
    r = subprocess.run(
        [petrinav, "gspn", "optimize", path, "--objective", prop, "--json", "--precision", precision],
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        return None, wall, r.stderr.strip()
    v = json.loads(r.stdout)["value"]
    return (math.inf if v == "infinity" else float(v)), wall, ""


STORM_CHILD = r"""
import json, sys, time
import stormpy
path, props, sound = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3] == "sound"
t0 = time.perf_counter()
model = stormpy.build_model_from_drn(path)
t_read = time.perf_counter() - t0
out = {"read": t_read, "states": model.nr_states, "results": []}
env = stormpy.environments.sound() if sound else stormpy.Environment()
for p in props:
    t0 = time.perf_counter()
    formula = stormpy.parse_properties(p)[0]
    r = stormpy.model_checking(model, formula, environment=env)
    v = r.get_value(model.initial_states[0])
    out["results"].append({"property": p, "value": v if v != float("inf") else "inf", "check": time.perf_counter() - t0})
print(json.dumps(out))
"""


def storm(path, props, sound, timeout):
    try:
        r = subprocess.run(
            [sys.executable, "-c", STORM_CHILD, path, json.dumps(props), "sound" if sound else "default"],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        return None, "timeout"
    if r.returncode != 0:
        return None, r.stderr.strip().splitlines()[-1] if r.stderr.strip() else f"exit {r.returncode}"
    return json.loads(r.stdout), ""


def close(a, b):
    if a is None or b is None:
        return False
    if math.isinf(a) or math.isinf(b):
        return math.isinf(a) and math.isinf(b)
    return abs(a - b) <= 2e-6 * max(abs(a), abs(b)) + 1e-12


def compare(petrinav, files, timeout, markdown):
    rows = []
    failures = 0
    for path, kind in files:
        props = properties(kind)
        s, err = storm(path, props, True, timeout)
        if s is None:
            rows.append((os.path.basename(path), "(all)", "", f"Storm: {err}", "no"))
            failures += 1
            continue
        for res in s["results"]:
            p = res["property"]
            sv = math.inf if res["value"] == "inf" else float(res["value"])
            ov, _, oerr = ours(petrinav, path, p)
            ok = close(ov, sv)
            failures += not ok
            rows.append((os.path.basename(path), p, "n/a" if ov is None else f"{ov:.10g}", f"{sv:.10g}", "yes" if ok else f"NO {oerr}"))
    print_table(["file", "property", "petrinav", "Storm (sound)", "agree"], rows, markdown)
    return failures


def print_table(head, rows, markdown):
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print("| " + " | ".join(str(x) for x in r) + " |")
    else:
        w = [max(len(str(x)) for x in col) for col in zip(head, *rows)]
        for r in [head] + rows:
            print("  ".join(str(x).ljust(k) for x, k in zip(r, w)))


def convert(petrinav, net, out):
    subprocess.run([petrinav, "gspn", "convert", net, out], check=True, capture_output=True)


def family(petrinav, name, n, out):
    subprocess.run([petrinav, "gspn", "family", name, str(n), "-o", out], check=True, capture_output=True)


def timing(petrinav, workdir, size, repeat, timeout, markdown):
    net = os.path.join(workdir, f"corridors{size}.toml")
    drn = os.path.join(workdir, f"corridors{size}.drn")
    if not os.path.exists(drn):
        family(petrinav, "corridors", size, net)
        convert(petrinav, net, drn)
    props = ['Pmax=? [F "all_working"]', 'Tmin=? [F "all_working" | "lost"]']
    load = os.getloadavg()
    rows = []
    for p in props:
        best_ours = min((ours(petrinav, drn, p, "1e-6") for _ in range(repeat)), key=lambda r: r[1])
        best = {}
        for sound in (False, True):
            runs = []
            for _ in range(repeat):
                s, err = storm(drn, [p], sound, timeout)
                if s is None:
                    runs.append((math.inf, err, None, None))
                else:
                    res = s["results"][0]
                    runs.append((s["read"] + res["check"], "", res["value"], s["states"]))
            best[sound] = min(runs, key=lambda r: r[0])
        for sound in (False, True):
            st, err, sv, n = best[sound]
            rows.append(
                (
                    p,
                    n,
                    f"{best_ours[1]:.2f}",
                    f"{st:.2f}" if err == "" else err,
                    "sound" if sound else "default",
                    f"{st / best_ours[1]:.1f}x" if err == "" else "-",
                    f"{best_ours[0]:.9g}",
                    sv,
                )
            )
    print(f"load average before the runs: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; file {drn} ({os.path.getsize(drn) / 1e6:.0f} MB)")
    print_table(["property", "states", "petrinav s", "Storm s", "Storm mode", "Storm/petrinav", "petrinav value", "Storm value"], rows, markdown)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("parts", nargs="*", default=["agree", "ours", "time"])
    ap.add_argument("--petrinav", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "petrinav"))
    ap.add_argument("--workdir")
    ap.add_argument("--storm-timeout", type=float, default=1800)
    ap.add_argument("--size", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args()
    workdir = a.workdir or tempfile.mkdtemp(prefix="storm_decisions_")
    os.makedirs(workdir, exist_ok=True)
    failures = 0
    if "agree" in a.parts:
        files = []
        for kind in ("dtmc", "ctmc", "mdp", "ma"):
            for i in range(3):
                path = os.path.join(workdir, f"random_{kind}_{i}.drn")
                random_drn(path, kind, 200 + 100 * i, seed=46 * 10 + i)
                files.append((path, kind))
        failures += compare(a.petrinav, files, a.storm_timeout, a.markdown)
    if "ours" in a.parts:
        files = []
        sup = os.path.join(workdir, "supervisor_decisions.drn")
        convert(a.petrinav, "models/supervisor_decisions.toml", sup)
        files.append((sup, "ma"))
        net = os.path.join(workdir, "corridors8.toml")
        family(a.petrinav, "corridors", 8, net)
        drn = os.path.join(workdir, "corridors8.drn")
        convert(a.petrinav, net, drn)
        files.append((drn, "ma"))
        # The properties of the random files name "goal" and "cost": give
        # ours their own.
        for path, _ in files:
            props = (
                ['Tmin=? [F "success"]', 'Tmax=? [F "success"]', 'R{"success"}max=? [LRA]', 'Pmax=? [F "failure"]', 'LRAmin=? ["localized"]']
                if "supervisor" in path
                else ['Pmax=? [F "all_working"]', 'Pmin=? [F "lost"]', 'Tmin=? [F "all_working" | "lost"]', 'R{"trips"}max=? [LRA]']
            )
            s, err = storm(path, props, True, a.storm_timeout)
            rows = []
            if s is None:
                rows.append((os.path.basename(path), "(all)", "", f"Storm: {err}", "no"))
                failures += 1
            else:
                for res in s["results"]:
                    sv = math.inf if res["value"] == "inf" else float(res["value"])
                    ov, _, oerr = ours(a.petrinav, path, res["property"])
                    ok = close(ov, sv)
                    failures += not ok
                    rows.append((os.path.basename(path), res["property"], f"{ov:.10g}" if ov is not None else oerr, f"{sv:.10g}", "yes" if ok else "NO"))
            print_table(["file (written by petrinav)", "property", "petrinav", "Storm (sound)", "agree"], rows, a.markdown)
    if "time" in a.parts:
        timing(a.petrinav, workdir, a.size, a.repeat, a.storm_timeout, a.markdown)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
