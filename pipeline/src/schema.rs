//! JSON Schemas of the scene and study files (`ribbar schema scene|study`),
//! generated from the raw spec types the parser reads, so that an editor
//! validates and completes a file with the same keys, types and choices as
//! `ribbar` itself. Each key's description is its field's doc comment; the
//! scene and study reference pages are written from the same schemas
//! (`crate::reference`).

use geom::spec::RawSpecimen;
use schemars::generate::SchemaSettings;
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::{self, Deserializer, Visitor};
use serde_json::Value;
use solve::spec::materials::NonAdhesive;

/// The root schema of a file whose raw type is `T` (`RawScene::schema`,
/// `RawStudy::schema`).
pub fn root<T: JsonSchema>(title: &str, description: &str) -> Value {
    let schema = SchemaSettings::draft2020_12()
        .into_generator()
        .into_root_schema_for::<T>();
    let mut value = schema.to_value();
    drop_section_defaults(&mut value);
    if let Value::Object(map) = &mut value {
        map.insert("title".into(), title.into());
        map.insert("description".into(), description.into());
    }
    value
}

/// Removes the `default` of every section: the derive writes the raw
/// type's `Default`, every key unset (null), which says nothing and which
/// an editor would insert; each key's default is in its description.
fn drop_section_defaults(value: &mut Value) {
    match value {
        Value::Object(map) => {
            if map.get("default").is_some_and(Value::is_object) {
                map.remove("default");
            }
            map.values_mut().for_each(drop_section_defaults);
        }
        Value::Array(items) => items.iter_mut().for_each(drop_section_defaults),
        _ => {}
    }
}

/// `specimen` as a file holds it: geom's keys and the solve's
/// `non_adhesive` (which `Scene::load` takes out before geom reads the
/// rest) in one object.
#[derive(JsonSchema)]
#[schemars(rename = "RawSpecimen", deny_unknown_fields)]
#[allow(dead_code)] // read by the schema's derive only
pub struct SpecimenSection {
    #[serde(flatten)]
    geometry: RawSpecimen,
    /// The interface of the non-adhesive zone z ∈ [l_adh, L]: `free` (no
    /// element) or `contact` (no tension, no friction); read by the solve
    /// stage, the geometry and the mesh do not depend on it (choice; default
    /// free).
    non_adhesive: Option<NonAdhesive>,
}

/// A study's `parameters`: dotted keys, each with a non-empty list (sweep,
/// convergence) or a range or choices (sample, sensitivity).
pub fn parameter_lists(_: &mut SchemaGenerator) -> Schema {
    json_schema!({
        "type": "object",
        "minProperties": 1,
        "additionalProperties": {
            "anyOf": [
                {"type": "array", "minItems": 1},
                {
                    "type": "object",
                    "properties": {
                        "range": {"type": "array", "minItems": 2, "maxItems": 2},
                        "scale": {"enum": ["linear", "log"]}
                    },
                    "required": ["range"],
                    "additionalProperties": false
                },
                {
                    "type": "object",
                    "properties": {"choices": {"type": "array", "minItems": 1}},
                    "required": ["choices"],
                    "additionalProperties": false
                }
            ]
        }
    })
}

/// The field names a derived `Deserialize` of a struct accepts, as serde
/// hands them to the deserializer (renames applied).
pub fn struct_fields<T: de::DeserializeOwned>() -> &'static [&'static str] {
    let mut probe = FieldProbe(&[]);
    let _ = T::deserialize(&mut probe);
    probe.0
}

/// A deserializer that records the field list of the struct asked of it.
struct FieldProbe(&'static [&'static str]);

#[derive(Debug)]
struct Probed;

impl std::fmt::Display for Probed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("fields probed")
    }
}

impl std::error::Error for Probed {}

impl de::Error for Probed {
    fn custom<M: std::fmt::Display>(_: M) -> Self {
        Probed
    }
}

impl<'de> Deserializer<'de> for &mut FieldProbe {
    type Error = Probed;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Probed> {
        Err(Probed)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Probed> {
        self.0 = fields;
        Err(Probed)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map enum identifier ignored_any
    }
}
