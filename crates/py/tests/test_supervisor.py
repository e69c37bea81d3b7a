"""pn.supervisor.select is `petrinav gspn select --json`, to the last bit."""

import petrinav as pn
from conftest import close


def test_select_equals_the_cli(cli, root):
    cases = [
        {},
        {"lambda7": 1 / 122.33, "lambda8": 1 / 186.98},
        {"lambda7": "1/122.33", "lambda8": "1/186.98"},
        {"lambda3": 0.5, "lambda9": 2, "lambda11": 1e-7},
    ]
    for rates in cases:
        args = ["gspn", "select"]
        for k, v in rates.items():
            args += ["--set", f"{k}={v!r}" if not isinstance(v, str) else f"{k}={v}"]
        expected = cli.json(*args)
        got = pn.supervisor.select(**rates)
        assert got.keys() == expected.keys()
        assert got["choice"] == expected["choice"]
        for k, v in expected.items():
            if isinstance(v, float):
                assert close(got[k], v), (rates, k)
            else:
                assert got[k] == v
        assert got == expected  # in fact the same bits


def test_select_on_another_model(cli, root):
    model = root / "models" / "supervisor.toml"
    assert pn.supervisor.select(model=model, lambda7=0.01) == cli.json(
        "gspn", "select", "--model", model, "--set", "lambda7=0.01"
    )


def test_the_decision_follows_the_throughputs():
    d = pn.supervisor.select(lambda7=1 / 122.33, lambda8=1 / 186.98)
    assert d["choice"] == ("automove" if d["f_auto"] > d["f_cont"] else "contour")
    assert d["tangible_markings"] == 13
