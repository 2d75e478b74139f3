//! Hand-built paths for the rules' tests.

use super::state::PathView;
use crate::curve::CurveRow;
use crate::spec::solver::Loading;

/// A row at λ = `u` with force `f` (σ_mb = f, FED = u / 2).
pub fn row(step: usize, u: f64, f: f64) -> CurveRow {
    CurveRow {
        step,
        u_imposed: u,
        force: f,
        fed: 0.5 * u,
        bond_stress: f,
        iterations: 3,
        impl_ex_error: None,
    }
}

/// A path of `rows`, its last step from (λ0, F0) to (λ, F) in the view.
pub fn view(rows: &[CurveRow], start: [f64; 2], end: [f64; 2]) -> PathView<'_> {
    let ([l0, f0], [l, f]) = (start, end);
    PathView {
        rows,
        lambda: l,
        lambda_increment: l - l0,
        fed: 0.5 * l,
        fed_increment: 0.5 * (l - l0),
        load: f,
        load_increment: f - f0,
        peak_load: rows.iter().map(|r| r.force.abs()).fold(0.0, f64::max),
    }
}

pub fn loading() -> Loading {
    Loading {
        u_final: 1e-3,
        initial_step: 5e-6,
        min_step: 1e-9,
        max_step: 2e-5,
        ..Loading::default()
    }
}
