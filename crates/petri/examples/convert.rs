//! Converts a net from one file format to another, chosen by extension:
//!
//! ```text
//! cargo run -p petri --example convert -- FlexibleManufacturingSystem.PNPRO fms.toml
//! cargo run -p petri --example convert -- fms.toml fms.dot && dot -Tsvg fms.dot -o fms.svg
//! ```

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output] = args.as_slice() else {
        eprintln!("usage: convert INPUT OUTPUT (by extension: .pnpro, .pnml, .toml; .dot for output only)");
        return ExitCode::from(2);
    };
    let converted = petri::io::read_file(input).and_then(|net| {
        petri::io::write_file(&net, output)?;
        Ok(net)
    });
    match converted {
        Ok(net) => {
            println!(
                "{input} -> {output}: net `{}`, {} places, {} transitions, {} arcs, {} parameters",
                net.name,
                net.places.len(),
                net.transitions.len(),
                net.arcs.len(),
                net.params.len()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
