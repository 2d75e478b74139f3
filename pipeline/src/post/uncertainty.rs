//! Numerical uncertainty of every grid of a series of four or more grids by
//! least-squares fits, after the procedure of Eça & Hoekstra (2014), "A
//! procedure for the estimation of the numerical uncertainty of CFD
//! calculations based on grid refinement studies", J. Comput. Phys. 262,
//! 104–130.
//!
//! Celik's three-grid estimate (`convergence`) needs each triplet in its
//! asymptotic range; a series whose differences grow or scatter gets no
//! GCI from it. The least-squares form uses all grids at once and gives an
//! uncertainty for any series, with a larger safety factor where the data
//! do not behave:
//!
//! * Error estimate: φ_i − φ_0 = α h_i^p fitted to all grids (p > 0),
//!   unweighted and with weights w_i ∝ 1/h_i (the finer grids count more);
//!   the fit with the smaller standard deviation σ is kept. Where p < 0.5
//!   the series is not in its asymptotic range and the fit with the
//!   smallest σ among the fixed orders α h (p = 1), α h² (p = 2) and
//!   α₁ h + α₂ h² is taken instead. ε_i = |fit_i − φ_0|.
//! * σ = √(n Σ w_i (φ_i − fit_i)² / (n − q)), Σ w_i = 1, q the number of
//!   fitted parameters; the data range Δ = (φ_max − φ_min)/(n − 1).
//! * Safety factor F_s = 1.25 where 0.5 ≤ p < 2.1 and σ < Δ, 3 otherwise.
//! * U_i = F_s ε_i + σ + |φ_i − fit_i| where σ < Δ; otherwise (the fit
//!   misses the data by more than their spread)
//!   U_i = 3 σ/Δ (ε_i + σ + |φ_i − fit_i|).

use nalgebra::{DMatrix, DVector};

/// Range of orders searched for in the fit of unknown order.
const LOWEST_ORDER: f64 = 1e-3;
const MAX_ORDER: f64 = 8.0;

/// Which expansion the error estimate comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorFit {
    /// α h^p with the fitted order p.
    FittedOrder,
    /// α h.
    FirstOrder,
    /// α h².
    SecondOrder,
    /// α₁ h + α₂ h².
    FirstAndSecondOrder,
}

impl ErrorFit {
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorFit::FittedOrder => "a h^p",
            ErrorFit::FirstOrder => "a h",
            ErrorFit::SecondOrder => "a h^2",
            ErrorFit::FirstAndSecondOrder => "a h + b h^2",
        }
    }
}

/// The least-squares estimate of a series of four or more grids.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LeastSquaresEstimate {
    /// The fit the error estimate comes from.
    pub fit: ErrorFit,
    /// Whether that fit weights the grids by 1/h.
    pub weighted: bool,
    /// Order p of the fit of unknown order (also when a fixed-order fit
    /// was taken because it is below 0.5); None where the best p is the
    /// search's lower end: the differences grow under refinement and no
    /// positive order fits.
    pub order: Option<f64>,
    /// φ_0, the fit's value at h = 0.
    pub extrapolated: f64,
    /// Standard deviation σ of the kept fit, in the quantity's unit.
    pub standard_deviation: f64,
    /// Data range Δ = (φ_max − φ_min)/(n − 1), in the quantity's unit.
    pub data_range: f64,
    /// 1.25 or 3.
    pub safety_factor: f64,
    /// U_i of each grid in the order given, in the quantity's unit.
    pub uncertainty: Vec<f64>,
}

impl LeastSquaresEstimate {
    /// U_i/|φ_i| of the grid `i` (in the order given), None where φ_i = 0.
    pub fn relative(&self, i: usize, value: f64) -> Option<f64> {
        (value != 0.0).then(|| self.uncertainty[i] / value.abs())
    }
}

/// One least-squares fit of the grids.
#[derive(Debug, Clone)]
struct Fit {
    kind: ErrorFit,
    weighted: bool,
    phi0: f64,
    /// Fitted value at each grid.
    values: Vec<f64>,
    standard_deviation: f64,
}

/// The estimate for grids of distinct positive sizes `h` and finite
/// values `phi` (the same length); None with fewer than four grids (the
/// fit of unknown order has three parameters and needs one grid more to
/// measure its scatter).
pub fn least_squares_uncertainty(h: &[f64], phi: &[f64]) -> Option<LeastSquaresEstimate> {
    let n = h.len();
    if n < 4 || phi.len() != n {
        return None;
    }
    let max = phi.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = phi.iter().cloned().fold(f64::INFINITY, f64::min);
    let data_range = (max - min) / (n - 1) as f64;
    // Sizes scaled by the finest keep h^p in range for any unit.
    let h_min = h.iter().cloned().fold(f64::INFINITY, f64::min);
    let x: Vec<f64> = h.iter().map(|h| h / h_min).collect();
    let uniform = vec![1.0 / n as f64; n];
    let inverse_h: f64 = x.iter().map(|x| 1.0 / x).sum();
    let by_size: Vec<f64> = x.iter().map(|x| (1.0 / x) / inverse_h).collect();
    let weightings = [(false, &uniform), (true, &by_size)];

    let (fitted, order) = weightings
        .iter()
        .filter_map(|(weighted, w)| unknown_order_fit(&x, phi, w, *weighted))
        .min_by(|a, b| a.0.standard_deviation.total_cmp(&b.0.standard_deviation))?;
    let kept = if order < 0.5 {
        let kinds = [
            ErrorFit::FirstOrder,
            ErrorFit::SecondOrder,
            ErrorFit::FirstAndSecondOrder,
        ];
        let fixed: Vec<Fit> = weightings
            .iter()
            .flat_map(|(weighted, w)| {
                kinds
                    .iter()
                    .filter_map(|&kind| fixed_order_fit(&x, phi, w, *weighted, kind))
            })
            .collect();
        fixed
            .into_iter()
            .min_by(|a, b| a.standard_deviation.total_cmp(&b.standard_deviation))?
    } else {
        fitted
    };
    let sigma = kept.standard_deviation;
    let behaves = sigma < data_range;
    let safety_factor = if (0.5..2.1).contains(&order) && behaves {
        1.25
    } else {
        3.0
    };
    let uncertainty = phi
        .iter()
        .zip(&kept.values)
        .map(|(&value, &fit)| {
            let error = (fit - kept.phi0).abs();
            let miss = (value - fit).abs();
            if data_range == 0.0 {
                0.0
            } else if behaves {
                safety_factor * error + sigma + miss
            } else {
                3.0 * sigma / data_range * (error + sigma + miss)
            }
        })
        .collect();
    Some(LeastSquaresEstimate {
        fit: kept.kind,
        weighted: kept.weighted,
        order: (order > 2.0 * LOWEST_ORDER).then_some(order),
        extrapolated: kept.phi0,
        standard_deviation: sigma,
        data_range,
        safety_factor,
        uncertainty,
    })
}

