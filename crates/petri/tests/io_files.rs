//! The file formats on real files (GreatSPN PNPRO, MCC PNML), round trips
//! between formats, and hand-written PNML fixtures in the tool-specific
//! forms other tools use.

use petri::io::{self, Format};
use petri::{ArcKind, Error, Expr, Net, Param, ParamKind, Params, Servers, Transition, TransitionKind};

const GREATSPN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/greatspn");
const MCC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mcc");

/// `(file, places, transitions, arcs)`, counted in the files.
const GREATSPN_FILES: [(&str, usize, usize, usize); 5] = [
    ("2PhaseLockViolation.PNPRO", 8, 6, 18),
    ("Cycle_of_Four_Seasons.PNPRO", 8, 4, 16),
    ("FlexibleManufacturingSystem.PNPRO", 22, 18, 52),
    ("Philosophers4.PNPRO", 16, 12, 40),
    ("ReaderWriter.PNPRO", 7, 7, 19),
];

const MCC_FILES: [(&str, usize, usize, usize); 4] = [
    ("TokenRing-PT-005.pnml", 36, 156, 624),
    ("Philosophers-PT-000005.pnml", 25, 25, 80),
    ("Philosophers-PT-000010.pnml", 50, 50, 160),
    ("FMS-PT-00002.pnml", 22, 20, 50),
];

fn greatspn(file: &str) -> Net {
    io::read_file(format!("{GREATSPN}/{file}")).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn mcc(file: &str) -> Net {
    io::read_file(format!("{MCC}/{file}")).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn all_files() -> Vec<(String, Net)> {
    let mut out: Vec<(String, Net)> = GREATSPN_FILES
        .iter()
        .map(|(f, ..)| (f.to_string(), greatspn(f)))
        .collect();
    out.extend(MCC_FILES.iter().map(|(f, ..)| (f.to_string(), mcc(f))));
    out
}

/// Asserts two nets are equal, reporting the first difference rather than
/// two whole nets.
#[track_caller]
fn assert_same(got: &Net, want: &Net, context: &str) {
    if got == want {
        return;
    }
    let first = |a: String, b: String, what: &str| -> Option<String> {
        (a != b).then(|| format!("{what}:\n  got  {a}\n  want {b}"))
    };
    let diff = first(got.name.clone(), want.name.clone(), "name")
        .or_else(|| first(format!("{:?}", got.doc), format!("{:?}", want.doc), "doc"))
        .or_else(|| {
            (0..got.params.len().max(want.params.len())).find_map(|i| {
                first(
                    format!("{:?}", got.params.get(i)),
                    format!("{:?}", want.params.get(i)),
                    "param",
                )
            })
        })
        .or_else(|| {
            (0..got.places.len().max(want.places.len())).find_map(|i| {
                first(
                    format!("{:?}", got.places.get(i)),
                    format!("{:?}", want.places.get(i)),
                    "place",
                )
            })
        })
        .or_else(|| {
            (0..got.transitions.len().max(want.transitions.len())).find_map(|i| {
                first(
                    format!("{:?}", got.transitions.get(i)),
                    format!("{:?}", want.transitions.get(i)),
                    "transition",
                )
            })
        })
        .or_else(|| {
            (0..got.arcs.len().max(want.arcs.len())).find_map(|i| {
                first(
                    format!("{:?}", got.arcs.get(i)),
                    format!("{:?}", want.arcs.get(i)),
                    "arc",
                )
            })
        })
        .unwrap_or_else(|| "equal Debug output, different values (NaN?)".into());
    panic!("{context}: nets differ, first difference in {diff}");
}

fn transition<'a>(net: &'a Net, name: &str) -> &'a Transition {
    let id = net
        .transition_id(name)
        .unwrap_or_else(|| panic!("no transition {name}"));
    &net.transitions[id.index()]
}

fn param<'a>(net: &'a Net, name: &str) -> &'a Param {
    net.param(name).unwrap_or_else(|| panic!("no parameter {name}"))
}

fn arcs_between(net: &Net, place: &str, transition: &str) -> Vec<(ArcKind, Expr)> {
    let p = net.place_id(place).unwrap();
    let t = net.transition_id(transition).unwrap();
    net.arcs
        .iter()
        .filter(|a| a.place == p && a.transition == t)
        .map(|a| (a.kind, a.multiplicity.clone()))
        .collect()
}

// ---------------------------------------------------------------------------
// GreatSPN files
// ---------------------------------------------------------------------------

