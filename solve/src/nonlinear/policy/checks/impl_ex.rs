//! The IMPL-EX check: a converged step whose extrapolation error (the
//! relative residual of its displacement under the implicit damage) is
//! above `solver.expert.impl_ex_reject` × `impl_ex_tolerance` is redone
//! shorter, never at the minimum step, which cannot be shortened. A step
//! in which points start to damage has no increment to extrapolate from,
//! and its error is not bounded by the next step's size.

use crate::nonlinear::failure::Refusal;
use crate::spec::solver::SolverSettings;

/// The verdict on a step with extrapolation error `e`.
pub fn check(e: f64, at_min_step: bool, settings: &SolverSettings) -> Option<Refusal> {
    let limit = settings.impl_ex_reject? * settings.impl_ex_tolerance;
    if e <= limit || at_min_step {
        return None;
    }
    Some(Refusal::ExtrapolationError {
        indicator: e,
        limit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Above the rejection limit a step is refused, at or below it and at
    /// the minimum step it is kept, and without a limit nothing is refused.
    #[test]
    fn steps_above_the_rejection_limit_are_refused_except_at_the_floor() {
        let settings = SolverSettings {
            impl_ex_tolerance: 1e-2,
            impl_ex_reject: Some(2.0),
            ..SolverSettings::default()
        };
        assert!(check(2.5e-2, false, &settings).is_some());
        assert!(check(2e-2, false, &settings).is_none());
        assert!(check(1.0, true, &settings).is_none());
        let off = SolverSettings {
            impl_ex_reject: None,
            ..settings
        };
        assert!(check(1.0, false, &off).is_none());
    }
}
