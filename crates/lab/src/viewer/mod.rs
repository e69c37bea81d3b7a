//! The run viewer: replayed runs as one self-contained HTML page that
//! opens offline in any browser (no network, no library: the data, the map
//! as a PNG data URI, the style and a small hand-written script are all in
//! the file). A page shows one run ([`page`], what `lab replay --html`
//! writes) or several ([`runs_page`]: a report's scenario picture draws up
//! to 8 over each other, and its page holds them all), one at a time: a run
//! selector (and `[`/`]`) above the map, `#run=K` in the URL (K from 0),
//! the slider back at the run's first tick on every switch.
//!
//! The page draws the map, the trajectory so far coloured by the behaviour
//! in control (the whole path dashed), the footprint and heading (the
//! controller's own estimate dashed where it differs), the current tick's
//! laser beams, sonar cones and IR beams, people, start, goal, the
//! controller's latest point sets (a particle cloud) and the events so far
//! as the suite's markers draw them; a slider with play/pause and step
//! keys; and a panel with the tick's behaviour,
//! command, poses, the controller's named values (a key → value table with
//! bars over the run's range: votes and weights for voting, activations
//! for priority arbitration, localizer state for the guide), the tick's
//! events with their payloads (CP events, dead-locks, supervisor decisions
//! with `f_auto`/`f_cont`…), every event of the run, and the run's record.
//! A run that carries a net ([`crate::net_view::NetView`]: the tour-guide
//! supervisor's) has it drawn in a small panel as the run plays: the
//! places marked at the tick (their tokens are the run's values named
//! after them), and the payload of the last decision played — the
//! context, the rates used, the net's marking and the value of each
//! choice (`<body data-net-marking data-net-event-tick>`).
//!
//! Nothing here knows a controller: what a controller wants shown it puts
//! in its trace notes ([`robot::Notes`]: behaviour, values, events, and
//! named pose sets — the guide's localizer notes its particle cloud at
//! every filter iteration, drawn as teal dots until the next, thinned to
//! [`data::CLOUD_POINTS`]).
//!
//! The page's state is readable from the DOM (`<body data-ready data-runs
//! data-run data-run-key data-tick data-time data-robot-x data-robot-y
//! data-robot-page-x data-robot-page-y>`), script errors are listed in
//! `#errors` and counted in `<html data-errors>`, and the URL hash sets the
//! run and the time (`#run=3`, `#t=40`, `#tick=400`, `&play=1`,
//! `&speed=5`), so a headless browser can check a page
//! (`crates/cli/tests/viewer_browser.rs`). The runs are listed in the HTML
//! too: one `<script class="run-data" data-run="K" data-key="SCENARIO#I">`
//! each.
//!
//! Size: what the runs share (the suite, the distinct maps, the view, the
//! markers, the behaviours' labels: [`data::PageData`]) is written once;
//! each run's ticks are columns of rounded numbers ([`data::RunData`]) in a
//! block of its own, inflated when the run is first shown. Every block is
//! zlib-compressed JSON in base64 (a fifth of the JSON's size; the page
//! inflates it with the browser's `DecompressionStream`, in every current
//! browser since 2023). A voting run of 37.5 s takes 52 kB (22 kB of
//! them the script and style), the 8 pictured runs of its scenario
//! (`e4/field12`) 270 kB; a 116 s museum mission with a 181-beam laser
//! among 25 visitors, its particle cloud at 128 filter iterations, 0.58 MB
//! (`lab run tourguide`'s mission page); a minute of a maps-suite leg
//! 0.25–0.3 MB.

pub mod data;

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::page::html_escape;
use crate::pictures::{EventMarker, Replay};
pub use data::PageRun;

const SCRIPT: &str = include_str!("viewer.js");
const STYLE: &str = include_str!("viewer.css");

