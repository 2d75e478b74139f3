//! Discretisation error from a mesh series: observed order, Richardson
//! extrapolation and the Grid Convergence Index, following the procedure of
//! Celik, Ghia, Roache, Freitas, Coleman & Raad (2008), "Procedure for
//! estimation and reporting of uncertainty due to discretization in CFD
//! applications", J. Fluids Eng. 130(7), 078001.
//!
//! With grids 1 (finest) < 2 < 3 (coarsest) of representative sizes h_i and
//! values φ_i: r21 = h2/h1, r32 = h3/h2, ε21 = φ2 − φ1, ε32 = φ3 − φ2,
//! s = sign(ε32/ε21), and the observed order p solves
//!
//!   p ln r21 = ln|ε32/ε21| + q(p),   q(p) = ln((r21^p − s)/(r32^p − s)),
//!
//! by fixed-point iteration (q ≡ 0 when r21 = r32). Celik et al. write the
//! right-hand side inside an absolute value; that turns a series whose
//! differences grow under refinement into a spurious positive order, so
//! here the equation is solved as written above and a series without a
//! positive solution is reported as divergent instead.

use super::error::PostError;
use super::uncertainty::{least_squares_uncertainty, LeastSquaresEstimate};

/// Safety factor of the GCI for studies with three or more grids (Roache;
/// Celik et al. 2008, Eq. 8).
pub const GCI_SAFETY_FACTOR: f64 = 1.25;

/// Orders above this are not searched for: r^p would carry no information.
const MAX_ORDER: f64 = 64.0;

/// One grid of a mesh series.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GridResult {
    /// Representative cell size h, m (e.g. the interface element size, or
    /// (V/N)^(1/3)); only ratios of h matter.
    pub h: f64,
    /// The quantity of interest on this grid (any unit; the same for all).
    pub value: f64,
    /// Degrees of freedom, if known.
    pub dofs: Option<u64>,
    /// Wall time of the run, s, if known.
    pub wall_time: Option<f64>,
}

/// How a three-grid series behaves under refinement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ConvergenceKind {
    /// ε32 and ε21 have the same sign and a positive observed order exists.
    Monotonic,
    /// ε32/ε21 < 0: values alternate around the limit. Order and GCI are
    /// computed with s = −1 as Celik et al. do when a positive order
    /// exists, but deserve less trust; `half_range` is a model-free bound.
    Oscillatory,
    /// ε32 and ε21 have the same sign but no positive order fits: the
    /// differences do not shrink under refinement. Nothing is extrapolated.
    Divergent,
    /// All three values agree to round-off: no discretisation error seen.
    GridIndependent,
    /// Exactly one of ε21, ε32 vanishes: the order is undefined.
    Indeterminate,
}

impl ConvergenceKind {
    pub fn as_str(self) -> &'static str {
        match self {
            ConvergenceKind::Monotonic => "monotonic",
            ConvergenceKind::Oscillatory => "oscillatory",
            ConvergenceKind::Divergent => "divergent",
            ConvergenceKind::GridIndependent => "grid-independent",
            ConvergenceKind::Indeterminate => "indeterminate",
        }
    }
}

/// Celik's three-grid estimate for grids (fine, medium, coarse).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TripletEstimate {
    /// h1 < h2 < h3, m.
    pub h: [f64; 3],
    /// φ1, φ2, φ3.
    pub values: [f64; 3],
    /// r21 = h2/h1.
    pub r21: f64,
    /// r32 = h3/h2.
    pub r32: f64,
    pub kind: ConvergenceKind,
    /// Observed order p (None unless a positive finite order was found).
    pub order: Option<f64>,
    /// Richardson extrapolation φ_ext^21 = (r21^p φ1 − φ2)/(r21^p − 1).
    pub extrapolated: Option<f64>,
    /// Approximate relative error e_a^21 = |(φ1 − φ2)/φ1| (None if φ1 = 0).
    pub approx_rel_error: Option<f64>,
    /// Extrapolated relative error e_ext^21 = |(φ_ext − φ1)/φ_ext|.
    pub extrap_rel_error: Option<f64>,
    /// Fine-grid GCI^21 = 1.25 e_a^21 / (r21^p − 1), a relative uncertainty.
    pub gci_fine: Option<f64>,
    /// The same index for the medium grid: 1.25 e_a^32 / (r32^p − 1), with
    /// e_a^32 = |(φ2 − φ3)/φ2|.
    pub gci_medium: Option<f64>,
    /// ½ (max φ − min φ): the uncertainty Stern et al. (2001) use for
    /// oscillatory series, in the quantity's unit.
    pub half_range: f64,
}

