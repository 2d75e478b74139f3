//! The remedies a step gets before it counts as failed, each with its
//! budget (docs/architecture.md, "The stepping policy"):
//!
//! - explicit tets: the tets whose damage switched between growing and
//!   not between Newton iterates of a failed attempt take their damage
//!   from an extrapolation for a retry of the step;
//! - interface holds: the interface points whose regime kept switching are
//!   held at a history for a retry (`solver.expert.interface_holds`);
//! - damage passes: after a retried (or chattering) attempt converged,
//!   fixed-point passes give those points the history their implicit law
//!   reached, until it settles (`crate::nonlinear::settle`).

/// Retries of a step with remedies, without interface holds ...
pub const RETRIES: usize = 2;
/// ... and when the step may hold interface points.
pub const RETRIES_WITH_HOLDS: usize = 3;
/// Most damage passes of a retried step.
pub const DAMAGE_PASSES: usize = 20;
/// A retried tet's damage is settled when the implicit one exceeds the one
/// its stress used by no more than this.
pub const DAMAGE_SETTLED: f64 = 1e-3;

/// A retry's remedy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Remedy {
    /// Make the new flipping tets explicit for the step.
    ExplicitTets,
    /// Hold the new flipping interface points at a history.
    HoldPoints,
}

/// How many retries with remedies a step gets.
pub fn retry_budget(holds_points: bool) -> usize {
    if holds_points {
        RETRIES_WITH_HOLDS
    } else {
        RETRIES
    }
}

/// The remedy of a failed attempt after `retries` retries, with
/// `new_tets` flipping tets and `new_points` flipping interface points not
/// treated yet: tets first, as their retry settles monotonically; points
/// only when no new tet flipped (holding both at once turned retries that
/// the tets alone settle into unsettled ones); none past the budget or
/// with nothing new.
pub fn next_remedy(
    retries: usize,
    budget: usize,
    new_tets: usize,
    new_points: usize,
) -> Option<Remedy> {
    if retries >= budget {
        None
    } else if new_tets > 0 {
        Some(Remedy::ExplicitTets)
    } else if new_points > 0 {
        Some(Remedy::HoldPoints)
    } else {
        None
    }
}

/// Whether a converged attempt goes through the damage passes: it was
/// retried with remedies, or it ended on its best iterate with points
/// flipping.
pub fn needs_settling(retried: bool, force_only: bool, flipping: bool) -> bool {
    retried || (force_only && flipping)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Flipping tets are made explicit before any interface point is held,
    /// points only when no new tet flipped, and nothing past the budget of
    /// 2 retries (3 with holds).
    #[test]
    fn tets_first_then_points_within_the_budget() {
        assert_eq!(retry_budget(false), 2);
        assert_eq!(retry_budget(true), 3);
        assert_eq!(next_remedy(0, 2, 4, 9), Some(Remedy::ExplicitTets));
        assert_eq!(next_remedy(1, 2, 0, 9), Some(Remedy::HoldPoints));
        assert_eq!(next_remedy(1, 2, 0, 0), None);
        assert_eq!(next_remedy(2, 2, 4, 9), None);
        assert_eq!(next_remedy(2, 3, 4, 9), Some(Remedy::ExplicitTets));
    }

    /// The damage passes follow a retry, or a best-iterate ending with
    /// points flipping; a plain converged attempt skips them.
    #[test]
    fn damage_passes_follow_retries_and_chattering_endings() {
        assert!(needs_settling(true, false, false));
        assert!(needs_settling(false, true, true));
        assert!(!needs_settling(false, true, false));
        assert!(!needs_settling(false, false, true));
    }
}
