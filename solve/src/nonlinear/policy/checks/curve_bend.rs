//! The curve-bend check (`loading.curve_tolerance`): after a
//! displacement-controlled step, how far the curve's last point lies off
//! the chord between the point before it (or the origin) and the new one,
//! on axes scaled to the FED's range and to the largest |σ_mb| so far. A
//! step more than [`CURVE_REJECT`] times the tolerance off is redone
//! shorter; otherwise the bend sizes the next step (`sizers`).

use super::super::controls::Plan;
use super::super::state::PathView;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::Refusal;
use crate::spec::solver::{CurveError, Loading};

/// A displacement-controlled step whose curve bends by more than this
/// multiple of `loading.curve_tolerance` is redone shorter.
pub const CURVE_REJECT: f64 = 2.0;

/// Steps sized by the curve's bend aim this much below the size that
/// would meet the tolerance exactly.
pub const CURVE_SAFETY: f64 = 0.9;

/// How far the curve bends at its last point once a displacement-
/// controlled step (`plan`, the steps' mode `mode`) ends at (`fed`,
/// `bond`), and the step size that would bring it to the tolerance. The
/// distance grows with the product of the two steps' lengths, whence the
/// geometric mean in the next size. `None` when the control is off, under
/// path-following or before the first step.
pub fn bend(
    view: &PathView,
    plan: &Plan,
    mode: ControlMode,
    fed: f64,
    bond: f64,
    loading: &Loading,
) -> Option<(f64, f64)> {
    let tolerance = loading.curve_tolerance;
    if tolerance <= 0.0
        || plan.mode != ControlMode::Displacement
        || mode != ControlMode::Displacement
    {
        return None;
    }
    let rows = view.rows;
    let last = rows.last()?;
    let before = rows.len().checked_sub(2).map(|i| &rows[i]);
    let fed_range = loading.fed_stop.unwrap_or(loading.u_final);
    let stress_range = rows
        .iter()
        .map(|r| r.bond_stress.abs())
        .fold(bond.abs(), f64::max);
    if !(stress_range > 0.0 && fed.is_finite()) {
        return None;
    }
    let scaled = |fed: f64, bond: f64| [fed / fed_range, bond / stress_range];
    let deviation = chord_deviation(
        loading.curve_error,
        scaled(last.fed, last.bond_stress),
        before.map_or([0.0, 0.0], |r| scaled(r.fed, r.bond_stress)),
        scaled(fed, bond),
    );
    if !deviation.is_finite() {
        return None;
    }
    let previous = match view.lambda_increment {
        d if d > 0.0 => d,
        _ => plan.size,
    };
    let next = if deviation > 0.0 {
        CURVE_SAFETY * (previous * plan.size * tolerance / deviation).sqrt()
    } else {
        f64::INFINITY
    };
    Some((deviation, next))
}

/// The verdict on a step whose curve bends by `deviation`: refused above
/// [`CURVE_REJECT`] × the tolerance, with the size of the shorter step
/// (the bend shrinks in proportion to it); never for a step at or below
/// `initial_step`.
pub fn check(deviation: f64, plan: &Plan, loading: &Loading) -> Option<Refusal> {
    let limit = CURVE_REJECT * loading.curve_tolerance;
    let floor = loading.initial_step;
    if deviation <= limit || plan.size <= floor * (1.0 + 1e-12) {
        return None;
    }
    let next_step = (CURVE_SAFETY * plan.size * loading.curve_tolerance / deviation).max(floor);
    Some(Refusal::CurveResolution {
        deviation,
        limit,
        next_step,
    })
}

/// How far `p` lies from the chord `a`–`b` (scaled axes: FED, σ_mb), as
/// `measure` asks. `Stress` takes, where the FED grows through the three
/// points, the σ_mb distance at `p`'s FED: the error a curve read along
/// FED gets from the chord there; on a steep rise to an adhesion peak
/// (scaled slope 10–20) the shortest distance is that many times smaller.
/// Elsewhere (a snap-back, a FED at a standstill) both take the shortest
/// distance.
fn chord_deviation(measure: CurveError, p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    if measure == CurveError::Stress && a[0] < p[0] && p[0] < b[0] {
        let t = (p[0] - a[0]) / (b[0] - a[0]);
        (p[1] - (a[1] + t * (b[1] - a[1]))).abs()
    } else {
        distance_to_segment(p, a, b)
    }
}

