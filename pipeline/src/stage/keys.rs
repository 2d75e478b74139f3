//! Stage keys: a stage's key is a hash of exactly what it reads (the spec
//! sections below, resolved; its upstream stage's key; the versions that
//! change its result), so a stage reruns when and only when one of them
//! changed.

use super::kinds::Stage;
use crate::scene::Scene;
use crate::store::StageKey;
use serde_json::{json, Map, Value};

impl Stage {
    /// Version of what the stage produces; bumped when its output for the
    /// same inputs changes, so old artifacts are not reused.
    fn format(self) -> u32 {
        match self {
            Stage::Geometry => 4,
            // 3: mesh.vtu's `region` is 0 steel, 1 concrete, as in the fields.
            Stage::Mesh => 3,
            Stage::Solve => 12,
            Stage::Post => 3,
        }
    }

    /// The spec sections the stage reads (JSON pointers into the scene),
    /// and the parts of them it does not.
    fn reads(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            // The non-adhesive option only changes which interface law the
            // solver puts there.
            Stage::Geometry => (&["/bar", "/specimen"], &["/specimen/non_adhesive"]),
            Stage::Mesh => (&["/mesh"], &[]),
            // f_cm only sets the design code's law beside the curve: post
            // reads it (resolved and as written), the solve does not.
            Stage::Solve => (
                &[
                    "/specimen/non_adhesive",
                    "/materials",
                    "/loading",
                    "/solver",
                    "/outputs/fields",
                ],
                &["/materials/concrete_fcm", "/materials/concrete/fcm"],
            ),
            Stage::Post => (
                &[
                    "/outputs/post",
                    "/materials/concrete_fcm",
                    "/materials/concrete/fcm",
                ],
                &[],
            ),
        }
    }

    /// The same as [`Stage::reads`] in the spec as written, where `status`
    /// names the keys a user changed: post's options are written directly
    /// under `outputs` (beside `fields`), resolved into `outputs.post`.
    fn reads_as_written(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            Stage::Post => (
                &["/outputs", "/materials/concrete/fcm"],
                &["/outputs/fields"],
            ),
            _ => self.reads(),
        }
    }

    /// Whether gmsh's version changes the stage's result.
    fn uses_gmsh(self) -> bool {
        matches!(self, Stage::Geometry | Stage::Mesh)
    }
}

/// The keys of all four stages of a scene (each depends on its upstream key).
pub struct Keys {
    keys: [StageKey; 4],
}

impl Keys {
    pub fn of(scene: &Scene, gmsh_version: &str) -> Keys {
        let resolved = serde_json::to_value(scene).expect("resolved scenes serialise");
        let mut keys: Vec<StageKey> = Vec::with_capacity(Stage::ALL.len());
        for stage in Stage::ALL {
            let (reads, ignores) = stage.reads();
            let mut inputs = select(&resolved, reads, ignores);
            inputs.insert("format".into(), json!(stage.format()));
            // A part of a symmetric specimen weights its FED nodes by their
            // images in the whole since this input: whole models' results
            // did not change, so their keys (and stored solves) stay.
            let symmetry = resolved
                .pointer("/specimen/symmetry")
                .and_then(Value::as_str);
            if matches!(stage, Stage::Solve) && symmetry != Some("full") {
                inputs.insert("fed".into(), json!("whole-specimen node weights"));
            }
            if stage.uses_gmsh() {
                inputs.insert("gmsh".into(), json!(gmsh_version));
            }
            if let Some(up) = stage.upstream() {
                inputs.insert(up.name().into(), json!(keys[up as usize].key));
            }
            let (written_reads, written_ignores) = stage.reads_as_written();
            let written = select(&scene.written, written_reads, written_ignores);
            keys.push(
                StageKey::new(stage.name(), Value::Object(inputs))
                    .with_written(Value::Object(written)),
            );
        }
        Keys {
            keys: keys.try_into().expect("one key per stage"),
        }
    }

