//! A scene spec: the sections owned by each crate, composed; read from YAML
//! with `--set` overrides applied to the tree first, then resolved to SI.

use crate::outputs::{Outputs, RawOutputs};
use crate::overrides::Override;
use geom::spec::{Bar, RawBar, RawSpecimen, Specimen};
use mesh::spec::{MeshSpec, RawMeshSpec};
use serde::{Deserialize, Serialize};
use solve::spec::materials::{Materials, NonAdhesive, RawMaterials};
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
    /// `specimen.non_adhesive`, taken out of the `specimen` section before
    /// geom reads it: the solve stage reads it (which law the free zone
    /// gets), the geometry does not depend on it.
    #[serde(skip)]
    pub non_adhesive: Option<NonAdhesive>,
}

/// The specimen section: its geometry (geom's) and the interface the solve
/// puts on its non-adhesive zone (solve's). Serialised as one `specimen`
/// object, as written.
#[derive(Debug, Clone, Serialize)]
pub struct SpecimenSection {
    #[serde(flatten)]
    pub geometry: Specimen,
    pub non_adhesive: NonAdhesive,
}

/// The resolved scene: every value in SI, defaults filled in, bounds checked.
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    pub name: String,
    pub bar: Bar,
    pub specimen: SpecimenSection,
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
    #[error("{key}: {detail}")]
    Inconsistent { key: &'static str, detail: String },
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

/// Removes `specimen.non_adhesive` from the spec tree and reads it.
fn take_non_adhesive(tree: &mut serde_yaml::Value) -> Result<Option<NonAdhesive>, String> {
    let Some(specimen) = tree
        .get_mut("specimen")
        .and_then(serde_yaml::Value::as_mapping_mut)
    else {
        return Ok(None);
    };
    match specimen.remove("non_adhesive") {
        None => Ok(None),
        Some(v) => serde_yaml::from_value(v)
            .map(Some)
            .map_err(|e| format!("specimen.non_adhesive: {e}")),
    }
}

/// A deserialisation error prefixed with the dotted key it concerns (the
/// spec tree has lost its line numbers once overrides are applied), and the
/// `--set` argument that wrote the key, if one did.
fn located_message(
    err: &serde_path_to_error::Error<serde_yaml::Error>,
    overrides: &[String],
) -> String {
    let key = err.path().to_string();
    let inner = err.inner().to_string();
    if key.is_empty() || key == "." {
        return inner;
    }
    // The last of repeated `--set`s of a key is the one that holds.
    let set_by = overrides.iter().rev().find(|arg| {
        arg.split_once('=').is_some_and(|(k, _)| {
            let k = k.trim();
            key == k || key.starts_with(&format!("{k}."))
        })
    });
    match set_by {
        Some(arg) => format!("{key}: {inner} (from --set {arg})"),
        None => format!("{key}: {inner}"),
    }
}

impl Scene {
    /// Reads `path`, applies `overrides` (`key.path=value`), resolves.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
        let text =
            geom::fsutil::read_capped(path, geom::fsutil::MAX_SPEC_BYTES).map_err(|source| {
                SceneError::Read {
                    path: path.to_path_buf(),
                    source,
                }
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
        let non_adhesive = take_non_adhesive(&mut tree).map_err(|message| SceneError::Yaml {
            path: path.to_path_buf(),
            message,
        })?;
        let mut raw: RawScene =
            serde_path_to_error::deserialize(tree).map_err(|e| SceneError::Yaml {
                path: path.to_path_buf(),
                message: located_message(&e, overrides),
            })?;
        raw.non_adhesive = non_adhesive;
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
        let (bar, geometry) = geom::spec::resolve(&self.bar, &self.specimen)?;
        let materials = self.materials.resolve()?;
        let solver = self.solver_for(&materials).resolve()?;
        averaging_is_staggered(&materials, &solver)?;
        let mesh = self.mesh.resolve()?;
        // Before any work: a mesh far finer than meant is refused here.
        mesh::estimate::check_size(&bar, &geometry, &mesh)?;
        Ok(Scene {
            name: self.name.clone(),
            bar,
            specimen: SpecimenSection {
                geometry,
                non_adhesive: self.non_adhesive.unwrap_or_default(),
            },
            mesh,
            materials,
            loading: self.loading.resolve()?,
            solver,
            outputs: self.outputs.resolve()?,
            written: serde_json::Value::Null,
        })
    }

    /// The solver section as written, with IMPL-EX concrete where a
    /// gradient-enhanced damage leaves the integration unset: that is the
    /// only integration it runs with, so the default follows it; an
    /// integration written out is kept (and refused below if implicit).
    fn solver_for(&self, materials: &solve::spec::materials::Materials) -> RawSolver {
        use solve::spec::materials::ConcreteModel;
        use solve::spec::solver::ConcreteIntegration;
        let mut solver = self.solver.clone();
        let averaged = matches!(materials.concrete,
            ConcreteModel::Mazars(m) if m.nonlocal_length.is_some());
        if averaged && solver.concrete_integration.is_none() {
            solver.concrete_integration = Some(ConcreteIntegration::ImplEx);
        }
        solver
    }
}

/// A gradient-enhanced damage runs only staggered under IMPL-EX concrete
/// (`solve::nonlocal::admits`); said before anything is meshed.
fn averaging_is_staggered(
    materials: &solve::spec::materials::Materials,
    solver: &solve::spec::solver::SolverSettings,
) -> Result<(), SectionError> {
    use solve::spec::materials::ConcreteModel;
    let length = match materials.concrete {
        ConcreteModel::Mazars(m) => m.nonlocal_length,
        ConcreteModel::Elastic(_) => None,
    };
    if solve::nonlocal::admits(length, solver.concrete_integration) {
        return Ok(());
    }
    Err(SectionError::Inconsistent {
        key: "materials.concrete.nonlocal_length",
        detail: solve::nonlocal::NEEDS_IMPL_EX.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A gradient-enhanced damage with implicit concrete is refused naming
    /// both keys; with the integration unset it takes IMPL-EX.
    #[test]
    fn nonlocal_length_needs_impl_ex() {
        use solve::spec::solver::ConcreteIntegration;
        let path = Path::new("s.yaml");
        let set = |extra: &[&str]| {
            let mut sets = vec![
                "materials.concrete.regularisation_length=2 mm".to_string(),
                "materials.concrete.nonlocal_length=1 mm".to_string(),
            ];
            sets.extend(extra.iter().map(|s| s.to_string()));
            Scene::from_yaml(SCENE, path, &sets)
        };
        let err = set(&["solver.concrete_integration=implicit"])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("materials.concrete.nonlocal_length")
                && err.contains("solver.concrete_integration: impl_ex"),
            "{err}"
        );
        assert!(set(&["solver.concrete_integration=impl_ex"]).is_ok());
        // Left unset, the integration follows the averaging.
        let scene = set(&[]).unwrap();
        assert_eq!(
            scene.solver.concrete_integration,
            ConcreteIntegration::ImplEx
        );
        let local = Scene::from_yaml(SCENE, Path::new("s.yaml"), &[]).unwrap();
        assert_eq!(
            local.solver.concrete_integration,
            ConcreteIntegration::Implicit
        );
    }

    const SCENE: &str = "name: s\nbar: {kind: smooth, diameter: 8 mm}\n";

    /// `specimen.non_adhesive` is read for the solve, not by geom: it
    /// resolves into the scene's specimen section, appears in the resolved
    /// specimen object where it was written (the solve key's pointer), and
    /// a bad value names the key.
    #[test]
    fn non_adhesive_is_read_beside_the_geometry() {
        let path = Path::new("s.yaml");
        let scene =
            Scene::from_yaml(SCENE, path, &["specimen.non_adhesive=contact".into()]).unwrap();
        assert_eq!(scene.specimen.non_adhesive, NonAdhesive::Contact);
        let json = serde_json::to_value(&scene).unwrap();
        assert_eq!(json.pointer("/specimen/non_adhesive").unwrap(), "contact");
        assert!(json.pointer("/specimen/cube_side").is_some());
        let default = Scene::from_yaml(SCENE, path, &[]).unwrap();
        assert_eq!(default.specimen.non_adhesive, NonAdhesive::Free);
        let err = Scene::from_yaml(SCENE, path, &["specimen.non_adhesive=glued".into()])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("specimen.non_adhesive") && err.contains("glued"),
            "{err}"
        );
    }

    /// Type errors found after the tree is built name the key, and the
    /// `--set` argument when one wrote it.
    #[test]
    fn type_errors_name_the_key_and_the_override() {
        let path = Path::new("s.yaml");
        let in_file = format!("{SCENE}solver: {{max_iterations: abc}}\n");
        let err = Scene::from_yaml(&in_file, path, &[])
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("s.yaml: solver.max_iterations: ") && !err.contains("--set"),
            "{err}"
        );
        let sets = [
            "solver.max_iterations=abc".to_string(),
            "solver.max_iterations=also wrong".to_string(),
        ];
        let err = Scene::from_yaml(SCENE, path, &sets)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("solver.max_iterations: ")
                && err.ends_with("(from --set solver.max_iterations=also wrong)"),
            "{err}"
        );
        let err = Scene::from_yaml(SCENE, path, &["bar.diameter=[8]".into()])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bar.diameter: ") && err.contains("quantity with a unit"),
            "{err}"
        );
    }
}
