//! The controls: what a step prescribes, when each control takes over,
//! and the plan of the next step. One file per control:
//!
//! - `displacement`: the imposed displacement λ (the default);
//! - `free_end`: the free-end displacement, λ an unknown
//!   (`solver.path_following: fed`);
//! - `dissipation`: the energy a step releases, λ an unknown (`energy`,
//!   and `auto` past a stall after a dissipating step);
//! - `process_zone`: the jumps of the interface points that softened in
//!   the last step (`process_zone`).
//!
//! `plan` holds the plan of a step and its bounds; an indirect control
//! lands on the end of the loading by displacement or FED control
//! (`landing`).

pub(crate) mod displacement;
pub(crate) mod dissipation;
pub(crate) mod free_end;
mod landing;
mod plan;
pub(crate) mod process_zone;

pub use plan::{at_min_step, max_step, min_step, Plan, Zone};

use super::state::{PathView, Rules, Steps};
use crate::nonlinear::control::ControlMode;

/// The next step's plan: the control may change first (the free end and
/// the process zone take over or hand back here; dissipation control's
/// changes follow a commit or a failure), then the control plans the step.
/// `zone` is the process zone under `path_following: process_zone`, when
/// points softened in the last step.
pub fn next(steps: &mut Steps, view: &PathView, zone: Option<Zone>, rules: &Rules) -> Plan {
    free_end::take_over(steps, view, rules);
    process_zone::take_over_or_hand_back(steps, view, zone, rules);
    match steps.mode {
        ControlMode::ProcessZone => {
            process_zone::plan(steps, view, zone.expect("a process zone"), rules)
        }
        ControlMode::Displacement => {
            displacement::by_lambda(view, steps.next.min(steps.curve_limit), rules.loading)
        }
        ControlMode::Energy => dissipation::plan(steps, view, rules),
        ControlMode::FreeEnd => free_end::plan(steps, view, rules),
    }
}
