//! gmsh missing: `GMSH` naming a nonexistent file is a clear error (SPEC §4, §8).
//! Alone in its test binary because it sets an environment variable.

use mesh::{Gmsh, MeshError};

/// `GMSH` pointing to a nonexistent file is an error naming that file and
/// the way out, not a silent fallback to another gmsh (SPEC §4, §8).
#[test]
fn gmsh_missing_is_reported() {
    std::env::set_var("GMSH", "/nonexistent/gmsh");
    let err: MeshError = Gmsh::locate().unwrap_err().into();
    std::env::remove_var("GMSH");
    assert!(matches!(err, MeshError::Gmsh(_)), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("/nonexistent/gmsh") && msg.contains("GMSH"),
        "{msg}"
    );
}
