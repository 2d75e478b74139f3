//! Wall time and peak resident memory of a child process (wait4 rusage),
//! with a timeout: how the benchmarks measure every solve they start.

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Exit, wall time (s) and peak resident memory (bytes) of a child.
pub(crate) struct Measured {
    pub(crate) success: bool,
    pub(crate) timed_out: bool,
    pub(crate) wall: f64,
    pub(crate) max_rss: u64,
}

/// Waits for `child` (at most `timeout` s, then kills it) and measures it
/// with wait4's rusage: the peak resident set of that process alone.
pub(crate) fn wait_measured(
    child: &mut std::process::Child,
    start: Instant,
    timeout: f64,
) -> Result<Measured> {
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain data; wait4 writes it and the status.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let mut timed_out = false;
    loop {
        // SAFETY: pid is our own child, not yet reaped (std's Child is
        // never waited on afterwards).
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        if r < 0 {
            bail!("wait4 on child {pid}: {}", std::io::Error::last_os_error());
        }
        if !timed_out && start.elapsed().as_secs_f64() > timeout {
            timed_out = true;
            let _ = child.kill();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let wall = start.elapsed().as_secs_f64();
    Ok(Measured {
        success: !timed_out && libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        timed_out,
        wall,
        // ru_maxrss is in KiB on Linux.
        max_rss: usage.ru_maxrss.max(0) as u64 * 1024,
    })
}

/// Runs `command` with its output in the file `log`, measured, at most
/// `timeout` s; an error naming `name` and the log when it fails or times
/// out.
pub(crate) fn run_logged(
    command: &mut Command,
    name: &str,
    log: &Path,
    timeout: f64,
) -> Result<Measured> {
    let file = std::fs::File::create(log).with_context(|| format!("creating {}", log.display()))?;
    let start = Instant::now();
    let mut child = command
        .stdin(Stdio::null())
        .stdout(
            file.try_clone()
                .with_context(|| log.display().to_string())?,
        )
        .stderr(file)
        .spawn()
        .with_context(|| format!("starting {name}"))?;
    let m = wait_measured(&mut child, start, timeout)?;
    if !m.success {
        bail!(
            "{name} {} after {:.1} s (see {})",
            if m.timed_out { "timed out" } else { "failed" },
            m.wall,
            log.display()
        );
    }
    Ok(m)
}
