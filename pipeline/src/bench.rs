//! `ribbar bench`: run time against error, written as Markdown tables and
//! plots (see docs/performance.md).

use crate::cli::BenchArgs;
use crate::progress::Printer;
use anyhow::Result;
use std::process::ExitCode;

pub fn run(args: &BenchArgs, _printer: &Printer) -> Result<ExitCode> {
    anyhow::bail!("bench {:?}: not available in this build", args.kind)
}
