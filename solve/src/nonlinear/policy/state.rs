//! The stepping policy's state, what it reads of the path, and the
//! settings its rules read.

use crate::assembly::States;
use crate::curve::CurveRow;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::summary::{Ending, Summary};
use crate::spec::solver::{InterfaceHolds, Loading, SolverSettings};
use serde::{Deserialize, Serialize};

/// Where the steps are: what the next one prescribes and how far.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Steps {
    /// What the next step prescribes.
    pub mode: ControlMode,
    /// Its size, in the mode's unit (`ControlMode::step_unit`).
    pub next: f64,
    /// The largest next displacement-controlled step the curve's bend
    /// allows (`loading.curve_tolerance`), m; infinite when it sets none.
    /// Kept apart from `next`, which Newton's effort sets, so that a step
    /// shortened for the curve's sake does not slow the steps after the
    /// bend.
    pub curve_limit: f64,
    /// The next step is taken under displacement control after a
    /// process-zone attempt moved λ too far (a load jump); cleared by the
    /// next commit.
    pub zone_paused: bool,
}

impl Steps {
    /// The steps of a run's start: displacement control at `initial_step`.
    pub fn start(loading: &Loading) -> Self {
        Self {
            mode: ControlMode::Displacement,
            next: loading.initial_step,
            curve_limit: f64::INFINITY,
            zone_paused: false,
        }
    }
}

/// Everything the stepping policy remembers from one step to the next.
/// It goes whole into the checkpoint, so a run resumed from any
/// checkpoint takes the decisions the uninterrupted run takes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PolicyState {
    pub steps: Steps,
    /// The step from which interface points may be held under
    /// `solver.expert.interface_holds: on_stall`: the first that would have
    /// stalled at its minimum size without them (1 once the run started
    /// again from the beginning with them).
    pub holds_from_step: Option<usize>,
    /// Under `on_stall`, before the holds: the converged path before the
    /// first cut-back since the last easy step, which a stall goes back
    /// to.
    pub rewind: Option<Box<RewindPoint>>,
    /// How the run ends at its last committed step, once an ending after a
    /// step found it (a run resumed there ends there too).
    #[serde(with = "ending_as_json")]
    pub ended: Option<Ending>,
}

/// [`Ending`] is tagged by its `kind` inside (as solve.json shows it),
/// which a format that is not self-describing (the checkpoint's bincode)
/// cannot read back: the state holds it as its JSON text.
mod ending_as_json {
    use crate::nonlinear::summary::Ending;
    use serde::{de::Error, Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(ending: &Option<Ending>, s: S) -> Result<S::Ok, S::Error> {
        ending
            .as_ref()
            .map(|e| serde_json::to_string(e).expect("endings serialise"))
            .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Ending>, D::Error> {
        Option::<String>::deserialize(d)?
            .map(|text| serde_json::from_str(&text).map_err(D::Error::custom))
            .transpose()
    }
}

impl PolicyState {
    pub fn start(loading: &Loading) -> Self {
        Self {
            steps: Steps::start(loading),
            holds_from_step: None,
            rewind: None,
            ended: None,
        }
    }

    /// Whether the next step may hold interface points
    /// (`solver.expert.interface_holds`).
    pub fn holds_points(&self, settings: &SolverSettings) -> bool {
        match settings.interface_holds {
            InterfaceHolds::Off => false,
            InterfaceHolds::OnStall => self.holds_from_step.is_some(),
            InterfaceHolds::Always => true,
        }
    }

    /// Whether a stall may still start the run again with the interface
    /// points held from step 1: under `on_stall`, once they were held from
    /// a later step.
    pub fn may_hold_from_start(&self, settings: &SolverSettings) -> bool {
        settings.interface_holds == InterfaceHolds::OnStall
            && self.holds_from_step.is_some_and(|k| k > 1)
    }
}

/// A converged state a stall may go back to, with the steps and the
/// summary it had.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RewindPoint {
    pub path: ConvergedPath,
    pub steps: Steps,
    pub summary: Summary,
}

/// The converged state of a run between steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergedPath {
    /// Global displacement, m.
    pub u: Vec<f64>,
    pub states: States,
    pub rows: Vec<CurveRow>,
    /// λ of the last converged step, m.
    pub lambda: f64,
    /// Global displacement increment and Δλ (m) of the last converged
    /// step (the predictor's; empty and 0 before the first).
    pub last_increment: Vec<f64>,
    pub last_lambda_increment: f64,
    /// The generalised load F = Σ rate_a f_int,a of the last converged
    /// step (N) and its increment in that step.
    pub load: f64,
    pub last_load_increment: f64,
}