#[test]
fn every_greatspn_file_loads_with_its_counts() {
    for (file, places, transitions, arcs) in GREATSPN_FILES {
        let net = greatspn(file);
        assert_eq!(
            (net.places.len(), net.transitions.len(), net.arcs.len()),
            (places, transitions, arcs),
            "{file}"
        );
        assert!(net.places.iter().all(|p| p.position.is_some()), "{file}");
    }
}

#[test]
fn philosophers4_has_infinite_servers_and_constant_rates() {
    let net = greatspn("Philosophers4.PNPRO");
    assert_eq!(net.name, "Philosophers4");
    for t in &net.transitions {
        let TransitionKind::Timed { rate, servers } = &t.kind else {
            panic!("{} is not timed", t.name);
        };
        // No `nservers` attribute: GreatSPN's default, infinite servers.
        assert_eq!(*servers, Servers::Infinite, "{}", t.name);
        assert!(matches!(rate, Some(Expr::Param(_))), "{}", t.name);
    }
    assert_eq!(
        transition(&net, "T0").kind,
        TransitionKind::Timed {
            rate: Some(Expr::param("lambda")),
            servers: Servers::Infinite
        }
    );
    for name in ["lambda", "mu", "rho"] {
        let p = param(&net, name);
        assert_eq!((p.value, p.kind), (Some(1.0), ParamKind::Real), "{name}");
    }
    assert_eq!(net.places[0].name, "fork1");
    assert_eq!(net.places[0].initial, Expr::Num(1.0));
    assert_eq!(net.places[0].position, Some((21.0, 4.0)));
    assert!(net.instantiate(&Params::new()).is_ok());
}

