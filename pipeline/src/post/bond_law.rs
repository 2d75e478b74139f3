//! The bond law a run implies: fib Model Code 2010's bond–slip form
//! (§6.1.1) fitted to σ_mb against the free-end displacement, and a
//! piecewise-linear law with a stated number of points.
//!
//! Both fits read the curve as σ_mb(FED): the polyline through the unloaded
//! state and the converged steps, with the FED held at its running maximum
//! where the free end moves back (a snap-back becomes a vertical segment,
//! of no width along the slip). Both minimise, and report as `fit_error`,
//! the relative L2 distance along the slip over the curve's range [0, X]:
//!
//!   ‖τ_law − σ_mb‖ / ‖σ_mb‖,  ‖f‖² = ∫₀^X f(s)² ds.
//!
//! ```
//! use pipeline::post::{fit_mc2010, CurveRow, Mc2010Law};
//!
//! // A curve that is an MC2010 law: the fit finds it again.
//! let law = Mc2010Law { tau_max: 8e6, s1: 0.4e-3, s2: 0.6e-3, s3: 1.2e-3, alpha: 0.4, tau_f: 3e6 };
//! let rows: Vec<CurveRow> = (1..=150)
//!     .map(|i| {
//!         let s = 1.5e-3 * i as f64 / 150.0;
//!         CurveRow::new(i, s, 0.0, s, law.stress(s), 1)
//!     })
//!     .collect();
//! let fit = fit_mc2010(&rows).unwrap();
//! assert!(fit.fit_error < 1e-2);
//! assert!((fit.law.tau_max / 8e6 - 1.0).abs() < 1e-2);
//! ```

use super::curve::CurveRow;
use super::error::PostError;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn, OMatrix, OVector, U6};
use serde::{Deserialize, Serialize};

/// The MC2010 bond–slip form, SI (Pa, m): τ = τ_max (s/s1)^α up to s1,
/// τ_max up to s2, a linear fall to τ_f at s3, τ_f after.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mc2010Law {
    pub tau_max: f64,
    pub s1: f64,
    pub s2: f64,
    pub s3: f64,
    pub alpha: f64,
    pub tau_f: f64,
}

impl Mc2010Law {
    /// τ at slip `s` (m), Pa.
    pub fn stress(&self, s: f64) -> f64 {
        let s = s.max(0.0);
        if s <= self.s1 {
            self.tau_max * (s / self.s1).powf(self.alpha)
        } else if s <= self.s2 {
            self.tau_max
        } else if s < self.s3 {
            self.tau_max - (self.tau_max - self.tau_f) * (s - self.s2) / (self.s3 - self.s2)
        } else {
            self.tau_f
        }
    }

    /// The law's kinks inside (0, x), m.
    fn knots(&self, x: f64) -> Vec<f64> {
        [self.s1, self.s2, self.s3]
            .into_iter()
            .filter(|&k| k > 0.0 && k < x)
            .collect()
    }
}

/// The MC2010 form fitted to a curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FittedMc2010 {
    #[serde(flatten)]
    pub law: Mc2010Law,
    /// Relative L2 distance along the slip from the law to the curve.
    pub fit_error: f64,
    /// Parameters the curve does not determine: it ends before the branch
    /// they shape (s3 and τ_f once it ends before s3, s2 too before s2).
    /// Their values are where the fit left them, not measured.
    pub unidentified: Vec<String>,
    /// Parameters that ended on a bound of the fit (see [`FIT_BOUNDS`]).
    pub at_bounds: Vec<String>,
}

/// The bounds of the MC2010 fit, in words; X is the largest FED of the
/// curve, σ_max its largest σ_mb.
pub const FIT_BOUNDS: &str = "tau_max in [1e-3, 2] sigma_max; s1 in [1e-3, 1] X; \
     s2 - s1 in [0, 2] X; s3 - s2 in [1e-3, 2] X; alpha in [0.02, 1]; tau_f in [0, 1] tau_max";

/// A piecewise-linear bond law through the origin, constant after its last
/// point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PiecewiseLaw {
    /// (slip m, τ Pa), the origin first.
    pub points: Vec<[f64; 2]>,
    /// Relative L2 distance along the slip from the law to the curve.
    pub fit_error: f64,
}

impl PiecewiseLaw {
    /// τ at slip `s` (m), Pa: linear between the points, the last point's
    /// τ beyond it.
    pub fn stress(&self, s: f64) -> f64 {
        interpolate(&self.points, s)
    }
}

