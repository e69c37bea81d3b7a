"""Bad input raises the matching petrinav.Error subclass with the command
line's message (what `petrinav` prints after `error: `); nothing crashes
the interpreter, a Rust panic included."""

import subprocess
import sys

import pytest

import petrinav as pn


def raises(cls, fn, *args, **kwargs) -> str:
    with pytest.raises(cls) as info:
        fn(*args, **kwargs)
    assert isinstance(info.value, pn.Error)
    return str(info.value)


def test_missing_file(cli, tmp_path):
    missing = tmp_path / "nope.pnpro"
    msg = raises(pn.FileError, pn.load, missing)
    assert msg == cli.error("gspn", "info", missing)
    assert "No such file" in msg
    assert isinstance(pytest.raises(OSError, pn.load, missing).value, pn.FileError)


def test_malformed_nets(cli, tmp_path):
    cases = {
        "bad.pnml": "<pnml><net id='x'><place id='p'></net></pnml>",
        "bad.toml": "[[place]\nname = 'p'\n",
        "bad.pnpro": "not xml at all",
        "dup.toml": "[[place]]\nname = 'p'\n[[place]]\nname = 'p'\n",
    }
    for name, text in cases.items():
        path = tmp_path / name
        path.write_text(text)
        msg = raises(pn.FormatError, pn.load, path)
        assert msg == cli.error("gspn", "info", path), name
        assert isinstance(pytest.raises(ValueError, pn.load, path).value, pn.ParseError)
    msg = raises(pn.FormatError, pn.load, tmp_path / "net.txt")
    assert msg == cli.error("gspn", "info", tmp_path / "net.txt")
    raises(pn.FormatError, pn.loads, "[[place]]\nname = 1\n")


def test_unknown_place_in_a_measure(cli, kanban_pnpro):
    sol = pn.load(kanban_pnpro).solve()
    msg = raises(pn.MeasureError, sol.probability, "#Nope > 0")
    assert msg == cli.error("gspn", "solve", kanban_pnpro, "--measure", "#Nope > 0")
    assert msg == "measure `#Nope > 0`: cannot evaluate `#Nope` for a measure: unknown place `Nope`"
    msg = raises(pn.MeasureError, sol.mean, "#Pm1 +")
    assert msg == cli.error("gspn", "solve", kanban_pnpro, "--measure", "#Pm1 +")
    assert raises(pn.MeasureError, sol.throughput, "t99") == "the net has no transition `t99`"
    assert raises(pn.MeasureError, sol.mean_tokens, "P99") == "the net has no place `P99`"


def test_nan_rate(cli, tmp_path):
    net = tmp_path / "nanrate.toml"
    net.write_text(
        "[params]\nlambda = nan\n"
        "[[place]]\nname = 'p'\ninitial = 1\n[[place]]\nname = 'q'\n"
        "[[transition]]\nname = 'go'\nrate = 'lambda'\ninputs = ['p']\noutputs = ['q']\n"
        "[[transition]]\nname = 'back'\nrate = 1.0\ninputs = ['q']\noutputs = ['p']\n"
    )
    msg = raises(pn.ParameterError, pn.load(net).solve)
    assert msg == cli.error("gspn", "solve", net)
    assert msg == "the rate of timed transition `go` must be a finite number > 0, got NaN"
    # A NaN given as a parameter value: as `--param lambda=nan`.
    msg = raises(pn.ParameterError, pn.load, net, params={"lambda": float("nan")})
    assert msg == cli.error("gspn", "solve", net, "--param", "lambda=nan")
    msg = raises(pn.ParameterError, pn.load, net, params={"lambda": "0/0"})
    assert msg == cli.error("gspn", "solve", net, "--param", "lambda=0/0")
    with pytest.raises(TypeError):
        pn.load(net, params={"lambda": True})


def test_parameter_errors(cli, kanban_pnpro, root):
    msg = raises(pn.ParameterError, pn.load, kanban_pnpro, params={"M": 3})
    assert msg == cli.error("gspn", "info", kanban_pnpro, "--param", "M=3")
    fms = root / "crates/petri/tests/data/greatspn/FlexibleManufacturingSystem.PNPRO"
    assert raises(pn.ParameterError, pn.load, fms) == cli.error("gspn", "info", fms)
    raises(pn.ParameterError, pn.family("kanban", 1).solve, method="newton")
    msg = raises(pn.ParameterError, pn.supervisor.select, lambda12=1.0)
    assert msg == cli.error("gspn", "select", "--set", "lambda12=1")
    msg = raises(pn.ParameterError, pn.supervisor.select, speed=1.0)
    assert msg == cli.error("gspn", "select", "--set", "speed=1")


def test_state_limit(cli, kanban_pnpro):
    net = pn.load(kanban_pnpro, params={"N": 3})
    msg = raises(pn.StateLimitError, net.solve, max_states=1000)
    assert msg == cli.error("gspn", "solve", kanban_pnpro, "--param", "N=3", "--max-states", "1000")
    raises(pn.StateLimitError, pn.family, "philosophers", 10**6)


def test_simulation_limit(cli, root):
    model = root / "models" / "supervisor.toml"
    msg = raises(pn.SimulationError, pn.load(model).simulate, time=1e9, seed=1, max_events=1000)
    assert msg == cli.error("gspn", "simulate", model, "--time", "1e9", "--seed", "1", "--max-events", "1000")


def test_a_tour_goal_in_a_wall(cli, root, tmp_path):
    places = tmp_path / "places.yaml"
    places.write_text("south_west: [-8.0, -0.15, 0.0]\nin_a_wall: [-1.0, -1.0, 0.0]\n")
    levine = root / "maps/levine/levine.yaml"
    msg = raises(pn.NavError, pn.nav.tour, levine, goals=places)
    assert msg == cli.error("nav", "tour", levine, "--goals", places)
    assert "cannot stand there" in msg and "`in_a_wall` (-1, -1) is inside an obstacle" in msg
    raises(pn.ParameterError, pn.nav.tour, levine, goals=places, behaviour="teleport")
    msg = raises(pn.MapError, pn.nav.tour, root / "maps/README.md", goals=places)
    assert msg == cli.error("nav", "tour", root / "maps/README.md", "--goals", places)
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: nowhere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    msg = raises(pn.NavError, pn.nav.tour, bad, goals=places)
    assert msg == cli.error("nav", "tour", bad, "--goals", places)


def test_lab_errors(cli, tmp_path):
    msg = raises(pn.LabError, pn.lab.run, "nosuchsuite", out=tmp_path / "x")
    assert msg == cli.error("lab", "run", "nosuchsuite", "--out", tmp_path / "x")
    raises(pn.ParameterError, pn.lab.run, "voting", shard="9/2", out=tmp_path / "y")


def test_a_rust_panic_is_an_exception_not_a_crash():
    for detach in (False, True):
        with pytest.raises(pn.PanicError, match="a test panic") as info:
            pn._petrinav._panic_for_tests(detach)
        assert isinstance(info.value, RuntimeError)
    # The interpreter goes on.
    assert pn.family("kanban", 1).name == "kanban1"


def test_errors_never_crash_a_fresh_interpreter(tmp_path):
    script = (
        "import petrinav as pn\n"
        "for f in (lambda: pn.load('/no/such.pnml'), lambda: pn.loads('<pnml>', format='pnml'),\n"
        "          lambda: pn._petrinav._panic_for_tests(True)):\n"
        "    try: f()\n"
        "    except pn.Error as e: print(type(e).__name__)\n"
    )
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["FileError", "FormatError", "PanicError"]
