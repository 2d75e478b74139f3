//! How a run ends where it has no quasi-static continuation: at the
//! loaded member's limit load, by a brittle failure of the specimen, or
//! with its load lost (docs/architecture.md, "The stepping policy").
//! The stall endings ([`limit_load`], [`brittle_failure`]) are tried when
//! a step fails at its minimum size; the others ([`after_step`]) after
//! every commit.

use super::controls::Plan;
use super::state::PathView;
use crate::curve::CurveRow;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::{NotConverged, StepFailure};
use crate::nonlinear::summary::Ending;

/// A stall at this share of the yield force or more is a limit load.
pub const LIMIT_SHARE: f64 = 0.9;

/// A step on the yield plateau changes the force by less than this
/// fraction of it.
pub const PLATEAU: f64 = 1e-3;

/// A dissipation-controlled attempt whose last iterate puts λ below this
/// share of the last converged λ has found the path snapping back towards
/// the origin (see [`brittle_failure`]).
pub const SNAP_BACK: f64 = 0.5;

/// ... and concrete damage growing in at least this share of the concrete
/// tets in that iterate: a failure spreading through the cube.
pub const SPREADING: f64 = 0.01;

/// Concrete tets at or above this damage form a crack band; one that
/// crosses the cover from the bar to the cube's faces splits the cube.
pub const CRACKED: f64 = 0.9;

/// What the endings read of the specimen, counted only when a rule asks.
pub struct Specimen<'a> {
    /// The measured force at which the loaded member yields over its
    /// section (whole specimen, N), if its law has a yield limit.
    pub yield_force: Option<f64>,
    pub concrete_tets: usize,
    /// Concrete tets of the last converged state with damage of at least
    /// [`CRACKED`] in bands from the bar to the cube's faces.
    pub cracked_through: &'a dyn Fn() -> usize,
    /// Concrete tets of the last converged state with D > 0.99.
    pub broken: &'a dyn Fn() -> usize,
}

impl Specimen<'_> {
    /// `damaging` when it is at least [`SPREADING`] of the concrete tets.
    fn spreading(&self, damaging: usize) -> Option<usize> {
        (damaging as f64 >= SPREADING * self.concrete_tets as f64).then_some(damaging)
    }
}

/// The stall's end at the loaded member's limit load: the step failed with
/// the steel yielding and the last converged force at least
/// [`LIMIT_SHARE`] of the yield force (a perfectly plastic section has no
/// stiffness left; beyond it no quasi-static state carries more).
pub fn limit_load(rows: &[CurveRow], failure: &StepFailure, specimen: &Specimen) -> Option<Ending> {
    let yield_force = specimen.yield_force?;
    let force = rows.last()?.force;
    let yielding = failure.regimes().is_none_or(|r| r.steel_yield > 0);
    (yielding && force.abs() >= LIMIT_SHARE * yield_force)
        .then_some(Ending::LimitLoad { force, yield_force })
}

/// What a stalled attempt tells the brittle-failure rule.
pub struct Stall<'a> {
    pub plan: &'a Plan,
    /// The attempt's last λ, m.
    pub lambda: f64,
    pub failure: &'a StepFailure,
    /// The interface points were held from the first step (the last
    /// resort, `solver.expert.interface_holds`).
    pub held_from_start: bool,
    /// A stall may still start the run again with holds from step 1.
    pub may_hold_from_start: bool,
}

/// The stall's end where the specimen fails unstably: displacement control
/// found no equilibrium beyond the last converged step, and at the minimum
/// dissipation step the attempt's last iterate sits at λ below
/// [`SNAP_BACK`] of the last converged λ (or of the λ of the largest
/// force, where dissipation control converged some steps down that branch)
/// with concrete damage growing in at least [`SPREADING`] of the tets. The
/// energy stored at the last converged step then drives the failure with
/// the load falling back towards zero: under a monotone imposed
/// displacement the specimen fails dynamically, so there is no
/// quasi-static continuation and the force is the failure load. With
/// interface points held, the attempt may instead converge with λ in place
/// while the held points cannot settle (the same split seen from the other
/// side); once the points were held from the first step, iterates that
/// carry λ far forward with damage spreading have no equilibrium near the
/// path either; and with no remedy left, a converged state cracked through
/// the cover is the split itself.
pub fn brittle_failure(view: &PathView, stall: &Stall, specimen: &Specimen) -> Option<Ending> {
    let last = view.rows.last()?;
    let damaging = specimen.spreading(stall.failure.regimes()?.concrete_damage)?;
    if stall.plan.mode != ControlMode::Energy {
        return None;
    }
    let peak = largest_force_row(view.rows)?;
    let unsettled_points = match stall.failure {
        StepFailure::NotConverged(NotConverged::Unsettled { points, .. }) => *points,
        _ => 0,
    };
    let lambda = stall.lambda;
    // The snap-back is the evidence whenever λ went back; the held points'
    // only where it did not.
    let snapped = lambda < SNAP_BACK * view.lambda || lambda < SNAP_BACK * peak.u_imposed;
    let wandered = stall.held_from_start && lambda > (2.0 - SNAP_BACK) * view.lambda;
    let cracked_through = (specimen.cracked_through)();
    let split = cracked_through > 0 && !stall.may_hold_from_start;
    let (force, u_imposed) = if lambda < SNAP_BACK * view.lambda {
        (last.force, view.lambda)
    } else if snapped || wandered || unsettled_points > 0 || split {
        (peak.force, peak.u_imposed)
    } else {
        return None;
    };
    Some(Ending::BrittleFailure {
        force,
        u_imposed,
        snap_back_to: lambda,
        unsettled_points: if snapped { 0 } else { unsettled_points },
        cracked_through_tets: cracked_through,
        damaging_concrete_tets: damaging,
        concrete_tets: specimen.concrete_tets,
    })
}