/// Catches script errors before anything else runs (a syntax error in the
/// viewer's script included), lists them in `#errors` and counts them in
/// `<html data-errors>`.
const CATCH: &str = "window.__errors=0;function __error(m){window.__errors++;document.documentElement.dataset.errors=String(window.__errors);var l=document.getElementById('errors');var i=document.createElement('li');i.textContent=String(m);l.appendChild(i);l.hidden=false;}\nwindow.addEventListener('error',function(e){__error((e.message||'error')+(e.lineno?' (line '+e.lineno+')':''));});\nwindow.addEventListener('unhandledrejection',function(e){__error('unhandled rejection: '+e.reason);});\n(function(){var ce=console.error;console.error=function(){__error(Array.prototype.join.call(arguments,' '));ce.apply(console,arguments);};})();";

/// The viewer page of one run, `replay`, keyed `key` and titled with it
/// and the suite's name; events placed as `markers` say.
pub fn page(replay: &Replay, markers: &[EventMarker], suite: &str, key: &str) -> Result<String> {
    runs_page(&[PageRun { replay, key }], markers, suite, key)
}

/// The viewer page of several runs (a scenario's picture draws up to 8
/// over each other), titled `title` with the suite's name: the maps once,
/// each run's ticks in its own block, inflated when the run is chosen
/// (the run selector, or `#run=K` in the URL, K counted from 0 in the
/// order of `runs`); events placed as `markers` say.
pub fn runs_page(runs: &[PageRun<'_>], markers: &[EventMarker], suite: &str, title: &str) -> Result<String> {
    if runs.is_empty() {
        bail!("a viewer page needs a run to show");
    }
    if let Some(run) = runs.iter().find(|r| r.replay.trace.ticks.is_empty()) {
        bail!("run `{}` has no tick to show", run.key);
    }
    let (shared, data) = data::page_data(runs, markers, suite, title)?;
    let shared = zlib_base64(&shared)?;
    let mut blocks = String::new();
    let mut options = String::new();
    for (k, d) in data.iter().enumerate() {
        let key = attribute(&d.key);
        let _ = writeln!(
            blocks,
            "<script type=\"application/octet-stream\" class=\"run-data\" data-run=\"{k}\" data-key=\"{key}\" \
data-encoding=\"zlib+base64\">{}</script>",
            zlib_base64(d)?
        );
        let _ = write!(options, "<option value=\"{k}\">{}</option>", html_escape(&d.key));
    }
    let hidden = if data.len() == 1 { " hidden" } else { "" };
    let title = html_escape(&format!("{title} — {suite}"));
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\" data-errors=\"0\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width\"><title>{title} — petrinav run viewer</title>\n\
<style>\n{STYLE}</style></head>\n<body data-ready=\"0\" data-runs=\"{runs}\">\n<ol id=\"errors\" hidden></ol>\n\
<script>\n{CATCH}\n</script>\n\
<header><h1 id=\"title\">{title}</h1><p><label id=\"run-box\"{hidden}>run \
<select id=\"run\" aria-label=\"run\">{options}</select> \
<button id=\"prev-run\" type=\"button\" title=\"the run before ([)\">◀</button>\
<button id=\"next-run\" type=\"button\" title=\"the run after (])\">▶</button> </label>\
<span id=\"summary\"></span></p></header>\n\
<main><div id=\"stage\"><canvas id=\"map\" width=\"800\" height=\"600\"></canvas>\n\
<div id=\"controls\"><button id=\"play\" type=\"button\">▶ play</button>\
<button id=\"prev\" type=\"button\" title=\"one tick back (←)\">◀</button>\
<button id=\"next\" type=\"button\" title=\"one tick on (→)\">▶</button>\
<input id=\"slider\" type=\"range\" min=\"0\" max=\"0\" value=\"0\" aria-label=\"time\">\
<span id=\"clock\"></span>\
<select id=\"speed\" aria-label=\"speed\"><option value=\"0.5\">0.5×</option><option value=\"1\" selected>1×</option>\
<option value=\"2\">2×</option><option value=\"5\">5×</option><option value=\"10\">10×</option></select>\
<label><input id=\"follow\" type=\"checkbox\"> follow</label><button id=\"reset\" type=\"button\">fit</button></div>\n\
<p class=\"help\">space play/pause · ←/→ one tick (shift: one second) · Home/End · wheel or +/− zoom, drag to pan, double-click to fit · \
{run_help}URL <code>#t=SECONDS</code> opens at a time. Dashed purple: the controller's own pose estimate; teal dots: its latest particle cloud; blue cones: sonar; lines: IR (red when triggered) and laser beams.</p>\n\
<div id=\"legend\"></div></div>\n\
<aside><h2 id=\"clock-h\">This tick</h2><table>\
<tr><td>behaviour</td><td id=\"behaviour\"></td></tr><tr><td>step</td><td id=\"step\"></td></tr>\
<tr><td>command</td><td id=\"command\"></td></tr><tr><td>wheels</td><td id=\"wheels\"></td></tr>\
<tr><td>true pose</td><td id=\"pose\"></td></tr><tr><td>estimate</td><td id=\"estimate\"></td></tr>\
<tr><td>request</td><td id=\"request\"></td></tr>\
<tr id=\"cloud-row\"><td>cloud</td><td id=\"cloud\"></td></tr></table>\n\
<h2>Sensors</h2><pre id=\"sensors\"></pre>\n\
<div id=\"net-box\" hidden><h2 id=\"net-title\">Net</h2><svg id=\"net\" xmlns=\"http://www.w3.org/2000/svg\"></svg>\
<table id=\"net-event\"></table></div>\n\
<div id=\"values-box\"><h2>Controller's values</h2><table id=\"values\"></table></div>\n\
<h2>Events this tick</h2><ul id=\"now\"></ul>\n\
<div id=\"events-box\"><h2>All events (click to go)</h2><ol id=\"events\"></ol></div>\n\
<h2>Run</h2><table id=\"record\"></table></aside></main>\n\
<script type=\"application/octet-stream\" id=\"page-data\" data-encoding=\"zlib+base64\">{shared}</script>\n\
{blocks}<script>\n{SCRIPT}</script>\n</body></html>\n",
        runs = data.len(),
        run_help = if data.len() == 1 {
            ""
        } else {
            "[/] the run before/after (URL <code>#run=K&amp;t=SECONDS</code>) · "
        },
    ))
}

