//! Running gmsh as a subprocess: locating it, checking its version, meshing
//! a `.geo` into a binary `.msh` 4.1 with the options of a [`MeshSpec`],
//! under a wall-clock limit, with gmsh's own messages kept for errors.

use crate::spec::{MeshSpec, Optimize};
use crate::MeshError;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Where the project's set-up script installs gmsh (relative to the repository root).
const SETUP_VENV: &str = ".tools/gmsh-venv";

/// A located gmsh executable.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Gmsh {
    /// The gmsh program (binary, or the PyPI wheel's Python launcher script).
    pub program: PathBuf,
    /// Interpreter that runs `program` when it is a Python script of a venv.
    pub interpreter: Option<PathBuf>,
}

impl Gmsh {
    /// Finds gmsh: env `GMSH` (an error if it names no file), then the set-up
    /// venv under the repository root (`RIBBAR_ROOT`, else the workspace this
    /// crate was built in), then `gmsh` on `PATH`.
    pub fn locate() -> Result<Gmsh, MeshError> {
        if let Some(p) = std::env::var_os("GMSH") {
            let p = PathBuf::from(p);
            if !p.is_file() {
                return Err(MeshError::GmshNotFound {
                    detail: format!("GMSH={} is not a file", p.display()),
                });
            }
            return Ok(Gmsh::at(p));
        }
        let root = std::env::var_os("RIBBAR_ROOT")
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join(".."));
        let venv = root.join(SETUP_VENV).join("bin").join("gmsh");
        if venv.is_file() {
            return Ok(Gmsh::at(venv));
        }
        if let Some(paths) = std::env::var_os("PATH") {
            for dir in std::env::split_paths(&paths) {
                let p = dir.join("gmsh");
                if p.is_file() {
                    return Ok(Gmsh::at(p));
                }
            }
        }
        Err(MeshError::GmshNotFound {
            detail: format!(
                "GMSH is unset, {} does not exist and no gmsh is on PATH (run scripts/setup.sh)",
                venv.display()
            ),
        })
    }

    /// Uses the gmsh at `program`; a Python launcher script with a `python`
    /// beside it is run by that interpreter (the wheel's script must run in
    /// its own environment).
    pub fn at(program: impl Into<PathBuf>) -> Gmsh {
        let program = program.into();
        let mut interpreter = None;
        let mut head = [0u8; 64];
        if let Ok(mut f) = std::fs::File::open(&program) {
            let n = f.read(&mut head).unwrap_or(0);
            let head = &head[..n];
            if head.starts_with(b"#!") && head.windows(6).any(|w| w == b"python") {
                if let Some(dir) = program.parent() {
                    let py = dir.join("python");
                    if py.is_file() {
                        interpreter = Some(py);
                    }
                }
            }
        }
        Gmsh {
            program,
            interpreter,
        }
    }

    fn command(&self) -> Command {
        match &self.interpreter {
            Some(py) => {
                let mut c = Command::new(py);
                c.arg(&self.program);
                c
            }
            None => Command::new(&self.program),
        }
    }

    /// gmsh's version string, e.g. `4.15.2`.
    pub fn version(&self) -> Result<String, MeshError> {
        let out = self
            .command()
            .arg("--version")
            .stdin(Stdio::null())
            .output()
            .map_err(|source| MeshError::GmshLaunch {
                program: self.program.clone(),
                source,
            })?;
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let v = text.trim().lines().last().unwrap_or("").trim().to_string();
        if !out.status.success() || v.is_empty() || !v.starts_with(|c: char| c.is_ascii_digit()) {
            return Err(MeshError::GmshNotFound {
                detail: format!(
                    "{} --version did not give a version ({}): {}",
                    self.program.display(),
                    out.status,
                    text.trim()
                ),
            });
        }
        Ok(v)
    }

    /// Runs gmsh with `args` in `workdir`, killing it after `timeout` seconds.
    /// Returns gmsh's combined output on success.
    pub fn run(
        &self,
        args: &[String],
        workdir: &Path,
        timeout: f64,
        geo: &Path,
    ) -> Result<String, MeshError> {
        let mut child = self
            .command()
            .args(args)
            .current_dir(workdir)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| MeshError::GmshLaunch {
                program: self.program.clone(),
                source,
            })?;
        // Drain both pipes on threads so gmsh never blocks on a full pipe.
        let mut out = child.stdout.take().expect("stdout is piped");
        let mut err = child.stderr.take().expect("stderr is piped");
        let t_out = std::thread::spawn(move || {
            let mut b = Vec::new();
            let _ = out.read_to_end(&mut b);
            b
        });
        let t_err = std::thread::spawn(move || {
            let mut b = Vec::new();
            let _ = err.read_to_end(&mut b);
            b
        });
        let start = Instant::now();
        let status = loop {
            match child.try_wait() {
                Ok(Some(s)) => break Some(s),
                Ok(None) if start.elapsed().as_secs_f64() > timeout => {
                    let _ = child.kill();
                    let _ = child.wait();
                    break None;
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(20)),
                Err(source) => {
                    return Err(MeshError::GmshLaunch {
                        program: self.program.clone(),
                        source,
                    })
                }
            }
        };
        let mut text = String::from_utf8_lossy(&t_out.join().unwrap_or_default()).into_owned();
        text.push_str(&String::from_utf8_lossy(&t_err.join().unwrap_or_default()));
        match status {
            None => Err(MeshError::GmshTimeout {
                geo: geo.to_path_buf(),
                seconds: timeout,
                output: tail(&text),
            }),
            // gmsh reports .geo errors but may still exit 0: its "Error" lines decide too.
            Some(s) if !s.success() || text.lines().any(|l| l.starts_with("Error")) => {
                Err(MeshError::GmshFailed {
                    geo: geo.to_path_buf(),
                    status: s.to_string(),
                    output: tail(&text),
                })
            }
            Some(_) => Ok(text),
        }
    }
}