/// Linear interpolation on vertices sorted by their first coordinate;
/// constant beyond the ends.
fn interpolate(v: &[[f64; 2]], s: f64) -> f64 {
    let j = v.partition_point(|p| p[0] <= s);
    if j == 0 {
        return v[0][1];
    }
    if j == v.len() {
        return v[v.len() - 1][1];
    }
    let ([a, ta], [b, tb]) = (v[j - 1], v[j]);
    if b > a {
        ta + (tb - ta) * (s - a) / (b - a)
    } else {
        tb
    }
}

/// Samples of the curve the fits minimise over: midpoints of equal slip
/// intervals (a midpoint rule for the integral along the slip).
const SAMPLES: usize = 400;

/// σ_mb(FED) as a polyline with non-decreasing FED: the unloaded state,
/// then each step with the FED held at its running maximum.
pub fn folded_curve(rows: &[CurveRow]) -> Result<Vec<[f64; 2]>, PostError> {
    if rows.is_empty() {
        return Err(PostError::invalid("bond law", "the curve has no steps"));
    }
    let mut v = vec![[0.0, 0.0]];
    let mut x = 0.0f64;
    for r in rows {
        if !(r.fed.is_finite() && r.bond_stress.is_finite()) {
            return Err(PostError::invalid(
                format!("bond law: curve step {}", r.step),
                "FED or bond stress is not finite",
            ));
        }
        x = x.max(r.fed);
        v.push([x, r.bond_stress]);
    }
    if x <= 0.0 {
        return Err(PostError::invalid(
            "bond law",
            "the free end never slipped (FED stays 0): no law of the slip to fit",
        ));
    }
    Ok(v)
}

/// σ along the folded curve at `s`, from the right of any vertical segment.
fn curve_at(v: &[[f64; 2]], s: f64) -> f64 {
    interpolate(v, s)
}

fn samples(v: &[[f64; 2]]) -> Vec<(f64, f64)> {
    let x = v[v.len() - 1][0];
    (0..SAMPLES)
        .map(|k| {
            let s = x * (k as f64 + 0.5) / SAMPLES as f64;
            (s, curve_at(v, s))
        })
        .collect()
}

/// ‖law − σ‖ / ‖σ‖ along the slip over the folded curve's range: Simpson's
/// rule on every interval between the curve's vertices and the law's
/// kinks, where both are smooth.
pub fn relative_l2(v: &[[f64; 2]], law: impl Fn(f64) -> f64, kinks: &[f64]) -> f64 {
    let x = v[v.len() - 1][0];
    let mut cuts: Vec<f64> = v
        .iter()
        .map(|p| p[0])
        .chain(kinks.iter().copied())
        .collect();
    cuts.retain(|&c| (0.0..=x).contains(&c));
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let (mut diff2, mut ref2) = (0.0, 0.0);
    const PARTS: usize = 8;
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        let h = (b - a) / PARTS as f64;
        // The curve on (a, b) is linear: evaluate it from inside.
        let (ca, cb) = (curve_inside(v, a, b, a), curve_inside(v, a, b, b));
        for i in 0..=PARTS {
            let s = a + h * i as f64;
            let weight = if i == 0 || i == PARTS {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            } * h
                / 3.0;
            let sigma = ca + (cb - ca) * (s - a) / (b - a);
            let t = law(s.clamp(a + 1e-12 * (b - a), b - 1e-12 * (b - a)));
            diff2 += weight * (t - sigma) * (t - sigma);
            ref2 += weight * sigma * sigma;
        }
    }
    if ref2 > 0.0 {
        (diff2 / ref2).sqrt()
    } else {
        f64::INFINITY
    }
}

/// The curve's value at `at` ∈ [a, b] on the segment that spans (a, b).
fn curve_inside(v: &[[f64; 2]], a: f64, b: f64, at: f64) -> f64 {
    let mid = 0.5 * (a + b);
    let j = v.partition_point(|p| p[0] <= mid).clamp(1, v.len() - 1);
    let ([x0, t0], [x1, t1]) = (v[j - 1], v[j]);
    if x1 > x0 {
        t0 + (t1 - t0) * (at - x0) / (x1 - x0)
    } else {
        t1
    }
}

/// The fit's parameters: τ_max, s1, s2 − s1, s3 − s2, α, τ_f/τ_max, each
/// mapped from an unbounded q by a logistic onto its bounds.
struct Bounds([(f64, f64); 6]);

