//! The design space of a sampled or sensitivity study: one axis per key, a
//! range of a quantity (linear or logarithmic) or a list of choices, and
//! the map from a point of the unit cube to the values of a case.
//!
//! ```yaml
//! parameters:
//!   bar.ribs.height: {range: ["0.3 mm", "0.8 mm"]}
//!   materials.interface.delta_s: {range: [0.02, 1], scale: log}
//!   bar.ribs.side_b: {choices: [rotated, mirrored]}
//! ```

use geom::units::{Dim, RawQuantity};
use serde::Deserialize;
use serde_yaml::Value;

/// How a range is spread over the unit interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    #[default]
    Linear,
    /// Uniform in the logarithm: lo (hi/lo)^u.
    Log,
}

/// An axis as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAxis {
    range: Option<[RawQuantity; 2]>,
    #[serde(default)]
    scale: Option<Scale>,
    choices: Option<Vec<Value>>,
}

/// What one axis spans.
#[derive(Debug, Clone, PartialEq)]
pub enum Span {
    /// SI bounds, the dimension the values were written in (none: plain
    /// numbers, passed on as they are).
    Range {
        lo: f64,
        hi: f64,
        scale: Scale,
        dim: Option<Dim>,
    },
    /// Values as written, each equally likely.
    Choices(Vec<Value>),
}

/// One key of the design space.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub key: String,
    pub span: Span,
}

/// A value of an axis: what the table holds and what the case's `--set`
/// writes.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisValue {
    /// The value in SI (a number), or a choice as written.
    pub table: Value,
    /// The value as it goes after `key=` on the command line.
    pub arg: String,
}

impl Axis {
    /// Reads `key: {range: [lo, hi], scale: linear|log}` or
    /// `key: {choices: [...]}`; the message names the key.
    pub fn parse(key: &str, value: &Value) -> Result<Axis, String> {
        let field = format!("parameters.{key}");
        let raw: RawAxis = serde_yaml::from_value(value.clone()).map_err(|e| {
            format!(
                "{field}: expected {{range: [lo, hi]}} (with scale: linear or log) or \
                 {{choices: [...]}}: {e}"
            )
        })?;
        let span = match (raw.range, raw.choices) {
            (Some(range), None) => range_span(&field, &range, raw.scale.unwrap_or_default())?,
            (None, Some(choices)) => {
                if raw.scale.is_some() {
                    return Err(format!("{field}: scale is for a range, not for choices"));
                }
                if choices.is_empty() {
                    return Err(format!("{field}: choices is empty"));
                }
                Span::Choices(choices)
            }
            _ => {
                return Err(format!(
                    "{field}: give one of range: [lo, hi] or choices: [...]"
                ))
            }
        };
        Ok(Axis {
            key: key.to_string(),
            span,
        })
    }

    /// The value at `u` ∈ [0, 1] along the axis (a choice: the `u`-th
    /// of equal parts).
    pub fn value(&self, u: f64) -> AxisValue {
        let u = u.clamp(0.0, 1.0);
        match &self.span {
            Span::Range { lo, hi, scale, dim } => {
                // Exact at both ends and never outside [lo, hi]: a design
                // at the edge of its range is the bound as written, not
                // one rounding beyond it.
                let x = match scale {
                    Scale::Linear => (1.0 - u) * lo + u * hi,
                    Scale::Log if u == 1.0 => *hi,
                    Scale::Log => lo * (hi / lo).powf(u),
                }
                .clamp(*lo, *hi);
                AxisValue {
                    table: Value::from(x),
                    arg: match dim {
                        Some(d) => format!("{:?}", format!("{x} {}", d.si_unit())),
                        None => format!("{x}"),
                    },
                }
            }
            Span::Choices(choices) => {
                let i = ((u * choices.len() as f64) as usize).min(choices.len() - 1);
                let choice = &choices[i];
                AxisValue {
                    table: choice_in_si(choice),
                    arg: value_arg(choice),
                }
            }
        }
    }