/// Distance of `p` from the segment from `a` to `b` (a point when they
/// coincide).
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let length2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if length2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::curve::CurveRow;

    fn displacement(size: f64) -> Plan {
        Plan {
            mode: ControlMode::Displacement,
            size,
            target: 0.0,
            scale: 0.0,
        }
    }

    fn curve(points: &[(f64, f64)]) -> Vec<CurveRow> {
        points
            .iter()
            .enumerate()
            .map(|(i, &(fed, bond))| CurveRow {
                fed,
                bond_stress: bond,
                ..row(i + 1, 2.0 * fed, bond)
            })
            .collect()
    }

    /// A straight curve does not bend (to rounding); a kink's bend is the scaled distance
    /// of its corner from the chord, and it asks for a step shorter by the
    /// square root of tolerance over bend.
    #[test]
    fn the_bend_is_the_corners_distance_from_the_chord() {
        let loading = loading();
        let rows = curve(&[(1e-5, 1.0), (2e-5, 2.0)]);
        let v = view(&rows, [2e-5, 1.0], [4e-5, 2.0]);
        let plan = displacement(2e-5);
        let mode = ControlMode::Displacement;
        let (d, _) = bend(&v, &plan, mode, 3e-5, 3.0, &loading).unwrap();
        assert!(d < 1e-12, "{d}");
        // Flat after the corner: the corner at (0.02, 2/2) off the chord
        // from (0.01, 0.5) to (0.03, 1).
        let (d, next) = bend(&v, &plan, mode, 3e-5, 2.0, &loading).unwrap();
        let expected = distance_to_segment([0.02, 1.0], [0.01, 0.5], [0.03, 1.0]);
        assert!((d - expected).abs() < 1e-12);
        let want = CURVE_SAFETY * (2e-5 * 2e-5 * loading.curve_tolerance / d).sqrt();
        assert!((next - want).abs() < 1e-18);
        // Off under path-following and with the tolerance 0.
        assert!(bend(&v, &plan, ControlMode::Energy, 3e-5, 2.0, &loading).is_none());
        let off = Loading {
            curve_tolerance: 0.0,
            ..loading
        };
        assert!(bend(&v, &plan, mode, 3e-5, 2.0, &off).is_none());
    }

    /// Along FED, the stress measure takes the σ_mb distance at the point's
    /// FED, which on a steep rise is many times the shortest distance.
    #[test]
    fn the_stress_measure_reads_the_error_along_fed() {
        let p = [0.5, 1.0];
        let (a, b) = ([0.0, 0.0], [0.6, 10.0]);
        let shortest = chord_deviation(CurveError::Distance, p, a, b);
        let along = chord_deviation(CurveError::Stress, p, a, b);
        assert!((along - (10.0 * 0.5 / 0.6 - 1.0)).abs() < 1e-12);
        assert!(along > 10.0 * shortest);
        // A FED standing still: both the shortest distance.
        let back = [0.7, 1.0];
        assert_eq!(
            chord_deviation(CurveError::Stress, back, a, b),
            chord_deviation(CurveError::Distance, back, a, b)
        );
    }

    /// A bend above twice the tolerance refuses the step with a shorter one
    /// (never below `initial_step`); at or below twice it, or at
    /// `initial_step`, the step is kept.
    #[test]
    fn a_bend_above_twice_the_tolerance_is_redone_shorter() {
        let loading = loading();
        let tol = loading.curve_tolerance;
        let refusal = check(4.0 * tol, &displacement(4e-5), &loading).unwrap();
        let Refusal::CurveResolution { next_step, .. } = refusal else {
            panic!("{refusal:?}")
        };
        assert!((next_step - CURVE_SAFETY * 4e-5 / 4.0).abs() < 1e-18);
        let floored = check(1e3 * tol, &displacement(2e-5), &loading).unwrap();
        let Refusal::CurveResolution { next_step, .. } = floored else {
            panic!()
        };
        assert_eq!(next_step, loading.initial_step);
        assert!(check(2.0 * tol, &displacement(2e-5), &loading).is_none());
        assert!(check(1.0, &displacement(loading.initial_step), &loading).is_none());
    }
}
