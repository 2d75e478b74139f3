//! Everything needed to restart a run from a converged step, saved
//! atomically (bincode behind a format tag).

use super::control::ControlMode;
use super::summary::Summary;
use crate::assembly::States;
use crate::curve::CurveRow;
use crate::elements::interface::INTERFACE_POINTS;
use crate::energy::EnergyRow;
use crate::fields::ProfileRow;
use mesh::Model;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Everything needed to restart from a converged step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub n_nodes: usize,
    pub n_tets: usize,
    pub n_interfaces: usize,
    /// λ of the last converged step, m.
    pub u_imposed: f64,
    /// Size of the next step to try, m, in the unit `control_mode` says.
    pub next_step: f64,
    /// The largest next displacement-controlled step the curve's bend
    /// allows (`loading.curve_tolerance`), m; infinite when it sets none.
    pub curve_step: f64,
    /// What the steps prescribe at this point of the run.
    pub control_mode: ControlMode,
    /// Global displacement, m.
    pub u: Vec<f64>,
    pub states: States,
    pub rows: Vec<CurveRow>,
    pub summary: Summary,
    /// The matrix whose factor preconditions the next linear solves (PCG
    /// and GMRES keep one across steps); a resumed run factorises exactly
    /// these values, so its iterates equal the uninterrupted run's bit for
    /// bit. `None` when no factor is kept (Cholesky mode, or none yet).
    pub preconditioner: Option<PreconditionerState>,
    /// Global displacement increment of the last converged step (m; empty
    /// before the first), for the extrapolating predictor.
    pub last_increment: Vec<f64>,
    /// Increment of λ in the last converged step, m (0 before the first).
    pub last_step: f64,
    /// The generalised load Σ rate_a f_int,a of the last converged step,
    /// N, and its increment in that step (dissipation control).
    pub generalised_load: f64,
    pub last_load_increment: f64,
    /// Energy balance, one row per converged step (empty when it could not
    /// be evaluated, see `RunResult::energy`).
    pub energy: Vec<EnergyRow>,
    /// What the run's caller recorded up to this step; it travels with the
    /// state so that a resumed run continues it (the solver leaves it
    /// empty, the caller fills it before saving).
    pub record: ObserverRecord,
}

/// What an [`Observer`](super::Observer) recorded of a run up to a checkpoint.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ObserverRecord {
    /// Interface traction profiles of the field steps so far.
    pub profile: Vec<ProfileRow>,
    /// The profile of the current adhesion peak (replaced by each new one).
    pub peak_profile: Vec<ProfileRow>,
}

/// The kept preconditioner of a run: the lower-triangle values (N/m) that
/// were factorised, and whether the solver had decided to refactorise at
/// its next correction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreconditionerState {
    pub values: Vec<f64>,
    pub refactor: bool,
    pub wear: HierarchyWear,
}

/// The wear of a kept multigrid hierarchy that `solver.multigrid_rebuild:
/// amortised` counts: the GMRES iterations of the first solve with it,
/// and those the solves after it needed beyond that.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HierarchyWear {
    first: Option<usize>,
    excess: usize,
}

impl HierarchyWear {
    /// Counts a solve of `iterations` with the hierarchy; returns the
    /// excess so far.
    pub(crate) fn after_solve(&mut self, iterations: usize) -> usize {
        match self.first {
            None => self.first = Some(iterations),
            Some(first) => self.excess += iterations.saturating_sub(first),
        }
        self.excess
    }
}

/// A checkpoint file that cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("checkpoint {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("checkpoint {path}: corrupt or of another version ({detail})")]
    Corrupt { path: String, detail: String },
}

const CHECKPOINT_MAGIC: u64 = 0x7269_6262_6172_000c;

impl Checkpoint {
    /// Writes atomically (temporary file then rename), bincode.
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.display().to_string(),
            source,
        };
        let bytes = bincode::serialize(&(CHECKPOINT_MAGIC, self)).map_err(|e| {
            CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: e.to_string(),
            }
        })?;
        geom::fsutil::write_atomic(path, &bytes).map_err(io)
    }

    pub fn load(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let (magic, cp): (u64, Checkpoint) =
            bincode::deserialize(&bytes).map_err(|e| CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: e.to_string(),
            })?;
        if magic != CHECKPOINT_MAGIC {
            return Err(CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: format!("format tag {magic:#x}"),
            });
        }
        Ok(cp)
    }

    /// `Err` with what differs when this checkpoint was not taken on
    /// `model` (with `n_dofs` global DOFs).
    pub(crate) fn check_matches(&self, model: &Model, n_dofs: usize) -> Result<(), String> {
        if self.n_nodes != model.nodes.len()
            || self.n_tets != model.tets.len()
            || self.n_interfaces != model.interfaces.len()
            || self.u.len() != n_dofs
            || self.states.bulk.len() != model.tets.len()
            || self.states.interface.len() != INTERFACE_POINTS * model.interfaces.len()
        {
            return Err(format!(
                "checkpoint has {} nodes, {} tets, {} interface elements; model has {}, {}, {}",
                self.n_nodes,
                self.n_tets,
                self.n_interfaces,
                model.nodes.len(),
                model.tets.len(),
                model.interfaces.len()
            ));
        }
        Ok(())
    }
}
