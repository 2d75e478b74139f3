//! The four stages and their keys. Each stage reads exactly the inputs that
//! go into its key, writes into the store's in-progress directory, commits
//! by one rename and publishes its files under `WORK/<scene>/`.

use crate::progress::Printer;
use crate::scene::Scene;
use crate::store::{changed_keys, StageKey, Store};
use anyhow::{Context, Result};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Versions of what each stage produces; bumped when a stage's output for
/// the same inputs changes, so old artifacts are not reused.
const GEOMETRY_FORMAT: u32 = 1;
const MESH_FORMAT: u32 = 2;
const SOLVE_FORMAT: u32 = 9;
const POST_FORMAT: u32 = 2;

pub const STAGES: [&str; 4] = ["geometry", "mesh", "solve", "post"];

/// Files each stage publishes under `WORK/<scene>/`.
pub fn published_files(stage: &str) -> &'static [&'static str] {
    match stage {
        "geometry" => &["specimen.geo", "geometry.json"],
        "mesh" => &["specimen.msh", "model.bin", "mesh.vtu", "mesh.json"],
        "solve" => &["curve.csv", "solve.json", "fields"],
        "post" => &["summary.json", "plots", "interface_profile.csv"],
        _ => &[],
    }
}

fn to_json<T: serde::Serialize>(v: &T) -> serde_json::Value {
    serde_json::to_value(v).expect("resolved spec sections serialise")
}

/// The keys of all four stages of a scene (each depends on its upstream key).
pub struct Keys {
    pub geometry: StageKey,
    pub mesh: StageKey,
    pub solve: StageKey,
    pub post: StageKey,
}

impl Keys {
    pub fn of(scene: &Scene, gmsh_version: &str) -> Keys {
        let geometry = StageKey::new(
            "geometry",
            json!({
                "format": GEOMETRY_FORMAT,
                "gmsh": gmsh_version,
                "bar": to_json(&scene.bar),
                "specimen": geometry_specimen(scene),
            }),
        );
        let mesh = StageKey::new(
            "mesh",
            json!({
                "format": MESH_FORMAT,
                "gmsh": gmsh_version,
                "geometry": geometry.key,
                "mesh": to_json(&scene.mesh),
            }),
        );
        let solve = StageKey::new(
            "solve",
            json!({
                "format": SOLVE_FORMAT,
                "mesh": mesh.key,
                "specimen": {"non_adhesive": to_json(&scene.specimen.non_adhesive)},
                "materials": to_json(&scene.materials),
                "loading": to_json(&scene.loading),
                "solver": to_json(&scene.solver),
                "outputs": {"fields": to_json(&scene.outputs.fields)},
            }),
        );
        let post = StageKey::new(
            "post",
            json!({
                "format": POST_FORMAT,
                "solve": solve.key,
                "outputs": to_json(&scene.outputs.post),
            }),
        );
        let w = |pointer: &str| {
            scene
                .written
                .pointer(pointer)
                .cloned()
                .unwrap_or(serde_json::Value::Null)
        };
        Keys {
            geometry: geometry.with_written(json!({"bar": w("/bar"), "specimen": w("/specimen")})),
            mesh: mesh.with_written(json!({"mesh": w("/mesh")})),
            solve: solve.with_written(json!({
                "specimen": {"non_adhesive": w("/specimen/non_adhesive")},
                "materials": w("/materials"),
                "loading": w("/loading"),
                "solver": w("/solver"),
                "outputs": {"fields": w("/outputs/fields")},
            })),
            post: post.with_written(json!({"outputs": w("/outputs")})),
        }
    }

    pub fn get(&self, stage: &str) -> &StageKey {
        match stage {
            "geometry" => &self.geometry,
            "mesh" => &self.mesh,
            "solve" => &self.solve,
            _ => &self.post,
        }
    }
}

/// The specimen as the geometry reads it: the non-adhesive option only
/// changes which interface law the solver puts there.
fn geometry_specimen(scene: &Scene) -> serde_json::Value {
    let mut v = to_json(&scene.specimen);
    if let Some(map) = v.as_object_mut() {
        map.remove("non_adhesive");
    }
    v
}

/// What `status` says of one stage.
#[derive(Debug, Clone, PartialEq)]
pub enum StageStatus {
    UpToDate,
    /// Never run for this scene.
    Missing,
    /// Run before with other inputs: the dotted keys that changed.
    Stale(Vec<String>),
    /// An interrupted run that can be resumed.
    Interrupted,
}

