//! The `ribbar` program that study cases and benchmark runs start as
//! child processes.

use anyhow::{Context, Result};
use std::path::PathBuf;

/// How the first line of an error that `ribbar` reports starts
/// (`app::error_report`; a study reads a case's error back from its log).
pub const ERROR_PREFIX: &str = "error: ";
/// How each line of that error's causes starts.
pub const CAUSE_PREFIX: &str = "  caused by: ";

/// An error's message, then each cause that the line before it does not
/// already end with (errors that print their source as part of their own
/// message, `{path}: {source}`, would otherwise say it twice).
pub fn error_lines(err: &anyhow::Error) -> Vec<String> {
    let mut lines = vec![err.to_string()];
    let mut previous = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !previous.ends_with(&cause) {
            lines.push(cause.clone());
        }
        previous = cause;
    }
    lines
}

/// Environment variable naming the program that study cases and benchmark
/// runs start as child processes. Unset, it is this executable; the Python
/// package sets it, since there this process is the Python interpreter.
pub const SELF_EXE_ENV: &str = "RIBBAR_EXE";

/// The `ribbar` program to start child processes with.
pub fn self_exe() -> Result<PathBuf> {
    match std::env::var_os(SELF_EXE_ENV).filter(|v| !v.is_empty()) {
        Some(exe) => Ok(PathBuf::from(exe)),
        None => std::env::current_exe().context("locating the ribbar executable"),
    }
}
