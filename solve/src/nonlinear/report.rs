//! What a run returns and reports while it runs: the result (or the
//! error that keeps the converged part), and the per-step events an
//! [`Observer`] receives.

use super::checkpoint::Checkpoint;
use super::control::ControlMode;
use super::failure::StepFailure;
pub use super::summary::{Ending, Summary, WallTimes};
use crate::assembly::{AssemblyError, ElementLaws, States};
pub use crate::curve::CurveRow;
use crate::linalg::LinearError;
use mesh::Model;

/// A finished (or partial) run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    pub rows: Vec<CurveRow>,
    pub summary: Summary,
    /// The last converged state (for fields and restarts).
    pub last: Checkpoint,
    /// How the run ended.
    pub ending: Ending,
    /// The energy balance of every converged step (`crate::energy`), or
    /// why it could not be evaluated.
    pub energy: Result<Vec<crate::energy::EnergyRow>, String>,
}

/// Per converged step, for progress output.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    pub row: CurveRow,
    /// What the converged attempt prescribed, and its size in that mode's
    /// unit (`ControlMode::step_unit`: m, or J under dissipation control).
    pub mode: ControlMode,
    pub step_size: f64,
    /// Wall times of this step (all attempts).
    pub times: WallTimes,
    /// Relative residual ‖r‖/F_scale at each iterate of the converged
    /// attempt (the predictor first).
    pub residual_history: Vec<f64>,
    /// The attempt ended on its best iterate of a stagnating iteration
    /// (counted in `Summary::force_only_steps`).
    pub force_only: bool,
    /// IMPL-EX: relative residual of the converged displacement under the
    /// implicit damage (the extrapolation error of the step); `None` for
    /// implicit integration.
    pub impl_ex_residual: Option<f64>,
}

/// A failed attempt that led to a smaller step.
#[derive(Debug, Clone, PartialEq)]
pub struct Cutback {
    /// Step number being attempted.
    pub step: usize,
    /// Imposed displacement of the failed attempt, m.
    pub u_imposed: f64,
    /// What the failed attempt prescribed, and its size in that mode's
    /// unit (`ControlMode::step_unit`).
    pub failed_mode: ControlMode,
    pub failed_step_size: f64,
    /// What the next attempt prescribes, and its size: another mode where
    /// displacement control hands over to dissipation control.
    pub next_mode: ControlMode,
    pub next_step_size: f64,
    pub reason: StepFailure,
    /// ‖r‖/‖reaction‖ per iteration.
    pub residual_history: Vec<f64>,
}

/// The converged state offered to observers.
pub struct CommittedView<'a> {
    pub model: &'a Model,
    pub laws: &'a ElementLaws,
    pub checkpoint: &'a dyn Fn() -> Checkpoint,
    pub u: &'a [f64],
    pub states: &'a States,
}

/// Receives progress; every method has a no-op default.
pub trait Observer {
    fn step_converged(&mut self, _report: &StepReport, _state: &CommittedView<'_>) {}
    fn cutback(&mut self, _event: &Cutback) {}
    /// The run went back to the converged state `state` after step
    /// `stalled` stalled (`solver.expert.interface_holds: on_stall`): the steps
    /// after the state's are discarded and will be reported again.
    fn rewound(&mut self, _stalled: usize, _state: &CommittedView<'_>) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("model: {0}")]
    Model(String),
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    #[error("linear solver set-up: {0}")]
    Linear(#[from] LinearError),
    #[error(
        "checkpoint does not match the model: {0}; `ribbar clean` the scene to remove its \
         results and start over"
    )]
    Checkpoint(String),
    #[error(
        "step {step} did not converge at the minimum step size: imposed displacement {u_imposed:e} m \
         (step {step_size:e} {step_unit}); residual history {residual_history:?}; likely cause: {cause}; \
         {}; {} converged steps kept", cause.stall_advice(), partial.rows.len()
    )]
    Stalled {
        step: usize,
        u_imposed: f64,
        /// In the unit of the step's control: m (λ, FED) or J (energy).
        step_size: f64,
        step_unit: &'static str,
        residual_history: Vec<f64>,
        cause: Box<StepFailure>,
        partial: Box<RunResult>,
    },
    #[error(
        "solver.expert.max_steps = {max_steps} converged steps reached at imposed displacement \
         {u_imposed:e} m before the end of the loading; raise solver.expert.max_steps, or remove \
         it, to go further"
    )]
    StepLimit {
        max_steps: usize,
        u_imposed: f64,
        partial: Box<RunResult>,
    },
}