/// What a committed step did to the specimen.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepChanges {
    /// The steel's plastic strain grew in it.
    pub steel_yielding: bool,
    /// Concrete tets whose damage grew in it.
    pub damaging_tets: usize,
}

/// How the run ends at its last converged step, if it does there: on the
/// yield plateau, unloaded, or down a split's branch.
pub fn after_step(view: &PathView, changes: StepChanges, specimen: &Specimen) -> Option<Ending> {
    yield_plateau(view.rows, changes, specimen)
        .or_else(|| lost_load(view.rows, specimen))
        .or_else(|| split_branch(view, changes, specimen))
}

/// The end on the loaded member's yield plateau: the last step yielded
/// steel, carries at least [`LIMIT_SHARE`] of the yield force, and its
/// force grew by less than [`PLATEAU`] of itself. The bar then only
/// stretches plastically beyond the bearing face; the bond sees no more
/// load.
fn yield_plateau(rows: &[CurveRow], changes: StepChanges, specimen: &Specimen) -> Option<Ending> {
    let yield_force = specimen.yield_force?;
    let [.., before, last] = rows else {
        return None;
    };
    let force = last.force;
    let flat = (force - before.force).abs() <= PLATEAU * force.abs();
    (changes.steel_yielding && flat && force.abs() >= LIMIT_SHARE * yield_force)
        .then_some(Ending::LimitLoad { force, yield_force })
}

/// The end of a run whose specimen lost its load: the last force is below
/// [`super::state::UNLOADED`] of the peak, reached at an earlier step.
fn lost_load(rows: &[CurveRow], specimen: &Specimen) -> Option<Ending> {
    let [.., last] = rows else {
        return None;
    };
    let peak_force = largest_force_row(rows)?.force.abs();
    if peak_force == 0.0 || last.force.abs() > super::state::UNLOADED * peak_force {
        return None;
    }
    Some(Ending::Unloaded {
        force: last.force,
        peak_force,
        broken_concrete_tets: (specimen.broken)(),
    })
}

/// The end of a run whose dissipation control converged a step down a
/// split's branch: λ fell in the step, below [`SNAP_BACK`] of the λ of the
/// largest force, with concrete damage growing in at least [`SPREADING`]
/// of the tets. The specimen has split at that force; the branch beyond,
/// back to λ < 0 and loaded again, is a split cube's, not the pull-out's.
fn split_branch(view: &PathView, changes: StepChanges, specimen: &Specimen) -> Option<Ending> {
    if view.lambda_increment >= 0.0 {
        return None;
    }
    let peak = largest_force_row(view.rows)?;
    if view.lambda >= SNAP_BACK * peak.u_imposed {
        return None;
    }
    let damaging = specimen.spreading(changes.damaging_tets)?;
    Some(Ending::BrittleFailure {
        force: peak.force,
        u_imposed: peak.u_imposed,
        snap_back_to: view.lambda,
        unsettled_points: 0,
        cracked_through_tets: (specimen.cracked_through)(),
        damaging_concrete_tets: damaging,
        concrete_tets: specimen.concrete_tets,
    })
}

