//! A scene spec: the sections owned by each crate, composed; read from YAML
//! with `--set` overrides applied to the tree first, then resolved to SI.

use crate::outputs::{Outputs, RawOutputs};
use crate::overrides::Override;
use geom::spec::{Bar, RawBar, RawSpecimen, Specimen};
use mesh::spec::{MeshSpec, RawMeshSpec};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use solve::spec::materials::{Materials, NonAdhesive, RawMaterials};
use solve::spec::solver::{Loading, RawLoading, RawSolver, SolverSettings};
use std::path::{Path, PathBuf};

/// The spec as written (after overrides). Every field's doc comment is its
/// text in the scene reference and the JSON Schema (`ribbar schema scene`).
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    /// The scene's name: its results go to `WORK/<name>/` (text; required;
    /// 1–100 letters, digits, `-`, `_` or `.`, not starting with `.`).
    pub name: String,
    /// The bar: smooth or ribbed, its diameter and its ribs.
    pub bar: RawBar,
    /// The pull-out specimen: the concrete cube, the bonded length, the
    /// bar's overhangs and the modelled part.
    #[serde(default)]
    #[schemars(with = "crate::schema::SpecimenSection")]
    pub specimen: RawSpecimen,
    /// How gmsh meshes the specimen.
    #[serde(default)]
    pub mesh: RawMeshSpec,
    /// The constitutive laws of the concrete, the steel and the interface.
    #[serde(default)]
    pub materials: RawMaterials,
    /// The imposed displacement of the bar's loaded end and its steps.
    #[serde(default)]
    pub loading: RawLoading,
    /// The nonlinear solver: convergence criteria, linear solvers,
    /// integration of the laws.
    #[serde(default)]
    pub solver: RawSolver,
    /// Which fields, plots and summary quantities are produced.
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
    with_override(&key, format!("{key}: {inner}"), overrides)
}

/// `message` about `key`, with the `--set` argument that wrote the key (or
/// a mapping above it), if one did: the last of repeated ones, which holds.
fn with_override(key: &str, message: String, overrides: &[String]) -> String {
    let set_by = overrides.iter().rev().find(|arg| {
        arg.split_once('=').is_some_and(|(k, _)| {
            let k = k.trim();
            key == k || key.starts_with(&format!("{k}."))
        })
    });
    match set_by {
        Some(arg) => format!("{message} (from --set {arg})"),
        None => message,
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
        if let Err(e) = solve::spec::solver::moved_key(&tree) {
            let key = match &e {
                solve::spec::solver::SolverSpecError::Moved { key, .. } => key.clone(),
                _ => String::new(),
            };
            return Err(SceneError::Yaml {
                path: path.to_path_buf(),
                message: with_override(&key, e.to_string(), overrides),
            });
        }
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
    /// The JSON Schema of a scene file (`ribbar schema scene`).
    pub fn schema() -> serde_json::Value {
        crate::schema::root::<RawScene>(
            "ribbar scene",
            "A ribbar scene: one pull-out specimen, its mesh, laws, loading, solver and outputs.",
        )
    }

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
            loading: self.loading.resolve(&self.solver)?,
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
    use serde_json::Value;

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
        let in_file = format!("{SCENE}solver: {{expert: {{max_iterations: abc}}}}\n");
        let err = Scene::from_yaml(&in_file, path, &[])
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("s.yaml: solver.expert.max_iterations: ") && !err.contains("--set"),
            "{err}"
        );
        let sets = [
            "solver.expert.max_iterations=abc".to_string(),
            "solver.expert.max_iterations=also wrong".to_string(),
        ];
        let err = Scene::from_yaml(SCENE, path, &sets)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("solver.expert.max_iterations: ")
                && err.ends_with("(from --set solver.expert.max_iterations=also wrong)"),
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

    /// A key of the earlier `loading`/`solver` layout, in the file or from
    /// `--set`, is refused with its new place and the argument that wrote it.
    #[test]
    fn moved_keys_name_their_new_place() {
        let path = Path::new("s.yaml");
        let in_file = format!("{SCENE}solver: {{forcing: tolerance}}\n");
        let err = Scene::from_yaml(&in_file, path, &[])
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "s.yaml: solver.forcing: moved to solver.expert.forcing"
        );
        let err = Scene::from_yaml(SCENE, path, &["loading.growth=2".into()])
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "s.yaml: loading.growth: moved to solver.expert.growth (from --set loading.growth=2)"
        );
        let scene = Scene::from_yaml(SCENE, path, &["solver.expert.growth=2".into()]).unwrap();
        assert_eq!(scene.loading.growth, 2.0);
    }

    /// The schema of `loading`, `solver` and `solver.expert` lists exactly
    /// the keys their parser accepts, and a key of an earlier layout
    /// (`solver.max_iterations`) is not among them.
    #[test]
    fn loading_and_solver_schemas_list_the_parsers_keys() {
        use crate::schema::struct_fields;
        use solve::spec::solver::RawExpert;
        let scene = RawScene::schema();
        for (definition, parser) in [
            ("RawLoading", struct_fields::<RawLoading>()),
            ("RawSolver", struct_fields::<RawSolver>()),
            ("RawExpert", struct_fields::<RawExpert>()),
        ] {
            let properties = scene
                .pointer(&format!("/$defs/{definition}/properties"))
                .and_then(Value::as_object)
                .unwrap_or_else(|| panic!("{definition}: {scene}"));
            let mut schema_keys: Vec<&str> = properties.keys().map(String::as_str).collect();
            let mut parser_keys = parser.to_vec();
            schema_keys.sort_unstable();
            parser_keys.sort_unstable();
            assert_eq!(schema_keys, parser_keys, "{definition}");
        }
        let solver = scene.pointer("/$defs/RawSolver/properties").unwrap();
        assert!(solver.get("max_iterations").is_none());
        assert!(solver.get("profile").is_some());
    }
}
