//! A scene spec: the sections owned by each crate, composed; read from YAML
//! with `--set` overrides applied to the tree first, then resolved to SI.

use crate::outputs::{Outputs, RawOutputs};
use crate::overrides::Override;
use geom::spec::{Bar, RawBar, RawSpecimen, Specimen};
use mesh::spec::{MeshSpec, RawMeshSpec};
use serde::{Deserialize, Serialize};
use solve::spec::materials::{Materials, RawMaterials};
use solve::spec::solver::{Loading, RawLoading, RawSolver, SolverSettings};
use std::path::{Path, PathBuf};

/// The spec as written (after overrides).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    pub name: String,
    pub bar: RawBar,
    #[serde(default)]
    pub specimen: RawSpecimen,
    #[serde(default)]
    pub mesh: RawMeshSpec,
    #[serde(default)]
    pub materials: RawMaterials,
    #[serde(default)]
    pub loading: RawLoading,
    #[serde(default)]
    pub solver: RawSolver,
    #[serde(default)]
    pub outputs: RawOutputs,
}

/// The resolved scene: every value in SI, defaults filled in, bounds checked.
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    pub name: String,
    pub bar: Bar,
    pub specimen: Specimen,
    pub mesh: MeshSpec,
    pub materials: Materials,
    pub loading: Loading,
    pub solver: SolverSettings,
    pub outputs: Outputs,
    /// The spec tree as written, overrides applied: names the keys a user
    /// changed when a stage is stale. Not hashed (only resolved values are).
    #[serde(skip)]
    pub written: serde_json::Value,
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read the spec: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Yaml { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Override {
        path: PathBuf,
        #[source]
        source: crate::overrides::OverrideError,
    },
    #[error("{path}: {source}")]
    Invalid {
        path: PathBuf,
        #[source]
        source: SectionError,
    },
}

/// A section of a scene that does not resolve, with its owner's typed error.
#[derive(Debug, thiserror::Error)]
pub enum SectionError {
    #[error("{0}")]
    Name(String),
    #[error(transparent)]
    Geometry(#[from] geom::spec::SpecError),
    #[error(transparent)]
    Mesh(#[from] mesh::MeshError),
    #[error(transparent)]
    Materials(#[from] solve::spec::materials::MaterialsSpecError),
    #[error(transparent)]
    Solver(#[from] solve::spec::solver::SolverSpecError),
    #[error(transparent)]
    Outputs(#[from] crate::outputs::OutputsError),
}

/// Scene names become directory names: keep them portable.
fn check_name(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name.len() <= 100
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "name: {name:?} must be 1–100 characters of letters, digits, '-', '_' or '.', not starting with '.'"
        ))
    }
}

impl Scene {
    /// Reads `path`, applies `overrides` (`key.path=value`), resolves.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_yaml(&text, path, overrides)
    }

    pub fn from_yaml(text: &str, path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
        let yaml_err = |e: serde_yaml::Error| SceneError::Yaml {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut tree: serde_yaml::Value = serde_yaml::from_str(text).map_err(yaml_err)?;
        for arg in overrides {
            Override::parse(arg)
                .and_then(|o| o.apply(&mut tree))
                .map_err(|source| SceneError::Override {
                    path: path.to_path_buf(),
                    source,
                })?;
        }
        let written = serde_json::to_value(&tree).unwrap_or(serde_json::Value::Null);
        let raw: RawScene = serde_yaml::from_value(tree).map_err(yaml_err)?;
        let mut scene = raw.resolve().map_err(|source| SceneError::Invalid {
            path: path.to_path_buf(),
            source,
        })?;
        scene.written = written;
        Ok(scene)
    }
}

impl RawScene {
    pub fn resolve(&self) -> Result<Scene, SectionError> {
        check_name(&self.name).map_err(SectionError::Name)?;
        let (bar, specimen) = geom::spec::resolve(&self.bar, &self.specimen)?;
        Ok(Scene {
            name: self.name.clone(),
            bar,
            specimen,
            mesh: self.mesh.resolve()?,
            materials: self.materials.resolve()?,
            loading: self.loading.resolve()?,
            solver: self.solver.resolve()?,
            outputs: self.outputs.resolve()?,
            written: serde_json::Value::Null,
        })
    }
}
