//! gmsh discovery honours the GMSH variable (its own test binary: it sets
//! the process environment).

use geom::gmsh::{Gmsh, GmshError};

/// A GMSH variable naming a missing file is an error that says what to do, not a silent fallback (SPEC §4, issue 2).
#[test]
fn bad_gmsh_variable_is_reported_with_the_fix() {
    std::env::set_var("GMSH", "/nonexistent/gmsh");
    let err = Gmsh::locate().unwrap_err();
    assert!(matches!(err, GmshError::BadEnv { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("/nonexistent/gmsh")
            && msg.contains("scripts/setup.sh")
            && msg.contains("GMSH"),
        "{msg}"
    );
    std::env::remove_var("GMSH");
    // Without the variable the project-local install is found and its version read.
    let g = Gmsh::locate().expect("project-local gmsh (scripts/setup.sh)");
    assert!(g.version().starts_with('4'), "{}", g.version());
    // A failing run surfaces gmsh's own message.
    let dir = std::env::temp_dir();
    let err = g
        .run(
            &["/nonexistent/file.geo", "-0"],
            Some(&dir),
            std::time::Duration::from_secs(60),
        )
        .map(|o| format!("{}{}", o.stdout, o.stderr));
    let text = match err {
        Ok(out) => out,
        Err(e) => e.to_string(),
    };
    assert!(text.contains("nonexistent"), "{text}");
}
