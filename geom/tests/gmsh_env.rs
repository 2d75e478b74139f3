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

/// A gmsh that cannot load a system library (the PyPI wheel without X11/GL
/// libraries) is reported with the packages that provide them.
#[test]
fn missing_system_library_names_the_packages() {
    let dir = std::env::temp_dir().join(format!("ribbar-gmsh-lib-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fake = dir.join("gmsh");
    // Written by a child shell, not by this process: an executable this
    // process held open for writing while the other test forks would fail
    // to start with "Text file busy".
    let script = "#!/bin/sh\necho 'OSError: libGLU.so.1: cannot open shared object file: No such file or directory' >&2\nexit 1\n";
    let written = std::process::Command::new("sh")
        .arg("-c")
        .arg("printf '%s' \"$1\" > \"$2\" && chmod 755 \"$2\"")
        .arg("sh")
        .arg(script)
        .arg(&fake)
        .status()
        .unwrap();
    assert!(written.success());
    let msg = Gmsh::probe(fake).unwrap_err().to_string();
    assert!(
        msg.contains("libGLU.so.1") && msg.contains("libglu1-mesa") && msg.contains("setup.sh"),
        "{msg}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
