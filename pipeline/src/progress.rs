//! Progress output on standard error: a line rewritten in place on a
//! terminal, plain lines otherwise (logs, CI, cluster jobs); `-q` silences
//! everything but errors, `-v` adds detail.

use std::io::{IsTerminal, Write};
use std::sync::mpsc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    Quiet,
    Normal,
    Verbose,
}

pub struct Printer {
    pub verbosity: Verbosity,
    terminal: bool,
    /// Whether the last thing written was an in-place status line.
    transient: Mutex<bool>,
    prefix: String,
}

impl Printer {
    pub fn new(verbosity: Verbosity) -> Self {
        Printer {
            verbosity,
            terminal: std::io::stderr().is_terminal(),
            transient: Mutex::new(false),
            prefix: String::new(),
        }
    }

    /// A printer whose lines start with `[prefix] ` (study cases).
    pub fn with_prefix(&self, prefix: &str) -> Self {
        Printer {
            verbosity: self.verbosity,
            terminal: self.terminal,
            transient: Mutex::new(false),
            prefix: format!("[{prefix}] "),
        }
    }

    fn write(&self, text: &str, transient: bool) {
        let mut err = std::io::stderr().lock();
        let mut last = self.transient.lock().unwrap_or_else(|e| e.into_inner());
        if *last {
            let _ = write!(err, "\r\x1b[2K");
        }
        if transient && self.terminal {
            let _ = write!(err, "{}{text}", self.prefix);
            *last = true;
        } else {
            let _ = writeln!(err, "{}{text}", self.prefix);
            *last = false;
        }
        let _ = err.flush();
    }

    /// A normal message.
    pub fn line(&self, text: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.write(text, false);
        }
    }

    /// Progress of a long stage: in place on a terminal.
    pub fn progress(&self, text: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.write(text, true);
        }
    }

    /// Only with `-v`.
    pub fn detail(&self, text: &str) {
        if self.verbosity == Verbosity::Verbose {
            self.write(text, false);
        }
    }

    /// Ends an in-place line so that what follows starts on its own line.
    pub fn finish(&self) {
        let mut last = self.transient.lock().unwrap_or_else(|e| e.into_inner());
        if *last {
            let _ = writeln!(std::io::stderr());
            *last = false;
        }
    }

    /// Runs `work`, showing `what(elapsed)` while it runs: every second in
    /// place on a terminal; in a log at 5, 10, 20, 40, … s, so that a long
    /// gmsh run says it is alive without filling the log.
    pub fn while_running<T>(
        &self,
        what: impl Fn(Duration) -> String + Sync,
        work: impl FnOnce() -> T,
    ) -> T {
        if self.verbosity == Verbosity::Quiet {
            return work();
        }
        let started = Instant::now();
        let (stop, stopped) = mpsc::channel::<()>();
        let what = &what;
        std::thread::scope(|s| {
            s.spawn(move || {
                let mut next = if self.terminal { 1.0 } else { 5.0 };
                loop {
                    let wait = Duration::from_secs_f64(next).saturating_sub(started.elapsed());
                    match stopped.recv_timeout(wait) {
                        Err(mpsc::RecvTimeoutError::Timeout) => {}
                        _ => break,
                    }
                    self.progress(&what(started.elapsed()));
                    next = if self.terminal {
                        next + 1.0
                    } else {
                        next * 2.0
                    };
                }
            });
            let out = work();
            let _ = stop.send(());
            out
        })
    }
}
