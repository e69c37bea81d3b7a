"""Decisions from Python: `Net.optimize` on a net with decisions and
`pn.load("model.drn").optimize(...)` on DRN models, every number compared
with `petrinav gspn optimize --json` (the same engine: the same bits), the
policy against the command line's choices, and the errors."""

import math

import pytest

import petrinav as pn

OBJECTIVES = [
    'Tmin=? [F "success"]',
    'Tmax=? [F "success"]',
    'R{"success"}max=? [LRA]',
    'Pmax=? [F "failure"]',
]

#: A Markov automaton solvable by hand. State 0 chooses: `fast` reaches
#: the goal (state 2) with probability 1/2 and loses (state 3, absorbing)
#: otherwise; `safe` goes to state 1, which leaves at rate 2 for the goal.
#: Pmax = 1 (`safe`), Tmin to goal-or-lost = 0 + 1/2 (`fast`: no time in
#: probabilistic states; `safe`: 1/2 s in state 1; both 1/2 — `fast` is 0).
SMALL_MA = """// hand-made
@type: Markov Automaton
@value_type: double
@parameters

@reward_models
cost
@nr_states
4
@nr_choices
5
@model
state 0 !0.0 [0] init
\taction fast [1]
\t\t2 : 0.5
\t\t3 : 0.5
\taction safe [0]
\t\t1 : 1
state 1 !2.0 [3]
\taction 0 [0]
\t\t2 : 1
state 2 !1.0 [0] goal
\taction 0 [0]
\t\t2 : 1
state 3 !1.0 [0] lost
\taction 0 [0]
\t\t3 : 1
"""


@pytest.fixture(scope="module")
def supervisor(root):
    return pn.load(root / "models" / "supervisor_decisions.toml")


@pytest.fixture()
def small_ma(tmp_path):
    path = tmp_path / "small.drn"
    path.write_text(SMALL_MA)
    return path


def same(a, b):
    """The command line's JSON number (`"infinity"` for ∞) against ours."""
    if b == "infinity":
        return a == math.inf
    return a == b


@pytest.mark.parametrize("objective", OBJECTIVES)
def test_net_optimize_equals_the_cli(cli, root, supervisor, objective):
    expected = cli.json("gspn", "optimize", root / "models" / "supervisor_decisions.toml", "--objective", objective)
    got = supervisor.optimize(objective)
    for key in ("value", "bound", "lower", "upper"):
        assert same(got[key], expected[key]), key
    for key in ("property", "model", "method", "iterations", "failed_guesses"):
        assert got[key] == expected[key], key
    assert len(got["choices"]) == len(expected["choices"]) > 0
    for g, e in zip(got["choices"], expected["choices"]):
        assert (g["state"], g["marking"], g["chosen"]) == (e["state"], e["marking"], e["chosen"])
        for ga, ea in zip(g["alternatives"], e["alternatives"]):
            assert ga["action"] == ea["action"]
            assert same(ga["lower"], ea["lower"]) and same(ga["upper"], ea["upper"])
        assert got["policy"][g["marking"]] == g["chosen"]
    assert len(got["policy"]) == len(got["choices"])


def test_net_optimize_precision_and_cache(supervisor):
    coarse = supervisor.optimize('Tmin=? [F "success"]', precision=1e-3)
    fine = supervisor.optimize('Tmin=? [F "success"]', precision=1e-9)
    assert fine["bound"] <= 1e-9 * fine["value"] and coarse["bound"] <= 1e-3 * coarse["value"]
    assert fine["iterations"] >= coarse["iterations"]
    assert abs(coarse["value"] - fine["value"]) <= coarse["bound"] + fine["bound"]
    absolute = supervisor.optimize('Tmin=? [F "success"]', precision=1e-2, absolute=True)
    assert absolute["bound"] <= 1e-2