impl Bounds {
    fn of(x: f64, sigma_max: f64) -> Bounds {
        Bounds([
            (1e-3 * sigma_max, 2.0 * sigma_max),
            (1e-3 * x, x),
            (0.0, 2.0 * x),
            (1e-3 * x, 2.0 * x),
            (0.02, 1.0),
            (0.0, 1.0),
        ])
    }

    fn value(&self, q: &OVector<f64, U6>) -> [f64; 6] {
        std::array::from_fn(|i| {
            let (lo, hi) = self.0[i];
            lo + (hi - lo) / (1.0 + (-q[i]).exp())
        })
    }

    fn unbounded(&self, p: [f64; 6]) -> OVector<f64, U6> {
        OVector::<f64, U6>::from_fn(|i, _| {
            let (lo, hi) = self.0[i];
            let t = ((p[i] - lo) / (hi - lo)).clamp(1e-6, 1.0 - 1e-6);
            (t / (1.0 - t)).ln()
        })
    }

    fn law(&self, q: &OVector<f64, U6>) -> Mc2010Law {
        let [tau_max, s1, d2, d3, alpha, ratio] = self.value(q);
        Mc2010Law {
            tau_max,
            s1,
            s2: s1 + d2,
            s3: s1 + d2 + d3,
            alpha,
            tau_f: ratio * tau_max,
        }
    }
}

const PARAMETER_NAMES: [&str; 6] = ["tau_max", "s1", "s2", "s3", "alpha", "tau_f"];

struct Mc2010Problem<'a> {
    samples: &'a [(f64, f64)],
    bounds: &'a Bounds,
    q: OVector<f64, U6>,
    /// Residuals are divided by this (σ scale × √samples), so the objective
    /// is the squared relative error.
    scale: f64,
}

impl Mc2010Problem<'_> {
    fn residuals_at(&self, q: &OVector<f64, U6>) -> OVector<f64, Dyn> {
        let law = self.bounds.law(q);
        OVector::<f64, Dyn>::from_iterator(
            self.samples.len(),
            self.samples
                .iter()
                .map(|&(s, sigma)| (law.stress(s) - sigma) / self.scale),
        )
    }
}

impl LeastSquaresProblem<f64, Dyn, U6> for Mc2010Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U6>;
    type ParameterStorage = Owned<f64, U6>;

    fn set_params(&mut self, q: &OVector<f64, U6>) {
        self.q.copy_from(q);
    }

    fn params(&self) -> OVector<f64, U6> {
        self.q
    }

    fn residuals(&self) -> Option<OVector<f64, Dyn>> {
        Some(self.residuals_at(&self.q))
    }

    /// Central differences in q: the law's branches switch at the knots,
    /// so its derivatives in s1, s2, s3 are one-sided there anyway.
    fn jacobian(&self) -> Option<OMatrix<f64, Dyn, U6>> {
        let mut j = OMatrix::<f64, Dyn, U6>::zeros(self.samples.len());
        for i in 0..6 {
            let h = 1e-6 * (1.0 + self.q[i].abs());
            let (mut up, mut down) = (self.q, self.q);
            up[i] += h;
            down[i] -= h;
            let column = (self.residuals_at(&up) - self.residuals_at(&down)) / (2.0 * h);
            j.set_column(i, &column);
        }
        Some(j)
    }
}

