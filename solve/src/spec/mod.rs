//! Scene spec sections read by the solver: raw (as written) and resolved (SI).

pub mod materials;
pub mod solver;
