#!/usr/bin/env python3
"""petrinav's optimiser against Storm (stormpy) on DRN files.

Four parts, each optional:

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
* ``stiff``: the random MDP (``random_mdp_2``) on which neither tool's
  value iteration converges, its ``Tmax`` and ``R{"cost"}max`` solved
  exactly by policy iteration (numpy), with the spectral radius that
  makes value iteration slow.
* ``time``: end to end on a large file (``corridors N``; N = 175:
  1,046,501 states, a Markov automaton written by ``gspn convert``): the wall time of
  the whole ``petrinav gspn optimize`` process (reading, graph analysis,
  iteration, output) against Storm's ``build_model_from_drn`` plus
  ``model_checking`` in a child process (the interpreter's start and
  ``import stormpy`` not counted), for ``Pmax=? [F "all_working"]`` and
  ``Tmin=? [F "all_working" | "lost"]``; Storm with its default settings and
  in sound mode; each repeated (``--repeat``), the best kept.

Usage (from the repository root, after ``cargo build --release -p
petrinav``; stormpy 2.0 in a virtual environment):

    /tmp/storm/bin/python -u crates/petri/bench/storm_decisions.py agree ours
    /tmp/storm/bin/python -u crates/petri/bench/storm_decisions.py stiff
    /tmp/storm/bin/python -u crates/petri/bench/storm_decisions.py time --size 175 --repeat 1

Options: --petrinav PATH (default target/release/petrinav), --workdir DIR
(default a temporary directory), --storm-timeout SECONDS (default 1800),
--markdown (tables for BENCHMARKS.md).
"""

import argparse
import json
import math
import os
import random
import signal
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


def run_child(cmd, timeout=None):
    """Runs `cmd` under /usr/bin/time in its own process group (killed
    whole on timeout): (return code or None on timeout, stdout, stderr,
    wall seconds, peak resident memory in MiB)."""
    with tempfile.NamedTemporaryFile(suffix=".rss") as rss:
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            ["/usr/bin/time", "-f", "%M", "-o", rss.name] + cmd,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        try:
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            return None, "", "timeout", time.perf_counter() - t0, None
        wall = time.perf_counter() - t0
        try:
            peak = int(open(rss.name).read().split()[-1]) / 1024
        except (ValueError, IndexError):
            peak = None
        return proc.returncode, out, err, wall, peak


def ours(petrinav, path, prop, precision="1e-9", with_memory=False):
    code, out, err, wall, peak = run_child(
        [petrinav, "gspn", "optimize", path, "--objective", prop, "--json", "--precision", precision]
    )
    if code != 0:
        result = (None, wall, err.strip())
    else:
        v = json.loads(out)["value"]
        result = ((math.inf if v == "infinity" else float(v)), wall, "")
    return result + (peak,) if with_memory else result


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


def storm(path, props, sound, timeout, with_memory=False):
    code, out, err, _, peak = run_child(
        [sys.executable, "-c", STORM_CHILD, path, json.dumps(props), "sound" if sound else "default"], timeout
    )
    if code is None:
        result = (None, "timeout")
    elif code != 0:
        result = (None, err.strip().splitlines()[-1] if err.strip() else f"exit {code}")
    else:
        result = (json.loads(out), "")
    return result + (peak,) if with_memory else result


def close(a, b):
    if a is None or b is None:
        return False
    if math.isinf(a) or math.isinf(b):
        return math.isinf(a) and math.isinf(b)
    return abs(a - b) <= 2e-6 * max(abs(a), abs(b)) + 1e-12


def compare(petrinav, files, timeout, markdown, head_file="file"):
    """Both tools on every property of every file, one Storm process per
    property (a timeout loses one row, not a file); each row printed as it
    is measured."""
    head = [head_file, "property", "petrinav", "Storm (sound)", "agree"]
    table = Streaming(head, markdown)
    failures = 0
    for path, props in files:
        for p in props:
            s, err = storm(path, [p], True, timeout)
            ov, _, oerr = ours(petrinav, path, p)
            shown = "n/a" if ov is None else f"{ov:.10g}"
            if s is None:
                table.row((os.path.basename(path), p, shown, f"Storm: {err}", "no"))
                failures += 1
                continue
            res = s["results"][0]
            sv = math.inf if res["value"] == "inf" else float(res["value"])
            ok = close(ov, sv)
            failures += not ok
            table.row((os.path.basename(path), p, shown, f"{sv:.10g}", "yes" if ok else f"NO {oerr}"))
    print(f"{table.count} properties, {failures} disagreements", flush=True)
    return failures