/// Fits the MC2010 form to σ_mb(FED) by bounded least squares
/// (Levenberg–Marquardt, MINPACK's, on the logistic images of the bounds
/// in [`FIT_BOUNDS`]) from a grid of starts around the curve's peaks; the
/// start whose fit is closest wins.
pub fn fit_mc2010(rows: &[CurveRow]) -> Result<FittedMc2010, PostError> {
    let v = folded_curve(rows)?;
    let x = v[v.len() - 1][0];
    let sigma_max = v.iter().map(|p| p[1]).fold(0.0, f64::max);
    if sigma_max <= 0.0 {
        return Err(PostError::invalid(
            "bond law",
            "σ_mb is never positive: no bond law to fit",
        ));
    }
    let data = samples(&v);
    let bounds = Bounds::of(x, sigma_max);
    let scale = sigma_max * (data.len() as f64).sqrt();
    let (peak_s, _) = data.iter().fold(
        (0.0, f64::NEG_INFINITY),
        |a, &(s, t)| if t > a.1 { (s, t) } else { a },
    );
    let first_peak = super::summary::first_peak_bond_stress(rows).map_or(peak_s, |(_, fed, _)| fed);
    let mut best: Option<(f64, Mc2010Law, OVector<f64, U6>)> = None;
    for s1 in [first_peak, peak_s, 0.1 * x, 0.5 * x, x] {
        for alpha in [0.15, 0.4, 0.8] {
            let start = [sigma_max, s1, 0.1 * x, 0.3 * x, alpha, 0.5];
            let problem = Mc2010Problem {
                samples: &data,
                bounds: &bounds,
                q: bounds.unbounded(start),
                scale,
            };
            let (problem, _report) = LevenbergMarquardt::new()
                .with_patience(200)
                .minimize(problem);
            let law = bounds.law(&problem.q);
            let error = relative_l2(&v, |s| law.stress(s), &law.knots(x));
            if error.is_finite() && best.as_ref().is_none_or(|b| error < b.0) {
                best = Some((error, law, problem.q));
            }
        }
    }
    let (fit_error, law, q) = best.ok_or_else(|| {
        PostError::invalid("bond law", "no start of the MC2010 fit gave a finite error")
    })?;
    Ok(FittedMc2010 {
        law,
        fit_error,
        unidentified: unidentified(&law, x),
        at_bounds: (0..6)
            .filter(|&i| q[i].abs() > 12.0)
            .map(|i| PARAMETER_NAMES[i].to_string())
            .collect(),
    })
}

/// The parameters of `law` that a curve ending at slip `x` does not
/// determine.
fn unidentified(law: &Mc2010Law, x: f64) -> Vec<String> {
    let names: &[&str] = if x <= law.s1 * (1.0 + 1e-9) {
        &["s2", "s3", "tau_f"]
    } else if x <= law.s2 {
        &["s3", "tau_f"]
    } else if x < law.s3 {
        // The fall's slope is seen, not where it ends.
        &["s3", "tau_f"]
    } else {
        &[]
    };
    names.iter().map(|s| s.to_string()).collect()
}

/// Fits a piecewise-linear law of `points` points (the origin, fixed at
/// τ = 0, included; at least 2) to σ_mb(FED): the slips are the curve's
/// vertices chosen one by one where the curve is farthest from the law
/// through the points chosen so far (from the origin and the curve's end),
/// then the τ of the points by linear least squares along the slip.
pub fn fit_piecewise(rows: &[CurveRow], points: usize) -> Result<PiecewiseLaw, PostError> {
    if points < 2 {
        return Err(PostError::invalid(
            "piecewise bond law",
            format!("{points} points: at least 2 (the origin and one more)"),
        ));
    }
    let v = folded_curve(rows)?;
    let slips = breakpoints(&v, points);
    let data = samples(&v);
    // Hat functions of the points after the origin.
    let m = slips.len() - 1;
    let basis = DMatrix::<f64>::from_fn(data.len(), m, |r, c| {
        let mut knots: Vec<[f64; 2]> = slips.iter().map(|&s| [s, 0.0]).collect();
        knots[c + 1][1] = 1.0;
        interpolate(&knots, data[r].0)
    });
    let target = DVector::<f64>::from_iterator(data.len(), data.iter().map(|d| d.1));
    let tau = basis
        .svd(true, true)
        .solve(&target, 1e-12)
        .map_err(|e| PostError::invalid("piecewise bond law", e.to_string()))?;
    let mut law_points = vec![[0.0, 0.0]];
    law_points.extend(slips[1..].iter().zip(tau.iter()).map(|(&s, &t)| [s, t]));
    let fit_error = relative_l2(&v, |s| interpolate(&law_points, s), &slips);
    Ok(PiecewiseLaw {
        points: law_points,
        fit_error,
    })
}

