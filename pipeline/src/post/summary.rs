//! Scalar quantities of interest of one σ_mb–FED curve.
//!
//! The curve is read as the polyline through the unloaded state
//! (FED = 0, σ_mb = 0) followed by the converged steps in file order, i.e. a
//! piecewise-linear σ_mb(FED). All integrals are exact for that polyline
//! (trapezoidal rule), and follow the path in step order, so a step where
//! the free end moves back contributes with its sign.

use super::cell::Cell;
use super::curve::CurveRow;
use super::error::PostError;
use serde::{Deserialize, Serialize};

/// How the curve summary is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SummaryOptions {
    /// FED up to which the energy under the curve is integrated, m
    /// (`None`: up to the last step's FED).
    pub energy_fed_limit: Option<f64>,
    /// Fraction f ∈ (0, 1] of the final FED over which the residual σ_mb is
    /// averaged: the window is [(1 − f)·FED_end, FED_end]. Dimensionless.
    pub residual_fraction: f64,
}

impl Default for SummaryOptions {
    fn default() -> Self {
        SummaryOptions {
            energy_fed_limit: Some(1e-3),
            residual_fraction: 0.2,
        }
    }
}

/// Scalar summary of one curve (SI units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveSummary {
    /// Largest σ_mb over the curve, Pa.
    pub peak_bond_stress: f64,
    /// FED of the first step where the peak is reached, m.
    pub fed_at_peak: f64,
    /// Step number where the peak is reached.
    pub step_at_peak: usize,
    /// First (adhesion) peak σ_mb, Pa: see [`first_peak_bond_stress`].
    #[serde(default)]
    pub first_peak_bond_stress: f64,
    /// FED at the first peak, m.
    #[serde(default)]
    pub fed_at_first_peak: f64,
    /// ∫ σ_mb dFED from the unloaded state up to `energy_fed_limit`, J/m²
    /// (= Pa·m = N/m: work per unit bar–concrete contact area). `None` when
    /// the curve stops before that FED.
    pub energy: Option<f64>,
    /// FED up to which `energy` is integrated, m.
    pub energy_fed_limit: f64,
    /// Mean σ_mb over the last `residual_fraction` of the final FED, Pa.
    /// `None` when the final FED is not positive (the bar never slipped).
    pub residual_bond_stress: Option<f64>,
    /// Fraction of the final FED used for `residual_bond_stress`.
    pub residual_fraction: f64,
    /// FED of the last converged step, m.
    pub final_fed: f64,
    /// Largest FED reached, m.
    pub max_fed: f64,
    /// Converged steps in the curve.
    pub steps: usize,
    /// Newton iterations summed over the steps.
    pub total_iterations: usize,
}

impl CurveSummary {
    /// Entries for a study table, in a fixed order, with the unit in each
    /// name: stresses in MPa, displacements in mm, energy in J/m².
    pub fn table_entries(&self) -> Vec<(String, Cell)> {
        let num = |x: f64| Cell::Num(x);
        vec![
            (
                "peak_bond_stress_MPa".into(),
                num(self.peak_bond_stress * 1e-6),
            ),
            ("fed_at_peak_mm".into(), num(self.fed_at_peak * 1e3)),
            (
                "first_peak_bond_stress_MPa".into(),
                num(self.first_peak_bond_stress * 1e-6),
            ),
            (
                "fed_at_first_peak_mm".into(),
                num(self.fed_at_first_peak * 1e3),
            ),
            (
                format!("energy_to_{}mm_J_per_m2", fmt_mm(self.energy_fed_limit)),
                self.energy.map_or(Cell::Empty, Cell::Num),
            ),
            (
                "residual_bond_stress_MPa".into(),
                self.residual_bond_stress
                    .map_or(Cell::Empty, |r| Cell::Num(r * 1e-6)),
            ),
            ("final_fed_mm".into(), num(self.final_fed * 1e3)),
            ("steps".into(), Cell::Int(self.steps as i64)),
            ("iterations".into(), Cell::Int(self.total_iterations as i64)),
        ]
    }
}

