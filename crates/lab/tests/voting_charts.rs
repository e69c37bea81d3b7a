//! The voting report's charts draw the numbers of `summary.json`: a short
//! batch of the real suite, its report written, and each chart read back
//! from `index.html` — the data lines of its `<desc>` against the summary,
//! and the bars' heights against the values they stand for.

use lab::runner::BatchParams;
use lab::suite::SuiteArgs;
use serde_json::Value;

/// The inline SVG charts of the page, in order.
fn charts(index: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = index;
    while let Some(a) = rest.find("<svg") {
        let b = rest[a..].find("</svg>").expect("closed svg") + a;
        out.push(&rest[a..b]);
        rest = &rest[b..];
    }
    out
}

fn attr(tag: &str, name: &str) -> f64 {
    let key = format!(" {name}=\"");
    let a = tag.find(&key).expect(name) + key.len();
    let b = tag[a..].find('"').unwrap() + a;
    tag[a..b].parse().unwrap()
}

/// Bars of one colour, in drawing order, as (height px, bottom y px).
fn rects(svg: &str, fill: &str) -> Vec<(f64, f64)> {
    svg.split("<rect")
        .skip(1)
        .filter(|t| t.contains(&format!("fill=\"{fill}\"")))
        .map(|t| {
            let tag = &t[..t.find("/>").unwrap()];
            (attr(tag, "height"), attr(tag, "y") + attr(tag, "height"))
        })
        .collect()
}

const COLOURS: [&str; 5] = ["#1F77B4", "#FF7F0E", "#2CA02C", "#D62728", "#9467BD"];

#[test]
fn charts_draw_the_summary_numbers() {
    let dir = std::env::temp_dir().join(format!("petrinav-voting-charts-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let suite = lab::suites::voting::suite(&SuiteArgs {
        runs: Some(3),
        files: Vec::new(),
    })
    .unwrap();
    let params = BatchParams {
        results: dir.join("results.jsonl"),
        resume: false,
        jobs: Some(2),
        progress: false,
        stop: None,
    };
    lab::suite::run(&suite, &params, None).unwrap();
    lab::report::write(&dir, &suite, false).unwrap();
    let index = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let summary: Vec<Value> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let svgs = charts(&index);
    assert_eq!(svgs.len(), 2, "an I_R and an I_T chart");
    // The charts come before the first table: the shape first.
    assert!(index.find("<svg").unwrap() < index.find("<table").unwrap());

    for (svg, key, name) in [(svgs[0], "reliability", "I_R"), (svgs[1], "time", "I_T")] {
        let desc = &svg[svg.find("<desc>").unwrap() + 6..svg.find("</desc>").unwrap()];
        let lines: Vec<&str> = desc.lines().collect();
        assert_eq!(lines.len(), summary.len(), "{name}: one bar per scenario");
        for s in &summary {
            let scenario = s["scenario"].as_str().unwrap();
            let (e, f) = scenario.split_once('/').unwrap();
            let line = lines
                .iter()
                .find(|l| l.starts_with(&format!("{e} {f} {name} ")))
                .unwrap_or_else(|| panic!("{name}: no bar for {scenario}"));
            let nums: Vec<f64> = line.split(' ').skip(3).map(|x| x.parse().unwrap()).collect();
            let (value, low, high) = if key == "reliability" {
                let r = &s["reliability"];
                (
                    r["value"].as_f64().unwrap(),
                    r["low"].as_f64().unwrap(),
                    r["high"].as_f64().unwrap(),
                )
            } else if s["time"]["n"].as_u64().unwrap() == 0 {
                (f64::NAN, f64::NAN, f64::NAN)
            } else {
                let t = &s["time"];
                let (m, h) = (
                    t["mean"].as_f64().unwrap(),
                    t["half_width"].as_f64().unwrap_or(f64::NAN),
                );
                (m, m - h, m + h)
            };
            for (got, want) in nums.iter().zip([value, low, high]) {
                assert!(
                    (got.is_nan() && want.is_nan()) || (got - want).abs() < 5e-4,
                    "{name} {scenario}: chart says {line}, summary {value} [{low}, {high}]"
                );
            }
        }
        // The bars: one rect per finite value, per series colour, in field
        // order, all standing on the same axis, heights in proportion to
        // the values (1 px of rounding).
        let experiments: Vec<String> = (1..=5).map(|k| format!("e{k}")).collect();
        let mut pairs: Vec<(f64, f64)> = Vec::new();
        let mut bottom = None;
        for (k, e) in experiments.iter().enumerate() {
            let values: Vec<f64> = summary
                .iter()
                .filter(|s| s["scenario"].as_str().unwrap().starts_with(&format!("{e}/")))
                .map(|s| {
                    if key == "reliability" {
                        s["reliability"]["value"].as_f64().unwrap()
                    } else if s["time"]["n"].as_u64().unwrap() == 0 {
                        f64::NAN
                    } else {
                        s["time"]["mean"].as_f64().unwrap()
                    }
                })
                .filter(|v| v.is_finite())
                .collect();
            let drawn = rects(svg, COLOURS[k]);
            // The legend's swatch is drawn after the bars.
            assert_eq!(drawn.len(), values.len() + 1, "{name} {e}: bars drawn");
            for (v, (h, b)) in values.iter().zip(&drawn) {
                let bottom = *bottom.get_or_insert(*b);
                assert!((b - bottom).abs() <= 1.0, "{name} {e}: bars on one axis");
                pairs.push((*v, *h));
            }
        }
        // The scale from the tallest bar (least rounding), then every bar
        // within a pixel and a half of its value.
        let (vmax, hmax) = pairs
            .iter()
            .copied()
            .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
        assert!(vmax > 0.0 && hmax > 100.0, "{name}: a tall bar");
        for (v, h) in pairs {
            let want = v * hmax / vmax;
            assert!(
                (h - want).abs() <= 1.5,
                "{name}: bar {h} px for {v}, expected {want:.1}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
