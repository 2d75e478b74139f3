//! Physical quantities in specs: a plain number in SI base units, or a string
//! with a unit (`"8 mm"`, `"30 GPa"`, `"130 N/m"`, `"55 deg"`).
//!
//! Specs are parsed raw ([`RawQuantity`]) and resolved to SI `f64` with the
//! dimension the key expects ([`Dim`]); a unit of the wrong dimension is an
//! error naming the key. Inside the code every value is SI (m, Pa, N/m, rad).
//!
//! ```
//! use geom::units::{Dim, RawQuantity};
//! let q: RawQuantity = serde_yaml::from_str("\"8 mm\"").unwrap();
//! assert!((q.to_si(Dim::Length, "bar.diameter").unwrap() - 0.008).abs() < 1e-15);
//! ```

use serde::{Deserialize, Serialize};
use std::fmt;

/// The physical dimension a spec key expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    /// metre
    Length,
    /// pascal
    Stress,
    /// N/m = J/m² (fracture energy)
    EnergyPerArea,
    /// radian
    Angle,
    /// N/m³ = Pa/m (interface stiffness)
    StiffnessPerArea,
    /// newton
    Force,
    /// second
    Time,
    /// pure number
    Dimensionless,
}

impl Dim {
    /// Every dimension, in the order the units reference lists them.
    pub const ALL: [Dim; 8] = [
        Dim::Length,
        Dim::Stress,
        Dim::EnergyPerArea,
        Dim::StiffnessPerArea,
        Dim::Angle,
        Dim::Force,
        Dim::Time,
        Dim::Dimensionless,
    ];

    /// The SI unit written in messages.
    pub fn si_unit(self) -> &'static str {
        match self {
            Dim::Length => "m",
            Dim::Stress => "Pa",
            Dim::EnergyPerArea => "N/m",
            Dim::Angle => "rad",
            Dim::StiffnessPerArea => "N/m^3",
            Dim::Force => "N",
            Dim::Time => "s",
            Dim::Dimensionless => "(none)",
        }
    }

    /// Units accepted for this dimension and their factor to SI.
    pub fn units(self) -> &'static [(&'static str, f64)] {
        match self {
            Dim::Length => &[
                ("m", 1.0),
                ("cm", 1e-2),
                ("mm", 1e-3),
                ("um", 1e-6),
                ("µm", 1e-6),
            ],
            Dim::Stress => &[
                ("Pa", 1.0),
                ("kPa", 1e3),
                ("MPa", 1e6),
                ("GPa", 1e9),
                ("N/m2", 1.0),
                ("N/m^2", 1.0),
                ("N/mm2", 1e6),
                ("N/mm^2", 1e6),
            ],
            Dim::EnergyPerArea => &[
                ("N/m", 1.0),
                ("J/m2", 1.0),
                ("J/m^2", 1.0),
                ("N/mm", 1e3),
                ("kN/m", 1e3),
            ],
            Dim::Angle => &[
                ("rad", 1.0),
                ("deg", std::f64::consts::PI / 180.0),
                ("°", std::f64::consts::PI / 180.0),
            ],
            Dim::StiffnessPerArea => &[
                ("N/m3", 1.0),
                ("N/m^3", 1.0),
                ("Pa/m", 1.0),
                ("MPa/m", 1e6),
                ("GPa/m", 1e9),
                ("N/mm3", 1e9),
                ("N/mm^3", 1e9),
                ("MPa/mm", 1e9),
            ],
            Dim::Force => &[("N", 1.0), ("kN", 1e3), ("MN", 1e6)],
            Dim::Time => &[("s", 1.0), ("ms", 1e-3), ("min", 60.0), ("h", 3600.0)],
            Dim::Dimensionless => &[("", 1.0), ("%", 1e-2)],
        }
    }
}

impl fmt::Display for Dim {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = match self {
            Dim::Length => "length",
            Dim::Stress => "stress",
            Dim::EnergyPerArea => "energy per area",
            Dim::Angle => "angle",
            Dim::StiffnessPerArea => "stiffness per area",
            Dim::Force => "force",
            Dim::Time => "time",
            Dim::Dimensionless => "pure number",
        };
        f.write_str(name)
    }
}

