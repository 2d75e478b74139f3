//! Finding and running gmsh as a subprocess.
//!
//! Search order: the `GMSH` environment variable (an error if it does not
//! work: an explicit choice is never silently replaced), the project-local
//! install of `scripts/setup.sh` (`.tools/gmsh-venv/bin/gmsh`, looked up next
//! to this crate's workspace and next to every ancestor of the running
//! executable), then `gmsh` on `PATH`. The PyPI wheel's `bin/gmsh` is a Python
//! script: it is run with the `python` beside it, which also has gmsh's
//! Python API (used for measurements on the OpenCASCADE model).

use crate::capture::Capture;
use std::ffi::{OsStr, OsString};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Relative location of the project-local gmsh install.
pub const LOCAL_GMSH: &str = ".tools/gmsh-venv/bin/gmsh";
/// Oldest gmsh whose OpenCASCADE `.geo` features we rely on.
pub const MIN_VERSION: (u32, u32) = (4, 8);

const SETUP_HINT: &str = "run `scripts/setup.sh` (installs a pinned gmsh in .tools/gmsh-venv), \
                          or set GMSH to a working gmsh executable";

/// The system libraries gmsh's PyPI wheel links against without bundling
/// them (Debian package names, as `scripts/setup.sh` installs them).
const WHEEL_SYSTEM_LIBRARIES: &str = "libglu1-mesa libgl1 libxrender1 libxcursor1 libxfixes3 \
                                      libxext6 libxft2 libfontconfig1 libxinerama1 libx11-6 libgomp1";

/// A gmsh that cannot load a shared library (the PyPI wheel on a machine
/// without X11/GL libraries) says which packages provide them.
fn with_library_hint(problem: String) -> String {
    if problem.contains("cannot open shared object file") {
        format!(
            "{problem}\ngmsh cannot load a system library: install {WHEEL_SYSTEM_LIBRARIES} \
             (Debian/Ubuntu: apt-get install; `scripts/setup.sh --no-build` does it)"
        )
    } else {
        problem
    }
}

/// A located, working gmsh.
#[derive(Debug, Clone)]
pub struct Gmsh {
    program: PathBuf,
    /// Interpreter that runs `program` when it is a Python script.
    interpreter: Option<PathBuf>,
    /// Python with gmsh's API, when known.
    python: Option<PathBuf>,
    version: String,
}

/// What a finished gmsh run printed.
#[derive(Debug, Clone)]
pub struct GmshOutput {
    pub stdout: String,
    pub stderr: String,
    /// Wall time of the run.
    pub elapsed: Duration,
}

/// Why gmsh could not be found or run.
#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    #[error("gmsh not found (looked at $GMSH, {local}, and `gmsh` on PATH): {hint}", local = LOCAL_GMSH, hint = SETUP_HINT)]
    NotFound,
    #[error("GMSH={path}: {problem}; fix or unset GMSH, or {hint}", path = .path.display(), hint = SETUP_HINT)]
    BadEnv { path: PathBuf, problem: String },
    #[error("{path}: `--version` failed: {problem}; {hint}", path = .path.display(), hint = SETUP_HINT)]
    Version { path: PathBuf, problem: String },
    #[error("{path}: version {found} is older than {}.{}; {hint}", MIN_VERSION.0, MIN_VERSION.1, path = .path.display(), hint = SETUP_HINT)]
    TooOld { path: PathBuf, found: String },
    #[error("cannot start {program}: {source}")]
    Spawn {
        program: String,
        #[source]
        source: std::io::Error,
    },
    #[error("gmsh {args} timed out after {secs:.0} s (killed)")]
    Timeout { args: String, secs: f64 },
    #[error("gmsh {args} failed (exit {code:?}):\n{stderr}")]
    Failed {
        args: String,
        code: Option<i32>,
        stderr: String,
    },
    #[error("gmsh's Python API is not available next to {program}; {hint}", program = .program.display(), hint = SETUP_HINT)]
    NoPythonApi { program: PathBuf },
    #[error("{path}: {source}", path = .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