pub fn status(
    store: &Store,
    scene: &Scene,
    keys: &Keys,
) -> Result<Vec<(&'static str, StageStatus)>> {
    let record = store.read_record(&scene.name)?;
    Ok(STAGES
        .iter()
        .map(|&stage| {
            let key = keys.get(stage);
            let st = if store.is_done(key) {
                StageStatus::UpToDate
            } else if store.partial_dir(key).join(CHECKPOINT_FILE).is_file() {
                StageStatus::Interrupted
            } else if let Some(old) = record.get(stage) {
                StageStatus::Stale(stale_reasons(old, key))
            } else {
                StageStatus::Missing
            };
            (stage, st)
        })
        .collect())
}

/// What made a stage stale, in the user's words where possible: the spec
/// keys as written, then upstream stages, then (when the written spec did
/// not change, e.g. a program version) the resolved inputs.
fn stale_reasons(old: &StageKey, new: &StageKey) -> Vec<String> {
    let mut reasons = if old.written.is_null() {
        Vec::new()
    } else {
        changed_keys(&old.written, &new.written)
    };
    let resolved = changed_keys(&old.inputs, &new.inputs);
    reasons.extend(
        resolved
            .iter()
            .filter(|k| STAGES.contains(&k.as_str()))
            .cloned(),
    );
    if reasons.is_empty() {
        reasons = resolved;
    }
    reasons
}

pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// Shared by the stage runners.
pub struct Ctx<'a> {
    pub store: &'a Store,
    pub scene: &'a Scene,
    pub keys: &'a Keys,
    pub gmsh: &'a geom::gmsh::Gmsh,
    pub printer: &'a Printer,
}

impl Ctx<'_> {
    fn done_dir(&self, stage: &str) -> PathBuf {
        self.store.artifact_dir(self.keys.get(stage))
    }

    /// Runs `stage` unless its key is done; publishes either way.
    /// Returns whether it ran.
    pub fn ensure(&self, stage: &str) -> Result<bool> {
        let key = self.keys.get(stage);
        let ran = if self.store.is_done(key) {
            false
        } else {
            let _lock = self.store.lock(key)?;
            if self.store.is_done(key) {
                false
            } else {
                let started = Instant::now();
                let resumable = stage == "solve";
                let partial = self.store.begin(key, resumable)?;
                self.run_stage(stage, &partial)
                    .with_context(|| format!("stage {stage} of scene {}", self.scene.name))?;
                let seconds = started.elapsed().as_secs_f64();
                self.store.commit(key, &partial, seconds)?;
                self.printer
                    .line(&format!("{stage}: done in {seconds:.1} s"));
                true
            }
        };
        if !ran {
            self.printer.line(&format!("{stage}: up to date"));
        }
        self.store
            .publish(&self.scene.name, key, published_files(stage))?;
        Ok(ran)
    }

    fn run_stage(&self, stage: &str, out: &Path) -> Result<()> {
        match stage {
            "geometry" => self.geometry(out),
            "mesh" => self.mesh(out),
            "solve" => crate::solve_stage::run(self, &self.done_dir("mesh"), out),
            _ => crate::post_stage::run(self, &self.done_dir("solve"), out),
        }
    }

    fn geometry(&self, out: &Path) -> Result<()> {
        let report = geom::build_geometry(&self.scene.bar, &self.scene.specimen, self.gmsh, out)?;
        self.printer.detail(&format!(
            "geometry: f_R = {:.4}, rib volume {:.3e} m³, adhesive interface {:.4e} m²",
            report.f_r, report.rib_volume_m3, report.interface_area_adhesive_m2
        ));
        Ok(())
    }

    fn mesh(&self, out: &Path) -> Result<()> {
        let geo = self.done_dir("geometry").join("specimen.geo");
        let report = mesh::mesh_specimen(
            self.gmsh,
            &geo,
            &self.scene.mesh,
            self.scene.bar.diameter,
            self.scene.specimen.adhesive_length,
            out,
        )?;
        self.printer.detail(&format!(
            "mesh: {} nodes, {} steel + {} concrete tets, {} interface elements, min quality {:.3}",
            report.nodes,
            report.tets_steel,
            report.tets_concrete,
            report.interface_elements_adhesive + report.interface_elements_free,
            report.min_quality
        ));
        Ok(())
    }
}
