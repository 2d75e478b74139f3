//! The named responses of a sampled or sensitivity study: scalars of each
//! case's summary.json (the curve's peaks and energy, the fitted bond
//! law) and σ_mb at a given slip from its curve, in SI.
//!
//! ```yaml
//! responses: [first_peak_bond_stress, energy, {bond_stress_at_slip: 0.5 mm}]
//! ```

use crate::post::CurveRow;
use geom::units::{Dim, RawQuantity};
use serde_json::Value as Json;
use serde_yaml::Value;

/// The responses read from summary.json: name, JSON pointer, SI unit.
pub const SUMMARY_RESPONSES: [(&str, &str, &str); 14] = [
    (
        "first_peak_bond_stress",
        "/curve/first_peak_bond_stress",
        "Pa",
    ),
    ("fed_at_first_peak", "/curve/fed_at_first_peak", "m"),
    ("peak_bond_stress", "/curve/peak_bond_stress", "Pa"),
    ("fed_at_peak", "/curve/fed_at_peak", "m"),
    ("energy", "/curve/energy", "J/m^2"),
    ("residual_bond_stress", "/curve/residual_bond_stress", "Pa"),
    ("mc2010_tau_max", "/bond_law/mc2010/tau_max", "Pa"),
    ("mc2010_s1", "/bond_law/mc2010/s1", "m"),
    ("mc2010_s2", "/bond_law/mc2010/s2", "m"),
    ("mc2010_s3", "/bond_law/mc2010/s3", "m"),
    ("mc2010_alpha", "/bond_law/mc2010/alpha", "1"),
    ("mc2010_tau_f", "/bond_law/mc2010/tau_f", "Pa"),
    ("mc2010_fit_error", "/bond_law/mc2010/fit_error", "1"),
    ("tau_max_ratio", "/design_code/tau_max_ratio", "1"),
];

/// The slip of the default σ_mb-at-slip response, m: the RILEM/CEB bond
/// test's τ_0.1.
pub const DEFAULT_RESPONSE_SLIP: f64 = 1e-4;

/// One response of a study.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// An entry of [`SUMMARY_RESPONSES`].
    Summary(usize),
    /// σ_mb where the free end first reaches this slip, m.
    BondStressAtSlip(f64),
}

impl Response {
    pub fn name(&self) -> String {
        match self {
            Response::Summary(i) => SUMMARY_RESPONSES[*i].0.to_string(),
            Response::BondStressAtSlip(s) => {
                format!("bond_stress_at_{}mm", (s * 1e3 * 1e9).round() / 1e9)
            }
        }
    }

    pub fn unit(&self) -> &'static str {
        match self {
            Response::Summary(i) => SUMMARY_RESPONSES[*i].2,
            Response::BondStressAtSlip(_) => "Pa",
        }
    }

    /// The response of one case from its summary.json and curve; `None`
    /// where the case does not define it (an energy to a FED the curve
    /// never reaches, a bond-law parameter the curve does not determine).
    pub fn value(&self, summary: &Json, curve: &[CurveRow]) -> Option<f64> {
        match self {
            Response::Summary(i) => {
                let (name, pointer, _) = SUMMARY_RESPONSES[*i];
                if let Some(parameter) = name.strip_prefix("mc2010_") {
                    let unidentified = summary.pointer("/bond_law/mc2010/unidentified")?;
                    let listed = unidentified
                        .as_array()
                        .is_some_and(|a| a.iter().any(|p| p.as_str() == Some(parameter)));
                    if listed {
                        return None;
                    }
                }
                summary.pointer(pointer)?.as_f64().filter(|x| x.is_finite())
            }
            Response::BondStressAtSlip(s) => stress_at_slip(curve, *s),
        }
    }
}

/// σ_mb where the FED first reaches `slip`, interpolated in the step.
pub fn stress_at_slip(rows: &[CurveRow], slip: f64) -> Option<f64> {
    let mut previous = (0.0, 0.0);
    for r in rows {
        if r.fed >= slip {
            let (f0, s0) = previous;
            return Some(if r.fed > f0 {
                s0 + (r.bond_stress - s0) * (slip - f0) / (r.fed - f0)
            } else {
                r.bond_stress
            });
        }
        previous = (r.fed, r.bond_stress);
    }
    None
}

