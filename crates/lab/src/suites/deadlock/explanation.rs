//! The dead-lock suite's explanation, from the batch's numbers: every
//! figure and verdict below is computed from `results.jsonl`, none is
//! written in advance.

use std::fmt::Write as _;

use crate::record::Runs;
use crate::suites::shared::DEADLOCKS;
use crate::summary::{Summary, paired};

fn find<'a>(summaries: &'a [Summary], name: &str) -> Option<&'a Summary> {
    summaries.iter().find(|s| s.scenario == name && s.runs > 0)
}

fn pct(x: f64) -> String {
    format!("{:.0} %", 100.0 * x)
}

fn verdict(ok: bool) -> &'static str {
    if ok { "met" } else { "NOT met" }
}

/// Failed runs of `scenario` in which no dead-lock was detected.
fn failures_without_deadlock(runs: &Runs, scenario: &str) -> usize {
    runs.get(scenario).map_or(0, |rs| {
        rs.iter()
            .filter(|(_, r)| !r.success && r.metric(DEADLOCKS) == Some(0.0))
            .count()
    })
}

/// Markdown paragraphs for the report.
pub fn explanation(summaries: &[Summary], runs: &Runs) -> String {
    let mut out = String::from("\n## What the table shows, and why\n\n");
    out.push_str(
        "Every scenario meets, in run k, the same trap, start and sensor noise (common random numbers), so the rows differ only by the controller. The priority controller drives the `ring` robot (16 sonars all round: its behaviours react to every side); the voting controller drives AIBOT (7 IR + 3 sonars), the robot its behaviours are built for. Unless a row says otherwise the odometry is calibrated (1 % Gaussian wheel slip, no large slips), so the rows measure escaping the trap, not dead reckoning.\n\n",
    );
    let pair = |a: &str, b: &str| (find(summaries, a), find(summaries, b));
    if let (Some(off), Some(on)) = pair("priority", "priority_recovery") {
        let pu = paired(runs, "priority", "priority_recovery");
        let _ = writeln!(
            out,
            "**U-shaped dead ends, priority arbitration.** Without recovery the robot reaches the goal in {} of {} traps ({} time limits, {} collisions): goal tracking steers into the U, avoid front turns it away at the back wall, goal tracking takes over as soon as the wall is out of sight and leads it back in, and the trace shows the same chunk `CP2, CP3, CP2` again and again ({:.1} dead-locks detected per run; the detector runs, nothing acts on it). Few successes without recovery — {}. With detection and potential-field recovery it reaches the goal in {} (95 % interval {}–{}), {:.1} dead-locks per run: each is a point the robot is repelled from, so the goal-tracking heading bends around the trap instead of into it; the detour costs time ({:.1} s against {:.1} s for the few that got out alone) and path ({:.1} m against {:.1} m). At least 95 % with recovery — {}. Run by run, recovery got out of {} traps that held the plain controller and stayed in {} that it got out of alone.\n",
            pct(off.reliability.value),
            off.runs,
            off.timeouts,
            off.collisions,
            off.metric_mean(DEADLOCKS),
            verdict(off.reliability.value <= 0.3),
            pct(on.reliability.value),
            pct(on.reliability.low),
            pct(on.reliability.high),
            on.metric_mean(DEADLOCKS),
            on.time.mean,
            off.time.mean,
            on.path_length.mean,
            off.path_length.mean,
            verdict(on.reliability.value >= 0.95),
            pu.wins,
            pu.losses,
        );
    }
    if let (Some(on), Some(slips)) = pair("priority_recovery", "priority_recovery_slips") {
        let _ = writeln!(
            out,
            "**The same with the default odometry** (large wheel slips, as in the voting suite): {} instead of {}; {} runs end `lost` — the robot stopped where its dead reckoning put the goal, farther than the tolerance from the real one. The recovery's detour is longer than the straight course, so the drift it accumulates is larger; the detector itself works in the odometry frame and is unaffected (CP points drift with the robot's estimate, but three of them within seconds drift together).\n",
            pct(slips.reliability.value),
            pct(on.reliability.value),
            slips.lost,
        );
    }
    if let (Some(off), Some(on)) = pair("priority_v", "priority_v_recovery") {
        let _ = writeln!(
            out,
            "**V-shaped dead ends.** {} without recovery, {} with it. A V is a funnel: avoid left / avoid right turn the robot along an arm, which leads it out past the arm's end, so the plain controller mostly escapes by itself{}; the trace still helps with the rest.\n",
            pct(off.reliability.value),
            pct(on.reliability.value),
            if off.reliability.value > 0.5 {
                " — a V is not a trap for this controller"
            } else {
                ""
            },
        );
    }
    if let (Some(off), Some(on)) = pair("voting", "voting_trace") {
        let pv = paired(runs, "voting", "voting_trace");
        let failed = on.runs - on.reliability.successes;
        let _ = writeln!(
            out,
            "**Dynamic weighted voting** on the U traps: {} without the trace layer, {} with it ({:.1} dead-locks detected per run). The layer reads the voting outcome as characteristic events (the goal team's favourite chosen → CP2; the obstacle team overruling it with the goal ahead → CP3) and repels goal seeking from the recorded dead-locks; run by run it wins {} and loses {} runs, and {} runs are identical (no dead-lock detected). It can only act on a dead-lock it sees: {} of the {} runs with the layer that did not reach the goal detected none. Replays of such runs (`petrinav lab replay DIR 'voting_trace#K'`) show why: the robot drives to the back wall and stays there, the obstacle team's escape action alternating left and right with every IR detector triggered. The goal team never wins a ballot again, so no `CP2` follows the `CP3` — a dead-lock without behaviour switches, which the trace cannot show. The other runs that did not reach the goal ended in collisions ({} with the layer): contacts with the trap's walls that no dead-lock memory prevents.\n",
            pct(off.reliability.value),
            pct(on.reliability.value),
            on.metric_mean(DEADLOCKS),
            pv.wins,
            pv.losses,
            pv.identical,
            failures_without_deadlock(runs, "voting_trace"),
            failed,
            on.collisions,
        );
    }
    out
}
