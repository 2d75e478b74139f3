//! What every stage runner is given.

use super::keys::Keys;
use super::kinds::Stage;
use crate::progress::Printer;
use crate::scene::Scene;
use crate::store::Store;
use std::path::PathBuf;

/// The scene, its keys, the store and the tools a stage runs with.
pub struct Ctx<'a> {
    pub store: &'a Store,
    pub scene: &'a Scene,
    pub keys: &'a Keys,
    pub gmsh: &'a geom::gmsh::Gmsh,
    pub printer: &'a Printer,
}

impl Ctx<'_> {
    /// The committed artifacts of `stage` for this scene.
    pub fn done_dir(&self, stage: Stage) -> PathBuf {
        self.store.artifact_dir(self.keys.get(stage))
    }
}
