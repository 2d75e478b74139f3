//! Geometry of ribbar: units, the bar and specimen sections of a scene spec,
//! rib metrics, and the gmsh `.geo` that builds the specimen.
//!
//! ```no_run
//! use geom::spec::{resolve, RawBar, RawSpecimen};
//! let bar: RawBar = serde_yaml::from_str("{kind: ribbed, diameter: 8 mm}").unwrap();
//! let (bar, specimen) = resolve(&bar, &RawSpecimen::default()).unwrap();
//! let report = geom::build_geometry(&bar, &specimen, std::path::Path::new("work/r1")).unwrap();
//! println!("f_R = {:.3}", report.f_r);
//! ```

pub mod build;
pub mod capture;
pub mod diagnose;
pub mod fsutil;
pub mod geo;
pub mod gmsh;
pub mod layout;
pub mod metrics;
pub mod occ;
pub mod spec;
pub mod units;

pub use build::{build_geometry, GeomError, GeometryReport};
