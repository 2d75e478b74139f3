//! Meshing with gmsh, reading `.msh` 4.1, duplicating interface nodes and
//! building the solver's [`Model`].
//!
//! The stage in one call, [`mesh_specimen`]: gmsh meshes `specimen.geo`
//! ([`run_gmsh`]), the `.msh` is read ([`read_msh`]), the model is built
//! ([`build_model`]) and `specimen.msh`, `model.bin`, `mesh.vtu` and
//! `mesh.json` are written atomically.
//!
//! ```no_run
//! use mesh::{mesh_specimen, Gmsh, MeshSpec, Model};
//! use std::path::Path;
//! let gmsh = Gmsh::locate()?;
//! let report = mesh_specimen(&gmsh, Path::new("work/specimen.geo"), &MeshSpec::default(),
//!                            0.008, 0.040, Path::new("work"))?;
//! println!("{} tets of concrete", report.tets_concrete);
//! let model = Model::load(Path::new("work/model.bin"))?;
//! # Ok::<(), mesh::MeshError>(())
//! ```

pub mod build;
pub mod error;
pub mod gmsh_run;
pub mod model;
pub mod read;
pub mod spec;
pub mod vtu;

pub use build::{build_model, MeshReport, Timings};
pub use error::MeshError;
pub use gmsh_run::{gmsh_args, run_gmsh, Gmsh, GmshTiming};
pub use model::*;
pub use read::{read_msh, RawMesh};
pub use spec::{MeshSpec, RawMeshSpec};

use std::path::{Path, PathBuf};
use std::time::Instant;

/// Names of the files [`mesh_specimen`] writes in its output directory.
pub const MSH_FILE: &str = "specimen.msh";
pub const MODEL_FILE: &str = "model.bin";
pub const VTU_FILE: &str = "mesh.vtu";
pub const REPORT_FILE: &str = "mesh.json";

/// Writes `bytes` to `path` through a temporary file in the same directory
/// and a rename, so `path` is either the old file or the complete new one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    geom::fsutil::write_atomic(path, bytes).map_err(|e| MeshError::io(path, e))
}

/// Removes the listed temporary files when dropped (on any early return).
struct TempFiles(Vec<PathBuf>);
impl Drop for TempFiles {
    fn drop(&mut self) {
        for p in &self.0 {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// The mesh stage: meshes `geo` with gmsh under `spec`, reads and builds the
/// model (bar diameter and adhesive length in m), and writes
/// `specimen.msh`, `model.bin`, `mesh.vtu` and `mesh.json` into `out_dir`.
/// Every file is first written under a temporary name; the renames happen
/// only once everything succeeded (`mesh.json` last), so a failure leaves
/// the previous artifacts untouched.
pub fn mesh_specimen(
    gmsh: &Gmsh,
    geo: &Path,
    spec: &MeshSpec,
    bar_diameter: f64,
    adhesive_length: f64,
    out_dir: &Path,
) -> Result<MeshReport, MeshError> {
    std::fs::create_dir_all(out_dir).map_err(|e| MeshError::io(out_dir, e))?;
    let gmsh_version = gmsh.version().to_string();
    let finals: Vec<PathBuf> = [MSH_FILE, MODEL_FILE, VTU_FILE, REPORT_FILE]
        .iter()
        .map(|f| out_dir.join(f))
        .collect();
    // gmsh picks the format from the extension: keep ".msh" last.
    let tmp_msh = out_dir.join(format!("specimen.tmp-{}.msh", std::process::id()));
    let temps = TempFiles(
        std::iter::once(tmp_msh.clone())
            .chain(finals[1..].iter().map(|p| geom::fsutil::temp_sibling(p)))
            .collect(),
    );

    let timing = run_gmsh(gmsh, geo, spec, &tmp_msh)?;
    let t = Instant::now();
    let mut raw = read_msh(&tmp_msh)?;
    raw.source = finals[0].clone();
    let t_read = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (model, mut report) = build_model(&raw, bar_diameter, adhesive_length)?;
    let t_build = t.elapsed().as_secs_f64();
    drop(raw);

    let t = Instant::now();
    let write = |path: &Path, bytes: &[u8]| -> Result<(), MeshError> {
        use std::io::Write;
        let mut f = std::fs::File::create(path).map_err(|e| MeshError::io(path, e))?;
        f.write_all(bytes)
            .and_then(|_| f.sync_all())
            .map_err(|e| MeshError::io(path, e))
    };
    model.save(&temps.0[1])?;
    write(&temps.0[2], &vtu::model_vtu(&model))?;
    report.gmsh_version = gmsh_version;
    report.timings_s = Timings {
        gmsh: timing.seconds,
        read: t_read,
        build: t_build,
        write: t.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_vec_pretty(&report).map_err(|e| MeshError::ModelFile {
        path: finals[3].clone(),
        detail: e.to_string(),
    })?;
    write(&temps.0[3], &json)?;
    for (tmp, fin) in temps.0.iter().zip(&finals) {
        std::fs::rename(tmp, fin).map_err(|e| MeshError::io(fin, e))?;
    }
    Ok(report)
}
