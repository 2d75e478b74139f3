//! The `ribbar` program that study cases and benchmark runs start as
//! child processes.

use anyhow::{Context, Result};
use std::path::PathBuf;

/// How the first line of an error that `ribbar` reports starts
/// (`app::error_report`; a study reads a case's error back from its log).
pub const ERROR_PREFIX: &str = "error: ";
/// How each line of that error's causes starts.
pub const CAUSE_PREFIX: &str = "  caused by: ";

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