    /// The SI unit of the axis's values in the table ("1" for plain
    /// numbers, "" for choices that are not quantities).
    pub fn unit(&self) -> &'static str {
        match &self.span {
            Span::Range { dim: Some(d), .. } => d.si_unit(),
            Span::Range { dim: None, .. } => "1",
            Span::Choices(choices) => {
                let dims: Vec<Option<Dim>> = choices.iter().map(quantity_dim).collect();
                match dims.first() {
                    Some(Some(d)) if dims.iter().all(|x| *x == Some(*d)) => d.si_unit(),
                    _ => "",
                }
            }
        }
    }

    /// Whether the axis is numeric in the table (a trend can be fitted).
    pub fn is_numeric(&self) -> bool {
        match &self.span {
            Span::Range { .. } => true,
            Span::Choices(c) => c.iter().all(|v| choice_in_si(v).is_number()),
        }
    }

    /// A value of the axis as people read it: a quantity in mm, MPa or deg,
    /// four significant digits.
    pub fn show(&self, value: &AxisValue) -> String {
        match value.table.as_f64() {
            Some(x) => {
                let (scale, unit) = display_unit(self.unit());
                let text = format!("{:.4}", x * scale);
                let text = if text.contains('.') {
                    text.trim_end_matches('0').trim_end_matches('.').to_string()
                } else {
                    text
                };
                let text = if (x * scale).abs() < 1e-3 && x != 0.0 {
                    format!("{:.3e}", x * scale)
                } else {
                    text
                };
                if unit.is_empty() {
                    text
                } else {
                    format!("{text} {unit}")
                }
            }
            None => value_arg(&value.table).trim_matches('"').to_string(),
        }
    }

    /// Whether trends along the axis are fitted in its logarithm.
    pub fn is_log(&self) -> bool {
        matches!(
            self.span,
            Span::Range {
                scale: Scale::Log,
                ..
            }
        )
    }
}

/// The shortest dotted suffix of `key` that no other axis shares.
pub fn short_key(key: &str, axes: &[Axis]) -> String {
    let parts: Vec<&str> = key.split('.').collect();
    for n in 1..=parts.len() {
        let suffix = parts[parts.len() - n..].join(".");
        let clash = axes
            .iter()
            .filter(|a| a.key != key)
            .any(|a| a.key.ends_with(&format!(".{suffix}")) || a.key == suffix);
        if !clash {
            return suffix;
        }
    }
    key.to_string()
}

/// A SI unit's factor to the unit plots and messages use, and that unit's
/// name ("" for a pure number).
pub fn display_unit(unit: &str) -> (f64, &str) {
    match unit {
        "m" => (1e3, "mm"),
        "Pa" => (1e-6, "MPa"),
        "rad" => (180.0 / std::f64::consts::PI, "deg"),
        "J/m^2" => (1.0, "J/m²"),
        "1" => (1.0, ""),
        other => (1.0, other),
    }
}

fn range_span(field: &str, range: &[RawQuantity; 2], scale: Scale) -> Result<Span, String> {
    let [lo, hi] = [&range[0], &range[1]].map(|q| q.to_si_any(field).map_err(|e| e.to_string()));
    let ((lo, dim_lo), (hi, dim_hi)) = (lo?, hi?);
    if dim_lo != dim_hi {
        return Err(format!(
            "{field}: the range's ends have different dimensions ({} and {})",
            dim_lo.map_or("pure number".into(), |d| d.to_string()),
            dim_hi.map_or("pure number".into(), |d| d.to_string()),
        ));
    }
    if lo >= hi {
        return Err(format!(
            "{field}: range [{lo}, {hi}] (SI) must have lo < hi"
        ));
    }
    if scale == Scale::Log && lo <= 0.0 {
        return Err(format!(
            "{field}: a log scale needs a range above 0, found lo = {lo} (SI)"
        ));
    }
    Ok(Span::Range {
        lo,
        hi,
        scale,
        dim: dim_lo,
    })
}

/// A quantity's dimension, if the value is a string with a unit.
fn quantity_dim(v: &Value) -> Option<Dim> {
    let Value::String(s) = v else { return None };
    RawQuantity::Text(s.clone()).to_si_any("").ok()?.1
}

/// A choice as the table holds it: a quantity with a unit in SI, a number
/// as it is, anything else as written.
fn choice_in_si(v: &Value) -> Value {
    match v {
        Value::String(s) => match RawQuantity::Text(s.clone()).to_si_any("") {
            Ok((x, Some(_))) => Value::from(x),
            _ => v.clone(),
        },
        other => other.clone(),
    }
}

