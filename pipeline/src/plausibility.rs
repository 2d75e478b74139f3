//! Warnings on values that pass every bound but are probably a unit slip:
//! a plain number is read in SI units, so `E: 30` is 30 Pa and
//! `u_final: 1` is 1 m. Each warning names the key, the value as read and,
//! for a plain number, the unit that was probably meant.

use crate::scene::Scene;
use geom::units::{Dim, RawQuantity};
use serde_json::Value;

/// A key whose values below `min` (SI) are implausible, and the units to
/// suggest in order: the first that puts the number written in `typical`.
struct Floor {
    key: &'static str,
    dim: Dim,
    min: f64,
    /// (unit, its value in SI units)
    suggestions: &'static [(&'static str, f64)],
    /// The range of values of this kind, SI.
    typical: (f64, f64),
    what: &'static str,
}

/// A modulus: below 1 MPa no concrete or steel has one.
const fn modulus(key: &'static str) -> Floor {
    Floor {
        key,
        dim: Dim::Stress,
        min: 1e6,
        suggestions: &[("GPa", 1e9), ("MPa", 1e6)],
        typical: (1e8, 1e12),
        what: "a modulus",
    }
}

/// A strength: below 1 kPa no concrete, steel or bond has one.
const fn strength(key: &'static str) -> Floor {
    Floor {
        key,
        dim: Dim::Stress,
        min: 1e3,
        suggestions: &[("MPa", 1e6)],
        typical: (1e4, 1e10),
        what: "a strength",
    }
}

const FLOORS: [Floor; 5] = [
    modulus("materials.concrete.E"),
    modulus("materials.steel.E"),
    strength("materials.concrete.ft"),
    strength("materials.steel.sigma_y"),
    strength("materials.interface.ft"),
];

/// The value written at a dotted key of the spec tree.
fn written<'v>(tree: &'v Value, key: &str) -> Option<&'v Value> {
    key.split('.').try_fold(tree, |node, part| node.get(part))
}

/// The written value as a quantity, and whether it was a plain number.
fn quantity(value: &Value) -> Option<(RawQuantity, bool)> {
    match value {
        Value::Number(n) => Some((RawQuantity::Number(n.as_f64()?), true)),
        Value::String(s) => Some((RawQuantity::Text(s.clone()), false)),
        _ => None,
    }
}

/// Shortest text of a number as written back (`30`, `0.5`, `2.5e-5`).
fn number_text(x: f64) -> String {
    let text = format!("{x}");
    if text.len() > 12 {
        format!("{x:e}")
    } else {
        text
    }
}

fn below_floor(tree: &Value, floor: &Floor) -> Option<String> {
    let (q, plain) = quantity(written(tree, floor.key)?)?;
    let si = q.to_si(floor.dim, floor.key).ok()?;
    if si >= floor.min || si <= 0.0 {
        return None;
    }
    let unit = floor.dim.si_unit();
    let mut text = format!(
        "{} = {} {unit} is implausibly small for {}",
        floor.key,
        number_text(si),
        floor.what
    );
    if plain {
        let meant = floor
            .suggestions
            .iter()
            .find(|(_, factor)| (floor.typical.0..=floor.typical.1).contains(&(si * factor)));
        if let Some((suggested, _)) = meant {
            text.push_str(&format!(
                " (a plain number is read in {unit}): did you mean {} {suggested}?",
                number_text(si)
            ));
        }
    }
    Some(text)
}

/// An imposed displacement past the bonded length pulls the bar out of
/// its bonded zone: the curve beyond it is no bond-slip curve.
fn past_bonded_length(tree: &Value, scene: &Scene) -> Option<String> {
    let u_final = scene.loading.u_final;
    let bonded = scene.specimen.geometry.adhesive_length;
    if u_final <= bonded {
        return None;
    }
    let plain = written(tree, "loading.u_final").is_some_and(Value::is_number);
    let mut text = format!(
        "loading.u_final = {} mm is past the bonded length specimen.adhesive_length = {} mm: \
         beyond it the bar is pulled out of the bonded zone and the curve is no bond-slip curve",
        number_text(u_final * 1e3),
        number_text(bonded * 1e3)
    );
    if plain {
        text.push_str(&format!(
            " (a plain number is read in m): did you mean {} mm?",
            number_text(u_final)
        ));
    }
    Some(text)
}

/// Every plausibility warning of a resolved scene.
pub fn warnings(scene: &Scene) -> Vec<String> {
    let tree = &scene.written;
    FLOORS
        .iter()
        .filter_map(|f| below_floor(tree, f))
        .chain(past_bonded_length(tree, scene))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(sets: &[&str]) -> Scene {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/tiny-smooth.yaml"),
        )
        .unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Scene::from_yaml(&text, Path::new("tiny.yaml"), &sets).unwrap()
    }

    /// A plain-number modulus below 1 MPa is named with the unit meant; a
    /// sound scene has no warning.
    #[test]
    fn a_modulus_in_pascals_asks_for_the_unit_meant() {
        assert!(warnings(&scene(&[])).is_empty());
        let w = warnings(&scene(&["materials.concrete.E=30"]));
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("materials.concrete.E = 30 Pa")
                && w[0].ends_with("did you mean 30 GPa?"),
            "{w:?}"
        );
        let w = warnings(&scene(&["materials.concrete.E=30000"]));
        assert!(w[0].ends_with("did you mean 30000 MPa?"), "{w:?}");
        let w = warnings(&scene(&["materials.interface.ft=1.8"]));
        assert!(w[0].ends_with("did you mean 1.8 MPa?"), "{w:?}");
        // Written with a unit: still implausible, no unit to suggest.
        let w = warnings(&scene(&["materials.steel.E=20 kPa"]));
        assert!(
            w[0].contains("implausibly small") && !w[0].contains("mean"),
            "{w:?}"
        );
    }

    /// An imposed displacement past the bonded length warns; a plain number
    /// of metres is offered in millimetres.
    #[test]
    fn a_displacement_past_the_bonded_length_warns() {
        let w = warnings(&scene(&["loading.u_final=1"]));
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("loading.u_final = 1000 mm is past the bonded length")
                && w[0].ends_with("did you mean 1 mm?"),
            "{w:?}"
        );
        assert!(warnings(&scene(&["loading.u_final=11 mm"])).is_empty());
    }
}