/// `s` for an attribute's value in double quotes.
fn attribute(s: &str) -> String {
    html_escape(s).replace('"', "&quot;")
}

/// `value` as JSON, zlib-compressed, in base64.
fn zlib_base64(value: &impl serde::Serialize) -> Result<String> {
    Ok(crate::encode::base64(&deflate(&serde_json::to_vec(value)?)?))
}

/// `bytes` in the zlib format (RFC 1950), as the browser's
/// `DecompressionStream("deflate")` reads it.
fn deflate(bytes: &[u8]) -> Result<Vec<u8>> {
    use std::io::Write as _;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(bytes)?;
    Ok(z.finish()?)
}

/// Writes the viewer page of `replay` to `path`.
pub fn write_page(
    replay: &Replay,
    markers: &[EventMarker],
    suite: &str,
    key: &str,
    path: &Path,
) -> Result<()> {
    let html = page(replay, markers, suite, key)?;
    std::fs::write(path, html).with_context(|| format!("writing {}", path.display()))
}

/// Writes the viewer page of `runs` ([`runs_page`]) to `path`.
pub fn write_runs_page(
    runs: &[PageRun<'_>],
    markers: &[EventMarker],
    suite: &str,
    title: &str,
    path: &Path,
) -> Result<()> {
    let html = runs_page(runs, markers, suite, title)?;
    std::fs::write(path, html).with_context(|| format!("writing {}", path.display()))
}
