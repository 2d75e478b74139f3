//! How a run ends where no quasi-static continuation exists: at the
//! loaded member's limit load, by a brittle split of the cube, or with
//! its load lost; each diagnosed from the last converged state and the
//! failed attempt (docs/solver.md, "How a run ends").

use super::{Driver, Path, Plan};
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::StepFailure;
use crate::nonlinear::report::{CurveRow, Ending};
use crate::spec::solver::InterfaceHolds;

/// A stall at this share of the yield force or more is a limit load.
const LIMIT_SHARE: f64 = 0.9;

/// A step on the yield plateau changes the force by less than this
/// fraction of it.
const PLATEAU: f64 = 1e-3;

/// A load below this fraction of its largest value counts as unloaded.
pub(super) const UNLOADED: f64 = 1e-3;

/// A dissipation-controlled attempt whose last iterate puts λ below this
/// share of the last converged λ has found the path snapping back towards
/// the origin (see [`Driver::brittle_failure`]).
const SNAP_BACK: f64 = 0.5;

/// ... and concrete damage growing in at least this share of the
/// concrete tets in that iterate: a failure spreading through the cube.
const SPREADING: f64 = 0.01;

/// Concrete tets at or above this damage form a crack band; one that
/// crosses the cover from the bar to the cube's faces splits the cube
/// (see [`Driver::brittle_failure`]).
pub const CRACKED: f64 = 0.9;