    pub fn get(&self, stage: Stage) -> &StageKey {
        &self.keys[stage as usize]
    }
}

/// The parts of `tree` at the JSON pointers `reads`, without those at
/// `ignores`, as one object with the same nesting (a section absent from
/// `tree` is null).
fn select(tree: &Value, reads: &[&str], ignores: &[&str]) -> Map<String, Value> {
    let mut out = Value::Object(Map::new());
    for pointer in reads {
        let value = tree.pointer(pointer).cloned().unwrap_or(Value::Null);
        *slot(&mut out, pointer) = value;
    }
    for pointer in ignores {
        let (parent, last) = pointer.rsplit_once('/').expect("pointers start with /");
        if let Some(Value::Object(map)) = out.pointer_mut(parent) {
            map.remove(last);
        }
    }
    match out {
        Value::Object(map) => map,
        _ => unreachable!("built as an object"),
    }
}

/// The place of `pointer` in `tree`, creating the objects on the way.
fn slot<'v>(tree: &'v mut Value, pointer: &str) -> &'v mut Value {
    pointer.split('/').skip(1).fold(tree, |node, part| {
        if !node.is_object() {
            *node = Value::Object(Map::new());
        }
        let Value::Object(map) = node else {
            unreachable!("made an object above")
        };
        map.entry(part.to_string()).or_insert(Value::Null)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `materials.concrete.fcm` and the post options change post's key
    /// alone: the stored solves of a scene stay its solves.
    #[test]
    fn fcm_and_bond_options_rerun_post_only() {
        let spec = "name: s\nbar: {kind: smooth, diameter: 8 mm}\n";
        let path = std::path::Path::new("s.yaml");
        let keys = |sets: &[&str]| {
            let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
            Keys::of(&Scene::from_yaml(spec, path, &sets).unwrap(), "4.15.2")
        };
        let plain = keys(&[]);
        for sets in [
            &["materials.concrete.fcm=40 MPa"][..],
            &["outputs.bond_conditions=other"],
            &["outputs.bond_law_points=5"],
        ] {
            let changed = keys(sets);
            assert_eq!(
                changed.get(Stage::Solve).key,
                plain.get(Stage::Solve).key,
                "{sets:?}"
            );
            assert_ne!(
                changed.get(Stage::Post).key,
                plain.get(Stage::Post).key,
                "{sets:?}"
            );
        }
    }

    /// A post option changed on the command line is named as the user
    /// wrote it (`outputs.energy_fed_limit`), not by its resolved place.
    #[test]
    fn post_options_are_named_as_written() {
        let spec = "name: s\nbar: {kind: smooth, diameter: 8 mm}\n";
        let path = std::path::Path::new("s.yaml");
        let keys = |sets: &[&str]| {
            let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
            Keys::of(&Scene::from_yaml(spec, path, &sets).unwrap(), "4.15.2")
        };
        let (old, new) = (keys(&[]), keys(&["outputs.energy_fed_limit=2 mm"]));
        let changed = crate::store::changed_keys(
            &old.get(Stage::Post).written,
            &new.get(Stage::Post).written,
        );
        assert_eq!(changed, ["outputs.energy_fed_limit"]);
        let fields = keys(&["outputs.fields.at_end=false"]);
        assert!(crate::store::changed_keys(
            &old.get(Stage::Post).written,
            &fields.get(Stage::Post).written
        )
        .is_empty());
    }

    #[test]
    fn select_keeps_the_nesting_and_drops_the_ignored_parts() {
        let tree = json!({"a": {"x": 1, "y": 2}, "b": {"c": {"d": 3}, "e": 4}, "f": 5});
        let got = select(&tree, &["/a", "/b/c", "/g"], &["/a/y"]);
        assert_eq!(
            Value::Object(got),
            json!({"a": {"x": 1}, "b": {"c": {"d": 3}}, "g": null})
        );
    }
}
