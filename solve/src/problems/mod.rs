//! The boundary-value problems ribbar solves, built from a model's node sets.

pub mod pullout;
