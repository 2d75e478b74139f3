//! The four stages of a scene, in order, and what each one is.

use std::fmt;

/// A stage of the pipeline (SPEC §7): each reads its upstream stage's
/// artifacts and the spec sections in its key (`super::keys`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    Geometry,
    Mesh,
    Solve,
    Post,
}

/// The file in a solve's in-progress directory that makes it resumable.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

impl Stage {
    /// Every stage, in the order they run.
    pub const ALL: [Stage; 4] = [Stage::Geometry, Stage::Mesh, Stage::Solve, Stage::Post];

    /// The stage's name: its subcommand, its store folder, its key's name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Geometry => "geometry",
            Stage::Mesh => "mesh",
            Stage::Solve => "solve",
            Stage::Post => "post",
        }
    }

    /// The stage called `name`, if any.
    pub fn from_name(name: &str) -> Option<Stage> {
        Stage::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The stage whose artifacts this one reads.
    pub fn upstream(self) -> Option<Stage> {
        match self {
            Stage::Geometry => None,
            Stage::Mesh => Some(Stage::Geometry),
            Stage::Solve => Some(Stage::Mesh),
            Stage::Post => Some(Stage::Solve),
        }
    }

    /// This stage and the ones before it, in order.
    pub fn up_to(self) -> &'static [Stage] {
        &Stage::ALL[..=self as usize]
    }

    /// Files the stage publishes under `WORK/<scene>/`.
    pub fn published_files(self) -> &'static [&'static str] {
        match self {
            Stage::Geometry => &["specimen.geo", "geometry.json"],
            Stage::Mesh => &["specimen.msh", "model.bin", "mesh.vtu", "mesh.json"],
            Stage::Solve => &["curve.csv", "solve.json", "fields"],
            Stage::Post => &[
                "summary.json",
                "bond_law.json",
                "plots",
                "interface_profile.csv",
            ],
        }
    }

    /// Whether an interrupted run keeps its in-progress directory to resume
    /// from (a solve's checkpoint); other stages start again.
    pub fn resumable(self) -> bool {
        self == Stage::Solve
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_order_is_the_run_order() {
        for s in Stage::ALL {
            assert_eq!(Stage::from_name(s.name()), Some(s));
            assert_eq!(s.up_to().last(), Some(&s));
            assert_eq!(s.upstream(), s.up_to().iter().rev().nth(1).copied());
        }
        assert_eq!(Stage::from_name("sovle"), None);
    }
}
