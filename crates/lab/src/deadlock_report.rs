//! The dead-lock suite's explanation, from the batch's numbers.

use std::fmt::Write as _;

use crate::report::Summary;

fn find<'a>(summaries: &'a [Summary], name: &str) -> Option<&'a Summary> {
    summaries.iter().find(|s| s.scenario == name && s.runs > 0)
}

/// Markdown paragraphs for the report.
pub fn explanation(summaries: &[Summary]) -> String {
    let mut out = String::from("\n## What the table shows, and why\n\n");
    let pair = |a: &str, b: &str| (find(summaries, a), find(summaries, b));
    if let (Some(off), Some(on)) = pair("priority", "priority_recovery") {
        let _ = writeln!(
            out,
            "Priority arbitration meets a dead-end trap on its course in every run. Without the activity trace it reaches the goal in {:.0} % of the {} traps ({} time limits, {} collisions): goal tracking steers into the trap, avoid-front turns it away at the back wall, goal tracking takes over again as soon as the wall is out of the way, and the robot repeats the same chunk of behaviour switches (`CP2, CP3, CP2`) until the time limit. With dead-lock detection and potential-field recovery it reaches the goal in {:.0} % (95 % interval {:.0}–{:.0} %), with {:.1} dead-locks detected per run on average: each detected dead-lock is a point the robot is repelled from, so the goal-tracking heading bends around the trap instead of into it. Success target with recovery: at least 95 % — {}.\n",
            100.0 * off.reliability.value,
            off.runs,
            off.timeouts,
            off.collisions,
            100.0 * on.reliability.value,
            100.0 * on.reliability.low,
            100.0 * on.reliability.high,
            on.deadlocks_per_run,
            if on.reliability.value >= 0.95 {
                "met"
            } else {
                "NOT met"
            }
        );
    }
    if let (Some(off), Some(on)) = pair("voting", "voting_trace") {
        let _ = writeln!(
            out,
            "Dynamic weighted voting (IR + sonar, odometry + planning) on the same traps (run k meets the same trap in every scenario): {:.0} % without the trace layer, {:.0} % with it ({:.1} dead-locks detected per run). The layer reads the voting outcome as characteristic events (goal team's choice → CP2; obstacle team overruling the goal direction → CP3) and repels goal seeking from the recorded dead-locks, as for the priority controller.\n",
            100.0 * off.reliability.value,
            100.0 * on.reliability.value,
            on.deadlocks_per_run
        );
    }
    out
}
