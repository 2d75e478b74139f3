//! What a scene's solve will take, from its mesh and its loading, before it
//! runs: the memory a study admits solves under (`--memory-gib`) and the
//! `mem_mb` and `runtime` an exported workflow asks a scheduler for.
//! `ribbar estimate` prints it; the models and their calibration on the
//! shipped scenes are in docs/src/validation/cluster-resources.md
//! (`scripts/calibrate-resources.sh` remakes the data).

use crate::scene::Scene;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;

/// Memory a solve is expected to take, bytes, for `dofs` = 3 × mesh nodes:
/// the Cholesky factor dominates and grows like DOFs^(4/3) under nested
/// dissection (3.5 GB measured at 285 k DOFs, SPEC §9).
pub fn estimated_solve_bytes(dofs: f64) -> f64 {
    3.5e9 * (dofs / 285e3).powf(4.0 / 3.0) + 200e6
}

/// Runtime model of a solve on one thread, s:
/// `RUNTIME_S_PER_STEP · planned_steps · (dofs / 1e5)^RUNTIME_DOF_EXPONENT`,
/// fitted in log space to the one-thread CPU times of the calibration runs
/// (docs/src/validation/cluster-resources.md: within 0.79-1.50 of them).
pub const RUNTIME_S_PER_STEP: f64 = 8.5;
/// The exponent of the DOFs in the runtime model.
pub const RUNTIME_DOF_EXPONENT: f64 = 1.4;

/// A scene's solve before it runs.
#[derive(Debug, Clone, Serialize)]
pub struct SolveEstimate {
    pub scene: String,
    /// Nodes of the scene's mesh.
    pub nodes: u64,
    /// 3 × nodes: the displacement DOFs before the supports remove some.
    pub dofs: u64,
    /// Steps the loading takes at its largest step (`loading.u_final /
    /// loading.max_step`, rounded up): the fewest a run makes.
    pub planned_steps: u64,
    /// Peak resident memory of the solve, bytes.
    pub memory_bytes: f64,
    /// Wall time of the solve on one thread, s.
    pub runtime_s: f64,
}

impl SolveEstimate {
    /// The estimate for `scene` whose mesh has `nodes` nodes.
    pub fn new(scene: &Scene, nodes: u64) -> SolveEstimate {
        let dofs = 3 * nodes;
        let planned_steps = (scene.loading.u_final / scene.loading.max_step)
            .ceil()
            .max(1.0) as u64;
        SolveEstimate {
            scene: scene.name.clone(),
            nodes,
            dofs,
            planned_steps,
            memory_bytes: estimated_solve_bytes(dofs as f64),
            runtime_s: RUNTIME_S_PER_STEP
                * planned_steps as f64
                * (dofs as f64 / 1e5).powf(RUNTIME_DOF_EXPONENT),
        }
    }
}

/// Nodes of a mesh stage's `mesh.json`.
pub fn mesh_nodes(mesh_json: &Path) -> Result<u64> {
    let bytes =
        std::fs::read(mesh_json).with_context(|| format!("reading {}", mesh_json.display()))?;
    let v: serde_json::Value = serde_json::from_slice(&bytes)
        .with_context(|| format!("{}: not valid JSON", mesh_json.display()))?;
    v.get("nodes")
        .and_then(|n| n.as_u64())
        .with_context(|| format!("{}: no node count (\"nodes\")", mesh_json.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Memory and runtime grow with the mesh, and the runtime with the
    /// steps the loading plans.
    #[test]
    fn estimates_grow_with_the_mesh_and_the_steps() {
        let m = |d: f64| estimated_solve_bytes(d);
        assert!(m(2e5) > m(1e5) && m(1e5) > 200e6);
        let scene = |max_step: &str| {
            let dir = std::env::temp_dir().join(format!("ribbar-estimate-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let spec = dir.join("s.yaml");
            std::fs::write(
                &spec,
                format!(
                    "name: s\nbar: {{kind: smooth, diameter: 8 mm}}\n\
                     loading: {{u_final: 0.3 mm, initial_step: 5 um, max_step: {max_step}}}\n"
                ),
            )
            .unwrap();
            let s = Scene::load(&spec, &[]).unwrap();
            std::fs::remove_dir_all(&dir).unwrap();
            s
        };
        let coarse = SolveEstimate::new(&scene("20 um"), 10_000);
        assert_eq!(coarse.planned_steps, 15);
        assert_eq!(coarse.dofs, 30_000);
        let fine = SolveEstimate::new(&scene("10 um"), 10_000);
        assert_eq!(fine.planned_steps, 30);
        assert!((fine.runtime_s / coarse.runtime_s - 2.0).abs() < 1e-12);
        let bigger = SolveEstimate::new(&scene("20 um"), 20_000);
        assert!(bigger.runtime_s > 2.0 * coarse.runtime_s);
        assert!(bigger.memory_bytes > coarse.memory_bytes);
    }
}