/// The lines worth showing from gmsh's output: every Error/Warning line and
/// the last lines, at most ~60 lines.
fn tail(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .flat_map(|l| l.split('\r'))
        .filter(|l| !l.trim().is_empty() && !l.contains("Info    : [") )
        .collect();
    let mut keep: Vec<&str> = lines
        .iter()
        .filter(|l| l.starts_with("Error") || l.starts_with("Warning"))
        .take(40)
        .copied()
        .collect();
    let n = lines.len();
    for l in &lines[n.saturating_sub(20)..] {
        if !keep.contains(l) {
            keep.push(l);
        }
    }
    keep.join("\n")
}

/// Wall-clock time of one gmsh run, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmshTiming {
    pub seconds: f64,
}

/// The command-line arguments that mesh `geo` into `out_msh` with `spec`.
/// Options go through `-string` (read before the `.geo`, so the `.geo` must
/// not set them itself); sizes through `-setnumber` on the `.geo`'s
/// `DefineConstant`s `h_interface` and `h_outer` (m).
pub fn gmsh_args(geo: &Path, spec: &MeshSpec, out_msh: &Path) -> Vec<String> {
    let (opt, netgen) = match spec.optimize {
        Optimize::None => (0, 0),
        Optimize::Gmsh => (1, 0),
        Optimize::Netgen => (1, 1),
    };
    let options = format!(
        "Mesh.Algorithm3D={};Mesh.Optimize={};Mesh.OptimizeNetgen={};General.NumThreads={};Mesh.ElementOrder=1;",
        spec.algorithm_3d.gmsh_id(),
        opt,
        netgen,
        spec.threads
    );
    vec![
        geo.display().to_string(),
        "-3".into(),
        "-string".into(),
        options,
        "-setnumber".into(),
        "h_interface".into(),
        format!("{:e}", spec.h_interface),
        "-setnumber".into(),
        "h_outer".into(),
        format!("{:e}", spec.h_outer),
        "-format".into(),
        "msh41".into(),
        "-bin".into(),
        "-o".into(),
        out_msh.display().to_string(),
    ]
}

/// Meshes `geo` into the binary `.msh` 4.1 `out_msh` (written by gmsh as
/// given: callers pass a temporary name and rename on success).
pub fn run_gmsh(
    gmsh: &Gmsh,
    geo: &Path,
    spec: &MeshSpec,
    out_msh: &Path,
) -> Result<GmshTiming, MeshError> {
    if !geo.is_file() {
        return Err(MeshError::io(
            geo,
            std::io::Error::new(std::io::ErrorKind::NotFound, "geometry file not found"),
        ));
    }
    let geo_abs = std::path::absolute(geo).map_err(|e| MeshError::io(geo, e))?;
    let out_abs = std::path::absolute(out_msh).map_err(|e| MeshError::io(out_msh, e))?;
    let workdir = geo_abs.parent().unwrap_or(Path::new(".")).to_path_buf();
    let start = Instant::now();
    gmsh.run(&gmsh_args(&geo_abs, spec, &out_abs), &workdir, spec.timeout, geo)?;
    if !out_abs.is_file() {
        return Err(MeshError::GmshFailed {
            geo: geo.to_path_buf(),
            status: "exit status 0".into(),
            output: format!("gmsh wrote no mesh to {}", out_msh.display()),
        });
    }
    Ok(GmshTiming {
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl Gmsh {
    /// [`Gmsh::locate`], or a `gmsh` on PATH to be reported missing at first use.
    pub fn at_default_location() -> Gmsh {
        Gmsh::locate().unwrap_or_else(|_| Gmsh::at("gmsh"))
    }
}
