//! A scheduler's request to stop (SIGTERM), caught while a solve runs.
//!
//! Slurm ends a job at its time limit, or on `scancel`, with SIGTERM, then
//! SIGKILL after `KillWait` seconds. A solve that catches the first stops at
//! its next converged step, writes its checkpoint and exits with
//! [`TERMINATED_EXIT`]: nothing is committed, and the job's retry resumes
//! from that step. A second SIGTERM ends the process at once, as if none
//! were caught. Outside a solve the signal keeps its previous action (the
//! default: the process ends, and a stage that was running is never taken
//! as done because it commits only by its final rename).

use std::sync::atomic::{AtomicBool, Ordering};

/// The exit status of a solve stopped by SIGTERM: 128 + the signal's
/// number, what a shell reports for a process the signal ended.
pub const TERMINATED_EXIT: i32 = 128 + libc::SIGTERM;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Whether a SIGTERM arrived since [`catch_sigterm`].
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

extern "C" fn on_sigterm(_: libc::c_int) {
    // Only async-signal-safe calls: an atomic swap, signal(2) and raise(3).
    if REQUESTED.swap(true, Ordering::SeqCst) {
        unsafe {
            libc::signal(libc::SIGTERM, libc::SIG_DFL);
            libc::raise(libc::SIGTERM);
        }
    }
}

/// SIGTERM caught while this lives; the previous action is restored when
/// it is dropped.
pub struct SigtermGuard {
    previous: Option<libc::sigaction>,
}

/// Catches SIGTERM from now until the guard is dropped.
pub fn catch_sigterm() -> SigtermGuard {
    REQUESTED.store(false, Ordering::SeqCst);
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_sigterm as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SA_RESTART: reads and writes the signal interrupts go on.
        action.sa_flags = libc::SA_RESTART;
        libc::sigemptyset(&mut action.sa_mask);
        let mut previous: libc::sigaction = std::mem::zeroed();
        let installed = libc::sigaction(libc::SIGTERM, &action, &mut previous) == 0;
        SigtermGuard {
            previous: installed.then_some(previous),
        }
    }
}

impl Drop for SigtermGuard {
    fn drop(&mut self) {
        if let Some(previous) = &self.previous {
            unsafe {
                libc::sigaction(libc::SIGTERM, previous, std::ptr::null_mut());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A SIGTERM while the guard lives is recorded, not fatal.
    #[test]
    fn a_caught_sigterm_is_recorded() {
        let guard = catch_sigterm();
        assert!(!requested());
        unsafe {
            libc::raise(libc::SIGTERM);
        }
        assert!(requested());
        drop(guard);
    }
}