fn fmt_mm(m: f64) -> String {
    // Shortest decimal that round-trips, so 1e-3 m prints as "1", 5e-4 as "0.5".
    format!("{}", (m * 1e3 * 1e9).round() / 1e9)
}

fn check_rows(rows: &[CurveRow]) -> Result<(), PostError> {
    if rows.is_empty() {
        return Err(PostError::invalid("curve", "has no steps"));
    }
    if let Some(r) = rows
        .iter()
        .find(|r| !r.fed.is_finite() || !r.bond_stress.is_finite())
    {
        return Err(PostError::invalid(
            format!("curve step {}", r.step),
            "FED or bond stress is not finite",
        ));
    }
    Ok(())
}

/// The polyline's vertices: the unloaded state then the steps, as (FED, σ_mb).
fn vertices(rows: &[CurveRow]) -> impl Iterator<Item = (f64, f64)> + '_ {
    std::iter::once((0.0, 0.0)).chain(rows.iter().map(|r| (r.fed, r.bond_stress)))
}

/// Peak σ_mb (Pa), the FED at it (m) and its step; the first step wins ties.
pub fn peak_bond_stress(rows: &[CurveRow]) -> Result<(f64, f64, usize), PostError> {
    check_rows(rows)?;
    let mut best = &rows[0];
    for r in rows {
        if r.bond_stress > best.bond_stress {
            best = r;
        }
    }
    Ok((best.bond_stress, best.fed, best.step))
}

/// Energy ∫ σ_mb dFED (J/m²) from the unloaded state until the curve first
/// reaches FED = `fed_limit` (m), linearly interpolated inside the last
/// segment. Errors if the curve never reaches `fed_limit`.
pub fn energy_to_fed(rows: &[CurveRow], fed_limit: f64) -> Result<f64, PostError> {
    check_rows(rows)?;
    if !(fed_limit.is_finite() && fed_limit > 0.0) {
        return Err(PostError::invalid(
            "energy FED limit",
            format!("{fed_limit} m must be finite and > 0"),
        ));
    }
    let mut energy = 0.0;
    let mut prev = (0.0, 0.0);
    for (fed, s) in vertices(rows).skip(1) {
        let (fed0, s0) = prev;
        if fed0 < fed_limit && fed >= fed_limit {
            let t = (fed_limit - fed0) / (fed - fed0);
            let s_lim = s0 + t * (s - s0);
            return Ok(energy + 0.5 * (s0 + s_lim) * (fed_limit - fed0));
        }
        energy += 0.5 * (s0 + s) * (fed - fed0);
        prev = (fed, s);
    }
    Err(PostError::FedLimitBeyondCurve {
        limit: fed_limit,
        final_fed: rows[rows.len() - 1].fed,
        max_fed: rows.iter().map(|r| r.fed).fold(f64::NEG_INFINITY, f64::max),
    })
}

/// Residual σ_mb (Pa): the mean of σ_mb over the window
/// [(1 − f)·FED_end, FED_end] along the curve's tail, i.e.
/// ∫ σ_mb |dFED| / ∫ |dFED| over the steps since the curve last entered the
/// window (from below, or from above after a snap-back in FED). An
/// FED-weighted mean, so it does not depend on how densely the solver
/// stepped; on a tail that rises monotonically it is
/// (1 / (f·FED_end)) ∫ σ_mb dFED. A tail that enters the window at its
/// end (a curve whose FED snaps back to near zero in one step) has no
/// length to average over, and its last σ_mb is the residual.
pub fn residual_bond_stress(rows: &[CurveRow], fraction: f64) -> Result<f64, PostError> {
    check_rows(rows)?;
    if !(fraction > 0.0 && fraction <= 1.0) {
        return Err(PostError::invalid(
            "residual fraction",
            format!("{fraction} must be in (0, 1]"),
        ));
    }
    let end = rows[rows.len() - 1].fed;
    if end <= 0.0 {
        return Err(PostError::invalid(
            "curve",
            format!("final FED {end} m is not positive: no residual window"),
        ));
    }
    let lower = (1.0 - fraction) * end;
    let inside = |fed: f64| (lower..=end).contains(&fed);
    let v: Vec<(f64, f64)> = vertices(rows).collect();
    let (mut integral, mut length) = (0.0, 0.0);
    for i in (1..v.len()).rev() {
        let (fed0, s0) = v[i - 1];
        let (fed1, s1) = v[i];
        if inside(fed0) {
            integral += 0.5 * (s0 + s1) * (fed1 - fed0).abs();
            length += (fed1 - fed0).abs();
            continue;
        }
        // The tail enters the window inside this segment, across the
        // bound on fed0's side.
        let bound = if fed0 < lower { lower } else { end };
        let t = (bound - fed0) / (fed1 - fed0);
        let s_bound = s0 + t * (s1 - s0);
        integral += 0.5 * (s_bound + s1) * (fed1 - bound).abs();
        length += (fed1 - bound).abs();
        break;
    }
    Ok(if length > 0.0 {
        integral / length
    } else {
        rows[rows.len() - 1].bond_stress
    })
}