def test_drn_model_is_loaded_and_solved_by_hand(small_ma):
    model = pn.load(small_ma)
    assert isinstance(model, pn.Model)
    assert (model.type, len(model), model.states, model.actions, model.transitions) == ("MA", 4, 4, 5, 6)
    assert model.initial_states == [0]
    assert model.labels["goal"] == [2] and model.labels["lost"] == [3]
    assert model.reward_models == ["cost"]
    assert "4 states" in repr(model)
    best = model.optimize('Pmax=? [F "goal"]')
    assert best["value"] == 1.0 and best["policy"] == {"state 0": "safe"}
    worst = model.optimize('Pmin=? [F "goal"]')
    assert abs(worst["value"] - 0.5) <= worst["bound"] + 1e-15 and worst["policy"] == {"state 0": "fast"}
    fast = model.optimize('Tmin=? [F "goal" | "lost"]')
    assert fast["value"] == 0.0 and fast["policy"] == {"state 0": "fast"}
    slow = model.optimize('Tmax=? [F "goal" | "lost"]')
    assert abs(slow["value"] - 0.5) <= slow["bound"] + 1e-15 and slow["policy"] == {"state 0": "safe"}
    # `safe` costs 3 per second for 1/2 s, `fast` 1 at once.
    cheap = model.optimize('R{"cost"}min=? [F "goal" | "lost"]')
    assert abs(cheap["value"] - 1.0) <= cheap["bound"] + 1e-15 and cheap["policy"] == {"state 0": "fast"}


def test_drn_infinity_is_a_float(small_ma):
    # From state 0 under `fast` the goal is missed half of the time:
    # the expected time to it is infinite.
    r = pn.load(small_ma).optimize('Tmax=? [F "goal"]')
    assert r["value"] == math.inf and r["upper"] == math.inf
    alternatives = {a["action"]: a for a in r["choices"][0]["alternatives"]}
    assert alternatives["fast"]["value"] == math.inf
    assert r["policy"] == {"state 0": "fast"}


def test_drn_optimize_equals_the_cli(cli, root, supervisor, tmp_path):
    drn = tmp_path / "supervisor.drn"
    cli.run("gspn", "convert", root / "models" / "supervisor_decisions.toml", drn)
    model = pn.load(drn)
    assert model.type == "MA"
    for objective in OBJECTIVES:
        expected = cli.json("gspn", "optimize", drn, "--objective", objective)
        got = model.optimize(objective)
        for key in ("value", "bound", "lower", "upper"):
            assert same(got[key], expected[key]), (objective, key)
        assert [c["chosen"] for c in got["choices"]] == [c["chosen"] for c in expected["choices"]]
        # The DRN file and the net: the same values.
        assert got["value"] == supervisor.optimize(objective)["value"], objective


def test_errors(small_ma, supervisor, tmp_path):
    with pytest.raises(pn.ParameterError, match="DRN file holds numbers"):
        pn.load(small_ma, params={"N": 2})
    with pytest.raises(pn.MeasureError, match="property"):
        pn.load(small_ma).optimize("Pmax=? [G")
    with pytest.raises(pn.MeasureError):
        supervisor.optimize('Pmax=? [F "nowhere"]')
    with pytest.raises(pn.ParameterError, match="precision"):
        supervisor.optimize('Tmin=? [F "success"]', precision=0.0)
    bad = tmp_path / "bad.drn"
    bad.write_text(SMALL_MA.replace("2 : 0.5", "2 : 0.7"))
    with pytest.raises(pn.FormatError, match="bad.drn"):
        pn.load(bad)
    with pytest.raises(pn.FileError):
        pn.load(tmp_path / "missing.drn")
    # A net without decisions still optimises (its CTMC: nothing to choose).
    plain = pn.family("kanban", 1).optimize("Tmax=? [F #Pm1 = 1]")
    assert plain["choices"] == [] and plain["policy"] == {}


def test_docstrings():
    for obj in (pn.Net.optimize, pn.Model.optimize, pn.Model, pn.load):
        assert obj.__doc__ and len(obj.__doc__) > 40, obj
