//! Fault injection: the `ribbar` binary with real gmsh and real files, put
//! through what a careless user, a crash and a fuzzer do (edited,
//! truncated and deleted results and store files, flipped checkpoint
//! bytes, foreign checkpoints, folders that are not ribbar's, hostile
//! sizes, a hung gmsh). Each test asserts the outcome: the right result, or
//! a clear error naming the file or key with a non-zero exit, and no file
//! of the user's touched.

use crate::common::{repo, text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const TINY: &str = "tests/data/tiny-smooth.yaml";
/// Three steps to 0.02 mm: a whole run in about a second.
const SHORT: [&str; 2] = ["--set", "loading.u_final=0.02 mm"];
const STAGES: [&str; 4] = ["geometry", "mesh", "solve", "post"];

fn work_dir(name: &str) -> PathBuf {
    crate::common::scratch("faults", name)
}

fn ribbar_in(dir: &Path, args: &[&str], env: &[(&str, &Path)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ribbar"));
    cmd.args(args).current_dir(dir).stdin(Stdio::null());
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("ribbar runs")
}

fn ribbar(args: &[&str]) -> Output {
    ribbar_in(&repo(), args, &[])
}

fn ok(args: &[&str]) -> String {
    let o = ribbar(args);
    assert!(o.status.success(), "ribbar {args:?} failed:\n{}", text(&o));
    text(&o)
}

/// Runs and expects exit status 1; returns what it printed.
fn fails(args: &[&str]) -> String {
    let o = ribbar(args);
    assert_eq!(o.status.code(), Some(1), "ribbar {args:?}:\n{}", text(&o));
    text(&o)
}

fn with(args: &[&str], extra: &[&str]) -> Vec<String> {
    args.iter().chain(extra).map(|s| s.to_string()).collect()
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// `ribbar <command> TINY --work W` with the short loading and `extra`.
fn tiny(command: &str, work: &Path, extra: &[&str]) -> Vec<String> {
    let mut args = with(&[command, TINY, "--work", work.to_str().unwrap()], &SHORT);
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every file under `dir`, relative, with its bytes.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().display().to_string();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The results that must not change when a fault is repaired: the curve
/// and its summary, the geometry (timings and the record aside).
fn results(scene: &Path) -> Vec<(String, String)> {
    let summary: serde_json::Value =
        serde_json::from_str(&read(&scene.join("summary.json"))).unwrap();
    vec![
        ("curve.csv".into(), read(&scene.join("curve.csv"))),
        ("geometry.json".into(), read(&scene.join("geometry.json"))),
        (
            "interface_profile.csv".into(),
            read(&scene.join("interface_profile.csv")),
        ),
        ("summary.json /curve".into(), summary["curve"].to_string()),
    ]
}

/// Lets the file be written by its owner (store files are read-only).
fn writable(path: &Path) {
    use std::os::unix::fs::PermissionsExt;
    let mut perms = std::fs::metadata(path).unwrap().permissions();
    perms.set_mode(perms.mode() | 0o200);
    std::fs::set_permissions(path, perms).unwrap();
}

/// One of the three faults: flip bytes in place (same size), truncate to
/// half, delete.
fn damage(path: &Path, fault: usize) -> &'static str {
    match fault % 3 {
        0 => {
            writable(path);
            let mut b = std::fs::read(path).unwrap();
            let (at, end) = (b.len() / 2, (b.len() / 2 + 8).min(b.len()));
            for x in &mut b[at..end] {
                *x ^= 0x40;
            }
            // A later modification time than the recorded one, as any
            // editor gives (the clock may be coarse).
            std::thread::sleep(Duration::from_millis(15));
            std::fs::write(path, &b).unwrap();
            "flipped"
        }
        1 => {
            writable(path);
            let n = std::fs::metadata(path).unwrap().len();
            std::fs::File::options()
                .write(true)
                .open(path)
                .unwrap()
                .set_len(n / 2)
                .unwrap();
            "truncated"
        }
        _ => {
            std::fs::remove_file(path).unwrap();
            "deleted"
        }
    }
}

/// The folder of a stage's only finished key in the store.
fn stored(work: &Path, stage: &str) -> PathBuf {
    let dirs: Vec<PathBuf> = std::fs::read_dir(work.join(".store").join(stage))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir() && !p.to_string_lossy().ends_with(".partial"))
        .collect();
    assert_eq!(dirs.len(), 1, "{stage}: {dirs:?}");
    dirs[0].clone()
}

fn stage_line<'a>(out: &'a str, stage: &str) -> &'a str {
    out.lines()
        .find(|l| {
            l.starts_with(&format!("{stage}: "))
                && (l.contains("up to date") || l.contains("done in"))
        })
        .unwrap_or_else(|| panic!("no line for stage {stage} in:\n{out}"))
}

