//! Meshing a `.geo` into a binary `.msh` 4.1 with the options of a
//! [`MeshSpec`], under a wall-clock limit, with gmsh's own messages kept for
//! errors. Locating gmsh and checking its version is `geom::gmsh::Gmsh`'s
//! job (re-exported here).
//!
//! gmsh runs through its Python API with the command line `gmsh GEO -3 ...`
//! would take: the script is built, the built model is measured
//! (`geom::occ`), then meshed and written: the mesh is the command line's
//! byte for byte, and a ribbed specimen's OpenCASCADE booleans, most of
//! gmsh's time, are not repeated to measure it.

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

/// One gmsh run: its wall-clock time and what it measured on the built model.
#[derive(Debug, Clone, PartialEq)]
pub struct GmshRun {
    /// Wall-clock time of the whole run, s.
    pub seconds: f64,
    /// `geom::occ`'s `measure()` of the built model, as JSON.
    pub occ_measures: String,
}

const MESH_PY: &str = r#"
import json, sys, time
out_json, msh = sys.argv[1], sys.argv[2]
argv = sys.argv[3:]
# The options and sizes of the command line, read before the script as
# `gmsh GEO ...` reads them; `run=False`: building, meshing and writing are
# done below, with the measurement between.
gmsh.initialize(["gmsh"] + argv, run=False, interruptible=False)
start = time.time()
gmsh.open(argv[0])
built = time.time()
res = measure()
res["build_seconds"] = built - start
with open(out_json, "w") as f:
    json.dump(res, f)
gmsh.model.mesh.generate(3)
gmsh.write(msh)
gmsh.finalize()
"#;

/// The command-line arguments that mesh `geo` into `out_msh` with `spec`
/// (`gmsh` with them makes the mesh [`run_gmsh`] makes).
pub fn gmsh_args(geo: &Path, spec: &MeshSpec, out_msh: &Path) -> Vec<String> {
    let mut args = gmsh_options(geo, spec);
    args.extend(["-3".into(), "-o".into(), out_msh.display().to_string()]);
    args
}

/// `geo` and the options that mesh it with `spec`. Options and sizes go
/// through `-setnumber` (read before the `.geo`, so the `.geo` must not set
/// the options itself; the sizes are its `DefineConstant`s `h_interface`,
/// `h_outer` and, when set, `h_bar_core` and `h_unbonded`, m). Not `-string`: gmsh parses
/// that through one temporary file per user (`~/.gmsh-tmp`, written, read,
/// removed), so two gmsh runs at once (a study's cases, parallel tests) can
/// take each other's file or find it gone and mesh with gmsh's default
/// options (Delaunay instead of HXT, no optimisation): seen as one of four
/// concurrent mesh tests meshing a different mesh from the same `.geo`.
fn gmsh_options(geo: &Path, spec: &MeshSpec) -> Vec<String> {
    let (opt, netgen) = match spec.optimize {
        Optimize::None => (0, 0),
        Optimize::Gmsh => (1, 0),
        Optimize::Netgen => (1, 1),
    };
    let mut args = vec![geo.display().to_string()];
    for (name, h) in [
        ("h_bar_core", spec.h_bar_core),
        ("h_unbonded", spec.h_unbonded),
    ] {
        if let Some(h) = h {
            args.extend(["-setnumber".to_string(), name.into(), format!("{h:e}")]);
        }
    }
    for (name, value) in [
        ("Mesh.Algorithm3D", spec.algorithm_3d.gmsh_id().to_string()),
        ("Mesh.Optimize", opt.to_string()),
        ("Mesh.OptimizeNetgen", netgen.to_string()),
        ("General.NumThreads", spec.threads.to_string()),
        // OpenCASCADE's booleans on their own threads: a ribbed bar's
        // fuse of core and ribs is most of the mesh stage, and the result
        // (hence the mesh) is the same as the serial one
        // (docs/src/validation/performance.md, "r1-coarse end to end").
        ("Geometry.OCCParallel", "1".to_string()),
        ("Mesh.ElementOrder", "1".to_string()),
        ("h_interface", format!("{:e}", spec.h_interface)),
        ("h_outer", format!("{:e}", spec.h_outer)),
    ] {
        args.extend(["-setnumber".to_string(), name.to_string(), value]);
    }
    args.extend(["-format".into(), "msh41".into(), "-bin".into()]);
    args
}

/// Meshes `geo` into the binary `.msh` 4.1 `out_msh` (written by gmsh as
/// given: callers pass a temporary name and rename on success), measuring
/// the built model on the way.
pub fn run_gmsh(
    gmsh: &Gmsh,
    geo: &Path,
    spec: &MeshSpec,
    out_msh: &Path,
) -> Result<GmshRun, MeshError> {
    if !geo.is_file() {
        return Err(MeshError::io(
            geo,
            std::io::Error::new(std::io::ErrorKind::NotFound, "geometry file not found"),
        ));
    }
    let geo_abs = std::path::absolute(geo).map_err(|e| MeshError::io(geo, e))?;
    let out_abs = std::path::absolute(out_msh).map_err(|e| MeshError::io(out_msh, e))?;
    let workdir = geo_abs.parent().unwrap_or(Path::new(".")).to_path_buf();
    let measures = geom::fsutil::scratch_name(
        out_abs.parent().unwrap_or(Path::new(".")),
        "occ-measure",
        "json",
    );
    let start = Instant::now();
    let mut args: Vec<String> = vec![
        measures.display().to_string(),
        out_abs.display().to_string(),
    ];
    args.extend(gmsh_options(&geo_abs, spec));
    let script = format!("import gmsh\n{}{MESH_PY}", geom::occ::measure_py());
    let result = gmsh.run_python(
        &script,
        &args,
        &workdir,
        Duration::from_secs_f64(spec.timeout),
    );
    let occ_measures = std::fs::read_to_string(&measures).unwrap_or_default();
    let _ = std::fs::remove_file(&measures);
    let output = result.map_err(|e| match e {
        geom::gmsh::GmshError::Timeout { secs, .. } => MeshError::GmshTimeout {
            geo: geo.to_path_buf(),
            seconds: secs,
        },
        geom::gmsh::GmshError::Failed { code, stderr, .. } => MeshError::GmshFailed {
            geo: geo.to_path_buf(),
            status: format!("exit code {code:?}"),
            output: tail(&stderr),
        },
        other => MeshError::Gmsh(other),
    })?;
    // gmsh reports errors in a .geo but goes on (and writes an empty
    // mesh): its "Error" lines decide.
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
    Ok(GmshRun {
        seconds: start.elapsed().as_secs_f64(),
        occ_measures,
    })
}