class Streaming:
    """A table printed row by row (fixed column widths in text)."""

    WIDTHS = [24, 28, 20, 20, 8, 14, 18, 22]

    def __init__(self, head, markdown):
        self.markdown = markdown
        self.count = 0
        if markdown:
            print("| " + " | ".join(head) + " |")
            print("|" + "---|" * len(head), flush=True)
        else:
            self._text(head)

    def _text(self, r):
        print("  ".join(str(x).ljust(k) for x, k in zip(r, self.WIDTHS)), flush=True)

    def row(self, r):
        self.count += 1
        if self.markdown:
            print("| " + " | ".join(str(x) for x in r) + " |", flush=True)
        else:
            self._text(r)


def convert(petrinav, net, out):
    subprocess.run([petrinav, "gspn", "convert", net, out], check=True, capture_output=True)


def family(petrinav, name, n, out):
    subprocess.run([petrinav, "gspn", "family", name, str(n), "-o", out], check=True, capture_output=True)


def timing(petrinav, workdir, size, repeat, timeout, modes, markdown):
    """End to end on corridors `size`: each property, ours then Storm in
    each mode, `repeat` times, the best kept; a row printed per property
    and mode as soon as it is measured, with the peak memory of each."""
    net = os.path.join(workdir, f"corridors{size}.toml")
    drn = os.path.join(workdir, f"corridors{size}.drn")
    if not os.path.exists(drn):
        family(petrinav, "corridors", size, net)
        convert(petrinav, net, drn)
    props = ['Pmax=? [F "all_working"]', 'Tmin=? [F "all_working" | "lost"]']
    load = os.getloadavg()
    print(f"load average before the runs: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; file {drn} ({os.path.getsize(drn) / 1e6:.0f} MB)", flush=True)
    head = ["property", "states", "petrinav s", "petrinav MiB", "Storm s", "Storm MiB", "Storm mode", "Storm/petrinav", "petrinav value", "Storm value"]
    table = Streaming(head, markdown)
    for p in props:
        best_ours = min((ours(petrinav, drn, p, "1e-6", with_memory=True) for _ in range(repeat)), key=lambda r: r[1])
        for sound in [m == "sound" for m in modes]:
            runs = []
            for _ in range(repeat):
                s, err, peak = storm(drn, [p], sound, timeout, with_memory=True)
                if s is None:
                    runs.append((math.inf, err, None, None, peak))
                else:
                    res = s["results"][0]
                    runs.append((s["read"] + res["check"], "", res["value"], s["states"], peak))
            st, err, sv, n, peak = min(runs, key=lambda r: r[0])
            table.row(
                (
                    p,
                    n,
                    f"{best_ours[1]:.2f}",
                    f"{best_ours[3]:.0f}" if best_ours[3] else "?",
                    f"{st:.2f}" if err == "" else err,
                    f"{peak:.0f}" if peak else "?",
                    "sound" if sound else "default",
                    f"{st / best_ours[1]:.1f}x" if err == "" else "-",
                    f"{best_ours[0]:.9g}" if best_ours[0] is not None else best_ours[2],
                    sv,
                )
            )
    load = os.getloadavg()
    print(f"load average after the runs: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)


def read_discrete_drn(path):
    """The states of a DTMC / MDP DRN file as this script writes them:
    (state reward, is goal, [(action reward, {target: probability})])."""
    lines = open(path).read().splitlines()
    i = lines.index("@model") + 1
    states = []
    while i < len(lines):
        head = lines[i].split()
        i += 1
        rows = []
        while i < len(lines) and lines[i].startswith("\taction"):
            reward = float(lines[i].split()[2].strip("[]"))
            i += 1
            entries = {}
            while i < len(lines) and lines[i].startswith("\t\t"):
                t, _, p = lines[i].split()
                entries[int(t)] = float(p)
                i += 1
            rows.append((reward, entries))
        states.append((float(head[2].strip("[]")), "goal" in head, rows))
    return states


def policy_iteration(path, what, maximise):
    """An independent exact answer for `T [F "goal"]` (what = "time") or
    `R{"cost"} [F "goal"]` (what = "cost") on a DTMC / MDP file where the
    goal is reached almost surely under every policy: policy iteration, a
    dense linear solve (numpy) per policy. Returns the initial state's
    value, the improvements and the spectral radius of the optimal
    policy's transient part (how slowly value iteration converges)."""
    import numpy as np

    states = read_discrete_drn(path)
    n = len(states)

    def cost(s, r):
        return 1.0 if what == "time" else states[s][0] + states[s][2][r][0]

    def q(s, r, x):
        return cost(s, r) + sum(p * x[t] for t, p in states[s][2][r][1].items())

    def transient(policy):
        m = np.zeros((n, n))
        for s, (_, goal, rows) in enumerate(states):
            if not goal:
                for t, p in rows[policy[s]][1].items():
                    if not states[t][1]:
                        m[s, t] = p
        return m

    policy = [0] * n
    for improvements in range(1000):
        b = np.array([0.0 if states[s][1] else cost(s, policy[s]) for s in range(n)])
        x = np.linalg.solve(np.eye(n) - transient(policy), b)
        better = list(policy)
        for s, (_, goal, rows) in enumerate(states):
            if goal:
                continue
            pick = (max if maximise else min)(range(len(rows)), key=lambda r: q(s, r, x))
            if abs(q(s, pick, x) - q(s, policy[s], x)) > 1e-12 * max(1.0, abs(x[s])):
                better[s] = pick
        if better == policy:
            break
        policy = better
    rho = max(abs(np.linalg.eigvals(transient(policy))))
    return float(x[0]), improvements, float(rho)


def stiff(workdir):
    """The random MDP on which both tools' value iterations run out of
    time (BENCHMARKS.md): its exact maxima by policy iteration."""
    path = os.path.join(workdir, "random_mdp_2.drn")
    random_drn(path, "mdp", 400, seed=46 * 10 + 2)
    for what, prop in (("time", 'Tmax=? [F "goal"]'), ("cost", 'R{"cost"}max=? [F "goal"]')):
        v, k, rho = policy_iteration(path, what, True)
        print(f"{os.path.basename(path)}  {prop}  policy iteration: {v!r} ({k} improvements); spectral radius under the policy 1 - {1 - rho:.3g}: value iteration needs about {math.log(1e-9) / math.log(rho):.2g} sweeps for 1e-9", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("parts", nargs="*", default=["agree", "ours", "time"])
    ap.add_argument("--petrinav", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "petrinav"))
    ap.add_argument("--workdir")
    ap.add_argument("--storm-timeout", type=float, default=1800)
    ap.add_argument("--size", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--modes", default="default,sound", help="Storm's modes timed: default, sound or both")
    ap.add_argument("--agree-timeout", type=float, default=300, help="seconds per Storm call in agree and ours")
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
                files.append((path, properties(kind)))
        failures += compare(a.petrinav, files, a.agree_timeout, a.markdown)
    if "ours" in a.parts:
        files = []
        sup = os.path.join(workdir, "supervisor_decisions.drn")
        convert(a.petrinav, "models/supervisor_decisions.toml", sup)
        files.append((sup, ['Tmin=? [F "success"]', 'Tmax=? [F "success"]', 'R{"success"}max=? [LRA]', 'Pmax=? [F "failure"]', 'LRAmin=? ["localized"]']))
        net = os.path.join(workdir, "corridors8.toml")
        family(a.petrinav, "corridors", 8, net)
        drn = os.path.join(workdir, "corridors8.drn")
        convert(a.petrinav, net, drn)
        files.append((drn, ['Pmax=? [F "all_working"]', 'Pmin=? [F "lost"]', 'Tmin=? [F "all_working" | "lost"]', 'R{"trips"}max=? [LRA]']))
        failures += compare(a.petrinav, files, a.agree_timeout, a.markdown, "file (written by petrinav)")
    if "stiff" in a.parts:
        stiff(workdir)
    if "time" in a.parts:
        timing(a.petrinav, workdir, a.size, a.repeat, a.storm_timeout, a.modes.split(","), a.markdown)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
