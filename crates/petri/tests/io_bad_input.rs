//! Bad input gets a clear error — with the file position or the element at
//! fault — and never a panic.

use petri::Error;
use petri::io::{self, Format};
use proptest::prelude::*;

const GREATSPN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/greatspn");
const MCC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mcc");

fn read(text: &str, format: Format, source: &str) -> Error {
    match io::read_str(text, format, source) {
        Ok(net) => panic!("{source}: expected an error, read {} places", net.places.len()),
        Err(e) => e,
    }
}

/// A small valid project to break in different ways.
const PROJECT: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<project name="p" version="121">
  <gspn name="g">
    <nodes>
      <place name="a" marking="1" x="1" y="1"/>
      <place name="b" x="5" y="1"/>
      <transition name="t" type="EXP" delay="lambda" x="3" y="1"/>
      <constant name="lambda" consttype="REAL" value="2"/>
    </nodes>
    <edges>
      <arc head="t" kind="INPUT" tail="a"/>
      <arc head="b" kind="OUTPUT" tail="t"/>
    </edges>
  </gspn>
</project>
"#;

const PNML: &str = r#"<?xml version="1.0"?>
<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">
  <net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet">
    <page id="page0">
      <place id="a"><initialMarking><text>1</text></initialMarking></place>
      <place id="b"/>
      <transition id="t"/>
      <arc id="x" source="a" target="t"/>
      <arc id="y" source="t" target="b"/>
    </page>
  </net>
</pnml>
"#;

const TOML: &str = r#"name = "n"
[params]
lambda = 2.0

[[place]]
name = "a"
initial = 1

[[place]]
name = "b"

[[transition]]
name = "t"
rate = "lambda"
inputs = ["a"]
outputs = ["b"]
"#;

#[test]
fn the_fixtures_are_valid() {
    assert!(io::read_str(PROJECT, Format::Pnpro, "p.PNPRO").is_ok());
    assert!(io::read_str(PNML, Format::Pnml, "n.pnml").is_ok());
    assert!(io::read_str(TOML, Format::Toml, "n.toml").is_ok());
}

#[test]
fn malformed_xml_gives_the_line_and_column() {
    let text = PROJECT.replace(
        r#"<place name="b" x="5" y="1"/>"#,
        r#"<place name="b" x="5" y="1">"#,
    );
    let err = read(&text, Format::Pnpro, "bad.PNPRO");
    let Error::Xml { location, message } = &err else {
        panic!("expected Error::Xml, got {err}");
    };
    // The unclosed <place> on line 6 is noticed at </nodes>, line 9.
    assert_eq!(location, "bad.PNPRO:9:5", "{err}");
    assert!(message.contains("nodes") || message.contains("place"), "{err}");
    assert!(
        err.to_string().starts_with("bad.PNPRO:9:5: malformed XML"),
        "{err}"
    );

    let err = read(
        &PNML.replace("<transition id=\"t\"/>", "<transition id=\"t\">"),
        Format::Pnml,
        "bad.pnml",
    );
    assert!(
        matches!(&err, Error::Xml { location, .. } if location.starts_with("bad.pnml:")),
        "{err}"
    );

    // A file cut short: the position is its end.
    let cut = &PROJECT[..PROJECT.find("<edges>").unwrap()];
    let err = read(cut, Format::Pnpro, "cut.PNPRO");
    assert!(
        matches!(&err, Error::Xml { location, .. } if location.starts_with("cut.PNPRO:")),
        "{err}"
    );
    let err = read("<project", Format::Pnpro, "x.PNPRO");
    assert!(matches!(err, Error::Xml { .. }), "{err}");
}