/// A quantity as written in a spec: a number (SI) or "value unit".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "a number in SI units or a quantity with a unit, e.g. 8 mm or \"30 GPa\""
)]
pub enum RawQuantity {
    Number(f64),
    Text(String),
}

/// A number, or a string of a number and a unit: what [`RawQuantity`]
/// reads. The unit's dimension is the key's (its doc text says which), so
/// the schema checks the form, the resolution the unit.
const QUANTITY_PATTERN: &str =
    r"^\s*[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?\s*([^\s0-9.+-]\S*)?\s*$";

impl schemars::JsonSchema for RawQuantity {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Quantity".into()
    }

    fn inline_schema() -> bool {
        true
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "A number in SI units, or a number with a unit: 8 mm, \"30 GPa\", \"55 deg\".",
            "anyOf": [
                {"type": "number"},
                {"type": "string", "pattern": QUANTITY_PATTERN}
            ]
        })
    }
}

impl From<f64> for RawQuantity {
    fn from(v: f64) -> Self {
        RawQuantity::Number(v)
    }
}

/// A quantity that could not be resolved; `key` is the dotted spec path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UnitError {
    #[error("{key}: cannot read {text:?} as a number with a unit (expected e.g. \"8 mm\")")]
    Malformed { key: String, text: String },
    #[error("{key}: unit {unit:?} is not a {dim} unit (accepted: {accepted})")]
    WrongUnit {
        key: String,
        unit: String,
        dim: Dim,
        accepted: String,
    },
    #[error("{key}: value {value} is not finite")]
    NotFinite { key: String, value: String },
}

impl RawQuantity {
    /// Resolves to SI base units for `dim`; `key` names the spec field in errors.
    pub fn to_si(&self, dim: Dim, key: &str) -> Result<f64, UnitError> {
        let value = match self {
            RawQuantity::Number(v) => *v,
            RawQuantity::Text(text) => parse_with_unit(text, dim, key)?,
        };
        if value.is_finite() {
            Ok(value)
        } else {
            Err(UnitError::NotFinite {
                key: key.to_string(),
                value: format!("{self:?}"),
            })
        }
    }
}

impl RawQuantity {
    /// Resolves to SI base units with the dimension its unit names, for a
    /// value whose key's dimension is not known (a study's range): `None`
    /// for a plain number (SI as it stands) or a pure-number unit. Every
    /// unit belongs to one dimension.
    pub fn to_si_any(&self, key: &str) -> Result<(f64, Option<Dim>), UnitError> {
        let RawQuantity::Text(text) = self else {
            return Ok((self.to_si(Dim::Dimensionless, key)?, None));
        };
        let unit = split_number(text).map(|(_, unit)| unit);
        let dim = match unit {
            Some(unit) if !unit.is_empty() => Dim::ALL
                .into_iter()
                .find(|d| d.units().iter().any(|(name, _)| *name == unit))
                .ok_or_else(|| UnitError::WrongUnit {
                    key: key.to_string(),
                    unit: unit.to_string(),
                    dim: Dim::Dimensionless,
                    accepted: "a unit of any dimension, e.g. mm, MPa, N/m, deg".into(),
                })?,
            _ => Dim::Dimensionless,
        };
        let value = self.to_si(dim, key)?;
        Ok((value, (dim != Dim::Dimensionless).then_some(dim)))
    }
}

/// The longest prefix of `text` that reads as a number, and the rest.
fn split_number(text: &str) -> Option<(f64, &str)> {
    let trimmed = text.trim();
    let split = trimmed
        .char_indices()
        .map(|(i, _)| i)
        .chain(std::iter::once(trimmed.len()))
        .rev()
        .find(|&i| trimmed[..i].trim().parse::<f64>().is_ok())?;
    Some((
        trimmed[..split].trim().parse().ok()?,
        trimmed[split..].trim(),
    ))
}