/// Up to `n` distinct slips of the folded curve's vertices, the origin and
/// the end first, each next one where the curve is farthest (in σ) from the
/// polyline through the curve at those chosen.
fn breakpoints(v: &[[f64; 2]], n: usize) -> Vec<f64> {
    // One vertex per slip: the last, where a vertical segment ends.
    let mut distinct: Vec<[f64; 2]> = Vec::new();
    for p in v {
        match distinct.last_mut() {
            Some(last) if last[0] == p[0] => *last = *p,
            _ => distinct.push(*p),
        }
    }
    distinct[0] = [0.0, 0.0];
    let mut chosen = vec![0, distinct.len() - 1];
    while chosen.len() < n.min(distinct.len()) {
        let through: Vec<[f64; 2]> = chosen.iter().map(|&i| distinct[i]).collect();
        let farthest = (0..distinct.len())
            .filter(|i| !chosen.contains(i))
            .max_by(|&a, &b| {
                let d = |i: usize| (distinct[i][1] - interpolate(&through, distinct[i][0])).abs();
                d(a).total_cmp(&d(b))
            });
        let Some(i) = farthest else { break };
        let at = chosen.partition_point(|&c| c < i);
        chosen.insert(at, i);
    }
    chosen.iter().map(|&i| distinct[i][0]).collect()
}