/// A value as it goes on the command line after `key=`: YAML flow form.
pub fn value_arg(v: &serde_yaml::Value) -> String {
    match v {
        serde_yaml::Value::String(s) => format!("{s:?}"),
        other => serde_yaml::to_string(other)
            .unwrap_or_default()
            .trim()
            .to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(yaml: &str) -> Result<Axis, String> {
        Axis::parse("k.x", &serde_yaml::from_str(yaml).unwrap())
    }

    /// Ranges map the unit interval onto SI values, linearly or
    /// logarithmically, and write their arguments in the SI unit of the
    /// values as written; choices split it into equal parts.
    #[test]
    fn axes_map_the_unit_interval_to_values() {
        let h = axis("{range: [0.3 mm, 0.8 mm]}").unwrap();
        let v = h.value(0.5);
        assert!((v.table.as_f64().unwrap() - 0.55e-3).abs() < 1e-15);
        assert!(
            v.arg.ends_with(" m\"") && v.arg.starts_with('"'),
            "{}",
            v.arg
        );
        assert_eq!(h.unit(), "m");
        let log = axis("{range: [0.02, 1], scale: log}").unwrap();
        assert!((log.value(0.5).table.as_f64().unwrap() - 0.02f64.sqrt()).abs() < 1e-12);
        assert_eq!(log.value(1.0).arg, "1");
        assert!(log.is_log() && log.unit() == "1");
        let beta = axis("{range: [40 deg, 90 deg]}").unwrap();
        assert!(beta.value(1.0).arg.contains("rad"));
        let side = axis("{choices: [rotated, mirrored]}").unwrap();
        assert_eq!(side.value(0.49).arg, "\"rotated\"");
        assert_eq!(side.value(0.5).arg, "\"mirrored\"");
        assert_eq!(side.value(1.0).table, Value::from("mirrored"));
        assert!(!side.is_numeric());
        let sizes = axis("{choices: [1 mm, 2 mm]}").unwrap();
        assert_eq!(sizes.value(0.9).table, Value::from(2e-3));
        assert_eq!(sizes.unit(), "m");
        assert_eq!(h.show(&h.value(0.5)), "0.55 mm");
        assert_eq!(beta.show(&beta.value(1.0)), "90 deg");
        assert_eq!(side.show(&side.value(0.0)), "rotated");
    }

    /// The ends of the unit interval are the bounds themselves, and no
    /// value falls outside them by a rounding.
    #[test]
    fn ranges_keep_their_values_within_the_bounds() {
        for yaml in [
            "{range: [0.35 mm, 0.65 mm]}",
            "{range: [45 deg, 90 deg]}",
            "{range: [0.3 mm, 0.7 mm], scale: log}",
            "{range: [0.1, 0.3]}",
        ] {
            let a = axis(yaml).unwrap();
            let (lo, hi) = match &a.span {
                Span::Range { lo, hi, .. } => (*lo, *hi),
                Span::Choices(_) => panic!("{yaml} is a range"),
            };
            assert_eq!(a.value(0.0).table.as_f64(), Some(lo), "{yaml}");
            assert_eq!(a.value(1.0).table.as_f64(), Some(hi), "{yaml}");
            for i in 0..=1000 {
                let x = a.value(f64::from(i) / 1000.0).table.as_f64().unwrap();
                assert!((lo..=hi).contains(&x), "{yaml}: {x} outside [{lo}, {hi}]");
            }
        }
    }

    /// Bad axes are refused naming the key and the problem.
    #[test]
    fn bad_axes_name_the_key() {
        for (yaml, words) in [
            ("[1, 2]", "range: [lo, hi]"),
            ("{range: [2 mm, 1 mm]}", "lo < hi"),
            ("{range: [1 mm, 2 MPa]}", "different dimensions"),
            ("{range: [0, 1], scale: log}", "above 0"),
            ("{choices: []}", "empty"),
            ("{range: [0, 1], choices: [a]}", "one of"),
            ("{range: [0, 1], scale: cubic}", "scale"),
        ] {
            let err = axis(yaml).unwrap_err();
            assert!(
                err.contains("parameters.k.x") && err.contains(words),
                "{yaml}: {err}"
            );
        }
    }
}
