//! The maps suite's report links every leg of a pictured tour to its place
//! on the tour's viewer page, and the page carries the legs' particle
//! clouds.

use std::io::Write;

use lab::suite::Suite;
use lab::suites::maps::MapsSuite;
use serde_json::Value;

#[test]
fn each_leg_of_the_first_tour_opens_on_the_viewer_page() {
    let suite = MapsSuite::new(1).unwrap();
    let scenario = "levine/automove/0p";
    let campaign = suite
        .campaigns()
        .into_iter()
        .find(|c| c.jobs[0].scenario == scenario)
        .unwrap();
    let dir = std::env::temp_dir().join(format!("petrinav-maps-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The tour's first two legs on file, as the runner writes them.
    let mut earlier = Vec::new();
    let mut file = std::fs::File::create(dir.join("results.jsonl")).unwrap();
    for job in &campaign.jobs[..2] {
        let record = suite.run(job, &earlier).unwrap();
        let mut line = serde_json::to_value(&record).unwrap();
        let map = line.as_object_mut().unwrap();
        map.insert("key".into(), Value::from(job.key()));
        map.insert("scenario".into(), Value::from(job.scenario.clone()));
        map.insert("run".into(), Value::from(job.run));
        map.insert("seed".into(), Value::from(job.seed));
        writeln!(file, "{}", serde_json::to_string(&line).unwrap()).unwrap();
        earlier.push(record);
    }
    drop(file);
    lab::report::write(&dir, &suite, true).unwrap();

    let index = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let page = "viewer/levine-automove-0p.html";
    for k in 0..2 {
        assert!(
            index.contains(&format!("href=\"{page}#run={k}\"")),
            "leg {} is linked",
            k + 1
        );
    }
    assert!(
        !index.contains(&format!("{page}#run=2")),
        "no leg beyond the results"
    );
    let html = std::fs::read_to_string(dir.join(page)).unwrap();
    assert_eq!(html.matches("class=\"run-data\"").count(), 2);
    assert!(html.contains("data-key=\"levine/automove/0p#1\""));
    assert!(html.contains("id=\"cloud\""), "the panel's particle cloud row");
    // The leg's trace holds the localizer's cloud at its filter iterations.
    let replay = suite
        .replay(&campaign.jobs[0], &[], sim::TraceParams::full())
        .unwrap();
    let clouds: Vec<usize> = replay
        .trace
        .ticks
        .iter()
        .flat_map(|t| {
            t.clouds
                .iter()
                .filter(|(n, _)| *n == "particles")
                .map(|(_, c)| c.len())
        })
        .collect();
    assert!(
        clouds.len() > 10,
        "a cloud at every filter iteration: {}",
        clouds.len()
    );
    assert!(clouds.iter().all(|&n| n > 0));
    let _ = std::fs::remove_dir_all(&dir);
}
