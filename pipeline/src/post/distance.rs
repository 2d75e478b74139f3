//! Distance between two σ_mb curves: how far a run is from a reference run
//! (a finer mesh, a tighter tolerance) as one number.

use super::curve::CurveRow;
use super::error::PostError;

/// The abscissa two curves are compared along.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveAxis {
    /// Free-end displacement, as plotted. The pre-slip branch, where the
    /// free end has not moved yet, has zero width along this axis and does
    /// not count.
    Fed,
    /// Imposed loaded-end displacement: monotone by construction, so every
    /// converged step counts, including the pre-slip branch.
    ImposedDisplacement,
}

impl CurveAxis {
    fn name(self) -> &'static str {
        match self {
            CurveAxis::Fed => "free-end displacement",
            CurveAxis::ImposedDisplacement => "imposed displacement",
        }
    }

    fn of(self, r: &CurveRow) -> f64 {
        match self {
            CurveAxis::Fed => r.fed,
            CurveAxis::ImposedDisplacement => r.u_imposed,
        }
    }
}

/// How far, in all, a curve's abscissa may step back, as a share of its
/// largest value, for the recessions to be folded into the curve.
///
/// Measured on the FED of this project's study curves (51 distinct curves
/// that step back at all): 11 step back by 0.04–21 nm in all, at most
/// 9.6e-4 of their range (IMPL-EX and implicit runs alike); the other
/// 40 go back 1.4 µm and more, 4.7e-2 of the range and up (37 of them in
/// runs that end at a brittle failure or unloaded). The share sits between the
/// two. Folded, a recession is an interval of no width, as the pre-slip
/// branch is along FED: the distance leaves out the σ of at most that
/// share of the range.
pub const FOLDED_RECESSION_SHARE: f64 = 3e-3;

/// Vertices (x, σ) from the unloaded state on, with x made non-decreasing:
/// a step back is folded (x kept at its running maximum) while the depths
/// of all steps back add up to no more than `FOLDED_RECESSION_SHARE` of the
/// curve's range; beyond that it is refused, as σ(x) would not be a
/// function.
fn polyline(rows: &[CurveRow], axis: CurveAxis, name: &str) -> Result<Vec<(f64, f64)>, PostError> {
    if rows.is_empty() {
        return Err(PostError::invalid(
            format!("curve `{name}`"),
            "has no steps",
        ));
    }
    let scale = rows.iter().map(|r| axis.of(r).abs()).fold(0.0, f64::max);
    let allowed = FOLDED_RECESSION_SHARE * scale;
    let mut v = vec![(0.0, 0.0)];
    let mut x_max = 0.0f64;
    // The lowest abscissa of the recession under way, and the depth of
    // the finished ones.
    let mut low: Option<f64> = None;
    let mut folded = 0.0;
    for r in rows {
        let (x, s) = (axis.of(r), r.bond_stress);
        if !(x.is_finite() && s.is_finite()) {
            return Err(PostError::invalid(
                format!("curve `{name}` step {}", r.step),
                "abscissa or bond stress is not finite",
            ));
        }
        if x < x_max - 1e-9 * scale {
            let lowest = low.map_or(x, |l| l.min(x));
            low = Some(lowest);
            if folded + (x_max - lowest) > allowed {
                return Err(PostError::invalid(
                    format!("curve `{name}` step {}", r.step),
                    format!(
                        "the {} goes back from {x_max:.6e} m to {x:.6e} m, {:.1e} of its range \
                         in all (up to {FOLDED_RECESSION_SHARE:e} is folded): σ_mb is not a \
                         function of it, so the distance along it is not defined{}",
                        axis.name(),
                        (folded + x_max - lowest) / scale,
                        match axis {
                            CurveAxis::Fed => "; compare along the imposed displacement",
                            CurveAxis::ImposedDisplacement => "",
                        }
                    ),
                ));
            }
        } else if let Some(lowest) = low.take() {
            folded += x_max - lowest;
        }
        x_max = x_max.max(x);
        v.push((x_max, s));
    }
    Ok(v)
}

/// σ on (x0, x1), an interval free of the curve's vertices, evaluated from
/// inside it (so vertical jumps at x0 or x1 take the interval's side).
fn on_interval(v: &[(f64, f64)], x0: f64, x1: f64) -> (f64, f64) {
    let j = v.partition_point(|p| p.0 <= x0).saturating_sub(1);
    let j = j.min(v.len() - 2);
    let ((a, sa), (b, sb)) = (v[j], v[j + 1]);
    let at = |x: f64| {
        if b > a {
            sa + (sb - sa) * (x - a) / (b - a)
        } else {
            sb
        }
    };
    (at(x0), at(x1))
}

/// Relative L2 distance between two piecewise-linear curves σ(x):
///
///   ‖σ_test − σ_ref‖ / ‖σ_ref‖,  ‖f‖² = ∫₀^X f(x)² dx,
///
/// with X the smaller of the two curves' final abscissae (and of `x_max`,
/// m, if given). Both curves start at the unloaded state (0, 0). The
/// integral is exact for the polylines (the difference is linear between
/// merged breakpoints: ∫ d² = Δx (d₀² + d₀d₁ + d₁²)/3). Dimensionless.
pub fn curve_distance(
    test: &[CurveRow],
    reference: &[CurveRow],
    axis: CurveAxis,
    x_max: Option<f64>,
) -> Result<f64, PostError> {
    let a = polyline(test, axis, "test")?;
    let b = polyline(reference, axis, "reference")?;
    let mut end = a[a.len() - 1].0.min(b[b.len() - 1].0);
    if let Some(m) = x_max {
        if !(m.is_finite() && m > 0.0) {
            return Err(PostError::invalid(
                "curve distance range",
                format!("{m} m must be > 0"),
            ));
        }
        end = end.min(m);
    }
    if end <= 0.0 {
        return Err(PostError::invalid(
            "curve distance",
            format!("the curves share no {axis:?} range beyond 0"),
        ));
    }
    let mut xs: Vec<f64> = a
        .iter()
        .chain(&b)
        .map(|p| p.0)
        .filter(|&x| x < end)
        .collect();
    xs.push(end);
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let (mut diff2, mut ref2) = (0.0, 0.0);
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        let (a0, a1) = on_interval(&a, x0, x1);
        let (b0, b1) = on_interval(&b, x0, x1);
        let sq = |f0: f64, f1: f64| (x1 - x0) * (f0 * f0 + f0 * f1 + f1 * f1) / 3.0;
        diff2 += sq(a0 - b0, a1 - b1);
        ref2 += sq(b0, b1);
    }
    if ref2 <= 0.0 {
        return Err(PostError::invalid(
            "curve distance",
            "the reference curve is zero on the range",
        ));
    }
    Ok((diff2 / ref2).sqrt())
}
