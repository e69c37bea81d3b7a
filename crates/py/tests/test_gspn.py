"""The GSPN engine from Python: loading, the state space, the steady state,
properties, simulation, saving — every number compared with the command
line's `--json` output (to 1e-12; in practice they are the same bits)."""

import numpy as np
import pytest

import petrinav as pn
from conftest import close

MEASURES = ["#Pm1 >= 1", "#Pkan1 + 2 * #Pout4", "#Pm1 = 1 and #Pm4 = 0"]


@pytest.fixture(scope="module")
def kanban3(kanban_pnpro):
    return pn.load(kanban_pnpro, params={"N": 3})


@pytest.fixture(scope="module")
def kanban3_solution(kanban3):
    return kanban3.solve()


def test_load_reads_every_format_and_binds_params(kanban_pnpro, tmp_path, root):
    net = pn.load(kanban_pnpro, params={"N": 3})
    assert net.name == "kanban1"
    assert net.params["N"] == 3.0
    assert [p.name for p in net.places][:4] == ["Pm1", "Pback1", "Pkan1", "Pout1"]
    assert net.places[2].initial == 3
    tin1 = net.transitions[0]
    assert (tin1.name, tin1.kind, tin1.rate, tin1.servers) == ("tin1", "timed", 1.0, 1)
    assert len(net.arcs) == 40 and net.arcs[0].kind == "input"
    assert list(net.initial_marking) == [p.initial for p in net.places]
    sup = pn.load(root / "models" / "supervisor.toml")
    immediate = [t for t in sup.transitions if t.kind == "immediate"]
    assert immediate and all(t.weight > 0 and t.priority >= 1 for t in immediate)
    # The same net through every format, and from a string.
    for ext in ("pnml", "toml", "pnpro"):
        path = tmp_path / f"k.{ext}"
        net.save(path)
        again = pn.load(path, params={"N": 3})
        assert [(p.name, p.initial) for p in again.places] == [(p.name, p.initial) for p in net.places]
        assert [(t.name, t.rate) for t in again.transitions] == [(t.name, t.rate) for t in net.transitions]
        text = net.dumps(ext)
        assert pn.loads(text, format=ext, params={"N": 3}).dumps(ext) == text
    assert net.with_params(N=2).places[2].initial == 2
    assert "pnml" in pn.formats()


def test_family_builds_the_cli_nets(cli, tmp_path):
    path = tmp_path / "fms2.toml"
    cli.run("gspn", "family", "fms", "2", "-o", path)
    assert pn.family("fms", 2).dumps("toml") == path.read_text()


def test_state_space_markings_as_numpy(kanban3):
    space = kanban3.state_space()
    assert len(space) == 58_400 and space.tangible_markings == 58_400
    assert space.vanishing_markings == 0 and space.reachable_markings == 58_400
    m = space.markings
    assert m.shape == (58_400, 16) and m.dtype == np.int64
    assert space.place_names[0] == "Pm1"
    # P-invariant of each cell: Pm + Pback + Pkan + Pout = N.
    for c in range(4):
        assert (m[:, 4 * c : 4 * c + 4].sum(axis=1) == 3).all()
    assert (m[0] == kanban3.initial_marking).all()


def test_solve_equals_the_cli_on_kanban_3(cli, kanban_pnpro, kanban3_solution):
    sol = kanban3_solution
    args = ["gspn", "solve", kanban_pnpro, "--param", "N=3"]
    for m in MEASURES:
        args += ["--measure", m]
    expected = cli.json(*args)
    got = sol.to_dict(MEASURES)
    assert got["tangible_markings"] == expected["tangible_markings"] == 58_400
    assert got["solver"] == expected["solver"] and got["iterations"] == expected["iterations"]
    assert close(got["residual"], expected["residual"])
    for name, e in expected["places"].items():
        assert close(sol.mean_tokens(name), e["mean_tokens"]), name
        assert close(sol.prob_nonempty(name), e["prob_nonempty"]), name
    for name, e in expected["transitions"].items():
        assert close(sol.throughput(name), e["throughput"]), name
    for m in MEASURES:
        assert close(sol.mean(m), expected["measures"][m]), m
    assert close(sol.probability("#Pm1 >= 1"), expected["measures"]["#Pm1 >= 1"])
    p = sol.probabilities
    assert p.dtype == np.float64 and p.shape == (58_400,)
    assert abs(p.sum() - 1) < 1e-12 and (p >= 0).all()
    # The arrays agree with the measures.
    markings = sol.markings
    assert close(float(p @ markings[:, 0]), sol.mean_tokens("Pm1"))
    marginal = sol.marginal("Pm1")
    assert len(marginal) == 4 and abs(marginal.sum() - 1) < 1e-12
    assert close(1 - marginal[0], sol.probability("#Pm1 >= 1"))