/// Fraction of the running maximum σ_mb must fall below for that maximum to
/// count as the first (adhesion) peak.
pub const FIRST_PEAK_DROP: f64 = 0.05;

/// The first peak (Pa), its FED (m) and step: the running maximum up to the
/// first step where σ_mb has fallen more than [`FIRST_PEAK_DROP`] below it.
/// On a ribbed bar the frictional branch can rise above the adhesion peak
/// later; this is the peak of the bond's first failure. Without such a drop
/// it is the overall peak.
pub fn first_peak_bond_stress(rows: &[CurveRow]) -> Result<(f64, f64, usize), PostError> {
    check_rows(rows)?;
    let mut best = &rows[0];
    for r in rows {
        if r.bond_stress > best.bond_stress {
            best = r;
        } else if r.bond_stress < (1.0 - FIRST_PEAK_DROP) * best.bond_stress {
            break;
        }
    }
    Ok((best.bond_stress, best.fed, best.step))
}

/// Peak, energy, residual and counts of one curve.
pub fn summarize(rows: &[CurveRow], opts: &SummaryOptions) -> Result<CurveSummary, PostError> {
    check_rows(rows)?;
    let (peak, fed_at_peak, step_at_peak) = peak_bond_stress(rows)?;
    let (first_peak, fed_at_first_peak, _) = first_peak_bond_stress(rows)?;
    let final_fed = rows[rows.len() - 1].fed;
    let energy_fed_limit = opts.energy_fed_limit.unwrap_or(final_fed);
    if let Some(limit) = opts.energy_fed_limit {
        if !(limit.is_finite() && limit > 0.0) {
            return Err(PostError::invalid(
                "energy FED limit",
                format!("{limit} m must be finite and > 0"),
            ));
        }
    }
    if !(opts.residual_fraction > 0.0 && opts.residual_fraction <= 1.0) {
        return Err(PostError::invalid(
            "residual fraction",
            format!("{} must be in (0, 1]", opts.residual_fraction),
        ));
    }
    // A curve that stops before the bar slips (a run cut short) still gets
    // its peak and counts; the quantities it cannot define are absent.
    let energy = if energy_fed_limit > 0.0 {
        match energy_to_fed(rows, energy_fed_limit) {
            Ok(e) => Some(e),
            Err(PostError::FedLimitBeyondCurve { .. }) => None,
            Err(e) => return Err(e),
        }
    } else {
        None
    };
    let residual = if final_fed > 0.0 {
        Some(residual_bond_stress(rows, opts.residual_fraction)?)
    } else {
        None
    };
    Ok(CurveSummary {
        peak_bond_stress: peak,
        fed_at_peak,
        step_at_peak,
        first_peak_bond_stress: first_peak,
        fed_at_first_peak,
        energy,
        energy_fed_limit,
        residual_bond_stress: residual,
        residual_fraction: opts.residual_fraction,
        final_fed,
        max_fed: rows.iter().map(|r| r.fed).fold(f64::NEG_INFINITY, f64::max),
        steps: rows.len(),
        total_iterations: rows.iter().map(|r| r.iterations).sum(),
    })
}
