//! The scene's `loading` and `solver` sections: raw (as written, with units;
//! `raw`) and resolved (SI, validated, defaults filled).
//!
//! ```
//! use solve::spec::solver::{RawLoading, RawSolver};
//! let l: RawLoading = serde_yaml::from_str("u_final: 0.5 mm\ninitial_step: 2 um").unwrap();
//! let s: RawSolver = serde_yaml::from_str("profile: impl_ex\nexpert: {max_iterations: 30}").unwrap();
//! let l = l.resolve(&s).unwrap();
//! assert!((l.u_final - 0.5e-3).abs() < 1e-15);
//! let s = s.resolve().unwrap();
//! assert_eq!((s.max_iterations, s.energy_tolerance), (30, 0.5));
//! ```

mod raw;
mod settings;

pub use raw::{moved_key, Profile, RawExpert, RawLoading, RawSolver};
pub use settings::*;
