//! Sensitivity indices of a response to the parameters of a design.
//!
//! Sobol' indices from Saltelli's design (rows of A, B and A with column i
//! from B, AB_i), with the variance V of the responses at A and B together:
//!
//! - first order (Saltelli et al. 2010, their eq. (b) of Table 2):
//!   S1_i = (1/N) Σ_j f(B)_j (f(AB_i)_j − f(A)_j) / V
//! - total (Jansen 1999): ST_i = (1/2N) Σ_j (f(A)_j − f(AB_i)_j)² / V
//!
//! and their 95 % confidence half-widths 1.96 × the standard deviation of
//! the index over bootstrap resamples of the rows (as SALib states its
//! `S1_conf`, `ST_conf`).
//!
//! Morris's elementary effects EE_i = (f(x + Δ e_i) − f(x)) / Δ along
//! each trajectory, Δ in the unit cube's coordinates (so the effects carry
//! the response's unit per unit of the parameter's range): μ* = mean |EE|
//! (Campolongo et al. 2007), σ = their standard deviation, μ = their mean,
//! and μ*'s bootstrap half-width.

use super::cell::Cell;
use super::error::PostError;
use super::table::Table;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The normal quantile of a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

/// Bootstrap resamples of the confidence intervals.
pub const BOOTSTRAP_RESAMPLES: usize = 1000;

/// Sobol' indices of one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SobolIndex {
    pub s1: f64,
    pub s1_conf: f64,
    pub st: f64,
    pub st_conf: f64,
}

fn mean(x: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = x.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n as f64
}

fn std_dev(x: &[f64]) -> f64 {
    let m = mean(x.iter().copied());
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() as f64 - 1.0)).sqrt()
}

/// (S1, ST) of parameter `i` on the rows `rows` (indices into a, b, ab[i]).
fn sobol_point(a: &[f64], b: &[f64], ab: &[f64], rows: &[usize]) -> (f64, f64) {
    let all = rows.iter().flat_map(|&j| [a[j], b[j]]);
    let m = mean(all.clone());
    let variance = mean(all.map(|y| (y - m) * (y - m)));
    let s1 = mean(rows.iter().map(|&j| b[j] * (ab[j] - a[j]))) / variance;
    let st = 0.5 * mean(rows.iter().map(|&j| (a[j] - ab[j]) * (a[j] - ab[j]))) / variance;
    (s1, st)
}

