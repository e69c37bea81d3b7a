"""pn.nav.tour gives the legs `petrinav nav tour --json` gives, for the same
seed."""

import petrinav as pn

PLACES = (
    "south_west: [-8.0, -0.15, 0.0]\n"
    "south_middle: [-1.0, -0.15, 0.0]\n"
    "south_east: [5.0, -0.15, 0.0]\n"
)


def test_a_seeded_tour_gives_the_cli_legs(cli, root, tmp_path):
    places = tmp_path / "places.yaml"
    places.write_text(PLACES)
    levine = root / "maps/levine/levine.yaml"
    for behaviour, people in [("automove", 20), ("contour", 0)]:
        lines = cli.json_lines(
            "nav", "tour", levine, "--goals", places, "--behaviour", behaviour,
            "--people", people, "--seed", 3,
        )
        *expected, summary = lines
        legs = pn.nav.tour(levine, goals=places, behaviour=behaviour, people=people, seed=3)
        assert legs == expected
        assert len(legs) == summary["summary"]["legs"] == 2
        assert [(l["from"], l["to"]) for l in legs] == [
            ("south_west", "south_middle"),
            ("south_middle", "south_east"),
        ]


def test_tour_picture_and_mission_log(cli, root, tmp_path):
    places = tmp_path / "places.yaml"
    places.write_text(PLACES)
    levine = root / "maps/levine/levine.yaml"
    picture = tmp_path / "tour.png"
    log = tmp_path / "missions.jsonl"
    legs = pn.nav.tour(levine, goals=places, seed=5, output=picture, log=log, calibration=True)
    assert picture.stat().st_size > 1000
    # One calibration run per leg that had a route.
    entries = log.read_text().splitlines()
    assert len(entries) == sum(l["outcome"] != "unreachable" for l in legs) == 2
    assert all('"kind":"calibration"' in e for e in entries)
    assert "automove" in pn.nav.BEHAVIOURS
