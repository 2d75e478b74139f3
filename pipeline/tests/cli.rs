//! End-to-end tests of the `ribbar` binary with real gmsh and real files:
//! every stage, the store's make-style behaviour, bad input, interruption.

use crate::common::{repo, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const TINY: &str = "tests/data/tiny-smooth.yaml";

fn work_dir(name: &str) -> PathBuf {
    crate::common::scratch("cli", name)
}

fn ribbar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args(args)
        .current_dir(repo())
        .stdin(Stdio::null())
        .output()
        .expect("ribbar runs")
}

fn ok(args: &[&str]) -> String {
    let o = ribbar(args);
    assert!(o.status.success(), "ribbar {args:?} failed:\n{}", text(&o));
    text(&o)
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn stage_line<'a>(out: &'a str, stage: &str) -> &'a str {
    out.lines()
        .find(|l| {
            l.starts_with(&format!("{stage}: "))
                && (l.contains("up to date") || l.contains("done in"))
        })
        .unwrap_or_else(|| panic!("no line for stage {stage} in:\n{out}"))
}

/// SPEC §1/§7: `run` produces every artifact of every stage under
/// WORK/<name>/, readable by the tools users have (CSV, JSON, VTU, PNG/SVG).
#[test]
fn run_writes_every_artifact() {
    let work = work_dir("artifacts");
    let w = work.to_str().unwrap();
    ok(&["run", TINY, "--work", w]);
    let scene = work.join("tiny-smooth");
    for f in [
        "specimen.geo",
        "geometry.json",
        "specimen.msh",
        "model.bin",
        "mesh.vtu",
        "mesh.json",
        "curve.csv",
        "solve.json",
        "summary.json",
        "plots/bond_slip.png",
        "plots/bond_slip.svg",
        "plots/interface_profile.png",
        "fields/step0002_bulk.vtu",
        "fields/peak_bulk.vtu",
        "fields/end_interface.vtu",
    ] {
        assert!(scene.join(f).is_file(), "missing {f}");
    }
    let curve = read(&scene.join("curve.csv"));
    // The six required columns, then the energy balance's (issue 7).
    let header = [
        solve::curve::CURVE_COLUMNS.as_slice(),
        &solve::curve::ENERGY_COLUMNS,
    ]
    .concat()
    .join(",");
    assert_eq!(curve.lines().next(), Some(header.as_str()), "{curve}");
    assert!(curve.lines().count() > 5, "{curve}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&scene.join("summary.json"))).unwrap();
    let peak = summary
        .pointer("/curve/peak_bond_stress")
        .and_then(|v| v.as_f64())
        .unwrap();
    assert!(peak > 1e5 && peak < 1e8, "peak bond stress {peak} Pa");
    assert!(summary
        .pointer("/solver/summary/wall_time_s/factorisation")
        .is_some());
    // The peak fields are those of the first peak's step (kept in memory
    // and written once the curve has dropped past it).
    let step_at_peak = summary
        .pointer("/curve/step_at_peak")
        .and_then(|v| v.as_u64())
        .unwrap();
    let profile = read(&scene.join("interface_profile.csv"));
    let steps: std::collections::BTreeSet<u64> = profile
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(
        steps.contains(&step_at_peak),
        "{steps:?} lacks {step_at_peak}"
    );
    assert_eq!(steps.len(), 3, "step 2, the peak and the end: {steps:?}");
    let vtu = read(&scene.join("fields/peak_bulk.vtu"));
    assert!(
        vtu.contains("<VTKFile") && vtu.contains("Name=\"D\"") && vtu.contains("principal_stress")
    );
    // The ParaView collection: every written step once, in loading order,
    // each with its bulk and interface parts, and each file present.
    let pvd = read(&scene.join("fields/fields.pvd"));
    let datasets: Vec<(f64, String)> = pvd
        .lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let attr = |name: &str| {
                let start = l.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
                l[start..start + l[start..].find('"').unwrap()].to_string()
            };
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect();
    let files: Vec<&str> = datasets.iter().map(|(_, f)| f.as_str()).collect();
    assert_eq!(
        files,
        [
            "step0002_bulk.vtu",
            "step0002_interface.vtu",
            "peak_bulk.vtu",
            "peak_interface.vtu",
            "end_bulk.vtu",
            "end_interface.vtu"
        ],
        "{pvd}"
    );
    for (_, f) in &datasets {
        assert!(scene.join("fields").join(f).is_file(), "{f}");
    }
    assert!(datasets.windows(3).all(|w| w[0].0 < w[2].0), "{pvd}");
    let u_final = curve.lines().last().unwrap().split(',').nth(1).unwrap();
    assert_eq!(datasets[5].0, u_final.parse::<f64>().unwrap(), "{pvd}");
    let png = std::fs::read(scene.join("plots/bond_slip.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Nothing half-written is left beside the published files.
    let leftovers: Vec<_> = std::fs::read_dir(&scene)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    outputs_reference_names_everything(&scene);
    std::fs::remove_dir_all(&work).unwrap();
}

/// The user guide's output reference names every file of a scene's
/// results, every column of curve.csv, every array of the field and mesh
/// files and every key of summary.json's curve and of mesh.json: what a
/// user reads there is what the files hold.
fn outputs_reference_names_everything(scene: &Path) {
    let page = read(&repo().join("docs/src/reference/outputs.md"));
    let named = |name: &str| page.contains(&format!("`{name}`"));
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(scene).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        // A directory is listed by its path (`fields/`, `plots/bond_slip.png`).
        if !page.contains(&format!("`{name}")) {
            missing.push(name);
        }
    }
    let header = read(&scene.join("curve.csv"));
    let columns = header.lines().next().unwrap().split(',').map(String::from);
    let summary: serde_json::Value =
        serde_json::from_str(&read(&scene.join("summary.json"))).unwrap();
    let curve_keys = summary["curve"]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| format!("curve.{k}"));
    let mesh: serde_json::Value = serde_json::from_str(&read(&scene.join("mesh.json"))).unwrap();
    let mesh_keys = mesh.as_object().unwrap().keys().cloned();
    let arrays = [
        "fields/peak_bulk.vtu",
        "fields/peak_interface.vtu",
        "mesh.vtu",
    ]
    .iter()
    .flat_map(|f| {
        // mesh.vtu's arrays are raw binary after its XML.
        String::from_utf8_lossy(&std::fs::read(scene.join(f)).unwrap())
            .split("Name=\"")
            .skip(1)
            .map(|s| s[..s.find('"').unwrap()].to_string())
            .filter(|n| !matches!(n.as_str(), "Points" | "connectivity" | "offsets" | "types"))
            .collect::<Vec<_>>()
    });
    for name in columns.chain(curve_keys).chain(mesh_keys).chain(arrays) {
        if !named(&name) {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "docs/src/reference/outputs.md does not name {missing:?}"
    );
}

/// Issue 6: a second run with nothing changed runs nothing; a materials
/// change reruns solve and post only; a mesh size change reruns mesh,
/// solve and post; `status` names the changed spec keys.
#[test]
fn stages_rerun_only_what_changed() {
    let work = work_dir("make");
    let w = work.to_str().unwrap();
    ok(&["run", TINY, "--work", w]);
    let again = ok(&["run", TINY, "--work", w]);
    for stage in ["geometry", "mesh", "solve", "post"] {
        assert!(stage_line(&again, stage).contains("up to date"), "{again}");
    }
    assert!(ok(&["status", TINY, "--work", w]).contains("every stage is up to date"));

    let mu = "materials.interface.mu=0.001";
    let status = ok(&["status", TINY, "--work", w, "--set", mu]);
    assert!(
        status.contains("geometry  up to date") && status.contains("mesh      up to date"),
        "{status}"
    );
    let solve_line = status.lines().find(|l| l.starts_with("solve")).unwrap();
    assert!(
        solve_line.contains("stale") && solve_line.contains("materials.interface.mu"),
        "{status}"
    );
    let out = ok(&["run", TINY, "--work", w, "--set", mu]);
    assert!(stage_line(&out, "geometry").contains("up to date"), "{out}");
    assert!(stage_line(&out, "mesh").contains("up to date"), "{out}");
    assert!(stage_line(&out, "solve").contains("done in"), "{out}");
    assert!(stage_line(&out, "post").contains("done in"), "{out}");

    let h = "mesh.h_interface=2.5 mm";
    let status = ok(&["status", TINY, "--work", w, "--set", h]);
    assert!(
        status
            .lines()
            .any(|l| l.starts_with("mesh") && l.contains("mesh.h_interface")),
        "{status}"
    );
    let out = ok(&["run", TINY, "--work", w, "--set", h]);
    assert!(stage_line(&out, "geometry").contains("up to date"), "{out}");
    for stage in ["mesh", "solve", "post"] {
        assert!(stage_line(&out, stage).contains("done in"), "{out}");
    }
    // Changing only how post reports reruns post alone.
    let out = ok(&[
        "run",
        TINY,
        "--work",
        w,
        "--set",
        "outputs.energy_fed_limit=0.1 mm",
    ]);
    assert!(stage_line(&out, "solve").contains("up to date"), "{out}");
    assert!(stage_line(&out, "post").contains("done in"), "{out}");

    // The quarter model's fields on the whole specimen: a solve option
    // (the stored solve without it stays valid for scenes that do not ask).
    let whole = "outputs.fields.whole_specimen=true";
    let out = ok(&["run", TINY, "--work", w, "--set", h, "--set", whole]);
    assert!(stage_line(&out, "mesh").contains("up to date"), "{out}");
    assert!(stage_line(&out, "solve").contains("done in"), "{out}");
    let model = mesh::Model::load(&work.join("tiny-smooth/model.bin")).unwrap();
    assert_eq!(model.symmetry, mesh::Symmetry::Quarter);
    let unfolded = model.unfold().model;
    for part in ["bulk", "interface"] {
        let vtu = read(&work.join(format!("tiny-smooth/fields/end_{part}.vtu")));
        assert!(
            vtu.contains(&format!("NumberOfPoints=\"{}\"", unfolded.nodes.len())),
            "{part}: not the whole specimen's {} points",
            unfolded.nodes.len()
        );
    }
    let bulk = read(&work.join("tiny-smooth/fields/end_bulk.vtu"));
    assert!(bulk.contains(&format!("NumberOfCells=\"{}\"", unfolded.tets.len())));
    std::fs::remove_dir_all(&work).unwrap();
}

/// README: the default work directory is relative to where ribbar runs,
/// and every stage (gmsh included) works from there.
#[test]
fn relative_work_directory() {
    let dir = work_dir("relative");
    std::fs::create_dir_all(&dir).unwrap();
    let spec = repo().join(TINY);
    let o = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args(["mesh", spec.to_str().unwrap()])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(dir.join("ribbar-work/tiny-smooth/mesh.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// SPEC §8: bad input names the file and key, exits non-zero, never panics
/// and leaves earlier artifacts intact.
#[test]
fn bad_input_is_reported_and_keeps_artifacts() {
    let work = work_dir("bad");
    let w = work.to_str().unwrap();
    ok(&["geometry", TINY, "--work", w]);
    let geo = work.join("tiny-smooth/specimen.geo");
    let before = read(&geo);
    let cases: &[(&[&str], &str)] = &[
        (&["--set", "bar.diameterr=8 mm"], "diameterr"),
        (&["--set", "bar.diameter=8 MPa"], "bar.diameter"),
        (
            &["--set", "specimen.adhesive_length=30 mm"],
            "specimen.adhesive_length",
        ),
        (
            &["--set", "materials.interface.mu=-1"],
            "materials.interface.mu",
        ),
        (&["--set", "mesh.h_outer=0.1 mm"], "mesh.h_outer"),
        (
            &["--set", "solver.expert.cutback=2"],
            "solver.expert.cutback",
        ),
        (
            &["--set", "solver.expert.max_steps=0"],
            "solver.expert.max_steps",
        ),
        (
            &["--set", "loading.cutback=0.4"],
            "loading.cutback: moved to solver.expert.cutback",
        ),
        (&["--set", "bar.diameter"], "KEY=VALUE"),
        (
            &["--set", "solver.expert.max_iterations=many"],
            "solver.expert.max_iterations: invalid type",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["run", TINY, "--work", w];
        args.extend_from_slice(extra);
        let o = ribbar(&args);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {t}");
        assert!(t.contains(needle), "{extra:?} should name {needle}: {t}");
        assert!(!t.contains("panicked"), "{t}");
    }
    let o = ribbar(&["run", "specs/no-such-scene.yaml", "--work", w]);
    assert!(
        !o.status.success() && text(&o).contains("no-such-scene.yaml"),
        "{}",
        text(&o)
    );
    let broken = work.join("broken.yaml");
    std::fs::write(&broken, "name: x\nbar: {kind: smooth, diameter: [\n").unwrap();
    let o = ribbar(&["run", broken.to_str().unwrap(), "--work", w]);
    assert!(
        !o.status.success() && text(&o).contains("broken.yaml"),
        "{}",
        text(&o)
    );
    // gmsh missing: a clear message, and the published geometry untouched.
    let o = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args(["run", TINY, "--work", w, "--set", "bar.diameter=6 mm"])
        .current_dir(repo())
        .env("GMSH", "/nonexistent/gmsh")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        text(&o).contains("/nonexistent/gmsh") && text(&o).contains("setup"),
        "{}",
        text(&o)
    );
    assert_eq!(read(&geo), before);
    std::fs::remove_dir_all(&work).unwrap();
}

/// `solver.expert.max_steps` ends the solve after that many converged steps: the
/// curve keeps them, solve.json says why it stopped, `run` exits non-zero,
/// and a rerun finds the (deterministic) result up to date; `-v` shows
/// each step's residuals.
#[test]
fn step_limit_keeps_the_converged_steps() {
    let work = work_dir("steplimit");
    let w = work.to_str().unwrap();
    let args = [
        "run",
        TINY,
        "--work",
        w,
        "--set",
        "solver.expert.max_steps=3",
    ];
    let mut verbose = args.to_vec();
    verbose.push("-v");
    let o = ribbar(&verbose);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("solver.expert.max_steps = 3"), "{t}");
    // -v: each converged step's residual history and phase times.
    assert_eq!(t.matches("relative residuals [").count(), 3, "{t}");
    assert!(t.contains("factorisation"), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    let curve = read(&work.join("tiny-smooth/curve.csv"));
    assert_eq!(curve.lines().count(), 1 + 3, "{curve}");
    let solve: serde_json::Value =
        serde_json::from_str(&read(&work.join("tiny-smooth/solve.json"))).unwrap();
    assert_eq!(solve["completed"], false);
    assert!(solve["stopped"].as_str().unwrap().contains("max_steps"));
    // Not one of the endings of a run that got to its end.
    assert!(solve["ending"].is_null(), "{solve}");
    assert!(work.join("tiny-smooth/plots/bond_slip.png").is_file());
    let again = text(&ribbar(&args));
    assert!(
        stage_line(&again, "solve").contains("up to date"),
        "{again}"
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// Issue 4: `ribbar material` drives a shipped material-point file and
/// writes the documented CSV columns.
#[test]
fn material_driver_writes_csv() {
    let work = work_dir("material");
    std::fs::create_dir_all(&work).unwrap();
    let dir = repo().join("specs/material");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .collect();
    files.sort();
    let fczm = files
        .iter()
        .find(|p| read(p).contains("law: fczm"))
        .expect("a shipped FCZM test file");
    let out = work.join("point.csv");
    ok(&[
        "material",
        fczm.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let csv = read(&out);
    assert!(
        csv.starts_with("t,un,ut,uh,tn,tt,th,D"),
        "{}",
        &csv[..80.min(csv.len())]
    );
    assert!(csv.lines().count() > 10);
    let bad = work.join("bad.yaml");
    std::fs::write(
        &bad,
        "law: fczm\nparameters: {ft: \"3 MPa\", mu: -1}\npath: [{t: 0}, {t: 1, un: 1e-5}]\n",
    )
    .unwrap();
    let o = ribbar(&["material", bad.to_str().unwrap()]);
    assert!(
        !o.status.success() && text(&o).contains("bad.yaml"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// A reader that stops early (`ribbar material F | head -1`) ends the
/// command quietly: exit 0, no error, no panic.
#[test]
fn closed_stdout_ends_quietly() {
    use std::io::{BufRead, BufReader};
    let file = repo().join("specs/material/fczm-shear-reverse.yaml");
    let mut child = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args(["material", file.to_str().unwrap()])
        .current_dir(repo())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    // The table is larger than a pipe's buffer, so the writer meets the
    // closed end.
    assert!(first.starts_with("t,un,ut"), "{first}");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.is_empty(), "{err}");
}

/// The six curve columns must agree to the bit; the energy diagnostics
/// after them are sums over elements, equal to round-off.
fn assert_same_curve(got: &str, expected: &str, context: &str) {
    let (g, e): (Vec<&str>, Vec<&str>) = (got.lines().collect(), expected.lines().collect());
    assert_eq!(g.len(), e.len(), "{context}: row count");
    assert_eq!(g[0], e[0], "{context}: header");
    for (a, b) in g.iter().zip(&e).skip(1) {
        let (fa, fb): (Vec<&str>, Vec<&str>) = (a.split(',').collect(), b.split(',').collect());
        assert_eq!(fa[..6], fb[..6], "{context}: curve row differs:\n{a}\n{b}");
        assert_eq!(fa.len(), fb.len(), "{context}");
        for (x, y) in fa[6..].iter().zip(&fb[6..]) {
            let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-12),
                "{context}: energy {x} vs {y}"
            );
        }
    }
}

/// Issue 6: killing `ribbar run` (SIGKILL) at any moment leaves no artifact
/// that looks complete, and the next run finishes with the same curve as an
/// uninterrupted run (a killed solve resumes from its checkpoint).
#[test]
fn killed_runs_resume_to_the_same_curve() {
    let slow = [
        "--set",
        "loading.max_step=4 um",
        "--set",
        "loading.initial_step=2 um",
    ];
    let reference = work_dir("kill-ref");
    let r = reference.to_str().unwrap();
    let mut args = vec!["run", TINY, "--work", r];
    args.extend_from_slice(&slow);
    let started = Instant::now();
    ok(&args);
    let full = started.elapsed();
    let expected = read(&reference.join("tiny-smooth/curve.csv"));

    let work = work_dir("kill");
    let w = work.to_str().unwrap();
    let mut resumed = false;
    // Kill times spread over the whole pipeline: geometry, mesh, solve, post.
    for fraction in [0.03, 0.1, 0.2, 0.3, 0.45, 0.6, 0.75, 0.9, 0.97] {
        let delay = full.mul_f64(fraction);
        let mut args = vec!["run", TINY, "--work", w, "-v"];
        args.extend_from_slice(&slow);
        let mut child = Command::new(env!("CARGO_BIN_EXE_ribbar"))
            .args(&args)
            .current_dir(repo())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while start.elapsed() < delay {
            if child.try_wait().unwrap().is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let _ = child.kill(); // SIGKILL on Unix
        let _ = child.wait();
        // Whatever is published parses.
        let scene = work.join("tiny-smooth");
        for json in ["geometry.json", "mesh.json", "solve.json", "summary.json"] {
            if let Ok(t) = std::fs::read_to_string(scene.join(json)) {
                serde_json::from_str::<serde_json::Value>(&t)
                    .unwrap_or_else(|e| panic!("{json}: {e}"));
            }
        }
        let out = ok(&args);
        resumed |= out.contains("resuming after step");
        // Should the curves differ, say whether the mesh did too.
        let mesh_line = |dir: &Path| {
            std::fs::read_to_string(dir.join("mesh.json"))
                .ok()
                .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
                .map(|m| {
                    format!(
                        "nodes {} tets {}+{} 3d {} fallback {}",
                        m["nodes"],
                        m["tets_steel"],
                        m["tets_concrete"],
                        m["algorithm_3d"],
                        m["algorithm_fallback"]
                    )
                })
                .unwrap_or_default()
        };
        assert_same_curve(
            &read(&scene.join("curve.csv")),
            &expected,
            &format!(
                "after a kill at {delay:?} (mesh: {} against the reference's {}; output of the resumed run:\n{out})",
                mesh_line(&scene),
                mesh_line(&reference.join("tiny-smooth"))
            ),
        );
        ok(&["clean", "--all", "--work", w]);
        std::fs::remove_dir_all(&scene).unwrap();
    }
    assert!(resumed, "no kill landed in the middle of a solve");
    std::fs::remove_dir_all(&work).unwrap();
    std::fs::remove_dir_all(&reference).unwrap();
}

/// `ribbar compare` reads two curve files (or scene directories) and prints
/// the relative L2 distance of σ_mb and both first peaks: a curve 1 % above
/// its reference is 1 % away with a first peak +1 %; a missing file is named.
#[test]
fn compare_prints_the_distance_of_two_curves() {
    let dir = work_dir("compare");
    std::fs::create_dir_all(dir.join("ref")).unwrap();
    let curve = |scale: f64| {
        let mut s = String::from("step,u_imposed,force,fed,bond_stress,iterations\n");
        for k in 0..=20 {
            let u = 1e-5 * k as f64;
            let fed = (u - 2e-5).max(0.0);
            // Rises to a peak at step 8, then softens.
            let sigma = scale
                * 1e6
                * if k <= 8 {
                    k as f64
                } else {
                    8.0 - 0.3 * (k - 8) as f64
                };
            s += &format!("{k},{u:e},{:e},{fed:e},{sigma:e},3\n", sigma * 1e-3);
        }
        s
    };
    std::fs::write(dir.join("ref/curve.csv"), curve(1.0)).unwrap();
    std::fs::write(dir.join("test.csv"), curve(1.01)).unwrap();
    let test = dir.join("test.csv");
    let reference = dir.join("ref");
    let out = ok(&[
        "compare",
        test.to_str().unwrap(),
        reference.to_str().unwrap(),
    ]);
    assert!(out.contains("along FED: 1.0000 %"), "{out}");
    assert!(
        out.contains("8.0800 MPa") && out.contains("8.0000 MPa") && out.contains("+1.000 %"),
        "{out}"
    );
    let along_u = ok(&[
        "compare",
        test.to_str().unwrap(),
        reference.to_str().unwrap(),
        "--along",
        "u",
    ]);
    assert!(along_u.contains("along u: 1.0000 %"), "{along_u}");
    let missing = ribbar(&[
        "compare",
        dir.join("nothing.csv").to_str().unwrap(),
        test.to_str().unwrap(),
    ]);
    assert!(!missing.status.success());
    assert!(text(&missing).contains("nothing.csv"), "{}", text(&missing));
    std::fs::remove_dir_all(&dir).unwrap();
}