/// A mesh series for one quantity with an estimate for every consecutive
/// triplet of grids.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ConvergenceStudy {
    /// Name of the quantity of interest (with its unit).
    pub quantity: String,
    /// Grids sorted from finest to coarsest.
    pub grids: Vec<GridResult>,
    /// `triplets[i]` uses grids i, i+1, i+2; `triplets[0]` is the finest.
    pub triplets: Vec<TripletEstimate>,
    /// The least-squares uncertainty of every grid (`uncertainty` module),
    /// from four grids on; its `uncertainty` follows `grids`.
    pub least_squares: Option<LeastSquaresEstimate>,
}

/// One line of a convergence table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ConvergenceRow {
    /// m
    pub h: f64,
    pub dofs: Option<u64>,
    pub value: f64,
    /// |φ_i − φ_ext| / |φ_ext| against the finest triplet's extrapolation.
    pub rel_error_vs_extrapolated: Option<f64>,
    /// GCI of this grid: the fine-grid GCI of the triplet it is the finest
    /// grid of; for the second-coarsest grid the coarsest triplet's
    /// `gci_medium`; none for the coarsest grid.
    pub gci: Option<f64>,
    /// U_i/|φ_i| of the least-squares estimate (four grids or more).
    pub uncertainty: Option<f64>,
    /// s
    pub wall_time: Option<f64>,
}

impl ConvergenceStudy {
    /// The estimate from the three finest grids.
    pub fn finest(&self) -> &TripletEstimate {
        &self.triplets[0]
    }

    /// Per-grid lines, finest first.
    pub fn rows(&self) -> Vec<ConvergenceRow> {
        let ext = self.finest().extrapolated;
        let n = self.grids.len();
        self.grids
            .iter()
            .enumerate()
            .map(|(i, g)| {
                let gci = if i + 2 < n {
                    self.triplets[i].gci_fine
                } else if i + 2 == n {
                    self.triplets[n - 3].gci_medium
                } else {
                    None
                };
                ConvergenceRow {
                    h: g.h,
                    dofs: g.dofs,
                    value: g.value,
                    rel_error_vs_extrapolated: ext
                        .filter(|e| *e != 0.0)
                        .map(|e| ((g.value - e) / e).abs()),
                    gci,
                    uncertainty: self
                        .least_squares
                        .as_ref()
                        .and_then(|e| e.relative(i, g.value)),
                    wall_time: g.wall_time,
                }
            })
            .collect()
    }
}