impl Driver<'_> {
    /// The end of the run at the loaded member's limit load: the step
    /// failed with the steel yielding and the last converged force at
    /// least [`LIMIT_SHARE`] of the yield force (a perfectly plastic
    /// section has no stiffness left; beyond it no quasi-static state
    /// carries more).
    pub(super) fn limit_load(&self, path: &Path, reason: &StepFailure) -> Option<Ending> {
        let yield_force = self.problem.yield_force?;
        let force = path.rows.last()?.force;
        let yielding = reason.regimes().is_none_or(|r| r.steel_yield > 0);
        (yielding && force.abs() >= LIMIT_SHARE * yield_force)
            .then_some(Ending::LimitLoad { force, yield_force })
    }

    /// The end of a run whose specimen fails unstably (a brittle split of
    /// the cube): displacement control found no equilibrium beyond the last
    /// converged step, and at the minimum dissipation step the attempt's
    /// last iterate sits at λ below [`SNAP_BACK`] of the last converged λ
    /// with concrete damage growing in at least [`SPREADING`] of the
    /// concrete tets. The energy stored at the
    /// last converged step then drives the failure with the load falling
    /// back towards zero: under a monotone imposed displacement the
    /// specimen fails dynamically at that step, so there is no
    /// quasi-static continuation and its force is the failure load.
    ///
    /// Dissipation control may also converge some steps down that branch
    /// before it stalls (λ back near zero or below it, the load a few per
    /// cent of the peak): the split then began at the step of the largest
    /// force, whose force is the failure load, and the stall counts as the
    /// same ending once the attempt's λ is below [`SNAP_BACK`] of that
    /// step's λ.
    ///
    /// With interface points held (tried before this diagnosis), the
    /// attempt at the smallest energy step may instead converge with λ in
    /// place while the held points cannot settle and concrete damage
    /// spreads: no state in balance with the interface's own history
    /// releases that little energy, the same unstable split seen from the
    /// other side (found on the stress holdout's cases 7 and 19, which
    /// end at a snap-back when their points are not held). The failure
    /// load is then the largest force.
    pub(super) fn brittle_failure(
        &self,
        path: &Path,
        plan: &Plan,
        lambda: f64,
        reason: &StepFailure,
    ) -> Option<Ending> {
        let last = path.rows.last()?;
        let (damaging, concrete) = self.spreading_damage(reason)?;
        if plan.mode != ControlMode::Energy {
            return None;
        }
        let peak = largest_force_row(&path.rows)?;
        let unsettled_points = match reason {
            StepFailure::Unsettled { points, .. } => *points,
            _ => 0,
        };
        // The snap-back is the evidence whenever λ went back; the held
        // points' only where it did not.
        let snapped = lambda < SNAP_BACK * path.lambda || lambda < SNAP_BACK * peak.u_imposed;
        // Once the points were held from the first step (the last
        // resort), an attempt at the smallest energy step whose iterates
        // carry λ far forward with damage spreading has no equilibrium
        // near the path either (the stress holdout-2's case 22: λ from
        // 0.133 to 0.455 mm, damage growing in 2 400 of the tets).
        let wandered = path.summary.interface_holds_from_step == Some(1)
            && lambda > (2.0 - SNAP_BACK) * path.lambda;
        // With no remedy left, a stall whose converged state is cracked
        // through the cover is the split itself, wherever λ went: the
        // ring of concrete that held the ribs' radial push is cut
        // (docs/solver.md, "How a run ends").
        let cracked_through = self.cracked_through(path);
        let split = cracked_through > 0 && !self.may_hold_from_start(path);
        let (force, u_imposed) = if lambda < SNAP_BACK * path.lambda {
            (last.force, path.lambda)
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
            concrete_tets: concrete,
        })
    }

    /// Whether a stall may still start the run again with the interface
    /// points held from step 1: under `on_stall`, once they were held from
    /// a later step ("Holds after a stall").
    pub(super) fn may_hold_from_start(&self, path: &Path) -> bool {
        self.settings.interface_holds == InterfaceHolds::OnStall
            && path
                .summary
                .interface_holds_from_step
                .is_some_and(|k| k > 1)
    }

    /// Concrete tets of the last converged state with damage of at least
    /// [`CRACKED`] in bands from the bar to the cube's faces.
    fn cracked_through(&self, path: &Path) -> usize {
        let cracked: Vec<bool> = path
            .committed
            .bulk
            .iter()
            .map(|s| s.damage >= CRACKED)
            .collect();
        self.problem.model.cover_crossing_tets(&cracked)
    }

    /// Of a failed attempt whose last iterate grew concrete damage in at
    /// least [`SPREADING`] of the concrete tets: those tets' count and the
    /// concrete's.
    fn spreading_damage(&self, reason: &StepFailure) -> Option<(usize, usize)> {
        self.spreading(reason.regimes()?.concrete_damage)
    }

    /// `damaging` and the count of concrete tets when `damaging` is at
    /// least [`SPREADING`] of them.
    fn spreading(&self, damaging: usize) -> Option<(usize, usize)> {
        let concrete = self
            .problem
            .model
            .tet_region
            .iter()
            .filter(|r| **r == mesh::Region::Concrete)
            .count();
        (damaging as f64 >= SPREADING * concrete as f64).then_some((damaging, concrete))
    }

    /// How the run ends at its last converged step, if it does there: on
    /// the yield plateau, unloaded, or down a split's branch.
    pub(super) fn ending_after_step(&self, path: &Path) -> Option<Ending> {
        self.yield_plateau(path)
            .or_else(|| self.lost_load(path))
            .or_else(|| self.split_branch(path))
    }

    /// The end of a run whose dissipation control converged a step down a
    /// split's branch: λ fell in the step, below [`SNAP_BACK`] of the λ of
    /// the largest force, with concrete damage growing in at least
    /// [`SPREADING`] of the tets. The specimen has split at that force
    /// (the same ending as a stall there, [`Driver::brittle_failure`]); the
    /// branch beyond, back to λ < 0 and loaded again, is a split cube's,
    /// not the pull-out's (found on the stress test's tiny smooth bar with
    /// λ_0 = 1e-6 m, which, followed on, pushed the bar back in and
    /// reloaded it with its dissipation falling by 2.4 % of W_ext).
    fn split_branch(&self, path: &Path) -> Option<Ending> {
        if path.last_lambda_increment >= 0.0 {
            return None;
        }
        let peak = largest_force_row(&path.rows)?;
        if path.lambda >= SNAP_BACK * peak.u_imposed {
            return None;
        }
        let (damaging, concrete) = self.spreading(path.damaging_tets)?;
        Some(Ending::BrittleFailure {
            force: peak.force,
            u_imposed: peak.u_imposed,
            snap_back_to: path.lambda,
            unsettled_points: 0,
            cracked_through_tets: self.cracked_through(path),
            damaging_concrete_tets: damaging,
            concrete_tets: concrete,
        })
    }

    /// The end of the run on the loaded member's yield plateau: the last
    /// converged step yielded steel, carries at least [`LIMIT_SHARE`] of
    /// the yield force, and its force grew by less than [`PLATEAU`] of
    /// itself. The bar then only stretches plastically beyond the bearing
    /// face; the bond sees no more load, so further steps carry no
    /// information.
    fn yield_plateau(&self, path: &Path) -> Option<Ending> {
        let yield_force = self.problem.yield_force?;
        let [.., before, last] = path.rows.as_slice() else {
            return None;
        };
        let force = last.force;
        let flat = (force - before.force).abs() <= PLATEAU * force.abs();
        (path.steel_yielding && flat && force.abs() >= LIMIT_SHARE * yield_force)
            .then_some(Ending::LimitLoad { force, yield_force })
    }

    /// The end of a run whose specimen lost its load: the last converged
    /// force is below [`UNLOADED`] of the peak, reached at an earlier step.
    fn lost_load(&self, path: &Path) -> Option<Ending> {
        let [.., last] = path.rows.as_slice() else {
            return None;
        };
        let peak_force = largest_force_row(&path.rows)?.force.abs();
        if peak_force == 0.0 || last.force.abs() > UNLOADED * peak_force {
            return None;
        }
        let broken_concrete_tets = path
            .committed
            .bulk
            .iter()
            .zip(&self.problem.model.tet_region)
            .filter(|(s, r)| **r == mesh::Region::Concrete && s.damage > 0.99)
            .count();
        Some(Ending::Unloaded {
            force: last.force,
            peak_force,
            broken_concrete_tets,
        })
    }
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
