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
pub mod crack;
pub mod error;
pub mod estimate;
pub mod gmsh_run;
pub mod half_turn;
pub mod model;
pub mod read;
pub mod spec;
pub mod unfold;
pub mod vtu;

pub use build::{build_model, MeshReport, Timings};
pub use error::MeshError;
pub use gmsh_run::{gmsh_args, run_gmsh, Gmsh, GmshRun};
pub use half_turn::HalfTurnTwins;
pub use model::*;
pub use read::{read_msh, RawMesh};
pub use spec::{MeshSpec, RawMeshSpec};
pub use unfold::Unfolded;

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

/// Turns a gmsh failure on a specimen built by `geom` into one that names
/// what gmsh could not mesh in the specimen's terms ([`MeshError::GmshFailedOn`]):
/// the entities on gmsh's error lines are rebuilt from `geo` and measured,
/// then located on the bar of `layout` (meshed at `h_interface`, m). Other
/// errors, and failures that name no entity (or whose entities cannot be
/// measured), are returned unchanged.
pub fn explain_gmsh_failure(
    gmsh: &Gmsh,
    err: MeshError,
    layout: &geom::layout::Layout,
    h_interface: f64,
) -> MeshError {
    let MeshError::GmshFailed {
        geo,
        status,
        output,
    } = err
    else {
        return err;
    };
    let entities = geom::diagnose::entities_in_gmsh_output(&output);
    let facts = match entities.is_empty() {
        true => vec![],
        false => geom::diagnose::query_entities(gmsh, &geo, &entities).unwrap_or_default(),
    };
    if facts.is_empty() {
        return MeshError::GmshFailed {
            geo,
            status,
            output,
        };
    }
    MeshError::GmshFailedOn {
        geo,
        diagnoses: geom::diagnose::diagnose(layout, &facts, h_interface),
        output,
    }
}

/// [`mesh_specimen`] for the specimen `geom` built from `bar` and
/// `specimen`: the model gmsh builds is checked against the geometry
/// (`geom::occ`: volumes and areas within 1 % of the analytic ones, no
/// empty group, no leftover entity; `mesh.json`'s `occ`), and a gmsh
/// failure is explained in the specimen's terms ([`explain_gmsh_failure`]).
pub fn mesh_built_specimen(
    gmsh: &Gmsh,
    geo: &Path,
    spec: &MeshSpec,
    bar: &geom::spec::Bar,
    specimen: &geom::spec::Specimen,
    out_dir: &Path,
) -> Result<MeshReport, MeshError> {
    let check = |measures: &str| {
        geom::occ::OccReport::check(measures, bar, specimen, geo)
            .map(Some)
            .map_err(MeshError::from)
    };
    mesh_checked(
        gmsh,
        geo,
        spec,
        (bar.diameter, specimen.adhesive_length),
        out_dir,
        &check,
    )
    .map_err(|e| {
        let layout = geom::layout::Layout::new(bar, specimen);
        explain_gmsh_failure(gmsh, e, &layout, spec.h_interface)
    })
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
    mesh_checked(
        gmsh,
        geo,
        spec,
        (bar_diameter, adhesive_length),
        out_dir,
        &|_| Ok(None),
    )
}

/// What turns gmsh's measurement of the built model into `mesh.json`'s
/// `occ`, or refuses the model.
type OccCheck<'a> = &'a dyn Fn(&str) -> Result<Option<geom::occ::OccReport>, MeshError>;

/// [`mesh_specimen`] with the built model checked by `check` before
/// anything is written.
fn mesh_checked(
    gmsh: &Gmsh,
    geo: &Path,
    spec: &MeshSpec,
    (bar_diameter, adhesive_length): (f64, f64),
    out_dir: &Path,
    check: OccCheck,
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

    let (run, used, fallback) = match run_gmsh(gmsh, geo, spec, &tmp_msh) {
        // gmsh 4.15.2's HXT aborts ("double free or corruption") in the
        // boundary recovery of some rib designs after inserting Steiner
        // points (35° ribs; docs/src/explanation/mesh.md), where Delaunay meshes them.
        Err(MeshError::GmshFailed { status, output, .. })
            if spec.algorithm_3d == spec::Algorithm3d::Hxt =>
        {
            let delaunay = MeshSpec {
                algorithm_3d: spec::Algorithm3d::Delaunay,
                ..spec.clone()
            };
            let run = run_gmsh(gmsh, geo, &delaunay, &tmp_msh)?;
            let said = output
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty() && !l.starts_with("Info"))
                .unwrap_or("")
                .trim()
                .to_string();
            let why = format!("hxt failed ({status}: {said}); meshed with delaunay");
            (run, spec::Algorithm3d::Delaunay, Some(why))
        }
        other => (other?, spec.algorithm_3d, None),
    };
    let occ = check(&run.occ_measures)?;
    let t = Instant::now();
    let mut raw = read_msh(&tmp_msh)?;
    raw.source = finals[0].clone();
    let t_read = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (mut model, mut report) = build_model(&raw, bar_diameter, adhesive_length)?;
    if spec.unfold && model.symmetry != Symmetry::Full {
        model = model.unfold().model;
        report = report.of_unfolded(&model);
    }
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
    report.algorithm_3d = Some(used);
    report.algorithm_fallback = fallback;
    report.occ = occ;
    report.timings_s = Timings {
        gmsh: run.seconds,
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