#[test]
fn unknown_arc_endpoints_are_named_with_their_position() {
    let text = PROJECT.replace(
        r#"<arc head="b" kind="OUTPUT" tail="t"/>"#,
        r#"<arc head="c" kind="OUTPUT" tail="t"/>"#,
    );
    let err = read(&text, Format::Pnpro, "p.PNPRO");
    let Error::UnknownNode {
        arc, expected, name, ..
    } = &err
    else {
        panic!("expected UnknownNode, got {err}");
    };
    assert_eq!((*expected, name.as_str()), ("place", "c"));
    assert!(
        arc.starts_with("p.PNPRO:12:7: OUTPUT arc from `t` to `c`"),
        "{err}"
    );

    // An arc whose ends are the wrong way round names the missing kind.
    let text = PROJECT.replace(
        r#"<arc head="t" kind="INPUT" tail="a"/>"#,
        r#"<arc head="a" kind="INPUT" tail="t"/>"#,
    );
    let err = read(&text, Format::Pnpro, "p.PNPRO");
    assert!(
        matches!(&err, Error::UnknownNode { expected: "place", name, .. } if name == "t"),
        "{err}"
    );

    let err = read(
        &PNML.replace(r#"target="b""#, r#"target="zz""#),
        Format::Pnml,
        "n.pnml",
    );
    assert!(
        matches!(&err, Error::UnknownNode { name, arc, .. } if name == "zz" && arc.contains("n.pnml:9:")),
        "{err}"
    );

    let err = read(
        &PNML.replace(
            r#"<arc id="y" source="t" target="b"/>"#,
            r#"<arc id="y" source="t"/>"#,
        ),
        Format::Pnml,
        "n",
    );
    assert!(err.to_string().contains("without a `target`"), "{err}");

    let err = read(
        &PNML.replace("</page>", r#"<referencePlace id="r" ref="nowhere"/></page>"#),
        Format::Pnml,
        "n",
    );
    assert!(
        matches!(&err, Error::UnknownNode { name, .. } if name == "nowhere"),
        "{err}"
    );
}

#[test]
fn duplicate_names_are_refused() {
    let text = PROJECT.replace(r#"<place name="b" "#, r#"<place name="a" "#);
    let err = read(&text, Format::Pnpro, "p");
    assert!(
        matches!(&err, Error::DuplicateName { name, first: "a place", second: "a place" } if name == "a"),
        "{err}"
    );

    let text = PROJECT.replace(r#"<transition name="t" "#, r#"<transition name="b" "#);
    let err = read(&text, Format::Pnpro, "p");
    assert!(
        matches!(&err, Error::DuplicateName { name, second: "a transition", .. } if name == "b"),
        "{err}"
    );

    let text = PROJECT.replace(r#"<constant name="lambda" "#, r#"<constant name="a" "#);
    let err = read(&text, Format::Pnpro, "p");
    assert!(
        matches!(&err, Error::DuplicateName { name, .. } if name == "a"),
        "{err}"
    );

    let err = read(
        &PNML.replace(r#"<place id="b"/>"#, r#"<place id="a"/>"#),
        Format::Pnml,
        "n",
    );
    assert!(
        matches!(&err, Error::DuplicateName { name, .. } if name == "a"),
        "{err}"
    );

    let text = TOML.replace("name = \"b\"", "name = \"a\"");
    let err = read(&text, Format::Toml, "n.toml");
    assert!(
        matches!(&err, Error::DuplicateName { name, .. } if name == "a"),
        "{err}"
    );
    let text = TOML.replace("name = \"t\"", "name = \"b\"");
    let err = read(&text, Format::Toml, "n.toml");
    assert!(
        matches!(&err, Error::DuplicateName { name, .. } if name == "b"),
        "{err}"
    );
    let text = TOML.replace("lambda = 2.0", "lambda = 2.0\na = 1");
    let err = read(&text, Format::Toml, "n.toml");
    assert!(
        matches!(&err, Error::DuplicateName { name, .. } if name == "a"),
        "{err}"
    );
}

#[test]
fn unsupported_transition_types_name_the_element() {
    for (ty, why) in [
        ("GEN", "general"),
        ("DET", "general"),
        ("CONT", "fluid"),
        ("XYZ", "unknown"),
    ] {
        let text = PROJECT.replace(r#"type="EXP""#, &format!(r#"type="{ty}""#));
        let err = read(&text, Format::Pnpro, "p.PNPRO");
        let msg = err.to_string();
        assert!(matches!(err, Error::Format { .. }), "{msg}");
        assert!(
            msg.contains("transition `t`") && msg.contains(ty) && msg.contains(why),
            "{msg}"
        );
        assert!(msg.starts_with("p.PNPRO:7:"), "{msg}");
    }
    let coloured = PROJECT.replace("<nodes>", r#"<nodes><colorclass name="C" definition="c{1..3}"/>"#);
    let msg = read(&coloured, Format::Pnpro, "p").to_string();
    assert!(
        msg.contains("<colorclass name=\"C\">") && msg.contains("coloured"),
        "{msg}"
    );
    let fluid = PROJECT.replace(r#"<place name="b" "#, r#"<place name="b" type="CONTINUOUS" "#);
    let msg = read(&fluid, Format::Pnpro, "p").to_string();
    assert!(msg.contains("place `b`") && msg.contains("fluid"), "{msg}");
    let guarded = PROJECT.replace(r#"delay="lambda""#, r##"delay="lambda" guard="#a &gt; 1""##);
    let msg = read(&guarded, Format::Pnpro, "p").to_string();
    assert!(msg.contains("guard"), "{msg}");
    let coloured = PNML.replace("grammar/ptnet", "grammar/symmetricnet");
    let msg = read(&coloured, Format::Pnml, "p").to_string();
    assert!(msg.contains("symmetricnet") && msg.contains("coloured"), "{msg}");
    let declared = PNML.replace(
        "<page id=\"page0\">",
        "<declaration><structure/></declaration><page id=\"page0\">",
    );
    assert!(
        read(&declared, Format::Pnml, "p")
            .to_string()
            .contains("coloured")
    );
}

#[test]
fn expressions_that_do_not_parse_name_the_element_and_attribute() {
    let text = PROJECT.replace(
        r#"<arc head="t" kind="INPUT" tail="a"/>"#,
        r#"<arc head="t" kind="INPUT" tail="a" mult="K+"/>"#,
    );
    let err = read(&text, Format::Pnpro, "p.PNPRO");
    let msg = err.to_string();
    assert!(matches!(err, Error::Format { .. }), "{msg}");
    assert!(msg.starts_with("p.PNPRO:11:"), "{msg}");
    assert!(
        msg.contains("INPUT arc from `a` to `t`, attribute `mult`"),
        "{msg}"
    );
    assert!(msg.contains("`K+`"), "{msg}");

    let text = PROJECT.replace(r#"delay="lambda""#, r#"delay="2 ** lambda""#);
    let msg = read(&text, Format::Pnpro, "p").to_string();
    assert!(msg.contains("transition `t`, attribute `delay`"), "{msg}");

    let text = PROJECT.replace(r#"value="2""#, r#"value="two""#);
    let msg = read(&text, Format::Pnpro, "p").to_string();
    assert!(
        msg.contains("constant `lambda`") && msg.contains("`two` is not defined"),
        "{msg}"
    );

    let text = PNML.replace(
        r#"<arc id="x" source="a" target="t"/>"#,
        r#"<arc id="x" source="a" target="t"><inscription><text>many</text></inscription></arc>"#,
    );
    let msg = read(&text, Format::Pnml, "n.pnml").to_string();
    assert!(
        msg.contains("arc `x`") && msg.contains("`many` is not a whole number"),
        "{msg}"
    );

    let text = PNML.replace("<text>1</text>", "<text>1.5</text>");
    let msg = read(&text, Format::Pnml, "n.pnml").to_string();
    assert!(
        msg.contains("place `a`") && msg.contains("`1.5` is not a whole number"),
        "{msg}"
    );

    let text = TOML.replace(r#"rate = "lambda""#, r#"rate = "lambda *""#);
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(
        msg.starts_with("n.toml:14:8:") && msg.contains("transition `t`, `rate`"),
        "{msg}"
    );
}

#[test]
fn toml_typos_name_the_key_and_its_line() {
    let text = TOML.replace(r#"rate = "lambda""#, r#"rat = "lambda""#);
    let err = read(&text, Format::Toml, "n.toml");
    let Error::Format { location, message } = &err else {
        panic!("expected Error::Format, got {err}");
    };
    assert_eq!(location, "n.toml:14:1");
    assert!(message.contains("unknown field `rat`"), "{err}");

    let text = TOML.replace("[[place]]", "[[places]]");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(msg.contains("unknown field `places`"), "{msg}");

    let text = TOML.replace("name = \"t\"", "name = \"t\"\nkind = \"imediate\"");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(msg.contains("imediate") && msg.contains("immediate"), "{msg}");

    let text = TOML.replace("lambda = 2.0", "lambda = { kind = \"real\", valeu = 2 }");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(
        msg.starts_with("n.toml:3:") && msg.contains("unknown field `valeu`"),
        "{msg}"
    );

    let text = TOML.replace("outputs = [\"b\"]", "outputs = [\"b\"]\nservers = \"many\"");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(msg.contains("\"single\", \"infinite\""), "{msg}");

    let msg = read("name = \"x\"\n[[place]\n", Format::Toml, "n.toml").to_string();
    assert!(msg.starts_with("n.toml:2:"), "{msg}");
}

#[test]
fn toml_unknown_places_and_misplaced_keys() {
    let text = TOML.replace(r#"outputs = ["b"]"#, r#"outputs = ["b", "c"]"#);
    let err = read(&text, Format::Toml, "n.toml");
    let Error::UnknownNode {
        arc, expected, name, ..
    } = &err
    else {
        panic!("expected UnknownNode, got {err}");
    };
    assert_eq!((*expected, name.as_str()), ("place", "c"));
    assert!(
        arc.starts_with("n.toml:16:17: output arc of transition `t`"),
        "{err}"
    );

    let text = TOML.replace(r#"inputs = ["a"]"#, r#"inhibitors = { zz = 2 }"#);
    let err = read(&text, Format::Toml, "n.toml");
    assert!(
        matches!(&err, Error::UnknownNode { name, .. } if name == "zz"),
        "{err}"
    );

    let text = TOML.replace("name = \"t\"", "name = \"t\"\nkind = \"immediate\"");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(
        msg.contains("transition `t` is immediate") && msg.contains("`rate`"),
        "{msg}"
    );

    let text = TOML.replace("name = \"t\"", "name = \"t\"\nweight = 2");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(
        msg.contains("transition `t` is timed") && msg.contains("`weight`"),
        "{msg}"
    );

    let text = TOML.replace("lambda = 2.0", "lambda = \"mu * 2\"");
    let msg = read(&text, Format::Toml, "n.toml").to_string();
    assert!(
        msg.contains("parameter `lambda`") && msg.contains("expression over numbers"),
        "{msg}"
    );
}

#[test]
fn pnml_arcs_must_join_a_place_and_a_transition() {
    let text = PNML.replace(
        r#"<arc id="y" source="t" target="b"/>"#,
        r#"<arc id="y" source="a" target="b"/>"#,
    );
    let err = read(&text, Format::Pnml, "n.pnml");
    let msg = err.to_string();
    assert!(matches!(err, Error::Format { .. }), "{msg}");
    assert!(
        msg.starts_with("n.pnml:9:7:") && msg.contains("joins two places"),
        "{msg}"
    );

    let text = PNML.replace(
        "</page>",
        r#"<transition id="u"/><arc id="z" source="t" target="u"/></page>"#,
    );
    assert!(
        read(&text, Format::Pnml, "n")
            .to_string()
            .contains("joins two transitions")
    );

    let text = PNML.replace(
        r#"<arc id="y" source="t" target="b"/>"#,
        r#"<arc id="y" source="t" target="b" type="inhibitor"/>"#,
    );
    assert!(
        read(&text, Format::Pnml, "n")
            .to_string()
            .contains("from a place to a transition")
    );

    let text = PNML.replace(
        r#"<arc id="y" source="t" target="b"/>"#,
        r#"<arc id="y" source="t" target="b"><type value="reset"/></arc>"#,
    );
    assert!(
        read(&text, Format::Pnml, "n")
            .to_string()
            .contains("arc type `reset` is not supported")
    );
}

#[test]
fn empty_files_and_wrong_documents() {
    for format in [Format::Pnpro, Format::Pnml, Format::Toml] {
        for text in ["", "   \n\t\n"] {
            let err = read(text, format, "empty");
            assert_eq!(err.to_string(), "empty: the file is empty");
        }
    }
    let msg = read(PNML, Format::Pnpro, "n.PNPRO").to_string();
    assert!(
        msg.contains("expected a GreatSPN project") && msg.contains("<pnml>"),
        "{msg}"
    );
    let msg = read(PROJECT, Format::Pnml, "p.pnml").to_string();
    assert!(msg.contains("expected a PNML document"), "{msg}");
    let msg = read(r#"<project name="x"/>"#, Format::Pnpro, "x").to_string();
    assert!(msg.contains("no <gspn>"), "{msg}");
    let msg = read(r#"<pnml/>"#, Format::Pnml, "x").to_string();
    assert!(msg.contains("no <net>"), "{msg}");
    let msg = read(PROJECT, Format::Toml, "p.toml").to_string();
    assert!(msg.starts_with("p.toml:1:"), "{msg}");
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    // The expression parser is recursive: 2000 parentheses used to abort the
    // process with a stack overflow.
    let marking = format!("{}1{}", "(".repeat(2000), ")".repeat(2000));
    let text = PROJECT.replace(r#"marking="1""#, &format!(r#"marking="{marking}""#));
    let msg = read(&text, Format::Pnpro, "p").to_string();
    assert!(
        msg.contains("place `a`, attribute `marking`") && msg.contains("longer than"),
        "{msg}"
    );
    let rate = format!("{}1{}", "(".repeat(100), ")".repeat(100));
    let text = TOML.replace(r#""lambda""#, &format!("\"{rate}\""));
    assert!(
        read(&text, Format::Toml, "n")
            .to_string()
            .contains("nested more than 64 levels")
    );
    let text = format!("name = \"x\"\n[params]\na = {}", "[".repeat(100_000));
    assert!(matches!(read(&text, Format::Toml, "n"), Error::Format { .. }));
    // Pages are flattened without recursion.
    let text = format!(
        "<pnml><net id=\"n\">{}<place id=\"p\"/>{}</net></pnml>",
        "<page>".repeat(20_000),
        "</page>".repeat(20_000)
    );
    assert_eq!(io::read_str(&text, Format::Pnml, "n").unwrap().places.len(), 1);
}

// ---------------------------------------------------------------------------
// Random and damaged input: Ok or Err, never a panic.
// ---------------------------------------------------------------------------

fn valid_inputs() -> Vec<(Format, String)> {
    let pnpro = std::fs::read_to_string(format!("{GREATSPN}/ReaderWriter.PNPRO")).unwrap();
    let pnml = std::fs::read_to_string(format!("{MCC}/FMS-PT-00002.pnml")).unwrap();
    let net = io::read_str(&pnpro, Format::Pnpro, "rw").unwrap();
    let toml = io::write_string(&net, Format::Toml).unwrap();
    let ours = io::write_string(&net, Format::Pnml).unwrap();
    vec![
        (Format::Pnpro, pnpro),
        (Format::Pnml, pnml),
        (Format::Toml, toml),
        (Format::Pnml, ours),
        (Format::Pnpro, PROJECT.to_string()),
        (Format::Toml, TOML.to_string()),
    ]
}

/// Reads with every reader; the result does not matter, only that it returns.
fn read_all_ways(text: &str) {
    for format in [Format::Pnpro, Format::Pnml, Format::Toml, Format::Dot] {
        let _ = io::read_str(text, format, "fuzz");
    }
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        read_all_ways(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn random_xml_and_toml_like_text_never_panics(text in "[<>/=\"a-z0-9 \\n\\[\\]{},.#-]{0,200}") {
        read_all_ways(&text);
        read_all_ways(&format!("<project><gspn><nodes>{text}</nodes></gspn></project>"));
        read_all_ways(&format!("<pnml><net><page>{text}</page></net></pnml>"));
    }

    #[test]
    fn truncated_files_never_panic(which in 0usize..6, cut in 0.0f64..1.0) {
        let inputs = valid_inputs();
        let (format, text) = &inputs[which % inputs.len()];
        let at = floor_char_boundary(text, (cut * text.len() as f64) as usize);
        let _ = io::read_str(&text[..at], *format, "truncated");
    }

    #[test]
    fn damaged_files_never_panic(
        which in 0usize..6,
        edits in proptest::collection::vec((0.0f64..1.0, any::<u8>()), 1..8),
    ) {
        let inputs = valid_inputs();
        let (format, text) = &inputs[which % inputs.len()];
        let mut bytes = text.clone().into_bytes();
        for (at, byte) in edits {
            let i = ((at * bytes.len() as f64) as usize).min(bytes.len().saturating_sub(1));
            if let Some(b) = bytes.get_mut(i) {
                *b = byte;
            }
        }
        let damaged = String::from_utf8_lossy(&bytes);
        let _ = io::read_str(&damaged, *format, "damaged");
        // Whatever reads must write and read back.
        if let Ok(net) = io::read_str(&damaged, *format, "damaged") {
            for out in [Format::Toml, Format::Pnml, Format::Dot] {
                let _ = io::write_string(&net, out);
            }
        }
    }
}
