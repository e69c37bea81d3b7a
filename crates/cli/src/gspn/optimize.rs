//! `petrinav gspn optimize`: the best policy of a net with decisions or of
//! a DRN model for a property, its value with a guaranteed bound (the work
//! in `lab::optimize`; here options and tables).

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use lab::optimize::{Optimization, OptimizeOptions, describe_model};
use petri::Interrupt;
use petri::mdp::Precision;

use super::{NetArgs, explore_params, print_json};
use crate::output::{Table, fields, num};
use crate::{out, outln};

#[derive(Args, Debug)]
pub struct OptimizeArgs {
    #[command(flatten)]
    net: NetArgs,
    /// The property, as in PRISM and Storm: `'Pmax=? [F "goal"]'`,
    /// `'Tmin=? [F #P3 = 1]'`, `'R{"cost"}min=? [F "done"]'`,
    /// `'R{"done"}max=? [LRA]'`, `'LRAmax=? ["up"]'`. Quoted names are
    /// labels (the net's `[labels]`, a DRN file's labels), `#P` token counts.
    #[arg(long, short = 'o', value_name = "PROPERTY")]
    objective: String,
    /// Half the width of the value's guaranteed interval, relative to the
    /// value (absolute with --absolute).
    #[arg(long, default_value_t = 1e-6, value_name = "EPS")]
    precision: f64,
    /// Make --precision absolute.
    #[arg(long)]
    absolute: bool,
    /// Rate for every timed transition that has none (plain P/T nets).
    #[arg(long, value_name = "R")]
    default_rate: Option<f64>,
    /// Write the policy to this file (JSON; `gspn solve NET --policy FILE`
    /// runs the net under it). Nets only.
    #[arg(long, value_name = "FILE")]
    policy_out: Option<PathBuf>,
    /// Choice states listed in the table (all with --json).
    #[arg(long, default_value_t = 40, value_name = "N")]
    show: usize,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

/// A value with its bound: `0.7312 ± 3.6e-7`, `infinity`, `1 ± 0`.
fn bounded(v: f64, b: f64) -> String {
    if v.is_infinite() {
        "infinity".into()
    } else if b == 0.0 {
        format!("{} ± 0", num(v))
    } else {
        format!("{} ± {:.1e}", num(v), b)
    }
}

fn mid(l: f64, u: f64) -> f64 {
    if l == u { l } else { l + (u - l) / 2.0 }
}

pub fn run(a: &OptimizeArgs) -> Result<()> {
    if !(a.precision.is_finite() && a.precision > 0.0) {
        bail!("--precision must be a number > 0, got {}", a.precision);
    }
    let options = OptimizeOptions {
        explore: explore_params(&a.net),
        precision: Precision {
            epsilon: a.precision,
            relative: !a.absolute,
            ..Precision::default()
        },
        default_rate: a.default_rate,
    };
    if a.policy_out.is_some() && lab::optimize::is_drn(&a.net.file) {
        bail!(
            "--policy-out writes a policy for a net (by marking); a DRN model's policy is printed (--json lists every state)"
        );
    }
    let problem = lab::optimize::load(&a.net.file, &a.net.params, &options)?;
    let result = problem.optimize(&a.objective, &options, Interrupt::NEVER)?;
    if let (Some(path), Some(policy)) = (&a.policy_out, &result.policy) {
        std::fs::write(path, policy.to_json())
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
    }
    if a.json {
        return print_json(&result.to_json());
    }
    report(a, &result)
}

fn report(a: &OptimizeArgs, r: &Optimization) -> Result<()> {
    let o = &r.optimum;
    let how = if o.iterations == 0 {
        "graph analysis".to_string()
    } else {
        format!("{}, {} sweeps", o.method, o.iterations)
    };
    let mut rows = vec![
        (
            "model",
            format!("{} ({})", a.net.file.display(), describe_model(&r.model)),
        ),
        ("property", r.property.text.clone()),
        (
            "value",
            format!("{}  ({how}, {:.3} s)", bounded(r.value(), r.bound()), o.seconds),
        ),
    ];
    if r.model.initial_states().len() > 1 {
        rows.push((
            "initial states",
            format!(
                "{} (the value is the first's; --json lists all)",
                r.model.initial_states().len()
            ),
        ));
    }
    rows.push(("choice states", r.choices.len().to_string()));
    if let Some(path) = &a.policy_out {
        rows.push(("policy written to", path.display().to_string()));
    }
    out!("{}", fields(&rows))?;
    if r.choices.is_empty() {
        return Ok(());
    }
    let mut t = Table::new(["choice state", "chosen", "alternatives (value ± bound)"]);
    for c in r.choices.iter().take(a.show) {
        let alts: Vec<String> = c
            .alternatives
            .iter()
            .enumerate()
            .map(|(i, (name, l, u))| match &c.relative {
                // Long-run averages: the gain is the same for every
                // alternative of a recurrent component; the relative
                // value tells them apart.
                Some(rel) => format!("{name} {} (relative {})", num(mid(*l, *u)), num(rel[i])),
                None => format!(
                    "{name} {}",
                    bounded(mid(*l, *u), if l == u { 0.0 } else { (u - l) / 2.0 })
                ),
            })
            .collect();
        t.row([c.name.clone(), c.chosen.clone(), alts.join(", ")]);
    }
    outln!("\n{}", t.render())?;
    if r.choices.len() > a.show {
        outln!("… {} choice states in all (--show N, or --json)", r.choices.len())?;
    }
    Ok(())
}