fn parse_with_unit(text: &str, dim: Dim, key: &str) -> Result<f64, UnitError> {
    let trimmed = text.trim();
    // The number is the longest prefix that parses; the rest is the unit.
    let split = trimmed
        .char_indices()
        .map(|(i, _)| i)
        .chain(std::iter::once(trimmed.len()))
        .rev()
        .find(|&i| trimmed[..i].trim().parse::<f64>().is_ok())
        .ok_or_else(|| UnitError::Malformed {
            key: key.to_string(),
            text: text.to_string(),
        })?;
    let number: f64 = trimmed[..split].trim().parse().expect("checked above");
    let unit = trimmed[split..].trim();
    // A quoted bare number is SI, like an unquoted one.
    if unit.is_empty() {
        return Ok(number);
    }
    dim.units()
        .iter()
        .find(|(name, _)| *name == unit)
        .map(|(_, factor)| number * factor)
        .ok_or_else(|| UnitError::WrongUnit {
            key: key.to_string(),
            unit: unit.to_string(),
            dim,
            accepted: dim
                .units()
                .iter()
                .map(|(n, _)| if n.is_empty() { "plain number" } else { n })
                .collect::<Vec<_>>()
                .join(", "),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn si(text: &str, dim: Dim) -> Result<f64, UnitError> {
        RawQuantity::Text(text.into()).to_si(dim, "k")
    }

    #[test]
    fn units_convert_to_si() {
        assert!((si("8 mm", Dim::Length).unwrap() - 8e-3).abs() < 1e-18);
        assert!((si("30 GPa", Dim::Stress).unwrap() - 30e9).abs() < 1e-3);
        assert!((si("130 N/m", Dim::EnergyPerArea).unwrap() - 130.0).abs() < 1e-12);
        assert!((si("55 deg", Dim::Angle).unwrap() - 55f64.to_radians()).abs() < 1e-15);
        assert!((si("-1 MPa", Dim::Stress).unwrap() + 1e6).abs() < 1e-9);
        assert!((si("2.0e-5 m", Dim::Length).unwrap() - 2e-5).abs() < 1e-20);
        assert!((si("4e10", Dim::StiffnessPerArea).unwrap() - 4e10).abs() < 1e-3);
        assert_eq!(
            RawQuantity::Number(0.25).to_si(Dim::Length, "k").unwrap(),
            0.25
        );
    }

    /// A quantity's dimension follows from its unit alone; plain numbers
    /// and pure-number units have none.
    #[test]
    fn the_dimension_is_read_off_the_unit() {
        let any = |t: &str| RawQuantity::Text(t.into()).to_si_any("k");
        let (v, d) = any("0.3 mm").unwrap();
        assert!((v - 3e-4).abs() < 1e-18 && d == Some(Dim::Length));
        assert_eq!(any("90 deg").unwrap().1, Some(Dim::Angle));
        assert_eq!(any("97 N/m").unwrap().1, Some(Dim::EnergyPerArea));
        assert_eq!(any("2 MPa").unwrap(), (2e6, Some(Dim::Stress)));
        assert_eq!(any("5 %").unwrap(), (0.05, None));
        assert_eq!(any("0.3").unwrap(), (0.3, None));
        assert_eq!(
            RawQuantity::Number(0.02).to_si_any("k").unwrap(),
            (0.02, None)
        );
        let err = any("3 furlongs").unwrap_err().to_string();
        assert!(err.contains("furlongs"), "{err}");
        // Every unit names one dimension.
        for a in Dim::ALL {
            for b in Dim::ALL.into_iter().filter(|&b| b != a) {
                for (unit, _) in a.units() {
                    assert!(!b.units().iter().any(|(u, _)| u == unit), "{unit}");
                }
            }
        }
    }

    #[test]
    fn wrong_dimension_names_the_key_and_the_unit() {
        let err = RawQuantity::Text("8 MPa".into())
            .to_si(Dim::Length, "bar.diameter")
            .unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("bar.diameter") && msg.contains("MPa") && msg.contains("length"),
            "{msg}"
        );
    }

    #[test]
    fn malformed_and_non_finite_are_errors() {
        assert!(matches!(
            si("mm 8", Dim::Length),
            Err(UnitError::Malformed { .. })
        ));
        assert!(matches!(
            si("", Dim::Length),
            Err(UnitError::Malformed { .. })
        ));
        assert!(matches!(
            RawQuantity::Number(f64::NAN).to_si(Dim::Length, "k"),
            Err(UnitError::NotFinite { .. })
        ));
    }
}
