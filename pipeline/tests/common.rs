//! What every module of the suite needs to run the `ribbar` binary: the
//! checkout it runs in, a scratch directory of its own and the text it
//! printed.

use std::path::{Path, PathBuf};
use std::process::Output;

/// The checkout: the binary runs here, so the scenes' relative paths hold.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the pipeline crate lies in the workspace")
        .to_path_buf()
}

/// An empty scratch path `ribbar-MODULE-NAME-PID` under the system's
/// temporary directory (the directory itself is not made: the command under
/// test makes it). The module in the name keeps tests of different files
/// apart, the process id runs of the suite.
pub fn scratch(module: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ribbar-{module}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// What a command printed, standard output then standard error.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}
