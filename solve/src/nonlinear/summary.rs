//! What a run records about itself: its summary (`solve.json`), wall
//! times by phase and how it ended.

use crate::assembly::EvalTimings;
use crate::spec::solver::PreconditionerKind;
use serde::{Deserialize, Serialize};

/// Wall times by phase, s.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct WallTimes {
    pub total: f64,
    /// Scatter into the global matrix and force vector.
    pub assembly: f64,
    /// Constitutive updates and element kernels.
    pub constitutive: f64,
    /// Numeric Cholesky factorisations (and the symbolic analysis).
    pub factorisation: f64,
    /// Triangular solves and conjugate gradients.
    pub solve: f64,
}

impl WallTimes {
    pub(crate) fn add(&mut self, o: &WallTimes) {
        self.total += o.total;
        self.assembly += o.assembly;
        self.constitutive += o.constitutive;
        self.factorisation += o.factorisation;
        self.solve += o.solve;
    }
    pub(crate) fn add_eval(&mut self, e: &EvalTimings) {
        self.assembly += e.assembly;
        self.constitutive += e.constitutive;
    }
}

/// Summary of a run (`summary.json`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Summary {
    /// Largest σ_mb, Pa.
    pub peak_bond_stress: f64,
    /// FED at the peak, m.
    pub fed_at_peak: f64,
    /// FED at the last converged step, m.
    pub final_fed: f64,
    pub steps: usize,
    pub cutbacks: usize,
    /// Free DOFs.
    pub dofs: usize,
    pub total_iterations: usize,
    pub factorisations: usize,
    pub pcg_iterations: usize,
    /// GMRES iterations of the Newton–Krylov solver.
    #[serde(default)]
    pub krylov_iterations: usize,
    /// Steps accepted on the force criterion alone: Newton stagnated with
    /// the residual already below `residual_tolerance` (points switching
    /// between loading and unloading, or stick and slip, kept the energy
    /// criterion out of reach).
    #[serde(default)]
    pub force_only_steps: usize,
    /// IMPL-EX: the largest relative residual of a converged step's
    /// displacement under the implicit damage (see
    /// `SolverSettings::impl_ex_tolerance`); 0 for implicit integration.
    #[serde(default)]
    pub impl_ex_max_residual: f64,
    /// IMPL-EX: converged steps redone shorter because their extrapolation
    /// error was above `impl_ex_reject` × `impl_ex_tolerance`.
    #[serde(default)]
    pub impl_ex_rejections: usize,
    /// Converged steps redone shorter because the curve bent more within
    /// them than `loading.curve_tolerance` allows.
    #[serde(default)]
    pub curve_rejections: usize,
    /// The largest distance of a kept curve point from the chord of its
    /// neighbours (scaled axes, see `loading.curve_tolerance`): how finely
    /// the steps sample the curve's bends; 0 when not checked.
    #[serde(default)]
    pub curve_max_deviation: f64,
    /// Converged states refused because they gave back dissipated energy,
    /// or left forces out of balance, beyond `solver.expert.dissipation_tolerance`
    /// (counted among the cut-backs too).
    #[serde(default)]
    pub dissipation_rejections: usize,
    /// Tets whose damage is integrated explicitly (IMPL-EX): all under
    /// `concrete_integration: impl_ex`, else the degenerate ones
    /// (`solver.expert.sliver_quality`).
    #[serde(default)]
    pub explicit_tets: usize,
    /// Attempts repeated with the tets whose damage switched between
    /// growing and not between Newton iterates integrated explicitly
    /// (their error is in `impl_ex_max_residual`).
    #[serde(default)]
    pub explicit_retries: usize,
    /// Newton solves repeated after a retry to settle the damage of its
    /// explicit tets and the history of its held interface points.
    #[serde(default)]
    pub damage_passes: usize,
    /// Interface points held at a history for a retried step (their
    /// regime kept switching between Newton iterates), counted per step.
    #[serde(default)]
    pub held_interface_points: usize,
    /// The step from which interface points may be held, under
    /// `solver.expert.interface_holds: on_stall`: the first that would have
    /// stalled at its minimum size without them. (Always serialised: the
    /// checkpoint's encoding is not self-describing.)
    #[serde(default)]
    pub interface_holds_from_step: Option<usize>,
    /// The checks of the stepping policy that were off in this run, from
    /// which step and why (the energy check where points are integrated
    /// explicitly for the whole run, or its record is not available).
    /// Always serialised: the checkpoint's encoding is not
    /// self-describing.
    #[serde(default)]
    pub checks_off: Vec<CheckOff>,
    /// The preconditioner GMRES used (`solver.expert.preconditioner` resolved;
    /// `cholesky` for the direct and PCG linear solvers).
    #[serde(default)]
    pub preconditioner: PreconditionerKind,
    /// Peak resident memory of the solving process, MiB (0 where the
    /// platform does not report it): the whole process, model included.
    #[serde(default)]
    pub peak_rss_mib: f64,
    pub wall_time_s: WallTimes,
}