impl ConvergedPath {
    /// The unloaded start of a run with `n_dofs` global DOFs.
    pub fn start(n_dofs: usize, states: States) -> Self {
        Self {
            u: vec![0.0; n_dofs],
            states,
            rows: Vec::new(),
            lambda: 0.0,
            last_increment: Vec::new(),
            last_lambda_increment: 0.0,
            load: 0.0,
            last_load_increment: 0.0,
        }
    }
}

/// What the policy reads of the converged path: the last step's
/// increments and loads, measured by the driver.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PathView<'a> {
    pub rows: &'a [CurveRow],
    /// λ of the last converged step and its increment in it, m.
    pub lambda: f64,
    pub lambda_increment: f64,
    /// The free-end displacement now and its increment in the last step
    /// (the FED as a linear quantity of the displacement), m.
    pub fed: f64,
    pub fed_increment: f64,
    /// The generalised load now and its increment in the last step, N.
    pub load: f64,
    pub load_increment: f64,
    /// The largest |F| of the converged steps (the model's load), N.
    pub peak_load: f64,
}

/// A load below this fraction of its largest value counts as unloaded.
pub const UNLOADED: f64 = 1e-3;

impl PathView<'_> {
    /// Energy released ½(F_0 λ − F λ_0) and external work ½(F_0 + F)Δλ of
    /// the last converged step (J).
    pub fn last_energies(&self) -> (f64, f64) {
        let (l, f) = (self.lambda, self.load);
        let (l0, f0) = (l - self.lambda_increment, f - self.load_increment);
        (0.5 * (f0 * l - f * l0), 0.5 * (f0 + f) * (l - l0))
    }

    /// The load has fallen to a negligible share of its largest value: the
    /// parts slide freely and nothing is left to release.
    pub fn unloaded(&self) -> bool {
        self.load.abs() <= UNLOADED * self.peak_load
    }

    /// The work of the load over a length of λ, ½ |F| × length (J): the
    /// size of a dissipation-controlled step that stands for it.
    pub fn load_work(&self, length: f64) -> f64 {
        0.5 * self.load.abs() * length
    }
}

/// The loading and solver settings the policy's rules read.
#[derive(Clone, Copy)]
pub struct Rules<'a> {
    pub loading: &'a Loading,
    pub settings: &'a SolverSettings,
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::*;

    /// The energies of the last step are ½(F₀λ − Fλ₀) released and
    /// ½(F₀ + F)Δλ of external work (a secant unloading releases all).
    #[test]
    fn last_energies_are_the_released_energy_and_the_work() {
        let rows = [row(1, 1e-5, 100.0), row(2, 2e-5, 50.0)];
        let v = view(&rows, [1e-5, 100.0], [2e-5, 50.0]);
        let (released, work) = v.last_energies();
        assert!((released - 0.5 * (100.0 * 2e-5 - 50.0 * 1e-5)).abs() < 1e-18);
        assert!((work - 0.5 * 150.0 * 1e-5).abs() < 1e-18);
        // Elastic loading along the secant through the origin releases none.
        let v = view(&rows, [1e-5, 50.0], [2e-5, 100.0]);
        assert!(v.last_energies().0.abs() < 1e-18);
    }

    /// A run counts as unloaded below 0.1 % of its largest load.
    #[test]
    fn unloaded_is_below_a_thousandth_of_the_peak() {
        let rows = [row(1, 1e-5, 1000.0), row(2, 2e-5, 0.5)];
        assert!(view(&rows, [1e-5, 1000.0], [2e-5, 0.5]).unloaded());
        assert!(!view(&rows, [1e-5, 1000.0], [2e-5, 1.5]).unloaded());
    }

    /// Holds are allowed by `always`, by `on_stall` once a stall set their
    /// first step, never by `off`; a restart with holds from step 1 is
    /// left only while they were held from a later step.
    #[test]
    fn interface_holds_follow_the_setting_and_the_stall() {
        let loading = loading();
        let mut policy = PolicyState::start(&loading);
        let mut settings = SolverSettings::default();
        assert!(!policy.holds_points(&settings));
        assert!(!policy.may_hold_from_start(&settings));
        policy.holds_from_step = Some(7);
        assert!(policy.holds_points(&settings));
        assert!(policy.may_hold_from_start(&settings));
        policy.holds_from_step = Some(1);
        assert!(!policy.may_hold_from_start(&settings));
        settings.interface_holds = InterfaceHolds::Off;
        assert!(!policy.holds_points(&settings));
        settings.interface_holds = InterfaceHolds::Always;
        policy.holds_from_step = None;
        assert!(policy.holds_points(&settings));
    }
}
