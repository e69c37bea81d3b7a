"""pn.bt is `petrinav bt check/analyze --json`, and its errors are the CLI's."""

import json

import pytest

import petrinav as pn
from conftest import close

TREE = "models/bt/nav2/navigate_w_replanning_time.xml"
PARAMS = "models/bt/nav2/nominal.toml"


def test_load_reads_a_shipped_tree(root):
    t = pn.bt.load(root / TREE)
    assert t.name == "NavigateWithReplanningTime"
    assert t.nodes > 5
    assert t.format == 4


def test_check_equals_the_cli(cli, root):
    for name in [TREE, "models/bt/nav2/navigate_on_route_graph_w_recovery.xml"]:
        # Exit code 1 with findings.
        out = cli.run("bt", "check", root / name, "--params", root / PARAMS, "--json", check=False)
        assert out.returncode in (0, 1), out.stderr
        expected = json.loads(out.stdout)
        assert pn.bt.load(root / name).check(root / PARAMS) == expected["findings"]


def test_analyze_equals_the_cli(cli, root):
    expected = cli.json("bt", "analyze", root / TREE, "--params", root / PARAMS)
    got = pn.bt.load(root / TREE).analyze(root / PARAMS)
    assert 0.0 < got["p_success"] <= 1.0
    assert same(got, expected)


def same(a, b) -> bool:
    """Equal structures, floats to 1e-12 (the CLI may be another build)."""
    if isinstance(a, float) or isinstance(b, float):
        return close(a, b)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return a == b


def test_bad_input_raises_the_cli_message(cli, root, tmp_path):
    bad = tmp_path / "t.xml"
    bad.write_text('<root BTCPP_format="4">\n<BehaviorTree ID="A">\n<Frobnicate><A/><B/></Frobnicate>')
    with pytest.raises(pn.FormatError) as e:
        pn.bt.load(bad)
    assert str(e.value) == cli.error("bt", "analyze", bad)
    sidecar = tmp_path / "p.toml"
    sidecar.write_text("[leaf.FollowPath]\np_success = 1.2\n")
    with pytest.raises(pn.ParameterError, match=r"p_success = 1.2"):
        pn.bt.load(root / TREE).analyze(sidecar)
    sidecar.write_text("[leaf.FollowPath]\np_true = 0.5\n")
    with pytest.raises(pn.Error, match=r"`FollowPath` is an action"):
        pn.bt.load(root / TREE).analyze(sidecar)