fn is_python_script(path: &Path) -> bool {
    let mut buf = [0u8; 128];
    let Ok(mut f) = std::fs::File::open(path) else {
        return false;
    };
    let n = f.read(&mut buf).unwrap_or(0);
    let head = String::from_utf8_lossy(&buf[..n]);
    head.starts_with("#!") && head.lines().next().is_some_and(|l| l.contains("python"))
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

fn local_candidates() -> Vec<PathBuf> {
    let mut out = vec![];
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Some(root) = manifest.parent() {
        out.push(root.join(LOCAL_GMSH));
    }
    if let Ok(exe) = std::env::current_exe() {
        for dir in exe.ancestors().skip(1) {
            out.push(dir.join(LOCAL_GMSH));
        }
    }
    out
}

fn parse_version(text: &str) -> Option<(String, (u32, u32))> {
    text.split_whitespace().rev().find_map(|w| {
        let mut it = w.split('.');
        let major = it.next()?.parse().ok()?;
        let minor = it.next()?.parse().ok()?;
        Some((w.to_string(), (major, minor)))
    })
}

impl Gmsh {
    /// Finds a working gmsh (module doc for the order) and checks its version.
    pub fn locate() -> Result<Gmsh, GmshError> {
        if let Some(env) = std::env::var_os("GMSH").filter(|v| !v.is_empty()) {
            let path = PathBuf::from(&env);
            let path = if path.components().count() == 1 && !path.exists() {
                find_on_path(&env.to_string_lossy()).ok_or_else(|| GmshError::BadEnv {
                    path: path.clone(),
                    problem: "not found on PATH".into(),
                })?
            } else {
                path
            };
            if !path.is_file() {
                return Err(GmshError::BadEnv {
                    path,
                    problem: "no such file".into(),
                });
            }
            return Gmsh::probe(path).map_err(|e| match e {
                GmshError::Version { path, problem } => GmshError::BadEnv { path, problem },
                other => other,
            });
        }
        let mut last_err = None;
        for cand in local_candidates().into_iter().chain(find_on_path("gmsh")) {
            if cand.is_file() {
                match Gmsh::probe(cand) {
                    Ok(g) => return Ok(g),
                    Err(e) => last_err = Some(e),
                }
            }
        }
        Err(last_err.unwrap_or(GmshError::NotFound))
    }

    /// Uses `program` (checked with `--version`).
    pub fn probe(program: PathBuf) -> Result<Gmsh, GmshError> {
        let (interpreter, python) = if is_python_script(&program) {
            let sibling = program.with_file_name("python");
            let interp = if sibling.is_file() {
                sibling
            } else {
                find_on_path("python3").unwrap_or_else(|| PathBuf::from("python3"))
            };
            (Some(interp.clone()), Some(interp))
        } else {
            // A native gmsh: its Python API may be installed for python3.
            let py = find_on_path("python3");
            (None, py)
        };
        let mut g = Gmsh {
            program,
            interpreter,
            python,
            version: String::new(),
        };
        let out = g
            .run(&[OsStr::new("--version")], None, Duration::from_secs(60))
            .map_err(|e| GmshError::Version {
                path: g.program.clone(),
                problem: with_library_hint(e.to_string()),
            })?;
        let text = format!("{}\n{}", out.stdout, out.stderr);
        let (version, (major, minor)) = parse_version(&text).ok_or_else(|| GmshError::Version {
            path: g.program.clone(),
            problem: format!("no version number in its output {:?}", text.trim()),
        })?;
        if (major, minor) < MIN_VERSION {
            return Err(GmshError::TooOld {
                path: g.program.clone(),
                found: version,
            });
        }
        g.version = version;
        Ok(g)
    }

    /// The version `--version` printed, e.g. "4.15.2".
    pub fn version(&self) -> &str {
        &self.version
    }

    /// The gmsh executable or script.
    pub fn program(&self) -> &Path {
        &self.program
    }

    /// Runs gmsh with `args` in `workdir`, killing it after `timeout`.
    /// A non-zero exit is an error carrying gmsh's stderr (or stdout).
    pub fn run<S: AsRef<OsStr>>(
        &self,
        args: &[S],
        workdir: Option<&Path>,
        timeout: Duration,
    ) -> Result<GmshOutput, GmshError> {
        let mut cmd = match &self.interpreter {
            Some(py) => {
                let mut c = Command::new(py);
                c.arg(&self.program);
                c
            }
            None => Command::new(&self.program),
        };
        cmd.args(args.iter().map(|a| a.as_ref()));
        let shown = args
            .iter()
            .map(|a| a.as_ref().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(" ");
        run_with_timeout(cmd, workdir, timeout, &shown)
    }

    /// Python with gmsh's API, if this gmsh has one.
    pub fn python(&self) -> Option<&Path> {
        self.python.as_deref()
    }

    /// Runs a Python script using gmsh's API (`import gmsh`) in `workdir` with
    /// extra command-line `args`; errors when no API is available.
    pub fn run_python<S: AsRef<OsStr>>(
        &self,
        script: &str,
        args: &[S],
        workdir: &Path,
        timeout: Duration,
    ) -> Result<GmshOutput, GmshError> {
        let py = self.python.as_ref().ok_or_else(|| GmshError::NoPythonApi {
            program: self.program.clone(),
        })?;
        // The child runs in `workdir`: a relative `workdir` would be applied
        // twice to a relative script path.
        let workdir = &std::path::absolute(workdir).map_err(|source| GmshError::Io {
            path: workdir.to_path_buf(),
            source,
        })?;
        let file = crate::fsutil::scratch_name(workdir, "gmsh-api", "py");
        std::fs::write(&file, script).map_err(|source| GmshError::Io {
            path: file.clone(),
            source,
        })?;
        let mut cmd = Command::new(py);
        cmd.arg(&file).args(args.iter().map(|a| a.as_ref()));
        let res = run_with_timeout(cmd, Some(workdir), timeout, "(python API)");
        let _ = std::fs::remove_file(&file);
        match res {
            Err(GmshError::Failed { stderr, .. }) if stderr.contains("No module named 'gmsh'") => {
                Err(GmshError::NoPythonApi {
                    program: self.program.clone(),
                })
            }
            other => other,
        }
    }
}

/// A running child in its own process group, killed with its whole group
/// (a wrapper script's children too) when dropped before it was reaped.
struct Group {
    child: std::process::Child,
    reaped: bool,
}

impl Group {
    fn spawn(cmd: &mut Command) -> std::io::Result<Group> {
        #[cfg(unix)]
        {
            use std::os::unix::process::CommandExt;
            // Its own group, so that a kill reaches every process it starts.
            cmd.process_group(0);
            #[cfg(target_os = "linux")]
            // SAFETY: prctl is async-signal-safe and touches nothing of the
            // parent's; it makes the kernel kill the child if ribbar dies
            // (even by SIGKILL) before it, so that gmsh never outlives it.
            unsafe {
                cmd.pre_exec(|| {
                    libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                    Ok(())
                });
            }
        }
        Ok(Group {
            child: cmd.spawn()?,
            reaped: false,
        })
    }

    /// Whether the child has ended, without reaping it: its pid (the
    /// group's id) stays taken until [`Group::reap`], so a kill of the
    /// group never reaches another process.
    fn has_ended(&mut self) -> std::io::Result<bool> {
        #[cfg(unix)]
        {
            // SAFETY: a zeroed siginfo_t is a valid out-parameter; waitid
            // with WNOWAIT only reads the child's state.
            let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
            let r = unsafe {
                libc::waitid(
                    libc::P_PID,
                    self.child.id() as libc::id_t,
                    &mut info,
                    libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
                )
            };
            if r != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // SAFETY: filled in by waitid for a child that changed state.
            Ok(unsafe { info.si_pid() } != 0)
        }
        #[cfg(not(unix))]
        {
            Ok(self.child.try_wait()?.is_some())
        }
    }

    /// Kills what is left of the group of an ended child (a wrapper's
    /// children, which would also hold the pipes open) and reaps it.
    fn reap(&mut self) -> std::io::Result<std::process::ExitStatus> {
        self.signal_group();
        self.reaped = true;
        self.child.wait()
    }

    fn signal_group(&self) {
        #[cfg(unix)]
        if let Ok(pid) = i32::try_from(self.child.id()) {
            // SAFETY: signals the group this process created, whose leader
            // is not yet reaped; the group's id is the child's pid.
            unsafe {
                libc::kill(-pid, libc::SIGKILL);
            }
        }
    }

    fn kill(&mut self) {
        self.signal_group();
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.reaped = true;
    }
}

impl Drop for Group {
    fn drop(&mut self) {
        if !self.reaped {
            self.kill();
        }
    }
}

fn run_with_timeout(
    mut cmd: Command,
    workdir: Option<&Path>,
    timeout: Duration,
    shown: &str,
) -> Result<GmshOutput, GmshError> {
    if let Some(dir) = workdir {
        cmd.current_dir(dir);
    }
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let program: OsString = cmd.get_program().to_owned();
    let start = Instant::now();
    let mut group = Group::spawn(&mut cmd).map_err(|source| GmshError::Spawn {
        program: program.to_string_lossy().into_owned(),
        source,
    })?;
    // Drain both pipes on threads so a chatty gmsh never blocks on a full
    // pipe; each keeps a bounded part of what it reads.
    let out_pipe = group.child.stdout.take().expect("piped");
    let err_pipe = group.child.stderr.take().expect("piped");
    let out_t = std::thread::spawn(move || Capture::read_all(out_pipe));
    let err_t = std::thread::spawn(move || Capture::read_all(err_pipe));
    let ended = loop {
        match group.has_ended() {
            Ok(true) => break group.reap(),
            Ok(false) if start.elapsed() > timeout => {
                group.kill();
                return Err(GmshError::Timeout {
                    args: shown.to_string(),
                    secs: timeout.as_secs_f64(),
                });
            }
            Ok(false) => std::thread::sleep(Duration::from_millis(20)),
            Err(source) => break Err(source),
        }
    };
    let status = ended.map_err(|source| GmshError::Spawn {
        program: program.to_string_lossy().into_owned(),
        source,
    })?;
    let stdout = out_t.join().map(|c| c.text()).unwrap_or_default();
    let stderr = err_t.join().map(|c| c.text()).unwrap_or_default();
    let elapsed = start.elapsed();
    if !status.success() {
        let msg = if stderr.trim().is_empty() {
            &stdout
        } else {
            &stderr
        };
        return Err(GmshError::Failed {
            args: shown.to_string(),
            code: status.code(),
            stderr: tail(msg, 40),
        });
    }
    Ok(GmshOutput {
        stdout,
        stderr,
        elapsed,
    })
}

/// The last `n` lines of `text`.
pub fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether a process runs `sleep <seconds>` (its command line in /proc).
    fn sleeping(seconds: &str) -> bool {
        let wanted = format!("sleep\0{seconds}\0");
        std::fs::read_dir("/proc").unwrap().any(|e| {
            let path = e.unwrap().path().join("cmdline");
            std::fs::read(path).is_ok_and(|c| c == wanted.as_bytes())
        })
    }

    /// A child that outlives its limit is killed with every process it
    /// started (a wrapper's children included), and so is what a child
    /// that ended left running (it would hold the pipes open).
    #[cfg(target_os = "linux")]
    #[test]
    fn a_timed_out_child_is_killed_with_its_whole_group() {
        let tag = format!("{}.{}", 7000 + std::process::id() % 1000, 1);
        let mut cmd = Command::new("sh");
        cmd.args(["-c", &format!("sleep {tag} & sleep {tag}; echo never")]);
        let err = run_with_timeout(cmd, None, Duration::from_millis(300), "hang").unwrap_err();
        assert!(matches!(err, GmshError::Timeout { .. }), "{err}");
        std::thread::sleep(Duration::from_millis(100));
        assert!(!sleeping(&tag), "sleep {tag} outlived the kill");
        let tag = format!("{}.{}", 7000 + std::process::id() % 1000, 2);
        let mut cmd = Command::new("sh");
        cmd.args(["-c", &format!("sleep {tag} & echo done")]);
        let out = run_with_timeout(cmd, None, Duration::from_secs(30), "bg").unwrap();
        assert_eq!(out.stdout.trim(), "done");
        std::thread::sleep(Duration::from_millis(100));
        assert!(!sleeping(&tag), "sleep {tag} outlived its parent");
    }

    /// Version strings from both the wheel and Debian's gmsh parse (SPEC §4: version checked).
    #[test]
    fn versions_parse() {
        assert_eq!(parse_version("4.15.2\n").unwrap().1, (4, 15));
        assert_eq!(parse_version("Info: blah\n4.8.4").unwrap().1, (4, 8));
        assert!(parse_version("no version here").is_none());
    }
}