/// Sobol' indices of every parameter from the responses at A, B and the
/// AB_i (`ab[i][j]`: parameter i, row j), with bootstrap confidence
/// intervals of `resamples` resamples seeded by `seed`.
pub fn sobol_indices(
    a: &[f64],
    b: &[f64],
    ab: &[Vec<f64>],
    resamples: usize,
    seed: u64,
) -> Result<Vec<SobolIndex>, PostError> {
    let n = a.len();
    if n < 2 || b.len() != n || ab.iter().any(|c| c.len() != n) {
        return Err(PostError::invalid(
            "Sobol' indices",
            format!("need at least 2 complete rows of A, B and each AB_i, found {n}"),
        ));
    }
    let all: Vec<usize> = (0..n).collect();
    let m = mean(a.iter().chain(b).copied());
    if a.iter().chain(b).all(|y| (y - m).abs() <= 1e-12 * m.abs()) {
        return Err(PostError::invalid(
            "Sobol' indices",
            "the response does not vary over the design (zero variance)",
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let draws: Vec<Vec<usize>> = (0..resamples)
        .map(|_| (0..n).map(|_| rng.random_range(0..n)).collect())
        .collect();
    Ok(ab
        .iter()
        .map(|abi| {
            let (s1, st) = sobol_point(a, b, abi, &all);
            let (boot_s1, boot_st): (Vec<f64>, Vec<f64>) = draws
                .iter()
                .map(|rows| sobol_point(a, b, abi, rows))
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .unzip();
            SobolIndex {
                s1,
                s1_conf: Z95 * std_dev(&boot_s1),
                st,
                st_conf: Z95 * std_dev(&boot_st),
            }
        })
        .collect())
}

/// Morris measures of one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MorrisIndex {
    pub mu_star: f64,
    pub sigma: f64,
    pub mu: f64,
    pub mu_star_conf: f64,
    /// Elementary effects the measures are from.
    pub effects: usize,
}

/// Morris measures of each parameter from its elementary effects
/// (`effects[i]`: the effects of parameter i over the trajectories that
/// have them); a parameter with fewer than 2 effects has none.
pub fn morris_indices(
    effects: &[Vec<f64>],
    resamples: usize,
    seed: u64,
) -> Vec<Option<MorrisIndex>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    effects
        .iter()
        .map(|e| {
            if e.len() < 2 {
                return None;
            }
            let abs: Vec<f64> = e.iter().map(|x| x.abs()).collect();
            let boot: Vec<f64> = (0..resamples)
                .map(|_| mean((0..abs.len()).map(|_| abs[rng.random_range(0..abs.len())])))
                .collect();
            Some(MorrisIndex {
                mu_star: mean(abs.iter().copied()),
                sigma: std_dev(e),
                mu: mean(e.iter().copied()),
                mu_star_conf: Z95 * std_dev(&boot),
                effects: e.len(),
            })
        })
        .collect()
}

/// sensitivity.csv of a Sobol' study: parameter, response, S1, S1_conf,
/// ST, ST_conf, and the rows the indices are from.
pub fn sobol_table(rows: &[(String, String, SobolIndex, usize)]) -> Table {
    Table {
        columns: [
            "parameter",
            "response",
            "S1",
            "S1_conf",
            "ST",
            "ST_conf",
            "rows",
        ]
        .map(String::from)
        .to_vec(),
        rows: rows
            .iter()
            .map(|(p, r, i, n)| {
                vec![
                    Cell::from(p.as_str()),
                    Cell::from(r.as_str()),
                    Cell::Num(i.s1),
                    Cell::Num(i.s1_conf),
                    Cell::Num(i.st),
                    Cell::Num(i.st_conf),
                    Cell::from(*n),
                ]
            })
            .collect(),
    }
}

/// sensitivity.csv of a Morris study: parameter, response, mu_star, sigma,
/// mu, mu_star_conf and the effects they are from.
pub fn morris_table(rows: &[(String, String, MorrisIndex)]) -> Table {
    Table {
        columns: [
            "parameter",
            "response",
            "mu_star",
            "sigma",
            "mu",
            "mu_star_conf",
            "effects",
        ]
        .map(String::from)
        .to_vec(),
        rows: rows
            .iter()
            .map(|(p, r, i)| {
                vec![
                    Cell::from(p.as_str()),
                    Cell::from(r.as_str()),
                    Cell::Num(i.mu_star),
                    Cell::Num(i.sigma),
                    Cell::Num(i.mu),
                    Cell::Num(i.mu_star_conf),
                    Cell::from(i.effects),
                ]
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An additive model y = 2 x1 + x2 on independent uniform inputs has
    /// S1 = ST = (4/5, 1/5): the estimators find them from plain random
    /// rows within their intervals.
    #[test]
    fn an_additive_model_has_equal_first_and_total_indices() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let n = 4000;
        let f = |x: [f64; 2]| 2.0 * x[0] + x[1];
        let (mut a, mut b, mut ab) = (Vec::new(), Vec::new(), vec![Vec::new(), Vec::new()]);
        for _ in 0..n {
            let xa: [f64; 2] = [rng.random(), rng.random()];
            let xb: [f64; 2] = [rng.random(), rng.random()];
            a.push(f(xa));
            b.push(f(xb));
            ab[0].push(f([xb[0], xa[1]]));
            ab[1].push(f([xa[0], xb[1]]));
        }
        let s = sobol_indices(&a, &b, &ab, 500, 1).unwrap();
        for (index, expected) in s.iter().zip([0.8, 0.2]) {
            assert!((index.s1 - expected).abs() <= index.s1_conf, "{s:?}");
            assert!((index.st - expected).abs() <= index.st_conf, "{s:?}");
            assert!(index.s1_conf < 0.12 && index.st_conf < 0.05, "{s:?}");
        }
        let err = sobol_indices(&[1.0; 4], &[1.0; 4], &[vec![1.0; 4]], 10, 0).unwrap_err();
        assert!(err.to_string().contains("zero variance"), "{err}");
    }

    /// μ*, σ and μ of known effects; fewer than two effects give none.
    #[test]
    fn morris_measures_of_known_effects() {
        let m = morris_indices(&[vec![1.0, -3.0], vec![2.0]], 100, 0);
        let first = m[0].unwrap();
        assert_eq!((first.mu_star, first.mu, first.effects), (2.0, -1.0, 2));
        assert!((first.sigma - 8f64.sqrt()).abs() < 1e-12);
        assert!(m[1].is_none());
    }
}
