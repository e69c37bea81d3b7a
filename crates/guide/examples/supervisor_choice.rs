//! The GSPN supervisor's choice between AutoMove and Contour tracking as
//! contour tracking's mean completion time grows, AutoMove's fixed.
//!
//! ```text
//! cargo run -p guide --example supervisor_choice -- [AUTOMOVE_S]
//! cargo run -p guide --example supervisor_choice -- 150
//! ```
//!
//! `AUTOMOVE_S` is AutoMove's mean time to complete a leg, seconds (default
//! 122.33, the source's). Prints, for contour tracking's mean time from 60
//! to 300 s, the two throughputs `f_auto`, `f_cont` and the choice.

use guide::supervisor::{Rates, Supervisor};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let automove_s: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(122.33);
    let supervisor = Supervisor::new()?;
    println!("AutoMove completes in {automove_s} s on average");
    println!("{:>10} {:>10} {:>10}  choice", "contour_s", "f_auto", "f_cont");
    for contour_s in (60..=300).step_by(30) {
        let mut rates = Rates::initial();
        rates.set(7, 1.0 / automove_s);
        rates.set(8, 1.0 / contour_s as f64);
        let d = supervisor.decide(&rates)?;
        println!(
            "{contour_s:>10} {:>10.5} {:>10.5}  {:?}",
            d.f_auto, d.f_cont, d.choice
        );
    }
    Ok(())
}