def test_solve_equals_the_cli_on_the_supervisor_net(cli, root):
    model = root / "models" / "supervisor.toml"
    expected = cli.json("gspn", "solve", model, "--measure", "#P1 = 1 and #P7 = 1")
    sol = pn.load(model).solve()
    assert len(sol.probabilities) == expected["tangible_markings"] == 13
    got = sol.to_dict(["#P1 = 1 and #P7 = 1"])
    for key in ("name", "reachable_markings", "tangible_markings", "vanishing_markings", "ergodic", "solver"):
        assert got[key] == expected[key], key
    for name, e in expected["places"].items():
        assert close(got["places"][name]["mean_tokens"], e["mean_tokens"])
        assert close(got["places"][name]["prob_nonempty"], e["prob_nonempty"])
    for name, e in expected["transitions"].items():
        assert close(sol.throughput(name), e["throughput"]), name
        assert got["transitions"][name]["immediate"] == e["immediate"]
    assert close(sol.probability("#P1 = 1 and #P7 = 1"), expected["measures"]["#P1 = 1 and #P7 = 1"])
    assert sol.throughputs.keys() == expected["transitions"].keys()


def test_solve_methods_and_default_rate(root, cli, kanban_pnpro):
    for method in ("gauss-seidel", "bicgstab", "direct"):
        expected = cli.json("gspn", "solve", kanban_pnpro, "--param", "N=2", "--method", method)
        sol = pn.load(kanban_pnpro, params={"N": 2}).solve(method=method)
        assert sol.solver == expected["solver"] and sol.iterations == expected["iterations"]
        for name, e in expected["transitions"].items():
            assert close(sol.throughput(name), e["throughput"]), (method, name)
    # A plain P/T net (no rates) with a default rate; it deadlocks, so the
    # long run is in its dead markings.
    mcc = root / "crates/petri/tests/data/mcc/Philosophers-PT-000005.pnml"
    expected = cli.json("gspn", "solve", mcc, "--default-rate", "1")
    sol = pn.load(mcc).solve(default_rate=1.0)
    assert not sol.ergodic and len(sol.bottom_probabilities) == expected["bottom_components"]
    for name, e in expected["places"].items():
        assert close(sol.mean_tokens(name), e["mean_tokens"]), name


def test_properties_equal_the_cli_info(cli, kanban_pnpro, root):
    for path, params in [(kanban_pnpro, {"N": 2}), (root / "models" / "supervisor.toml", {})]:
        args = ["gspn", "info", path] + [f"--param={k}={v}" for k, v in params.items()]
        expected = cli.json(*args)
        got = pn.load(path, params=params).properties()
        del expected["generation"], got["generation"]  # timings
        assert got == expected
    props = pn.load(root / "models" / "supervisor.toml").properties()
    assert props["live"] is True and props["dead_markings"] == 0
    assert props["bounds"]["P1"] == 1 and props["p_invariants"]


def test_simulate_equals_the_cli(cli, root):
    model = root / "models" / "supervisor.toml"
    expected = cli.json(
        "gspn", "simulate", model, "--time", "20000", "--seed", "7", "--measure", "#P1 = 1"
    )
    got = pn.load(model).simulate(time=20000, seed=7, measures=["#P1 = 1"])
    assert got == expected
    est = got["throughputs"][got["transition_names"].index("t9")]
    assert est["half_width"] > 0
    # Agrees with the steady state within its interval (generously).
    exact = pn.load(model).solve().throughput("t9")
    assert abs(est["mean"] - exact) < 5 * est["half_width"] + 1e-9


def test_save_writes_what_the_cli_converts(cli, kanban_pnpro, tmp_path):
    for ext in ("pnml", "toml", "pnpro", "dot"):
        ours, theirs = tmp_path / f"ours.{ext}", tmp_path / f"theirs.{ext}"
        pn.load(kanban_pnpro).save(ours)
        cli.run("gspn", "convert", kanban_pnpro, theirs)
        assert ours.read_text() == theirs.read_text(), ext


def test_save_writes_the_parameters_bound_at_load(root, tmp_path):
    fms = root / "crates/petri/tests/data/greatspn/FlexibleManufacturingSystem.PNPRO"
    with pytest.raises(pn.ParameterError):
        pn.load(fms)  # N is a template: it needs a value
    net = pn.load(fms, params={"N": 2})
    net.save(tmp_path / "fms2.pnml")
    again = pn.load(tmp_path / "fms2.pnml")  # no params needed now
    assert again.params["N"] == 2.0
    assert [(p.name, p.initial) for p in again.places] == [(p.name, p.initial) for p in net.places]
    assert len(again.state_space()) == len(net.state_space())


def test_reprs_and_docstrings():
    net = pn.family("kanban", 1)
    assert "16 places" in repr(net)
    assert "tangible" in repr(net.state_space())
    assert "residual" in repr(net.solve())
    for obj in (pn.load, pn.loads, pn.family, pn.Net.solve, pn.Net.state_space, pn.Net.properties,
                pn.Net.simulate, pn.Net.save, pn.Solution.probability, pn.Solution.marginal,
                pn.supervisor.select, pn.nav.tour, pn.lab.run):
        assert obj.__doc__ and len(obj.__doc__) > 40, obj