/// The bond-law columns of a study table from a case's summary.json: the
/// fitted MC2010 law (MPa, mm), its error, the piecewise law's error, the
/// fitted τ_max as a share of 2.5 √f_cm and the bar's f_R; a column the
/// summary lacks is left out.
pub fn bond_law_entries(summary: &serde_json::Value) -> Vec<(String, super::cell::Cell)> {
    const COLUMNS: [(&str, &str, f64); 10] = [
        ("mc2010_tau_max_MPa", "/bond_law/mc2010/tau_max", 1e-6),
        ("mc2010_s1_mm", "/bond_law/mc2010/s1", 1e3),
        ("mc2010_s2_mm", "/bond_law/mc2010/s2", 1e3),
        ("mc2010_s3_mm", "/bond_law/mc2010/s3", 1e3),
        ("mc2010_alpha", "/bond_law/mc2010/alpha", 1.0),
        ("mc2010_tau_f_MPa", "/bond_law/mc2010/tau_f", 1e-6),
        ("mc2010_fit_error", "/bond_law/mc2010/fit_error", 1.0),
        (
            "piecewise_fit_error",
            "/bond_law/piecewise_linear/fit_error",
            1.0,
        ),
        ("tau_max_ratio", "/design_code/tau_max_ratio", 1.0),
        ("f_R", "/geometry/f_R", 1.0),
    ];
    COLUMNS
        .iter()
        .filter_map(|(name, pointer, scale)| {
            let x = summary.pointer(pointer)?.as_f64()?;
            Some((name.to_string(), super::cell::Cell::Num(x * scale)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(points: &[(f64, f64)]) -> Vec<CurveRow> {
        points
            .iter()
            .enumerate()
            .map(|(i, &(s, t))| CurveRow::new(i + 1, s, 0.0, s, t, 1))
            .collect()
    }

    fn sampled(law: &Mc2010Law, end: f64, n: usize) -> Vec<CurveRow> {
        let pts: Vec<(f64, f64)> = (1..=n)
            .map(|i| {
                let s = end * i as f64 / n as f64;
                (s, law.stress(s))
            })
            .collect();
        curve(&pts)
    }

    /// The error along the slip of `law` itself against the polyline
    /// through its samples (the polyline's chords under s^α near 0).
    fn own_error(law: &Mc2010Law, rows: &[CurveRow]) -> f64 {
        let v = folded_curve(rows).unwrap();
        relative_l2(&v, |s| law.stress(s), &law.knots(v[v.len() - 1][0]))
    }

    /// The fit recovers all six parameters of a curve that is an MC2010
    /// law reaching past s3, no farther from the curve than the law itself
    /// and with nothing flagged.
    #[test]
    fn the_fit_recovers_an_mc2010_curve() {
        let law = Mc2010Law {
            tau_max: 12e6,
            s1: 0.3e-3,
            s2: 0.5e-3,
            s3: 1.1e-3,
            alpha: 0.35,
            tau_f: 4.8e6,
        };
        let rows = sampled(&law, 1.6e-3, 300);
        let fit = fit_mc2010(&rows).unwrap();
        assert!(fit.fit_error <= 1.01 * own_error(&law, &rows), "{fit:?}");
        for (got, want) in [
            (fit.law.tau_max, law.tau_max),
            (fit.law.s1, law.s1),
            (fit.law.s2, law.s2),
            (fit.law.s3, law.s3),
            (fit.law.alpha, law.alpha),
            (fit.law.tau_f, law.tau_f),
        ] {
            assert!((got / want - 1.0).abs() < 2e-2, "{fit:?}");
        }
        assert!(
            fit.unidentified.is_empty() && fit.at_bounds.is_empty(),
            "{fit:?}"
        );
    }

    /// A curve that ends on its plateau determines τ_max, s1 and α but not
    /// the fall: s3 and τ_f are named unidentified.
    #[test]
    fn a_curve_that_ends_early_names_what_it_does_not_determine() {
        let law = Mc2010Law {
            tau_max: 10e6,
            s1: 0.4e-3,
            s2: 2e-3,
            s3: 3e-3,
            alpha: 0.4,
            tau_f: 4e6,
        };
        let rows = sampled(&law, 1e-3, 200);
        let fit = fit_mc2010(&rows).unwrap();
        assert!(fit.fit_error <= 1.01 * own_error(&law, &rows), "{fit:?}");
        assert!((fit.law.tau_max / 10e6 - 1.0).abs() < 1e-2, "{fit:?}");
        assert!((fit.law.alpha / 0.4 - 1.0).abs() < 2e-2, "{fit:?}");
        assert_eq!(fit.unidentified, ["s3", "tau_f"], "{fit:?}");
    }

    /// An adhesion peak followed by a frictional rise is not the MC2010
    /// shape: the fit's error says so (well above that of an MC2010
    /// curve).
    #[test]
    fn an_adhesion_peak_before_a_frictional_rise_shows_in_the_error() {
        let mut pts = Vec::new();
        for i in 1..=200 {
            let s = 1e-3 * i as f64 / 200.0;
            // 5.7 MPa at 0.04 mm, down to 2.7 at 0.35 mm, up to 6 at 1 mm.
            let adhesion =
                5.7e6 * (s / 4e-5).min(1.0).powf(0.5) * (-(s - 4e-5).max(0.0) / 1.5e-4).exp();
            let friction = 2.7e6 * (s / 3.5e-4).min(1.0) + 5e6 * (s - 3.5e-4).max(0.0);
            pts.push((s, adhesion.max(friction)));
        }
        let fit = fit_mc2010(&curve(&pts)).unwrap();
        assert!(fit.fit_error > 0.08, "{fit:?}");
    }

    /// The piecewise law interpolates a polyline it has enough points for
    /// exactly, and its error falls as points are added to a curved one.
    #[test]
    fn the_piecewise_law_converges_with_its_points() {
        let exact = curve(&[(1e-4, 5e6), (3e-4, 2e6), (1e-3, 6e6)]);
        let law = fit_piecewise(&exact, 4).unwrap();
        assert!(law.fit_error < 1e-9, "{law:?}");
        assert_eq!(law.points.len(), 4);
        assert_eq!(law.points[0], [0.0, 0.0]);
        let smooth = sampled(
            &Mc2010Law {
                tau_max: 9e6,
                s1: 0.6e-3,
                s2: 0.7e-3,
                s3: 1.2e-3,
                alpha: 0.4,
                tau_f: 3e6,
            },
            1.5e-3,
            300,
        );
        let errors: Vec<f64> = [3, 5, 9, 17]
            .iter()
            .map(|&n| fit_piecewise(&smooth, n).unwrap().fit_error)
            .collect();
        assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
        assert!(errors[3] < 0.02, "{errors:?}");
    }

    /// The error along the slip is zero for the curve itself and equals
    /// the exact relative L2 norm for a constant offset of a constant
    /// curve.
    #[test]
    fn the_relative_l2_along_the_slip_is_exact_on_polylines() {
        let v = folded_curve(&curve(&[(1e-3, 4e6), (2e-3, 4e6)])).unwrap();
        assert!(relative_l2(&v, |s| curve_at(&v, s), &[]) < 1e-12);
        // σ = 4e6 s/1e-3 on [0, 1 mm], 4e6 on [1, 2 mm]; law = σ + 1e6.
        let err = relative_l2(&v, |s| curve_at(&v, s) + 1e6, &[]);
        let norm2: f64 = 16e12 * (1e-3 / 3.0 + 1e-3);
        let expected = (1e12 * 2e-3 / norm2).sqrt();
        assert!((err / expected - 1.0).abs() < 1e-9, "{err} {expected}");
    }

    /// A curve whose free end never moves has no law of the slip.
    #[test]
    fn no_slip_no_law() {
        let err = fit_mc2010(&curve(&[(0.0, 1e6), (0.0, 2e6)]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("never slipped"), "{err}");
        assert!(fit_piecewise(&curve(&[(1e-3, 1e6)]), 1).is_err());
    }
}