/// Every response, for a study that names none.
pub fn all_responses() -> Vec<Response> {
    let mut all: Vec<Response> = (0..SUMMARY_RESPONSES.len())
        .map(Response::Summary)
        .collect();
    all.insert(6, Response::BondStressAtSlip(DEFAULT_RESPONSE_SLIP));
    all
}

/// Reads `responses:` (names, or `{bond_stress_at_slip: length}`); absent,
/// every response.
pub fn parse_responses(raw: Option<&[Value]>) -> Result<Vec<Response>, String> {
    let Some(raw) = raw else {
        return Ok(all_responses());
    };
    if raw.is_empty() {
        return Err("responses: empty; leave it out for every response".into());
    }
    let known = || {
        let mut names: Vec<&str> = SUMMARY_RESPONSES.iter().map(|r| r.0).collect();
        names.push("{bond_stress_at_slip: LENGTH}");
        names.join(", ")
    };
    let mut out = Vec::new();
    for item in raw {
        let response = match item {
            Value::String(name) => SUMMARY_RESPONSES
                .iter()
                .position(|r| r.0 == name)
                .map(Response::Summary)
                .ok_or_else(|| {
                    format!("responses: unknown response {name:?} (known: {})", known())
                })?,
            Value::Mapping(m) if m.len() == 1 && m.contains_key("bond_stress_at_slip") => {
                let q: RawQuantity = serde_yaml::from_value(m["bond_stress_at_slip"].clone())
                    .map_err(|e| format!("responses: bond_stress_at_slip: {e}"))?;
                let s = q
                    .to_si(Dim::Length, "responses.bond_stress_at_slip")
                    .map_err(|e| e.to_string())?;
                if s <= 0.0 {
                    return Err(format!("responses: bond_stress_at_slip: {s} m must be > 0"));
                }
                Response::BondStressAtSlip(s)
            }
            other => {
                return Err(format!(
                    "responses: cannot read {other:?} as a response (known: {})",
                    known()
                ))
            }
        };
        if out.contains(&response) {
            return Err(format!("responses: {} is listed twice", response.name()));
        }
        out.push(response);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names and slips are read, unknown names listed with the known ones,
    /// and the default is every response.
    #[test]
    fn responses_are_read_by_name() {
        let raw: Vec<Value> =
            serde_yaml::from_str("[first_peak_bond_stress, {bond_stress_at_slip: 0.5 mm}]")
                .unwrap();
        let r = parse_responses(Some(&raw)).unwrap();
        assert_eq!(r[0].name(), "first_peak_bond_stress");
        assert_eq!(r[1].name(), "bond_stress_at_0.5mm");
        let bad: Vec<Value> = serde_yaml::from_str("[peak]").unwrap();
        let err = parse_responses(Some(&bad)).unwrap_err();
        assert!(
            err.contains("\"peak\"") && err.contains("peak_bond_stress"),
            "{err}"
        );
        let all = parse_responses(None).unwrap();
        assert_eq!(all.len(), SUMMARY_RESPONSES.len() + 1);
        assert!(all.iter().any(|r| r.name() == "bond_stress_at_0.1mm"));
    }

    /// σ_mb at a slip interpolates in the step that reaches it, and a bond
    /// law parameter the curve does not determine is no value.
    #[test]
    fn values_come_from_the_curve_and_the_summary() {
        let rows: Vec<CurveRow> = [(1e-4, 2e6), (3e-4, 4e6)]
            .iter()
            .enumerate()
            .map(|(i, &(f, s))| CurveRow::new(i + 1, f, 0.0, f, s, 1))
            .collect();
        assert!((stress_at_slip(&rows, 2e-4).unwrap() - 3e6).abs() < 1e-6);
        assert!((stress_at_slip(&rows, 5e-5).unwrap() - 1e6).abs() < 1e-6);
        assert_eq!(stress_at_slip(&rows, 4e-4), None);
        let summary = serde_json::json!({"bond_law": {"mc2010": {"s3": 2e-3, "s1": 1e-4, "unidentified": ["s3"]}}});
        let s3 = Response::Summary(9);
        assert_eq!(s3.name(), "mc2010_s3");
        assert_eq!(s3.value(&summary, &rows), None);
        assert_eq!(Response::Summary(7).value(&summary, &rows), Some(1e-4));
    }
}