/// Weighted linear least squares of φ on the basis functions `basis`
/// (φ_0's constant first): the coefficients, None if the basis is
/// degenerate on these grids. Solved by SVD of the √w-scaled design
/// matrix rather than by normal equations, whose conditioning is the
/// square of it (the columns 1 and h^p are nearly parallel for small p).
fn linear_fit(basis: &[Vec<f64>], phi: &[f64], w: &[f64]) -> Option<Vec<f64>> {
    let (n, m) = (phi.len(), basis.len());
    let design = DMatrix::from_fn(n, m, |k, i| w[k].sqrt() * basis[i][k]);
    let rhs = DVector::from_fn(n, |k, _| w[k].sqrt() * phi[k]);
    let svd = design.svd(true, true);
    let largest = svd.singular_values.max();
    if largest.is_nan() || largest <= 0.0 || svd.singular_values.min() <= 1e-12 * largest {
        return None;
    }
    let c = svd.solve(&rhs, 0.0).ok()?;
    Some(c.iter().copied().collect())
}

/// The fit with the basis `1, x^orders[0], …` and its standard deviation.
fn fit_with_orders(
    x: &[f64],
    phi: &[f64],
    w: &[f64],
    orders: &[f64],
    fitted_parameters: usize,
) -> Option<(f64, Vec<f64>, f64)> {
    let n = x.len();
    let mut basis = vec![vec![1.0; n]];
    basis.extend(
        orders
            .iter()
            .map(|&p| x.iter().map(|x| x.powf(p)).collect()),
    );
    let c = linear_fit(&basis, phi, w)?;
    let values: Vec<f64> = (0..n)
        .map(|k| (0..basis.len()).map(|i| c[i] * basis[i][k]).sum())
        .collect();
    let squares: f64 = (0..n).map(|k| w[k] * (phi[k] - values[k]).powi(2)).sum();
    let sigma = (n as f64 * squares / (n - fitted_parameters) as f64).sqrt();
    sigma.is_finite().then_some((c[0], values, sigma))
}

/// φ_0 + α x^p with p in (0, MAX_ORDER] minimising the weighted squares
/// (a scan in log p, then golden-section refinement around its best
/// point), and that p.
fn unknown_order_fit(x: &[f64], phi: &[f64], w: &[f64], weighted: bool) -> Option<(Fit, f64)> {
    let squares = |p: f64| fit_with_orders(x, phi, w, &[p], 3).map(|(_, _, s)| s);
    let samples = 400;
    let at = |i: usize| LOWEST_ORDER * (MAX_ORDER / LOWEST_ORDER).powf(i as f64 / samples as f64);
    let best = (0..=samples)
        .filter_map(|i| squares(at(i)).map(|s| (i, s)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(samples)));
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let c = b - ratio * (b - a);
        let d = a + ratio * (b - a);
        match (squares(c), squares(d)) {
            (Some(sc), Some(sd)) if sc <= sd => b = d,
            (Some(_), Some(_)) => a = c,
            _ => break,
        }
        if b - a <= 1e-12 * b {
            break;
        }
    }
    let p = 0.5 * (a + b);
    let (phi0, values, standard_deviation) = fit_with_orders(x, phi, w, &[p], 3)?;
    let fit = Fit {
        kind: ErrorFit::FittedOrder,
        weighted,
        phi0,
        values,
        standard_deviation,
    };
    Some((fit, p))
}

fn fixed_order_fit(
    x: &[f64],
    phi: &[f64],
    w: &[f64],
    weighted: bool,
    kind: ErrorFit,
) -> Option<Fit> {
    let orders: &[f64] = match kind {
        ErrorFit::FirstOrder => &[1.0],
        ErrorFit::SecondOrder => &[2.0],
        ErrorFit::FirstAndSecondOrder => &[1.0, 2.0],
        ErrorFit::FittedOrder => return None,
    };
    let (phi0, values, standard_deviation) = fit_with_orders(x, phi, w, orders, 1 + orders.len())?;
    Some(Fit {
        kind,
        weighted,
        phi0,
        values,
        standard_deviation,
    })
}
