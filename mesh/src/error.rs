//! Typed errors of the mesh stage: each names the file, group, key or
//! element concerned, so the caller can tell the user what to fix.

use std::path::PathBuf;

/// Everything that can go wrong between the `mesh` spec section and a
/// written model.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A key of the `mesh` spec section is invalid.
    #[error("mesh.{key}: {message}")]
    Spec { key: String, message: String },
    /// A quantity of the `mesh` spec section has a bad unit or number.
    #[error(transparent)]
    Unit(#[from] geom::units::UnitError),
    /// gmsh could not be found, checked or started.
    #[error(transparent)]
    Gmsh(#[from] geom::gmsh::GmshError),
    /// gmsh ran and failed; `output` holds the end of its messages.
    #[error("gmsh failed on {geo} ({status}); gmsh said:\n{output}", geo = .geo.display())]
    GmshFailed {
        geo: PathBuf,
        status: String,
        output: String,
    },
    /// gmsh ran and failed on entities that [`crate::explain_gmsh_failure`]
    /// located on the specimen: each diagnosis names the entity, where it
    /// is (which rib, which plane), what is wrong with it and what to change.
    #[error("gmsh could not mesh {geo}:\n{list}\ngmsh said:\n{output}",
            geo = .geo.display(),
            list = .diagnoses.iter().map(|d| format!("  - {d}")).collect::<Vec<_>>().join("\n"))]
    GmshFailedOn {
        geo: PathBuf,
        diagnoses: Vec<geom::diagnose::Diagnosis>,
        output: String,
    },
    /// The model gmsh built is not the specimen the geometry describes
    /// (a measure more than 1 % off, an empty group, leftover entities).
    #[error("the model gmsh built from the geometry's script: {0}")]
    Geometry(#[from] geom::GeomError),
    /// gmsh did not finish in time and was killed.
    #[error("gmsh did not finish meshing {geo} within {seconds} s (mesh.timeout) and was killed", geo = .geo.display())]
    GmshTimeout { geo: PathBuf, seconds: f64 },
    /// A file could not be read or written.
    #[error("{path}: {source}", path = .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The `.msh` file is truncated or not a valid gmsh 4.1 file.
    #[error("{path}: corrupt or truncated .msh file: {detail}", path = .path.display())]
    MshCorrupt { path: PathBuf, detail: String },
    /// An element references a node tag that the `$Nodes` section does not define.
    #[error("{path}: element {element} of {group} references node tag {tag}, which the $Nodes section does not define", path = .path.display())]
    BadNodeRef {
        path: PathBuf,
        group: String,
        element: u64,
        tag: u64,
    },
    /// A physical group the model needs is absent (or has no element of the needed type).
    #[error("{path}: physical group \"{group}\" is missing (expected {what})", path = .path.display())]
    MissingGroup {
        path: PathBuf,
        group: String,
        what: String,
    },
    /// The mesh is not the conforming steel/concrete mesh the model needs.
    #[error("{path}: {detail}", path = .path.display())]
    Topology { path: PathBuf, detail: String },
    /// A model file could not be encoded or decoded.
    #[error("{path}: model file: {detail}", path = .path.display())]
    ModelFile { path: PathBuf, detail: String },
}

impl MeshError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        MeshError::Io {
            path: path.into(),
            source,
        }
    }
}