/// A check of the stepping policy that was off in a run.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct CheckOff {
    /// The check's name (`energy`).
    pub check: String,
    /// The first step it did not apply to.
    pub from_step: usize,
    pub why: String,
}

/// How a run that returned a result ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Ending {
    /// The loading reached its end (`u_final` or `fed_stop`).
    Completed,
    /// The loaded member yields over its section: no quasi-static state
    /// carries more load, so the run ends there, its curve a result.
    LimitLoad {
        /// The last converged force (whole specimen), N.
        force: f64,
        /// σ_y times the member's section (whole specimen), N.
        yield_force: f64,
    },
    /// After its peak the specimen carries less than 0.1 % of the peak
    /// load: the cube split through or the bar pulled free, and there is
    /// no load left to follow.
    Unloaded {
        /// The last converged force (whole specimen), N.
        force: f64,
        /// The largest |F| of the run (whole specimen), N.
        peak_force: f64,
        /// Concrete tets with D > 0.99 (a crack through the cube shows as
        /// a layer of them).
        broken_concrete_tets: usize,
    },
    /// The specimen fails unstably (a brittle split of the cube): the
    /// equilibrium path beyond the last converged step snaps back towards
    /// the origin while concrete damage spreads, so a monotone imposed
    /// displacement has no quasi-static continuation and the last force is
    /// the failure load.
    BrittleFailure {
        /// The failure load (whole specimen), N: the force of the last
        /// converged step, or of the step of the largest force when
        /// dissipation control converged steps down the split branch
        /// before it stalled.
        force: f64,
        /// Imposed displacement of that step, m.
        u_imposed: f64,
        /// The imposed displacement the dissipation-controlled attempt
        /// fell back to, m (its own λ when the evidence is
        /// `unsettled_points` or `cracked_through_tets`, or where its
        /// iterates carried λ forward by more than half, the points held
        /// from the first step).
        snap_back_to: f64,
        /// Interface points held for the attempt at dissipation control's
        /// smallest step that did not settle: the split's other evidence,
        /// where the attempt converged without λ snapping back but no
        /// state with their laws' history was in balance; 0 when λ
        /// snapped back.
        #[serde(default)]
        unsettled_points: usize,
        /// Concrete tets of the last converged state with D ≥ 0.9 in bands
        /// that cross the cover from the bar to the cube's lateral faces
        /// (the split's crack; 0 where the damage stays inside the cover).
        /// With no remedy left, such a band is the split's evidence where
        /// the stalled attempt neither snapped back nor left held points
        /// unsettled.
        #[serde(default)]
        cracked_through_tets: usize,
        /// Concrete tets whose damage grew in that attempt's last iterate,
        /// of all concrete tets.
        damaging_concrete_tets: usize,
        concrete_tets: usize,
    },
}