/// Checks and sorts a mesh series, then estimates every consecutive triplet.
/// Needs at least three grids with distinct positive sizes and finite values.
pub fn convergence_study(
    quantity: &str,
    grids: &[GridResult],
) -> Result<ConvergenceStudy, PostError> {
    let err = |problem: String| PostError::Convergence {
        quantity: quantity.to_string(),
        problem,
    };
    if grids.len() < 3 {
        return Err(err(format!("needs at least 3 grids, got {}", grids.len())));
    }
    for (i, g) in grids.iter().enumerate() {
        if !(g.h.is_finite() && g.h > 0.0) {
            return Err(err(format!("grid {i}: size h = {} m is not > 0", g.h)));
        }
        if !g.value.is_finite() {
            return Err(err(format!(
                "grid {i} (h = {} m): value is not finite",
                g.h
            )));
        }
        if let Some(t) = g.wall_time {
            if !(t.is_finite() && t >= 0.0) {
                return Err(err(format!("grid {i}: wall time {t} s is not ≥ 0")));
            }
        }
    }
    let mut sorted = grids.to_vec();
    sorted.sort_by(|a, b| a.h.total_cmp(&b.h));
    if let Some(w) = sorted.windows(2).find(|w| w[0].h == w[1].h) {
        return Err(err(format!("two grids share the size h = {} m", w[0].h)));
    }
    let triplets = sorted
        .windows(3)
        .map(|w| {
            three_grid_estimate(
                [w[0].h, w[1].h, w[2].h],
                [w[0].value, w[1].value, w[2].value],
            )
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| err(e.to_string()))?;
    Ok(ConvergenceStudy {
        quantity: quantity.to_string(),
        least_squares: least_squares_uncertainty(
            &sorted.iter().map(|g| g.h).collect::<Vec<_>>(),
            &sorted.iter().map(|g| g.value).collect::<Vec<_>>(),
        ),
        grids: sorted,
        triplets,
    })
}

/// Celik's procedure on three grids; `h` must be strictly increasing
/// (fine, medium, coarse), m; `values` are φ1, φ2, φ3.
pub fn three_grid_estimate(h: [f64; 3], values: [f64; 3]) -> Result<TripletEstimate, PostError> {
    let positive = h.iter().all(|x| x.is_finite() && *x > 0.0);
    if !(positive && h[0] < h[1] && h[1] < h[2]) {
        return Err(PostError::invalid(
            "grid sizes",
            format!("{h:?} m must be positive and strictly increasing (fine to coarse)"),
        ));
    }
    if !values.iter().all(|v| v.is_finite()) {
        return Err(PostError::invalid(
            "grid values",
            format!("{values:?} are not all finite"),
        ));
    }
    let [f1, f2, f3] = values;
    let r21 = h[1] / h[0];
    let r32 = h[2] / h[1];
    let e21 = f2 - f1;
    let e32 = f3 - f2;
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // Differences below a few ulps of the values are round-off, not signal.
    let tiny = 8.0 * f64::EPSILON * scale;
    let max = values.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = values.iter().cloned().fold(f64::INFINITY, f64::min);
    let rel = |a: f64, b: f64| (b != 0.0).then(|| ((a - b) / b).abs());
    let mut est = TripletEstimate {
        h,
        values,
        r21,
        r32,
        kind: ConvergenceKind::Indeterminate,
        order: None,
        extrapolated: None,
        approx_rel_error: rel(f2, f1),
        extrap_rel_error: None,
        gci_fine: None,
        gci_medium: None,
        half_range: 0.5 * (max - min),
    };
    let zero21 = e21.abs() <= tiny;
    let zero32 = e32.abs() <= tiny;
    if zero21 && zero32 {
        est.kind = ConvergenceKind::GridIndependent;
        est.extrapolated = Some(f1);
        est.extrap_rel_error = (f1 != 0.0).then_some(0.0);
        est.gci_fine = est.approx_rel_error.map(|_| 0.0);
        est.gci_medium = rel(f3, f2).map(|_| 0.0);
        return Ok(est);
    }
    if zero21 || zero32 {
        return Ok(est);
    }
    let s = (e32 / e21).signum();
    est.kind = if s > 0.0 {
        ConvergenceKind::Monotonic
    } else {
        ConvergenceKind::Oscillatory
    };
    let Some(p) = observed_order(r21, r32, (e32 / e21).abs().ln(), s) else {
        if s > 0.0 {
            est.kind = ConvergenceKind::Divergent;
        }
        return Ok(est);
    };
    let a21 = r21.powf(p);
    let a32 = r32.powf(p);
    let ext = (a21 * f1 - f2) / (a21 - 1.0);
    if !ext.is_finite() {
        if s > 0.0 {
            est.kind = ConvergenceKind::Divergent;
        }
        return Ok(est);
    }
    est.order = Some(p);
    est.extrapolated = Some(ext);
    est.extrap_rel_error = (ext != 0.0).then(|| ((ext - f1) / ext).abs());
    est.gci_fine = est
        .approx_rel_error
        .map(|ea| GCI_SAFETY_FACTOR * ea / (a21 - 1.0));
    est.gci_medium = rel(f3, f2).map(|ea| GCI_SAFETY_FACTOR * ea / (a32 - 1.0));
    Ok(est)
}

/// Positive root of g(p) = p ln r21 − ln|ε32/ε21| − q(p): fixed-point
/// iteration as in Celik et al., with bisection as a fallback when the
/// iteration leaves p > 0 or does not settle (it contracts only when
/// |q'(p)| < ln r21, which strongly unequal ratios can violate).
fn observed_order(r21: f64, r32: f64, ln_ratio: f64, s: f64) -> Option<f64> {
    let ln21 = r21.ln();
    let q = |p: f64| ((r21.powf(p) - s) / (r32.powf(p) - s)).ln();
    let g = |p: f64| p * ln21 - ln_ratio - q(p);
    let accept = |p: f64| {
        (p.is_finite() && p > 0.0 && p <= MAX_ORDER && g(p).abs() <= 1e-10 * (1.0 + p * ln21))
            .then_some(p)
    };

    let mut p = ln_ratio / ln21;
    for _ in 0..500 {
        if !(p.is_finite() && p > 0.0 && p <= MAX_ORDER) {
            break;
        }
        let next = (ln_ratio + q(p)) / ln21;
        if (next - p).abs() <= 1e-14 * p.abs().max(1.0) {
            if let Some(p) = accept(next) {
                return Some(p);
            }
            break;
        }
        p = next;
    }

    // Bisection on a bracket found by scanning (0, MAX_ORDER].
    let mut lo = 1e-9;
    let mut g_lo = g(lo);
    let mut hi = lo;
    let mut bracket = None;
    while hi < MAX_ORDER {
        hi = (hi * 2.0).min(MAX_ORDER);
        let g_hi = g(hi);
        if !g_hi.is_finite() {
            break;
        }
        if g_lo.is_finite() && g_lo.signum() != g_hi.signum() {
            bracket = Some((lo, hi, g_lo));
            break;
        }
        lo = hi;
        g_lo = g_hi;
    }
    let (mut a, mut b, mut g_a) = bracket?;
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        let g_m = g(m);
        if g_m == 0.0 || (b - a) <= 1e-15 * m {
            return accept(m);
        }
        if g_m.signum() == g_a.signum() {
            a = m;
            g_a = g_m;
        } else {
            b = m;
        }
    }
    accept(0.5 * (a + b))
}