/// The step of the largest |force| (the latest of equal ones when the last
/// step is among them, else the earliest), `None` before the first step.
fn largest_force_row(rows: &[CurveRow]) -> Option<&CurveRow> {
    let last = rows.last()?;
    Some(rows.iter().fold(
        last,
        |a, r| if r.force.abs() > a.force.abs() { r } else { a },
    ))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::*;
    use crate::nonlinear::failure::RegimeChanges;

    fn specimen<'a>(yield_force: Option<f64>, cracked: &'a dyn Fn() -> usize) -> Specimen<'a> {
        Specimen {
            yield_force,
            concrete_tets: 1000,
            cracked_through: cracked,
            broken: &|| 7,
        }
    }

    fn stagnating(concrete_damage: usize, steel_yield: usize) -> StepFailure {
        NotConverged::Stagnating {
            relative_residual: 1e-2,
            regimes: RegimeChanges {
                concrete_damage,
                steel_yield,
                ..RegimeChanges::default()
            },
        }
        .into()
    }

    fn energy_plan() -> Plan {
        Plan {
            mode: ControlMode::Energy,
            size: 1e-9,
            target: 1e-9,
            scale: 0.0,
        }
    }

    /// A stall with the steel yielding at 90 % of the yield force or more
    /// is the limit load; below it, or with the steel elastic, it is not.
    #[test]
    fn a_stall_near_the_yield_force_with_the_steel_yielding_is_the_limit_load() {
        let none = || 0;
        let s = specimen(Some(1000.0), &none);
        let rows = [row(1, 1e-5, 950.0)];
        let ending = limit_load(&rows, &stagnating(0, 3), &s);
        assert!(matches!(ending, Some(Ending::LimitLoad { force, .. }) if force == 950.0));
        assert!(limit_load(&rows, &stagnating(0, 0), &s).is_none());
        let low = [row(1, 1e-5, 850.0)];
        assert!(limit_load(&low, &stagnating(0, 3), &s).is_none());
        assert!(limit_load(&rows, &stagnating(0, 3), &specimen(None, &none)).is_none());
    }

    /// At the smallest energy step, an attempt that snapped back below half
    /// the last λ with damage spreading is a brittle failure at the last
    /// force; one that stayed in place with nothing else to show is not;
    /// a cover cracked through is the split once no restart is left.
    #[test]
    fn a_snap_back_with_spreading_damage_is_a_brittle_failure() {
        let none = || 0;
        let s = specimen(None, &none);
        let rows = [row(1, 1e-5, 500.0), row(2, 2e-5, 800.0)];
        let v = view(&rows, [1e-5, 500.0], [2e-5, 800.0]);
        let plan = energy_plan();
        let failure = stagnating(20, 0);
        let stall = |lambda| Stall {
            plan: &plan,
            lambda,
            failure: &failure,
            held_from_start: false,
            may_hold_from_start: false,
        };
        let ending = brittle_failure(&v, &stall(0.4e-5), &s).unwrap();
        assert!(
            matches!(ending, Ending::BrittleFailure { force, u_imposed, damaging_concrete_tets: 20, .. }
                if force == 800.0 && u_imposed == 2e-5),
            "{ending:?}"
        );
        assert!(brittle_failure(&v, &stall(1.9e-5), &s).is_none());
        let quiet = stagnating(5, 0);
        let mut calm = stall(0.4e-5);
        calm.failure = &quiet;
        assert!(
            brittle_failure(&v, &calm, &s).is_none(),
            "damage not spreading"
        );
        let cracked = || 40;
        let split = specimen(None, &cracked);
        let ending = brittle_failure(&v, &stall(1.9e-5), &split).unwrap();
        assert!(matches!(
            ending,
            Ending::BrittleFailure {
                cracked_through_tets: 40,
                ..
            }
        ));
        let mut restart_left = stall(1.9e-5);
        restart_left.may_hold_from_start = true;
        assert!(brittle_failure(&v, &restart_left, &split).is_none());
    }

    /// After a commit: a flat step of yielding steel near the yield force
    /// ends on the plateau; a force below 0.1 % of the peak ends unloaded;
    /// a step back below half the peak's λ with damage spreading ends down
    /// the split's branch.
    #[test]
    fn a_committed_step_ends_on_the_plateau_unloaded_or_down_a_split() {
        let none = || 0;
        let s = specimen(Some(1000.0), &none);
        let plateau = [row(1, 1e-5, 950.0), row(2, 2e-5, 950.5)];
        let v = view(&plateau, [1e-5, 950.0], [2e-5, 950.5]);
        let yielding = StepChanges {
            steel_yielding: true,
            damaging_tets: 0,
        };
        assert!(matches!(
            after_step(&v, yielding, &s),
            Some(Ending::LimitLoad { .. })
        ));
        assert!(after_step(&v, StepChanges::default(), &s).is_none());
        let lost = [row(1, 1e-5, 950.0), row(2, 2e-5, 0.5)];
        let v = view(&lost, [1e-5, 950.0], [2e-5, 0.5]);
        let ending = after_step(&v, StepChanges::default(), &s);
        assert!(matches!(
            ending,
            Some(Ending::Unloaded {
                broken_concrete_tets: 7,
                ..
            })
        ));
        let split = [row(1, 2e-5, 950.0), row(2, 0.5e-5, 300.0)];
        let v = view(&split, [2e-5, 950.0], [0.5e-5, 300.0]);
        let spreading = StepChanges {
            steel_yielding: false,
            damaging_tets: 10,
        };
        let ending = after_step(&v, spreading, &s);
        assert!(matches!(ending, Some(Ending::BrittleFailure { force, .. }) if force == 950.0));
        assert!(after_step(&v, StepChanges::default(), &s).is_none());
    }
}