#[test]
fn flexible_manufacturing_system_needs_n() {
    let net = greatspn("FlexibleManufacturingSystem.PNPRO");
    assert_eq!(net.name, "FMS");
    assert_eq!(
        net.place_id("Pallets")
            .map(|p| net.places[p.index()].initial.clone()),
        Some(Expr::param("N"))
    );

    // Templates: no value; the measures page's assignment is preferred over
    // `last-binding` as the suggestion (t: 1.0 over 2.3).
    let n = param(&net, "N");
    assert_eq!((n.value, n.kind, n.suggested), (None, ParamKind::Int, Some(3.0)));
    let t = param(&net, "t");
    assert_eq!((t.value, t.kind, t.suggested), (None, ParamKind::Real, Some(1.0)));
    assert_eq!(param(&net, "lambda1").value, Some(1.2));
    assert_eq!(param(&net, "rho3").value, Some(0.07));

    for (name, priority) in [("repSpares", 2.0), ("repM3", 3.0), ("sw1", 1.0), ("repM2", 1.0)] {
        assert_eq!(
            transition(&net, name).kind,
            TransitionKind::Immediate {
                weight: Expr::Num(1.0),
                priority: Expr::Num(priority)
            },
            "{name}"
        );
    }
    assert_eq!(
        transition(&net, "load").kind,
        TransitionKind::Timed {
            rate: Some(Expr::Num(0.4)),
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        transition(&net, "ew1").kind,
        TransitionKind::Timed {
            rate: Some(Expr::param("lambda1")),
            servers: Servers::Infinite
        }
    );

    let err = net.instantiate(&Params::new()).unwrap_err();
    match &err {
        Error::UnboundParameter { name, hint, .. } => {
            assert_eq!(name, "N");
            assert!(hint.contains("N=3"), "{err}");
        }
        other => panic!("expected UnboundParameter, got {other}"),
    }
    let gspn = net.instantiate(&Params::new().with("N", 2.0)).unwrap();
    let pallets = gspn.place("Pallets").unwrap();
    assert_eq!(gspn.initial_marking()[pallets.index()], 2);
}

#[test]
fn reader_writer_has_an_inhibitor_arc_and_multiplicity_k() {
    let net = greatspn("ReaderWriter.PNPRO");
    let k = param(&net, "K");
    // last-binding 1, measures assignment 2: the assignment wins.
    assert_eq!((k.value, k.kind, k.suggested), (None, ParamKind::Int, Some(2.0)));
    let n = param(&net, "N");
    assert_eq!((n.value, n.kind), (Some(5.0), ParamKind::Int));
    assert_eq!(
        net.places[net.place_id("Think").unwrap().index()].initial,
        Expr::param("N")
    );

    assert_eq!(
        arcs_between(&net, "Reading", "startWrite"),
        [(ArcKind::Inhibitor, Expr::Num(1.0))]
    );
    assert_eq!(
        arcs_between(&net, "Choice", "is_read"),
        [(ArcKind::Input, Expr::param("K"))]
    );
    assert_eq!(
        arcs_between(&net, "Choice", "is_write"),
        [(ArcKind::Input, Expr::param("K"))]
    );
    assert_eq!(
        arcs_between(&net, "NumWrite", "startRead"),
        [
            (ArcKind::Input, Expr::Num(1.0)),
            (ArcKind::Output, Expr::Num(1.0))
        ]
    );
    assert_eq!(
        net.arcs.iter().filter(|a| a.kind == ArcKind::Inhibitor).count(),
        1
    );
    assert!(transition(&net, "is_read").is_immediate());
    assert_eq!(
        transition(&net, "arrival").kind,
        TransitionKind::Timed {
            rate: Some(Expr::Num(1.0)),
            servers: Servers::Infinite
        }
    );

    let err = net.instantiate(&Params::new()).unwrap_err().to_string();
    assert!(err.contains("`K`") && err.contains("K=2"), "{err}");
    let gspn = net.instantiate(&Params::new().with("K", 1.0)).unwrap();
    let start_write = gspn.transition("startWrite").unwrap();
    assert_eq!(gspn.inhibitors(start_write).len(), 1);
}

#[test]
fn editor_defaults_apply_to_attributes_left_out() {
    let seasons = greatspn("Cycle_of_Four_Seasons.PNPRO");
    assert_eq!(seasons.name, "Seasons");
    for t in &seasons.transitions {
        assert_eq!(
            t.kind,
            TransitionKind::Timed {
                rate: Some(Expr::Num(1.0)),
                servers: Servers::Infinite
            },
            "{}",
            t.name
        );
    }
    let locks = greatspn("2PhaseLockViolation.PNPRO");
    let processes = locks.place_id("Processes").unwrap();
    assert_eq!(locks.places[processes.index()].initial, Expr::Num(2.0));
    assert_eq!(
        locks.places[locks.place_id("haveA").unwrap().index()].initial,
        Expr::Num(0.0)
    );
    assert!(locks.params.is_empty());
}

// ---------------------------------------------------------------------------
// MCC files
// ---------------------------------------------------------------------------

#[test]
fn every_mcc_file_loads_as_a_plain_pt_net() {
    for (file, places, transitions, arcs) in MCC_FILES {
        let net = mcc(file);
        assert_eq!(
            (net.places.len(), net.transitions.len(), net.arcs.len()),
            (places, transitions, arcs),
            "{file}"
        );
        assert_eq!(net.name, file.trim_end_matches(".pnml"));
        for t in &net.transitions {
            assert_eq!(
                t.kind,
                TransitionKind::Timed {
                    rate: None,
                    servers: Servers::Single
                },
                "{file}: {}",
                t.name
            );
        }
        assert!(
            net.arcs
                .iter()
                .all(|a| a.kind != ArcKind::Inhibitor && a.multiplicity == Expr::Num(1.0))
        );
        let gspn = net.instantiate(&Params::new()).unwrap();
        assert!(
            gspn.rates(&Params::new(), None).is_err(),
            "{file}: rates must be missing"
        );
        assert!(gspn.rates(&Params::new(), Some(1.0)).is_ok());
    }
}

#[test]
fn mcc_markings_and_positions() {
    let fms = mcc("FMS-PT-00002.pnml");
    let p1 = fms.place_id("P1").unwrap();
    assert_eq!(fms.places[p1.index()].initial, Expr::Num(2.0));
    assert_eq!(fms.places[p1.index()].position, Some((458.0, 100.0)));
    let total: f64 = fms.places.iter().filter_map(|p| p.initial.as_number()).sum();
    assert!(total > 2.0);

    let phil = mcc("Philosophers-PT-000010.pnml");
    assert!(phil.places.iter().all(|p| p.position.is_none()));
    let marked = phil.places.iter().filter(|p| p.initial == Expr::Num(1.0)).count();
    assert_eq!(marked, 20, "10 thinking philosophers and 10 forks");

    let ring = mcc("TokenRing-PT-005.pnml");
    assert!(ring.place_id("State_3_1").is_some());
    assert!(ring.transition_id("OtherProcess_2_1_5").is_some());
}

// ---------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------

#[test]
fn every_file_round_trips_through_toml() {
    for (file, net) in all_files() {
        let text = io::write_string(&net, Format::Toml).unwrap();
        let back =
            io::read_str(&text, Format::Toml, "x.toml").unwrap_or_else(|e| panic!("{file}: {e}\n{text}"));
        assert_same(&back, &net, &format!("{file}\n{text}"));
    }
}

#[test]
fn every_file_round_trips_through_pnml() {
    for (file, net) in all_files() {
        let text = io::write_string(&net, Format::Pnml).unwrap();
        let back =
            io::read_str(&text, Format::Pnml, "x.pnml").unwrap_or_else(|e| panic!("{file}: {e}\n{text}"));
        assert_same(&back, &net, &file);
    }
}

#[test]
fn pnpro_files_round_trip_through_pnpro() {
    for (file, ..) in GREATSPN_FILES {
        let net = greatspn(file);
        let text = io::write_string(&net, Format::Pnpro).unwrap();
        let back =
            io::read_str(&text, Format::Pnpro, "x.PNPRO").unwrap_or_else(|e| panic!("{file}: {e}\n{text}"));
        assert_same(&back, &net, file);
    }
}

#[test]
fn mcc_files_round_trip_through_pnpro_up_to_the_default_rate() {
    for (file, ..) in MCC_FILES {
        let net = mcc(file);
        let text = io::write_string(&net, Format::Pnpro).unwrap();
        let mut back = io::read_str(&text, Format::Pnpro, "x.PNPRO").unwrap();
        forget_grid_positions(&mut back, &net);
        assert_same(&back, &pnpro_view(&net), file);
    }
}

/// PNPRO nodes always have a position: the writer lays out those that have
/// none on a grid. Forgets those.
fn forget_grid_positions(back: &mut Net, original: &Net) {
    for (b, n) in back.places.iter_mut().zip(&original.places) {
        assert!(b.position.is_some());
        if n.position.is_none() {
            b.position = None;
        }
    }
    for (b, n) in back.transitions.iter_mut().zip(&original.transitions) {
        assert!(b.position.is_some());
        if n.position.is_none() {
            b.position = None;
        }
    }
}

/// What PNPRO can hold of a net: no capacities, documentation, suggestions
/// for parameters with values, k = 1 servers or missing rates.
fn pnpro_view(net: &Net) -> Net {
    let mut n = net.clone();
    n.doc = None;
    for p in &mut n.params {
        p.doc = None;
        if p.value.is_some() {
            p.suggested = None;
        }
    }
    for p in &mut n.places {
        p.doc = None;
        p.capacity = None;
    }
    for t in &mut n.transitions {
        t.doc = None;
        if let TransitionKind::Timed { rate, servers } = &mut t.kind {
            rate.get_or_insert(Expr::Num(1.0));
            if *servers == Servers::K(1) {
                *servers = Servers::Single;
            }
        }
    }
    n
}

/// A net using everything a [`Net`] can hold.
fn everything() -> Net {
    let mut net = Net::new("every feature");
    net.doc = Some("A net with \"quotes\", <angles> & ampersands,\nnewlines\tand tabs; é ü ∞.".into());
    net.set_param("lambda", Some(0.001), ParamKind::Real);
    net.set_param("N", None, ParamKind::Int);
    net.set_param("K", Some(2.0), ParamKind::Int);
    net.set_param("p", Some(1.0 / 3.0), ParamKind::Real);
    net.params[1].suggested = Some(3.0);
    net.params[1].doc = Some("pallets".into());
    net.params[2].doc = Some("servers, \"k\"".into());

    let p0 = net.add_place("P0", Expr::param("N"));
    let p1 = net.add_place("P1", 1u32);
    let p2 = net.add_place("odd name \"2\"", Expr::parse("2 * K").unwrap());
    let p3 = net.add_place("3rd", 0u32);
    let p4 = net.add_place("P4", 1e6);
    net.places[p1.index()].capacity = Some(4);
    net.places[p1.index()].doc = Some("one token".into());
    net.places[p0.index()].position = Some((1.5, -2.25));
    net.places[p2.index()].position = Some((1e-7, 12345.0));

    let t0 = net.add_timed("t0", Expr::param("lambda"));
    let t1 = net.add_timed("t 1", Expr::parse("1 / (lambda + 2)").unwrap());
    net.set_servers(t1, Servers::K(3));
    let t2 = net.add_timed("t2", 2.5);
    net.set_servers(t2, Servers::Infinite);
    let t3 = net.add_transition(
        "t3",
        TransitionKind::Timed {
            rate: None,
            servers: Servers::Single,
        },
    );
    let i0 = net.add_immediate("i0", Expr::param("p"), 1);
    let i1 = net.add_transition(
        "i1",
        TransitionKind::Immediate {
            weight: Expr::parse("1 - p").unwrap(),
            priority: Expr::param("K"),
        },
    );
    net.transitions[t0.index()].doc = Some("timed".into());
    net.transitions[i1.index()].doc = Some("immediate".into());
    net.transitions[t2.index()].position = Some((3.0, 4.0));

    net.input(p0, t0);
    net.output(t0, p1);
    net.add_arc(ArcKind::Input, p1, t1, 2u32);
    net.add_arc(ArcKind::Output, p2, t1, Expr::param("K"));
    net.add_arc(ArcKind::Inhibitor, p3, t1, 3u32);
    net.inhibitor(p4, t2);
    net.input(p2, t2);
    net.output(t2, p3);
    net.input(p3, t3);
    net.output(t3, p0);
    net.input(p1, i0);
    net.output(i0, p4);
    net.input(p1, i1);
    net.add_arc(ArcKind::Input, p1, i1, Expr::parse("K + 1").unwrap());
    net.add_arc(ArcKind::Output, p0, i1, Expr::parse("N").unwrap());
    net.add_arc(ArcKind::Inhibitor, p2, i1, Expr::param("N"));
    io::sort_arcs(&mut net);
    net
}

#[test]
fn a_net_with_every_feature_round_trips_through_pnml_and_toml() {
    let net = everything();
    net.validate().unwrap();
    for format in [Format::Pnml, Format::Toml] {
        let text = io::write_string(&net, format).unwrap();
        let back = io::read_str(&text, format, "x").unwrap_or_else(|e| panic!("{format}: {e}\n{text}"));
        assert_same(&back, &net, &format!("{format}\n{text}"));
    }
}

#[test]
fn pnml_written_for_other_tools_is_standard() {
    let net = everything();
    let text = io::write_string(&net, Format::Pnml).unwrap();
    assert!(text.contains("<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">"));
    assert!(text.contains("type=\"http://www.pnml.org/version-2009/grammar/ptnet\""));
    // Names that are not XML ids are sanitised; the name is kept.
    assert!(text.contains("<place id=\"odd_name__2_\">"), "{text}");
    assert!(text.contains("<place id=\"_3rd\">"), "{text}");
    assert!(
        text.contains("<name><text>odd name \"2\"</text></name>"),
        "{text}"
    );
    // Numbers other tools understand, expressions kept for us.
    assert!(
        text.contains("<initialMarking><text>4</text></initialMarking>"),
        "{text}"
    );
    assert!(text.contains("<marking><value>2 * K</value></marking>"), "{text}");
    assert!(
        text.contains("<initialMarking><text>1000000</text></initialMarking>"),
        "{text}"
    );
    assert!(text.contains("<type value=\"inhibitor\"/>"));
    // pm4py (and ProM) read inhibitor arcs from `<arctype>` only.
    assert!(
        text.contains("<arctype><text>inhibitor</text></arctype>"),
        "{text}"
    );
    assert_eq!(
        text.matches("<arctype>").count(),
        net.arcs.iter().filter(|a| a.kind == ArcKind::Inhibitor).count()
    );
    assert!(
        text.contains("<parameter name=\"N\" kind=\"int\" suggested=\"3\" doc=\"pallets\"/>"),
        "{text}"
    );
    // A plain P/T net gets no tool-specific content at all.
    let plain = io::write_string(&mcc("Philosophers-PT-000005.pnml"), Format::Pnml).unwrap();
    assert!(!plain.contains("toolspecific"));
}

#[test]
fn a_net_with_every_feature_round_trips_through_pnpro_up_to_what_it_holds() {
    let mut net = everything();
    assert!(
        io::write_string(&net, Format::Pnpro)
            .unwrap_err()
            .to_string()
            .contains("capacit")
    );
    for p in &mut net.places {
        p.capacity = None;
    }
    let text = io::write_string(&net, Format::Pnpro).unwrap();
    let mut back = io::read_str(&text, Format::Pnpro, "x.PNPRO").unwrap_or_else(|e| panic!("{e}\n{text}"));
    forget_grid_positions(&mut back, &net);
    assert_same(&back, &pnpro_view(&net), "every feature");
}

#[test]
fn files_are_written_and_read_by_extension() {
    let dir = std::env::temp_dir().join(format!("petri-io-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let net = greatspn("ReaderWriter.PNPRO");
    for ext in ["toml", "pnml", "PNPRO", "xml"] {
        let path = dir.join(format!("rw.{ext}"));
        io::write_file(&net, &path).unwrap();
        assert_eq!(io::read_file(&path).unwrap(), net, "{ext}");
    }
    let dot = dir.join("rw.gv");
    io::write_file(&net, &dot).unwrap();
    assert!(std::fs::read_to_string(&dot).unwrap().starts_with("digraph"));
    assert!(io::read_file(&dot).is_err());
    assert!(matches!(
        io::write_file(&net, dir.join("rw.txt")),
        Err(Error::UnknownFormat { .. })
    ));
    assert!(matches!(
        io::read_file(dir.join("missing.toml")),
        Err(Error::Io { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn dot_export_of_a_real_net() {
    let net = greatspn("ReaderWriter.PNPRO");
    let dot = io::write_string(&net, Format::Dot).unwrap();
    assert_eq!(dot.matches(" -> ").count(), net.arcs.len());
    assert_eq!(dot.matches("arrowhead=odot").count(), 1);
    assert_eq!(dot.matches("shape=circle").count(), net.places.len());
    assert_eq!(dot.matches("fillcolor=black").count(), 4);
    assert!(dot.contains("\"Choice\" -> \"is_read\" [label=\"K\"];"), "{dot}");
    assert!(dot.contains("label=\"Think\\nN\""), "{dot}");
}

// ---------------------------------------------------------------------------
// PNML as other tools write it
// ---------------------------------------------------------------------------

/// PIPE 4 style: no page, GSPN attributes as direct children with `<value>`,
/// `Default,n` markings and inscriptions, capacity 0 for unbounded.
const PIPE: &str = r#"<?xml version="1.0" encoding="ISO-8859-1"?>
<pnml>
<net id="Net-One" type="P/T net">
<token id="Default" enabled="true" red="0" green="0" blue="0"/>
<place id="P0">
<graphics><position x="120.0" y="75.0"/></graphics>
<name><value>P0</value><graphics><offset x="0.0" y="0.0"/></graphics></name>
<initialMarking><value>Default,2</value><graphics><offset x="0.0" y="0.0"/></graphics></initialMarking>
<capacity><value>0</value></capacity>
</place>
<place id="P1">
<graphics><position x="300.0" y="75.0"/></graphics>
<name><value>P1</value></name>
<initialMarking><value>Default,0</value></initialMarking>
<capacity><value>3</value></capacity>
</place>
<transition id="T0">
<graphics><position x="210.0" y="75.0"/></graphics>
<name><value>T0</value></name>
<orientation><value>0</value></orientation>
<rate><value>2.5</value></rate>
<timed><value>true</value></timed>
<infiniteServer><value>true</value></infiniteServer>
<priority><value>1</value></priority>
</transition>
<transition id="T1">
<name><value>T1</value></name>
<rate><value>0.7</value></rate>
<timed><value>false</value></timed>
<infiniteServer><value>false</value></infiniteServer>
<priority><value>2</value></priority>
</transition>
<transition id="T2">
<name><value>T2</value></name>
<rate><value>1.0</value></rate>
<timed><value>true</value></timed>
<infiniteServer><value>false</value></infiniteServer>
<priority><value>1</value></priority>
</transition>
<arc id="P0 to T0" source="P0" target="T0">
<graphics/>
<inscription><value>Default,2</value><graphics/></inscription>
<tagged><value>false</value></tagged>
<arcpath id="000" x="146" y="87" curvePoint="false"/>
<type value="normal"/>
</arc>
<arc id="T0 to P1" source="T0" target="P1">
<inscription><value>Default,1</value></inscription>
<type value="normal"/>
</arc>
<arc id="P1 to T1" source="P1" target="T1">
<inscription><value>Default,1</value></inscription>
<type value="normal"/>
</arc>
<arc id="T1 to P0" source="T1" target="P0">
<inscription><value>Default,1</value></inscription>
<type value="normal"/>
</arc>
<arc id="P1 to T2" source="P1" target="T2">
<inscription><value>Default,1</value></inscription>
<type value="inhibitor"/>
</arc>
</net>
</pnml>"#;

#[test]
fn pipe_gspn() {
    let net = io::read_str(PIPE, Format::Pnml, "pipe.xml").unwrap();
    assert_eq!(net.name, "Net-One");
    assert_eq!(net.places[0].initial, Expr::Num(2.0));
    assert_eq!(net.places[0].capacity, None, "PIPE's capacity 0 is unbounded");
    assert_eq!(net.places[1].capacity, Some(3));
    assert_eq!(net.places[0].position, Some((120.0, 75.0)));
    assert_eq!(
        transition(&net, "T0").kind,
        TransitionKind::Timed {
            rate: Some(Expr::Num(2.5)),
            servers: Servers::Infinite
        }
    );
    // Immediate: PIPE keeps the weight in the rate field.
    assert_eq!(
        transition(&net, "T1").kind,
        TransitionKind::Immediate {
            weight: Expr::Num(0.7),
            priority: Expr::Num(2.0)
        }
    );
    assert_eq!(
        transition(&net, "T2").kind,
        TransitionKind::Timed {
            rate: Some(Expr::Num(1.0)),
            servers: Servers::Single
        }
    );
    assert_eq!(arcs_between(&net, "P0", "T0"), [(ArcKind::Input, Expr::Num(2.0))]);
    assert_eq!(
        arcs_between(&net, "P1", "T2"),
        [(ArcKind::Inhibitor, Expr::Num(1.0))]
    );
    assert_eq!(
        arcs_between(&net, "P0", "T1"),
        [(ArcKind::Output, Expr::Num(1.0))]
    );
    assert!(net.instantiate(&Params::new()).is_ok());
}

/// TAPAAL: attributes instead of elements, `tapnInhibitor` arcs.
const TAPAAL: &str = r#"<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<pnml xmlns="http://www.informatik.hu-berlin.de/top/pnml/ptNetb">
<net active="true" id="TAPN1" type="P/T net">
<place displayName="true" id="P0" initialMarking="3" invariant="&lt; inf" name="P0" nameOffsetX="0" nameOffsetY="0" positionX="120.0" positionY="90.0"/>
<place displayName="true" id="P1" initialMarking="0" invariant="&lt; inf" name="P1" nameOffsetX="0" nameOffsetY="0" positionX="360.0" positionY="90.0"/>
<transition angle="0" displayName="true" id="T0" infiniteServer="false" name="T0" nameOffsetX="0" nameOffsetY="0" player="0" positionX="240.0" positionY="90.0" priority="0" urgent="false"/>
<arc id="P0_to_T0" inscription="[0,inf)" nameOffsetX="0" nameOffsetY="0" source="P0" target="T0" type="timed" weight="2"/>
<arc id="T0_to_P1" inscription="1" nameOffsetX="0" nameOffsetY="0" source="T0" target="P1" type="normal" weight="1"/>
<arc id="P1_to_T0" inscription="[0,inf)" nameOffsetX="0" nameOffsetY="0" source="P1" target="T0" type="tapnInhibitor" weight="4"/>
</net>
</pnml>"#;

#[test]
fn tapaal_inhibitor_arcs() {
    let net = io::read_str(TAPAAL, Format::Pnml, "tapaal.pnml").unwrap();
    assert_eq!(net.places[0].initial, Expr::Num(3.0));
    assert_eq!(net.places[0].name, "P0");
    assert_eq!(arcs_between(&net, "P0", "T0"), [(ArcKind::Input, Expr::Num(2.0))]);
    assert_eq!(
        arcs_between(&net, "P1", "T0"),
        [
            (ArcKind::Output, Expr::Num(1.0)),
            (ArcKind::Inhibitor, Expr::Num(4.0))
        ]
    );
}

/// Standard PNML with inhibitor arcs as `<type>` children in several
/// spellings, GSPN attributes in another tool's `<toolspecific>`, nested
/// pages and reference nodes.
const PAGES: &str = r#"<?xml version="1.0"?>
<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">
  <net id="pages" type="http://www.pnml.org/version-2009/grammar/ptnet">
    <name><text>Pages and references</text></name>
    <page id="top">
      <place id="p1"><name><text>ready</text></name>
        <initialMarking><text> 2 </text></initialMarking></place>
      <page id="inner">
        <transition id="t1"><name><text>go</text></name>
          <toolspecific tool="SomeGspnTool" version="0.1">
            <rate><value>lambda</value></rate>
            <infiniteServer><value>TRUE</value></infiniteServer>
          </toolspecific>
        </transition>
        <place id="p2"><name><text>done</text></name></place>
        <referencePlace id="rp1" ref="p1"/>
        <referencePlace id="rp2" ref="rp1"/>
        <arc id="a1" source="rp2" target="t1"><inscription><text>2</text></inscription></arc>
        <arc id="a2" source="t1" target="p2"/>
      </page>
      <referenceTransition id="rt1" ref="t1"/>
      <transition id="t2"><name><text>stop</text></name>
        <toolspecific tool="OtherTool" version="1"><timed><value>false</value></timed><weight><value>0.25</value></weight></toolspecific>
        <toolspecific tool="Unknown" version="9"><whatever><value>ignored</value></whatever></toolspecific>
      </transition>
      <arc id="a3" source="p2" target="rt1"><type><text>inhibition</text></type></arc>
      <arc id="a4" source="p2" target="t2"><type value="Inhibitor"/><inscription><text>3</text></inscription></arc>
      <arc id="a5" source="p1" target="t2" type="inhibitor"/>
      <arc id="a6" source="p1" target="t2"><type><value>normal</value></type></arc>
    </page>
  </net>
</pnml>"#;

#[test]
fn nested_pages_references_and_inhibitor_spellings() {
    let net = io::read_str(PAGES, Format::Pnml, "pages.pnml").unwrap();
    assert_eq!(net.name, "Pages and references");
    let names: Vec<&str> = net.places.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["ready", "done"]);
    assert_eq!(net.places[0].initial, Expr::Num(2.0));
    assert_eq!(
        transition(&net, "go").kind,
        TransitionKind::Timed {
            rate: Some(Expr::param("lambda")),
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        transition(&net, "stop").kind,
        TransitionKind::Immediate {
            weight: Expr::Num(0.25),
            priority: Expr::Num(1.0)
        }
    );
    assert_eq!(
        arcs_between(&net, "ready", "go"),
        [(ArcKind::Input, Expr::Num(2.0))]
    );
    assert_eq!(
        arcs_between(&net, "done", "go"),
        [
            (ArcKind::Output, Expr::Num(1.0)),
            (ArcKind::Inhibitor, Expr::Num(1.0))
        ]
    );
    assert_eq!(
        arcs_between(&net, "done", "stop"),
        [(ArcKind::Inhibitor, Expr::Num(3.0))]
    );
    assert_eq!(
        arcs_between(&net, "ready", "stop"),
        [
            (ArcKind::Input, Expr::Num(1.0)),
            (ArcKind::Inhibitor, Expr::Num(1.0))
        ]
    );
}

// ---------------------------------------------------------------------------
// pm4py
// ---------------------------------------------------------------------------

/// A file written by pm4py (`pm4py.write_pnml`, see `tests/data/README.md`):
/// arc weights, an inhibitor arc as `<arctype>`, an invisible transition
/// (ProM's tool-specific content), two transitions with the same label, a
/// final marking.
#[test]
fn pm4py_pnml_with_an_inhibitor_arc_and_shared_labels() {
    let net = io::read_file("tests/data/pm4py/inhibitor_and_labels.pnml").unwrap();
    let mut places: Vec<&str> = net.places.iter().map(|p| p.name.as_str()).collect();
    places.sort_unstable();
    assert_eq!(places, ["end", "guard", "mid", "start"]);
    // Labels name transitions; the label two transitions share falls back to
    // their ids; the invisible transition is known by its id.
    let mut transitions: Vec<&str> = net.transitions.iter().map(|t| t.name.as_str()).collect();
    transitions.sort_unstable();
    assert_eq!(transitions, ["register", "t2", "t3", "tau"]);
    assert_eq!(net.arcs.len(), 9);
    assert_eq!(
        arcs_between(&net, "guard", "register"),
        [(ArcKind::Inhibitor, Expr::from(1u32))]
    );
    assert_eq!(
        arcs_between(&net, "start", "register"),
        [(ArcKind::Input, Expr::from(2u32))]
    );
    assert_eq!(
        arcs_between(&net, "end", "t3"),
        [(ArcKind::Output, Expr::from(3u32))]
    );
    let start = &net.places[net.place_id("start").unwrap().index()];
    assert_eq!(start.initial, Expr::from(4u32));
    // And through our writer and reader again, unchanged.
    let text = io::write_string(&net, Format::Pnml).unwrap();
    assert_same(
        &io::read_str(&text, Format::Pnml, "again.pnml").unwrap(),
        &net,
        "pm4py file",
    );
}
