//! Meshing a `.geo` into a binary `.msh` 4.1 with the options of a
//! [`MeshSpec`], under a wall-clock limit, with gmsh's own messages kept for
//! errors. Locating gmsh and checking its version is `geom::gmsh::Gmsh`'s
//! job (re-exported here).

use crate::spec::{MeshSpec, Optimize};
use crate::MeshError;
use std::path::Path;
use std::time::{Duration, Instant};

pub use geom::gmsh::Gmsh;

/// The lines worth showing from gmsh's output: every Error/Warning line
/// (at most 40) and the last 20 lines, without progress lines.
fn tail(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .flat_map(|l| l.split('\r'))
        .filter(|l| !l.trim().is_empty() && !l.contains("Info    : ["))
        .collect();
    let mut keep: Vec<&str> = lines
        .iter()
        .filter(|l| l.starts_with("Error") || l.starts_with("Warning"))
        .take(40)
        .copied()
        .collect();
    for l in &lines[lines.len().saturating_sub(20)..] {
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
/// Options and sizes go through `-setnumber` (read before the `.geo`, so
/// the `.geo` must not set the options itself; the sizes are its
/// `DefineConstant`s `h_interface`, `h_outer` and, when set, `h_bar_core`,
/// m). Not `-string`: gmsh parses that through one temporary file per user
/// (`~/.gmsh-tmp`, written, read, removed), so two gmsh runs at once (a
/// study's cases, parallel tests) can take each other's file or find it
/// gone and mesh with gmsh's default options (Delaunay instead of HXT, no
/// optimisation): seen as one of four concurrent mesh tests meshing a
/// different mesh from the same `.geo`.
pub fn gmsh_args(geo: &Path, spec: &MeshSpec, out_msh: &Path) -> Vec<String> {
    let (opt, netgen) = match spec.optimize {
        Optimize::None => (0, 0),
        Optimize::Gmsh => (1, 0),
        Optimize::Netgen => (1, 1),
    };
    let mut args = vec![geo.display().to_string()];
    if let Some(h) = spec.h_bar_core {
        args.extend([
            "-setnumber".to_string(),
            "h_bar_core".into(),
            format!("{h:e}"),
        ]);
    }
    args.push("-3".into());
    for (name, value) in [
        ("Mesh.Algorithm3D", spec.algorithm_3d.gmsh_id().to_string()),
        ("Mesh.Optimize", opt.to_string()),
        ("Mesh.OptimizeNetgen", netgen.to_string()),
        ("General.NumThreads", spec.threads.to_string()),
        ("Mesh.ElementOrder", "1".to_string()),
        ("h_interface", format!("{:e}", spec.h_interface)),
        ("h_outer", format!("{:e}", spec.h_outer)),
    ] {
        args.extend(["-setnumber".to_string(), name.to_string(), value]);
    }
    args.extend([
        "-format".into(),
        "msh41".into(),
        "-bin".into(),
        "-o".into(),
        out_msh.display().to_string(),
    ]);
    args
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
    let args = gmsh_args(&geo_abs, spec, &out_abs);
    let output = gmsh
        .run(&args, Some(&workdir), Duration::from_secs_f64(spec.timeout))
        .map_err(|e| match e {
            geom::gmsh::GmshError::Timeout { secs, .. } => MeshError::GmshTimeout {
                geo: geo.to_path_buf(),
                seconds: secs,
            },
            geom::gmsh::GmshError::Failed { code, stderr, .. } => MeshError::GmshFailed {
                geo: geo.to_path_buf(),
                status: format!("exit code {code:?}"),
                output: stderr,
            },
            other => MeshError::Gmsh(other),
        })?;
    // gmsh reports errors in a .geo on stderr but still exits 0 (and writes
    // an empty mesh): its "Error" lines decide.
    let text = format!("{}\n{}", output.stdout, output.stderr);
    if text.lines().any(|l| l.starts_with("Error")) {
        return Err(MeshError::GmshFailed {
            geo: geo.to_path_buf(),
            status: "exit code 0".into(),
            output: tail(&text),
        });
    }
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