/// Repro 1: a store folder without its `stage.json` (an interrupted
/// removal, a partial copy) holding a forged curve is not taken as
/// finished: it is moved aside with its path named, the solve is computed
/// again, and the published peak is the true one.
#[test]
fn a_folder_without_stage_json_is_moved_aside_and_recomputed() {
    let work = work_dir("no-stage-json");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let expected = results(&work.join("tiny-smooth"));
    let dir = stored(&work, "solve");
    std::fs::remove_file(dir.join("stage.json")).unwrap();
    writable(&dir.join("curve.csv"));
    std::fs::write(
        dir.join("curve.csv"),
        "step,u_imposed,force,fed,bond_stress,iterations\n1,1e-5,1,1e-5,9.99e9,1\n",
    )
    .unwrap();
    let status = ok(&strs(&tiny("status", &work, &[])));
    assert!(
        status.lines().any(|l| l.starts_with("solve")
            && l.contains("damaged")
            && l.contains("stage.json: missing")),
        "{status}"
    );
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(
        out.contains("solve: the stored result is not usable") && out.contains("quarantine"),
        "{out}"
    );
    assert!(stage_line(&out, "solve").contains("done in"), "{out}");
    assert!(stage_line(&out, "mesh").contains("up to date"), "{out}");
    assert_eq!(results(&work.join("tiny-smooth")), expected);
    // Computed once: the next run finds it finished.
    let again = ok(&strs(&tiny("run", &work, &[])));
    assert!(
        stage_line(&again, "solve").contains("up to date"),
        "{again}"
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// Every file of every stage's store folder, flipped, truncated or
/// deleted, is found by `status` (the stage is "damaged") and by `run`,
/// which recomputes that stage alone and publishes the true results.
#[test]
fn every_store_file_damaged_is_found_and_its_stage_alone_recomputed() {
    let work = work_dir("store-files");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let scene = work.join("tiny-smooth");
    let expected = results(&scene);
    let mut i = 0;
    for stage in STAGES {
        let dir = stored(&work, stage);
        for rel in files(&dir).into_keys() {
            let what = damage(&dir.join(&rel), i);
            i += 1;
            let context = format!("{stage}/{rel} {what}");
            let status = ok(&strs(&tiny("status", &work, &[])));
            let line = status.lines().find(|l| l.starts_with(stage)).unwrap();
            assert!(line.contains("damaged"), "{context}:\n{status}");
            let out = ok(&strs(&tiny("run", &work, &[])));
            for other in STAGES {
                let want = if other == stage {
                    "done in"
                } else {
                    "up to date"
                };
                assert!(
                    stage_line(&out, other).contains(want),
                    "{context}: {other}:\n{out}"
                );
            }
            assert_eq!(results(&scene), expected, "{context}");
        }
    }
    assert!(i > 15, "only {i} store files");
    std::fs::remove_dir_all(&work).unwrap();
}

/// Repro 2: every published file, edited in place, truncated or deleted,
/// is named by `status` and put back by `run` from the intact store (no
/// stage recomputed); an edited file is kept beside it, and a rerun of
/// post reads the stored curve, not the edited one.
#[test]
fn every_published_file_changed_is_named_and_put_back() {
    let work = work_dir("published");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let scene = work.join("tiny-smooth");
    let expected = results(&scene);
    let published: Vec<String> = files(&scene)
        .into_keys()
        .filter(|r| !r.starts_with(".ribbar"))
        .collect();
    for (i, rel) in published.iter().enumerate() {
        let path = scene.join(rel);
        let before = std::fs::read(&path).unwrap();
        let what = damage(&path, i);
        let context = format!("{rel} {what}");
        let status = ok(&strs(&tiny("status", &work, &[])));
        assert!(
            status.contains("every stage is up to date")
                && status.lines().any(|l| l.contains(path.to_str().unwrap())
                    && (l.contains("missing") || l.contains("changed since ribbar wrote it"))),
            "{context}:\n{status}"
        );
        let out = ok(&strs(&tiny("run", &work, &[])));
        for stage in STAGES {
            assert!(
                stage_line(&out, stage).contains("up to date"),
                "{context}:\n{out}"
            );
        }
        assert_eq!(std::fs::read(&path).unwrap(), before, "{context}");
        if what != "deleted" {
            let kept = ribbar_pipeline_edited(&path);
            assert!(
                kept.is_file() && out.contains("kept as"),
                "{context}:\n{out}"
            );
            std::fs::remove_file(kept).unwrap();
        }
    }
    // An edit of the published curve never reaches post.
    let curve = scene.join("curve.csv");
    let edited = read(&curve).replacen(",1,", ",7,", 1).replace("e6,", "e7,");
    std::fs::write(&curve, edited).unwrap();
    ok(&strs(&tiny(
        "run",
        &work,
        &["--set", "outputs.residual_fraction=0.3", "-q"],
    )));
    let summary: serde_json::Value =
        serde_json::from_str(&read(&scene.join("summary.json"))).unwrap();
    let solve: serde_json::Value = serde_json::from_str(&read(&scene.join("solve.json"))).unwrap();
    assert_eq!(
        summary["curve"]["peak_bond_stress"],
        serde_json::from_str::<serde_json::Value>(&expected[3].1).unwrap()["peak_bond_stress"]
    );
    assert!(solve.is_object());
    std::fs::remove_dir_all(&work).unwrap();
}

/// The name a changed published file is kept under.
fn ribbar_pipeline_edited(path: &Path) -> PathBuf {
    let stem = path.file_stem().unwrap().to_string_lossy();
    match path.extension() {
        Some(ext) => path.with_file_name(format!("{stem}.edited.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!("{stem}.edited")),
    }
}

/// Loading settings of a solve of 2000 tiny steps (seconds), long enough
/// to be killed after its first checkpoint.
const SLOW: [&str; 6] = [
    "--set",
    "loading.u_final=0.02 mm",
    "--set",
    "loading.initial_step=0.01 um",
    "--set",
    "loading.max_step=0.01 um",
];

/// The solve checkpoints in `work`'s store.
fn checkpoints(work: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(work.join(".store/solve"))
        .into_iter()
        .flatten()
        .filter_map(|e| Some(e.ok()?.path().join("checkpoint.bin")))
        .filter(|p| p.is_file())
        .collect()
}

/// Starts a slow solve in `work` and kills it (SIGKILL) once it has
/// written a checkpoint; returns the checkpoint's path.
fn interrupted_solve(work: &Path, extra: &[&str]) -> PathBuf {
    let w = work.to_str().unwrap();
    let mut args = with(&["mesh", TINY, "--work", w, "-q"], &SLOW);
    args.extend(extra.iter().map(|s| s.to_string()));
    ok(&strs(&args));
    args[0] = "solve".into();
    let before = checkpoints(work);
    let mut child = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args(&args)
        .current_dir(repo())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let checkpoint = loop {
        if let Some(p) = checkpoints(work).into_iter().find(|p| !before.contains(p)) {
            std::thread::sleep(Duration::from_millis(200));
            break p;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the solve ended before a checkpoint"
        );
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(checkpoint.is_file());
    checkpoint
}

/// A checkpoint file's frame (magic, format, key, length, SHA-256,
/// state) with its key replaced by `key`.
fn reframed(bytes: &[u8], key: &str) -> Vec<u8> {
    use sha2::Digest;
    let key_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let payload = &bytes[16 + key_len + 8 + 32..];
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(key.len() as u32).to_le_bytes());
    out.extend_from_slice(key.as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&sha2::Sha256::digest(payload));
    out.extend_from_slice(payload);
    out
}

/// Repro 5: a checkpoint with flipped bytes, a truncated one, one of
/// another run (another key) and one of another mesh under this run's key
/// are each refused with their path named,
/// moved to the quarantine, and the solve starts over to the same curve as
/// an uninterrupted run; `clean SPEC` removes an interrupted solve.
#[test]
fn damaged_and_foreign_checkpoints_are_set_aside() {
    let reference = work_dir("cp-ref");
    let mut args = with(
        &["run", TINY, "--work", reference.to_str().unwrap(), "-q"],
        &SLOW,
    );
    ok(&strs(&args));
    let expected = read(&reference.join("tiny-smooth/curve.csv"));
    for fault in ["flipped", "truncated", "foreign", "other-mesh"] {
        let work = work_dir(&format!("cp-{fault}"));
        let w = work.to_str().unwrap();
        let checkpoint = match fault {
            "foreign" => {
                let other = interrupted_solve(&work, &["--set", "materials.interface.mu=0.31"]);
                let mine = interrupted_solve(&work, &[]);
                std::fs::copy(&other, &mine).unwrap();
                mine
            }
            "other-mesh" => {
                // Another mesh's state framed with this run's own key: the
                // solver's check of the model refuses it.
                let other = interrupted_solve(&work, &["--set", "mesh.h_interface=1.8 mm"]);
                let mine = interrupted_solve(&work, &[]);
                let key = mine
                    .parent()
                    .unwrap()
                    .file_name()
                    .unwrap()
                    .to_string_lossy();
                let key = key.strip_suffix(".partial").unwrap().to_string();
                std::fs::write(&mine, reframed(&std::fs::read(&other).unwrap(), &key)).unwrap();
                mine
            }
            _ => {
                let cp = interrupted_solve(&work, &[]);
                damage(&cp, if fault == "flipped" { 0 } else { 1 });
                cp
            }
        };
        args = with(&["run", TINY, "--work", w], &SLOW);
        let out = ok(&strs(&args));
        let named = format!("not resuming from {}", checkpoint.display());
        assert!(
            out.contains(&named) && out.contains("starting over"),
            "{fault}:\n{out}"
        );
        if fault == "foreign" {
            assert!(out.contains("belongs to the run with key"), "{out}");
        }
        if fault == "other-mesh" {
            assert!(
                out.contains("does not match") || out.contains("checkpoint has"),
                "{out}"
            );
        }
        assert_eq!(
            read(&work.join("tiny-smooth/curve.csv")),
            expected,
            "{fault}"
        );
        std::fs::remove_dir_all(&work).unwrap();
    }
    // `clean SPEC` clears an interrupted solve (and its checkpoint).
    let work = work_dir("cp-clean");
    let checkpoint = interrupted_solve(&work, &[]);
    let w = work.to_str().unwrap();
    let status = ok(&strs(&with(&["status", TINY, "--work", w], &SLOW)));
    assert!(status.contains("interrupted"), "{status}");
    let out = ok(&strs(&with(&["clean", TINY, "--work", w], &SLOW)));
    assert!(out.contains("checkpoint") && !checkpoint.exists(), "{out}");
    let status = ok(&strs(&with(&["status", TINY, "--work", w], &SLOW)));
    assert!(!status.contains("interrupted"), "{status}");
    std::fs::remove_dir_all(&work).unwrap();
    std::fs::remove_dir_all(&reference).unwrap();
}

/// Repro 3: `clean` removes only what ribbar wrote: a folder named like
/// the scene that ribbar did not make is left whole; in a results folder,
/// a file of the user's and an edited result stay and are named; `--all`
/// keeps what it does not know in the store.
#[test]
fn clean_removes_only_what_ribbar_made() {
    let proj = work_dir("clean");
    std::fs::create_dir_all(proj.join("tiny-smooth")).unwrap();
    std::fs::write(proj.join("tiny-smooth/thesis.tex"), "chapter 1").unwrap();
    let spec = repo().join(TINY);
    let s = spec.to_str().unwrap();
    let o = ribbar_in(&proj, &["clean", s, "--work", "."], &[]);
    assert!(
        o.status.success() && text(&o).contains("ribbar did not make it"),
        "{}",
        text(&o)
    );
    assert_eq!(read(&proj.join("tiny-smooth/thesis.tex")), "chapter 1");
    // Nor does a run write into it.
    let o = ribbar_in(
        &proj,
        &["run", s, "--work", ".", "--set", "loading.u_final=0.02 mm"],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("not made by ribbar"), "{}", text(&o));
    assert_eq!(files(&proj.join("tiny-smooth")).len(), 1);
    std::fs::remove_dir_all(proj.join("tiny-smooth")).unwrap();

    let work = proj.join("work");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let scene = work.join("tiny-smooth");
    std::fs::write(scene.join("notes.txt"), "mine").unwrap();
    std::fs::write(scene.join("curve.csv"), "edited").unwrap();
    std::fs::write(work.join(".store/mine.txt"), "mine").unwrap();
    let out = ok(&strs(&tiny("clean", &work, &[])));
    assert!(
        out.contains("kept 2 files") && out.contains("notes.txt") && out.contains("curve.csv"),
        "{out}"
    );
    let left = |scene: &Path| -> Vec<String> {
        files(scene)
            .into_keys()
            .filter(|r| !r.starts_with(".ribbar"))
            .collect()
    };
    assert_eq!(left(&scene), ["curve.csv", "notes.txt"]);
    // The folder stays ribbar's: a run publishes beside the kept files.
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(out.contains("kept as curve.edited.csv"), "{out}");
    assert_eq!(read(&scene.join("notes.txt")), "mine");
    assert_eq!(read(&scene.join("curve.edited.csv")), "edited");
    let out = ok(&["clean", "--all", "--work", work.to_str().unwrap()]);
    assert!(
        out.contains("kept 1 entries") && out.contains("mine.txt"),
        "{out}"
    );
    assert_eq!(
        files(&work.join(".store")).into_keys().collect::<Vec<_>>(),
        ["mine.txt"]
    );
    std::fs::remove_dir_all(&proj).unwrap();
}

/// Repro 4 and its kin: no command overwrites its own input: `material
/// -o` its test file, a spec kept where its results are published or in
/// the store are refused, naming the file, and left as they were.
#[test]
fn no_output_is_one_of_the_inputs() {
    let dir = work_dir("inputs");
    std::fs::create_dir_all(dir.join("w/tiny-smooth")).unwrap();
    let test = dir.join("my-test.yaml");
    std::fs::copy(repo().join("specs/material/fczm-shear.yaml"), &test).unwrap();
    let before = read(&test);
    let t = test.to_str().unwrap();
    let out = fails(&["material", t, "-o", t]);
    assert!(
        out.contains("my-test.yaml") && out.contains("the test file"),
        "{out}"
    );
    assert_eq!(read(&test), before);
    let w = dir.join("w");
    for place in ["w/tiny-smooth/summary.json", "w/.store/spec.yaml"] {
        let spec = dir.join(place);
        std::fs::create_dir_all(spec.parent().unwrap()).unwrap();
        std::fs::copy(repo().join(TINY), &spec).unwrap();
        let out = fails(&[
            "run",
            spec.to_str().unwrap(),
            "--work",
            w.to_str().unwrap(),
            "--set",
            "loading.u_final=0.02 mm",
        ]);
        assert!(
            out.contains(place.rsplit('/').next().unwrap()) && out.contains("the spec"),
            "{out}"
        );
        assert_eq!(read(&spec), read(&repo().join(TINY)));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Repros 6 and 7: sizes that would run for hours or exhaust memory are
/// refused before any work with the count and the key that raises the
/// limit: a µm mesh size, a study of 10^6 cases (run or exported), a
/// material test of 10^12 increments; a spec that is a device or too large
/// is refused without reading it; a YAML alias bomb ends in an error, not
/// an abort.
#[test]
fn hostile_sizes_are_refused_before_the_work() {
    let dir = work_dir("sizes");
    std::fs::create_dir_all(&dir).unwrap();
    let w = dir.join("w");
    let out = fails(&[
        "mesh",
        TINY,
        "--work",
        w.to_str().unwrap(),
        "--set",
        "mesh.h_interface=1 um",
    ]);
    assert!(
        out.contains("mesh.max_elements") && out.contains("estimated") && out.contains("e1"),
        "{out}"
    );
    assert!(!w.join(".store").exists(), "work was done");

    let big = dir.join("big.yaml");
    let mut text = format!(
        "name: big\nbase: {}\nparameters:\n",
        repo().join(TINY).display()
    );
    for k in [
        "interface.mu",
        "interface.zeta",
        "interface.delta_s",
        "concrete.nu",
        "steel.nu",
        "interface.xi",
    ] {
        text += &format!(
            "  materials.{k}: [0.11, 0.12, 0.13, 0.14, 0.15, 0.16, 0.17, 0.18, 0.19, 0.2]\n"
        );
    }
    std::fs::write(&big, text).unwrap();
    for extra in [&[][..], &["--export", "snakemake"][..]] {
        let args = with(
            &[
                "study",
                big.to_str().unwrap(),
                "--work",
                w.to_str().unwrap(),
            ],
            extra,
        );
        let out = fails(&strs(&args));
        assert!(
            out.contains("1000000 cases") && out.contains("max_cases"),
            "{out}"
        );
    }

    let test = dir.join("many.yaml");
    let spec: String = read(&repo().join("specs/material/fczm-shear.yaml"))
        .lines()
        .filter(|l| !l.starts_with("increments:"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&test, format!("{spec}increments: 1000000000000\n")).unwrap();
    let out = fails(&["material", test.to_str().unwrap()]);
    assert!(
        out.contains("increments") && out.contains("max_rows"),
        "{out}"
    );

    let out = fails(&["run", "/dev/zero", "--work", w.to_str().unwrap()]);
    assert!(
        out.contains("/dev/zero") && out.contains("not a regular file"),
        "{out}"
    );
    // A pipe with no writer: opening it would wait for ever.
    let fifo = dir.join("spec.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let out = fails(&["run", fifo.to_str().unwrap(), "--work", w.to_str().unwrap()]);
    assert!(
        out.contains("spec.fifo") && out.contains("not a regular file"),
        "{out}"
    );
    let huge = dir.join("huge.yaml");
    std::fs::write(&huge, format!("name: huge\n#{}\n", "x".repeat(2 << 20))).unwrap();
    let out = fails(&[
        "status",
        huge.to_str().unwrap(),
        "--work",
        w.to_str().unwrap(),
    ]);
    assert!(
        out.contains("huge.yaml") && out.contains("bytes, more than"),
        "{out}"
    );
    let bomb = dir.join("bomb.yaml");
    let mut yaml = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
    for i in 1..10 {
        let p = i - 1;
        yaml += &format!(
            "a{i}: &a{i} [*a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}]\n"
        );
    }
    yaml += "name: *a9\n";
    std::fs::write(&bomb, yaml).unwrap();
    let out = fails(&[
        "status",
        bomb.to_str().unwrap(),
        "--work",
        w.to_str().unwrap(),
    ]);
    assert!(out.contains("bomb.yaml"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fake gmsh in `dir` whose `--version` answers and whose meshing runs
/// `body` (a shell script; `$1` is gmsh's Python API script).
fn fake_gmsh(dir: &Path, body: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    std::fs::create_dir_all(dir).unwrap();
    let gmsh = dir.join("gmsh");
    // A Python script as the PyPI wheel's: ribbar runs it with the
    // `python` beside it.
    std::fs::write(&gmsh, "#!/usr/bin/env python3\n").unwrap();
    let python = dir.join("python");
    std::fs::write(
        &python,
        format!("#!/bin/sh\nif [ \"$2\" = \"--version\" ]; then echo 4.15.2; exit 0; fi\n{body}\n"),
    )
    .unwrap();
    std::fs::set_permissions(&python, std::fs::Permissions::from_mode(0o755)).unwrap();
    gmsh
}

/// Whether a process runs `sleep <seconds>`.
fn sleeping(seconds: &str) -> bool {
    let wanted = format!("sleep\0{seconds}\0");
    std::fs::read_dir("/proc").unwrap().any(|e| {
        std::fs::read(e.unwrap().path().join("cmdline")).is_ok_and(|c| c == wanted.as_bytes())
    })
}

/// Repro 6: a gmsh that hangs (a wrapper with a child of its own) is
/// shown running, stopped at `mesh.timeout` with an error naming the key,
/// and killed with every process it started.
#[test]
fn a_hung_gmsh_is_stopped_at_its_limit_with_all_it_started() {
    let dir = work_dir("hung");
    let tag = format!("{}.5", 8000 + std::process::id() % 1000);
    let gmsh = fake_gmsh(&dir.join("bin"), &format!("sleep {tag} &\nsleep {tag}\n"));
    let w = dir.join("w");
    let o = ribbar_in(
        &repo(),
        &strs(&with(
            &[
                "mesh",
                TINY,
                "--work",
                w.to_str().unwrap(),
                "--set",
                "mesh.timeout=6 s",
            ],
            &[],
        )),
        &[("GMSH", &gmsh)],
    );
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(
        out.contains("mesh.timeout") && out.contains("killed"),
        "{out}"
    );
    assert!(
        out.contains("mesh: gmsh has run 5 s"),
        "no progress while gmsh ran:\n{out}"
    );
    std::thread::sleep(Duration::from_millis(200));
    assert!(!sleeping(&tag), "a process gmsh started outlived it");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Repro 7: a gmsh that floods its error output (50 MB) and fails gives an
/// error of bounded size that still ends with gmsh's last error line.
#[test]
fn a_flood_of_gmsh_output_gives_a_short_error() {
    let dir = work_dir("flood");
    let gmsh = fake_gmsh(
        &dir.join("bin"),
        "yes 'Info    : a line gmsh repeats' | head -c 50000000 >&2\n\
         echo 'Error   : the flood ended badly' >&2\nexit 3",
    );
    let w = dir.join("w");
    let o = ribbar_in(
        &repo(),
        &["mesh", TINY, "--work", w.to_str().unwrap()],
        &[("GMSH", &gmsh)],
    );
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{:.2000}", out);
    assert!(out.len() < 200_000, "{} bytes of error", out.len());
    assert!(
        out.contains("Error   : the flood ended badly"),
        "{:.2000}",
        out
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Repro 8: a run that fails in mesh leaves the results folder with this
/// spec's geometry only (none of the earlier run's mesh, curve, summary or
/// plots beside it), and `status` says which run the folder shows and how
/// it ended.
#[test]
fn a_failed_run_leaves_no_earlier_results_beside_its_own() {
    let work = work_dir("failed-run");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let scene = work.join("tiny-smooth");
    let bad = [
        "--set",
        "specimen.cube_side=8.01 mm",
        "--set",
        "specimen.adhesive_length=5 mm",
    ];
    let out = fails(&strs(&tiny("run", &work, &bad)));
    assert!(
        out.contains("results:") && out.contains("were taken out"),
        "{out}"
    );
    let left: Vec<String> = files(&scene).into_keys().collect();
    assert_eq!(
        left,
        [".ribbar-stages.json", "geometry.json", "specimen.geo"],
        "{out}"
    );
    assert!(read(&scene.join("geometry.json")).contains("0.00801"));
    let status = ok(&strs(&tiny("status", &work, &bad)));
    assert!(
        status.contains("which failed in stage mesh") && status.contains("geometry (this spec)"),
        "{status}"
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// Repro 9: `compare` refuses a curve that stopped at a fraction of its
/// reference's range, naming both ends; told to, it compares over the
/// common range and says which.
#[test]
fn compare_refuses_curves_that_end_far_apart() {
    let work = work_dir("compare");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let curve = work.join("tiny-smooth/curve.csv");
    let stalled = work.join("stalled.csv");
    let lines: Vec<String> = read(&curve).lines().take(2).map(String::from).collect();
    std::fs::write(&stalled, lines.join("\n") + "\n").unwrap();
    let (s, c) = (stalled.to_str().unwrap(), curve.to_str().unwrap());
    let out = fails(&["compare", s, c]);
    assert!(
        out.contains("end far apart") && out.contains("--common-range"),
        "{out}"
    );
    let out = ok(&["compare", s, c, "--common-range"]);
    assert!(out.contains("compared over FED = 0 –"), "{out}");
    let out = ok(&["compare", c, c]);
    assert!(
        out.contains("(100 % of the longer curve's range") && out.contains(": 0.0000 %"),
        "{out}"
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// Repro 10: a plain-number modulus in pascals and a displacement past the
/// bonded length are named with the unit that was probably meant.
#[test]
fn unit_slips_are_named_with_the_unit_meant() {
    let work = work_dir("slips");
    let o = ribbar(&strs(&tiny(
        "run",
        &work,
        &["--set", "materials.concrete.E=30"],
    )));
    assert!(
        text(&o).contains("materials.concrete.E = 30 Pa")
            && text(&o).contains("did you mean 30 GPa?"),
        "{}",
        text(&o)
    );
    let out = ok(&[
        "status",
        TINY,
        "--work",
        work.to_str().unwrap(),
        "--set",
        "loading.u_final=1",
    ]);
    assert!(
        out.contains("past the bonded length") && out.contains("did you mean 1 mm?"),
        "{out}"
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// `verify` checks every stored result by digest: on a sound store it
/// exits 0; a flipped byte whose file keeps its size and time is found,
/// named, moved aside, and the next run computes the stage again.
#[test]
fn verify_finds_what_the_cheap_checks_cannot() {
    let work = work_dir("verify");
    let w = work.to_str().unwrap();
    ok(&strs(&tiny("run", &work, &["-q"])));
    let out = ok(&["verify", "--work", w]);
    assert!(
        out.contains("verified 4 stored results") && out.contains("everything as recorded"),
        "{out}"
    );
    let model = stored(&work, "mesh").join("model.bin");
    let meta = std::fs::metadata(&model).unwrap();
    damage(&model, 0);
    // Give the file its recorded time back: only a digest finds it.
    std::fs::File::options()
        .write(true)
        .open(&model)
        .unwrap()
        .set_modified(meta.modified().unwrap())
        .unwrap();
    let o = ribbar(&["verify", "--work", w]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("model.bin") && text(&o).contains("quarantine"),
        "{}",
        text(&o)
    );
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(stage_line(&out, "mesh").contains("done in"), "{out}");
    assert!(ok(&["verify", "--work", w]).contains("everything as recorded"));
    std::fs::remove_dir_all(&work).unwrap();
}

/// Repro 10's study half: every case of a study has its row, with its
/// status, how it ended, and where it failed the cause and the log; the
/// summary line counts each status; a study whose every case fails still
/// writes its table and names the first cause and its log.
#[test]
fn every_study_case_has_a_row_saying_how_it_ended() {
    let dir = work_dir("study-rows");
    std::fs::create_dir_all(&dir).unwrap();
    let base = repo().join(TINY);
    let study = |name: &str, sides: &str, lengths: &str, steps: &str| {
        let path = dir.join(format!("{name}.yaml"));
        std::fs::write(
            &path,
            format!(
                "name: {name}\nbase: {}\ncombine: zip\nset:\n  loading.u_final: 0.02 mm\nparameters:\n  \
                 specimen.cube_side: {sides}\n  specimen.adhesive_length: {lengths}\n  solver.expert.max_steps: {steps}\n",
                base.display()
            ),
        )
        .unwrap();
        path
    };
    let w = dir.join("w");
    let mixed = study(
        "mixed",
        "[24 mm, 24 mm, 8.01 mm]",
        "[12 mm, 12 mm, 5 mm]",
        "[1000, 1, 1000]",
    );
    let out = fails(&[
        "study",
        mixed.to_str().unwrap(),
        "--work",
        w.to_str().unwrap(),
    ]);
    assert!(
        out.contains("study mixed: 3 cases: 1 completed, 0 ended otherwise, 1 stopped, 1 failed"),
        "{out}"
    );
    let table = read(&w.join("mixed/table.csv"));
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 4, "{table}");
    assert!(lines[0].contains(",status,ending,cause,log"), "{table}");
    assert!(
        lines[1].starts_with("mixed--0,") && lines[1].contains(",completed,completed,,"),
        "{table}"
    );
    assert!(
        lines[2].contains(",stopped,stopped,") && lines[2].contains("max_steps"),
        "{table}"
    );
    assert!(
        lines[3].contains(",failed,failed in mesh,") && lines[3].contains("mixed--2.mesh.log"),
        "{table}"
    );
    let failing = study(
        "failing",
        "[8.01 mm, 8.02 mm]",
        "[5 mm, 5 mm]",
        "[1000, 1000]",
    );
    let out = fails(&[
        "study",
        failing.to_str().unwrap(),
        "--work",
        w.to_str().unwrap(),
    ]);
    assert!(
        out.contains("no case of study failing has results; the first failed in mesh:")
            && out.contains("failing--0.mesh.log"),
        "{out}"
    );
    assert_eq!(read(&w.join("failing/table.csv")).lines().count(), 3);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The results folder's own record damaged, deleted, of the first format
/// (keys only), or a file where a folder of results goes: `status` and
/// `clean` say so without removing anything, and `run` publishes the
/// results again, losing no file (what was in the way is moved aside under
/// a name that says so).
#[test]
fn a_damaged_or_missing_record_loses_nothing() {
    let work = work_dir("record");
    ok(&strs(&tiny("run", &work, &["-q"])));
    let scene = work.join("tiny-smooth");
    let expected = files(&scene);
    let record = scene.join(".ribbar-stages.json");
    std::fs::write(&record, "{ not json").unwrap();
    let status = ok(&strs(&tiny("status", &work, &[])));
    assert!(
        status.contains(".ribbar-stages.json") && status.contains("corrupt"),
        "{status}"
    );
    let out = fails(&strs(&tiny("clean", &work, &[])));
    assert!(out.contains("nothing there was removed"), "{out}");
    assert_eq!(files(&scene).len(), expected.len());
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(
        out.contains("kept as") && out.contains(".ribbar-stages.damaged.json"),
        "{out}"
    );
    assert!(
        !out.contains(".edited"),
        "identical files are kept as they are:\n{out}"
    );
    std::fs::remove_file(&record).unwrap();
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(!out.contains(".edited"), "{out}");
    std::fs::remove_dir_all(scene.join("fields")).unwrap();
    std::fs::write(scene.join("fields"), "not a folder").unwrap();
    let out = ok(&strs(&tiny("run", &work, &[])));
    assert!(
        out.contains("fields") && out.contains("kept as fields.edited"),
        "{out}"
    );
    let now = files(&scene);
    for (rel, bytes) in expected.iter().filter(|(r, _)| !r.starts_with(".ribbar")) {
        assert_eq!(now.get(rel), Some(bytes), "{rel}");
    }
    assert_eq!(read(&scene.join("fields.edited")), "not a folder");
    // A folder published by a ribbar whose record kept only the keys
    // (stage → key): its results are replaced, a kept file is not.
    let record: serde_json::Value = serde_json::from_str(&read(&record)).unwrap();
    let legacy: serde_json::Map<String, serde_json::Value> = record["stages"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(stage, p)| {
            let mut key = p.clone();
            key.as_object_mut().unwrap().remove("files");
            (stage.clone(), key)
        })
        .collect();
    std::fs::write(
        scene.join(".ribbar-stages.json"),
        serde_json::to_vec(&legacy).unwrap(),
    )
    .unwrap();
    std::fs::write(scene.join("fields/peak_bulk.edited.vtu"), "mine").unwrap();
    std::fs::write(scene.join("fields/step0099_bulk.vtu"), "an old step").unwrap();
    ok(&strs(&tiny("run", &work, &["-q"])));
    assert_eq!(read(&scene.join("fields/peak_bulk.edited.vtu")), "mine");
    assert!(!scene.join("fields/step0099_bulk.vtu").exists());
    for (rel, bytes) in expected.iter().filter(|(r, _)| !r.starts_with(".ribbar")) {
        assert_eq!(files(&scene).get(rel), Some(bytes), "{rel}");
    }
    std::fs::remove_dir_all(&work).unwrap();
}
