"""PNML interop with pm4py (from PyPI), both ways: the same places,
transitions and arcs (kinds and multiplicities), and the initial marking."""

import warnings

import pytest

import petrinav as pn

pm4py = pytest.importorskip("pm4py")
from pm4py.objects.petri_net import properties as pm4py_props  # noqa: E402
from pm4py.objects.petri_net.obj import InhibitorNet, Marking, PetriNet  # noqa: E402
from pm4py.objects.petri_net.utils.petri_utils import add_arc_from_to  # noqa: E402


def read_pm4py(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pm4py.read_pnml(str(path))


def pm4py_shape(net, im):
    """Places, transitions (by label), arcs and the initial marking, by name."""
    pname = {p: p.name for p in net.places}
    tname = {t: t.label if t.label is not None else t.name for t in net.transitions}

    def kind(a):
        if isinstance(a.source, PetriNet.Transition):
            return "output"
        return "inhibitor" if a.properties.get(pm4py_props.ARCTYPE) == pm4py_props.INHIBITOR_ARC else "input"

    arcs = sorted(
        (kind(a), pname.get(a.source, pname.get(a.target)), tname.get(a.target, tname.get(a.source)), a.weight)
        for a in net.arcs
    )
    return (
        sorted(pname.values()),
        sorted(tname.values()),
        arcs,
        {pname[p]: n for p, n in im.items()},
    )


def petrinav_shape(net):
    arcs = sorted((a.kind, a.place, a.transition, a.multiplicity) for a in net.arcs)
    marking = {p.name: p.initial for p in net.places if p.initial > 0}
    return sorted(p.name for p in net.places), sorted(t.name for t in net.transitions), arcs, marking


@pytest.mark.parametrize("which", ["kanban", "supervisor", "philosophers", "fms-pnpro"])
def test_petrinav_pnml_opens_in_pm4py(which, root, tmp_path):
    net = {
        "kanban": lambda: pn.family("kanban", 2),
        "supervisor": lambda: pn.load(root / "models/supervisor.toml"),
        "philosophers": lambda: pn.load(root / "crates/petri/tests/data/mcc/Philosophers-PT-000005.pnml"),
        "fms-pnpro": lambda: pn.load(
            root / "crates/petri/tests/data/greatspn/FlexibleManufacturingSystem.PNPRO", params={"N": 2}
        ),
    }[which]()
    path = tmp_path / "net.pnml"
    net.save(path)
    pnet, im, _fm = read_pm4py(path)
    assert pm4py_shape(pnet, im) == petrinav_shape(net)
    assert sum(im.values()) > 0


def test_inhibitor_arcs_reach_pm4py(tmp_path):
    net = pn.loads(
        "[[place]]\nname = 'p'\ninitial = 1\n[[place]]\nname = 'q'\n[[place]]\nname = 'block'\n"
        "[[transition]]\nname = 't'\nrate = 1.0\ninputs = ['p']\noutputs = ['q']\ninhibitors = ['block']\n"
        "[[transition]]\nname = 'u'\nrate = 2.0\ninputs = ['q']\noutputs = ['p']\n"
    )
    path = tmp_path / "inh.pnml"
    net.save(path)
    pnet, im, _ = read_pm4py(path)
    assert isinstance(pnet, InhibitorNet)
    assert pm4py_shape(pnet, im) == petrinav_shape(net)
    assert ("inhibitor", "block", "t", 1) in petrinav_shape(net)[2]


def pm4py_net():
    """A net built in pm4py: weights, an inhibitor arc, an invisible
    transition, two transitions with the same label, a final marking."""
    net = InhibitorNet("from_pm4py")
    p = {n: PetriNet.Place(n) for n in ("start", "mid", "end", "guard")}
    for place in p.values():
        net.places.add(place)
    t = {
        "t1": PetriNet.Transition("t1", "register"),
        "t2": PetriNet.Transition("t2", "check"),
        "t3": PetriNet.Transition("t3", "check"),
        "tau": PetriNet.Transition("tau", None),
    }
    for tr in t.values():
        net.transitions.add(tr)
    add_arc_from_to(p["start"], t["t1"], net, weight=2)
    add_arc_from_to(t["t1"], p["mid"], net)
    add_arc_from_to(p["mid"], t["t2"], net)
    add_arc_from_to(p["mid"], t["t3"], net)
    add_arc_from_to(t["t2"], p["end"], net)
    add_arc_from_to(t["t3"], p["end"], net, weight=3)
    add_arc_from_to(p["end"], t["tau"], net)
    add_arc_from_to(t["tau"], p["start"], net, weight=2)
    add_arc_from_to(p["guard"], t["t1"], net, type=pm4py_props.INHIBITOR_ARC)
    return net, Marking({p["start"]: 4}), Marking({p["end"]: 1})


def test_pm4py_pnml_opens_in_petrinav(tmp_path):
    pnet, im, fm = pm4py_net()
    path = tmp_path / "pm4py.pnml"
    pm4py.write_pnml(pnet, im, fm, str(path))
    net = pn.load(path)
    places, transitions, arcs, marking = petrinav_shape(net)
    assert places == ["end", "guard", "mid", "start"]
    # Labels name the transitions; a label two transitions share falls back
    # to their ids, and the invisible transition is known by its id.
    assert transitions == ["register", "t2", "t3", "tau"]
    assert marking == {"start": 4}
    assert ("inhibitor", "guard", "register", 1) in arcs
    assert ("input", "start", "register", 2) in arcs and ("output", "end", "t3", 3) in arcs
    assert len(arcs) == 9
    # And back: what petrinav writes, pm4py reads as the same net.
    back = tmp_path / "back.pnml"
    net.save(back)
    bnet, bim, _ = read_pm4py(back)
    assert pm4py_shape(bnet, bim) == petrinav_shape(net)
    assert petrinav_shape(pn.load(back)) == petrinav_shape(net)
