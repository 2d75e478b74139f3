//! Builds the stress-sweep results table from a study already run by
//! `ribbar study`: `stress_report STUDY.yaml WORK OUT.md [COMMAND]`.
//! Exits non-zero if a case panicked, wrote a non-finite value or stopped
//! without a reason (see `pipeline::bench_series::stress_report`).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: stress_report STUDY.yaml WORK OUT.md [COMMAND]");
        return ExitCode::FAILURE;
    }
    let command = args
        .get(3)
        .cloned()
        .unwrap_or_else(|| format!("ribbar study {} --work {}", args[0], args[1]));
    match pipeline::bench_series::stress_report(
        &PathBuf::from(&args[0]),
        &PathBuf::from(&args[1]),
        &PathBuf::from(&args[2]),
        &command,
    ) {
        Ok(cases) => {
            let bad: Vec<&str> = cases
                .iter()
                .filter(|c| !c.explained())
                .map(|c| c.name.as_str())
                .collect();
            println!("{} cases; table {}", cases.len(), args[2]);
            if bad.is_empty() {
                ExitCode::SUCCESS
            } else {
                eprintln!("unexplained, panicked or non-finite: {}", bad.join(", "));
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
