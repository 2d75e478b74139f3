//! The checks a converged attempt passes before its commit, in the order
//! the review applies them; each returns its verdict, a [`Refusal`] that
//! sends the step back, or nothing:
//!
//! - `load_jump`: an indirect step that moved λ too far;
//! - `impl_ex`: an IMPL-EX extrapolation error above its rejection limit;
//! - `curve_bend`: a curve that bends too much within the step;
//! - `energy`: a state that creates energy, is out of balance, or would
//!   fail the run's energy check.
//!
//! [`Refusal`]: crate::nonlinear::Refusal

pub(crate) mod curve_bend;
pub(crate) mod energy;
pub(crate) mod impl_ex;
pub(crate) mod load_jump;
