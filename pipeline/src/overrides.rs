//! `--set key.path=value` overrides, applied to the raw YAML tree before the
//! spec is deserialised, so an override goes through exactly the same
//! parsing, unit resolution and validation as the file itself.

use serde_yaml::{Mapping, Value};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OverrideError {
    #[error("--set {0:?}: expected KEY=VALUE, e.g. bar.ribs.angle=\"60 deg\"")]
    NoEquals(String),
    #[error("--set {0:?}: empty key or key segment")]
    EmptyKey(String),
    #[error("--set {key}: cannot read the value {value:?} as YAML: {reason}")]
    BadValue {
        key: String,
        value: String,
        reason: String,
    },
    #[error("--set {key}: {parent} is not a mapping, it cannot hold {segment:?}")]
    NotAMapping {
        key: String,
        parent: String,
        segment: String,
    },
}

/// One parsed `--set` argument.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    pub path: Vec<String>,
    pub value: Value,
}

impl Override {
    pub fn key(&self) -> String {
        self.path.join(".")
    }

    /// Parses `a.b.c=value`; the value is read as a YAML scalar or flow
    /// collection so `0.3`, `true`, `"60 deg"`, `60 deg` and `[1, 2]` all work.
    pub fn parse(arg: &str) -> Result<Self, OverrideError> {
        let (key, raw_value) = arg
            .split_once('=')
            .ok_or_else(|| OverrideError::NoEquals(arg.to_string()))?;
        let path: Vec<String> = key
            .trim()
            .split('.')
            .map(|s| s.trim().to_string())
            .collect();
        if path.iter().any(|s| s.is_empty()) {
            return Err(OverrideError::EmptyKey(arg.to_string()));
        }
        let value = if raw_value.trim().is_empty() {
            Value::String(String::new())
        } else {
            serde_yaml::from_str(raw_value).map_err(|e| OverrideError::BadValue {
                key: key.to_string(),
                value: raw_value.to_string(),
                reason: e.to_string(),
            })?
        };
        Ok(Override { path, value })
    }

    /// Sets the value in `root`, creating intermediate mappings.
    pub fn apply(&self, root: &mut Value) -> Result<(), OverrideError> {
        let mut node = root;
        for (depth, segment) in self.path.iter().enumerate() {
            if node.is_null() {
                *node = Value::Mapping(Mapping::new());
            }
            let Value::Mapping(map) = node else {
                return Err(OverrideError::NotAMapping {
                    key: self.key(),
                    parent: if depth == 0 {
                        "the spec".to_string()
                    } else {
                        self.path[..depth].join(".")
                    },
                    segment: segment.clone(),
                });
            };
            let k = Value::String(segment.clone());
            if depth + 1 == self.path.len() {
                map.insert(k, self.value.clone());
                return Ok(());
            }
            node = map.entry(k).or_insert(Value::Null);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn override_sets_nested_values_with_units() {
        let mut root: Value = serde_yaml::from_str("bar: {ribs: {angle: 0.9}}\nname: r1").unwrap();
        Override::parse("bar.ribs.angle=\"60 deg\"")
            .unwrap()
            .apply(&mut root)
            .unwrap();
        Override::parse("materials.interface.mu=0.001")
            .unwrap()
            .apply(&mut root)
            .unwrap();
        assert_eq!(root["bar"]["ribs"]["angle"], Value::String("60 deg".into()));
        assert_eq!(root["materials"]["interface"]["mu"].as_f64(), Some(0.001));
        Override::parse("bar.ribs.angle=55 deg")
            .unwrap()
            .apply(&mut root)
            .unwrap();
        assert_eq!(root["bar"]["ribs"]["angle"], Value::String("55 deg".into()));
    }

    #[test]
    fn malformed_overrides_are_errors() {
        assert!(matches!(
            Override::parse("bar.ribs.angle"),
            Err(OverrideError::NoEquals(_))
        ));
        assert!(matches!(
            Override::parse("bar..angle=1"),
            Err(OverrideError::EmptyKey(_))
        ));
        let mut root: Value = serde_yaml::from_str("name: r1").unwrap();
        let err = Override::parse("name.first=1")
            .unwrap()
            .apply(&mut root)
            .unwrap_err();
        assert!(err.to_string().contains("name is not a mapping"), "{err}");
    }
}
