//! The energy check (`solver.expert.dissipation_tolerance`): the laws only
//! dissipate (but for the FCZM's non-potential exchange, a small part of a
//! step's work), so a converged state that gives back from the dissipated
//! energy, or leaves forces out of balance whose work is, more than the
//! tolerance's share of the work the step received (plus
//! [`DISSIPATION_FLOOR`] of W_ext) is another solution of the equilibrium
//! equations than the path's: typically a force jump after explicit
//! retries or holds, or a retry whose damage passes did not settle. So is
//! a state that would take the run's record outside the energy check of
//! solve.json.

use crate::energy::{EnergyRow, ENERGY_TOLERANCE};
use crate::nonlinear::failure::{Refusal, RegimeChanges};

/// A converged state may give back up to this fraction of W_ext from the
/// dissipated energy whatever its step's work: the scale of the residual
/// work the force criterion leaves in a step (`crate::energy`), so that a
/// step of a few nanometres is not refused for it.
pub const DISSIPATION_FLOOR: f64 = 2e-3;

/// The verdict on a step whose energy record goes from `last` to `row`,
/// with `limit` the tolerance in force (0: the check is off). A step back
/// along a snap-back receives no work and gives back nothing but the
/// floor.
pub fn check(
    row: &EnergyRow,
    last: &EnergyRow,
    limit: f64,
    regimes: RegimeChanges,
) -> Option<Refusal> {
    if limit == 0.0 || row.w_ext <= 0.0 {
        return None;
    }
    let step_work = (row.w_ext - last.w_ext).max(0.0);
    let allowed = limit * step_work + DISSIPATION_FLOOR * row.w_ext;
    let given_back = last.dissipated - row.dissipated;
    // The work of the forces left out of balance in the step.
    let unbalanced = ((row.w_ext - row.w_int) - (last.w_ext - last.w_int)).abs();
    if given_back > allowed {
        Some(Refusal::CreatesEnergy {
            of_step_work: given_back / step_work,
            of_total_work: given_back / row.w_ext,
            limit,
            regimes,
        })
    } else if unbalanced > allowed {
        Some(Refusal::OutOfBalance {
            of_step_work: unbalanced / step_work,
            of_total_work: unbalanced / row.w_ext,
            limit,
            regimes,
        })
    } else if !row.keeps_check(last, ENERGY_TOLERANCE) {
        // Each step within the rules above may still leave a part of its
        // work unbalanced; summed over a snap-back they can take the
        // record past the check that solve.json reports, so the check
        // itself bounds the path.
        Some(Refusal::FailsEnergyCheck {
            imbalance: row.relative_imbalance(),
            dissipation_increment: row.relative_dissipation_increment(last),
            limit: ENERGY_TOLERANCE,
            regimes,
        })
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(w_ext: f64, w_int: f64, dissipated: f64) -> EnergyRow {
        EnergyRow {
            w_ext,
            w_int,
            stored: w_int - dissipated,
            dissipated,
        }
    }

    /// A step that gives back dissipated energy beyond its share of the
    /// step's work is refused as creating energy; within it, kept.
    #[test]
    fn giving_back_dissipated_energy_beyond_the_share_is_refused() {
        let last = record(10.0, 10.0, 4.0);
        let back = record(11.0, 11.0, 3.0);
        let r = check(&back, &last, 0.15, RegimeChanges::default()).unwrap();
        assert!(matches!(r, Refusal::CreatesEnergy { of_step_work, .. } if of_step_work == 1.0));
        let within = record(11.0, 11.0, 3.9);
        assert!(check(&within, &last, 0.15, RegimeChanges::default()).is_none());
    }

    /// A step whose forces left out of balance did more work than the
    /// share is refused as out of balance.
    #[test]
    fn unbalanced_work_beyond_the_share_is_refused() {
        let last = record(10.0, 10.0, 4.0);
        let off = record(11.0, 10.5, 4.0);
        let r = check(&off, &last, 0.15, RegimeChanges::default()).unwrap();
        assert!(matches!(r, Refusal::OutOfBalance { .. }), "{r:?}");
    }

    /// Steps each within the share that take the record past solve.json's
    /// 1 % check are refused as failing it.
    #[test]
    fn a_record_past_the_runs_energy_check_is_refused() {
        let last = record(10.0, 9.92, 4.0);
        let drifted = record(10.1, 9.99, 4.0);
        let r = check(&drifted, &last, 0.15, RegimeChanges::default()).unwrap();
        assert!(matches!(r, Refusal::FailsEnergyCheck { .. }), "{r:?}");
    }

    /// With the tolerance 0 (off) or before any work nothing is refused.
    #[test]
    fn the_check_is_off_at_zero_and_before_any_work() {
        let last = record(10.0, 10.0, 4.0);
        let back = record(11.0, 11.0, 0.0);
        assert!(check(&back, &last, 0.0, RegimeChanges::default()).is_none());
        let none = record(0.0, 0.0, 0.0);
        assert!(check(&none, &EnergyRow::default(), 0.15, RegimeChanges::default()).is_none());
    }
}
