//! Geometry of ribbar: units, the bar and specimen sections of a scene spec,
//! rib metrics, and the gmsh `.geo` that builds the specimen.

pub mod units;
