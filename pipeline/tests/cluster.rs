//! A study on a cluster, end to end with real gmsh and a real `snakemake`
//! (scripts/test.sh installs it): the exported workflow lints clean, asks
//! for each solve's memory and time from ribbar's estimate, runs unchanged
//! when moved, keeps a stopped case, does not grow with the cases; a solve
//! stopped by SIGTERM resumes from its checkpoint to the same curve; the
//! store's lock lets one of two processes compute a shared stage.
//! scripts/test-slurm.sh runs the workflow under a real Slurm.

use crate::common::{repo, text};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn work_dir(name: &str) -> PathBuf {
    let dir = crate::common::scratch("cluster", name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `cmd`; its status and its stdout and stderr as one text.
fn output(cmd: &mut Command) -> (Output, String) {
    let o: Output = cmd.stdin(Stdio::null()).output().expect("command runs");
    let t = text(&o);
    (o, t)
}

fn ok(cmd: &mut Command) -> String {
    let (o, t) = output(cmd);
    assert!(o.status.success(), "{cmd:?} failed:\n{t}");
    t
}

fn ribbar() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ribbar"));
    c.current_dir(repo());
    c
}

fn snakemake(dir: &Path) -> Command {
    let exe = repo().join(".tools/snakemake-venv/bin/snakemake");
    assert!(
        exe.is_file(),
        "{} is missing: run scripts/test.sh (it installs snakemake for this test)",
        exe.display()
    );
    let mut c = Command::new(&exe);
    c.current_dir(dir).env(
        "PATH",
        format!(
            "{}:{}",
            exe.parent().unwrap().display(),
            std::env::var("PATH").unwrap_or_default()
        ),
    );
    c
}

/// Exports `study` (a path in the repository) with `work` into `dir`.
fn export(study: &str, work: &Path, dir: &Path) {
    ok(ribbar()
        .args(["study", study, "--export", "snakemake", "--work"])
        .arg(work)
        .arg("--export-dir")
        .arg(dir));
}

/// A study table's rows by case, without the columns of wall times (the
/// only values that differ between two runs of the same cases).
fn table_values(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let keep: Vec<bool> = rows[0].iter().map(|c| !c.contains("wall_time")).collect();
    rows.iter()
        .map(|r| {
            r.iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(c, _)| c.clone())
                .collect()
        })
        .collect()
}

/// Replaces the line starting with `key:` of a config file.
fn set_config(config: &Path, key: &str, value: &str) {
    let text = std::fs::read_to_string(config).unwrap();
    let mut found = false;
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            let indent = l.len() - l.trim_start().len();
            if l.trim_start().starts_with(&format!("{key}:")) {
                found = true;
                format!("{}{key}: {value}", &l[..indent])
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(found, "{key} not in {}", config.display());
    std::fs::write(config, lines.join("\n") + "\n").unwrap();
}

/// The rule blocks of a Snakefile: (name, text up to the next rule).
fn rules(snakefile: &str) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for line in snakefile.lines() {
        if let Some(name) = line.strip_prefix("rule ").and_then(|l| l.strip_suffix(':')) {
            out.push((name.to_string(), String::new()));
        } else if let Some((_, body)) = out.last_mut() {
            if !line.is_empty() && !line.starts_with(' ') {
                continue;
            }
            body.push_str(line);
            body.push('\n');
        }
    }
    out
}

/// Issue 56: `snakemake --lint` finds nothing in an exported workflow;
/// every rule that runs a solve declares `threads`, `mem_mb` and `runtime`,
/// and the solve jobs ask for ribbar's estimate of their memory and time
/// times the config's margins; the workflow's table equals `ribbar study`'s
/// value for value.
#[test]
fn an_exported_workflow_lints_clean_and_sizes_its_solves_from_ribbar_estimates() {
    let root = work_dir("lint");
    let (work, dir) = (root.join("work"), root.join("workflow"));
    export("tests/data/tiny-friction.yaml", &work, &dir);
    let lint = ok(snakemake(&dir).arg("--lint"));
    assert!(
        lint.contains("Congratulations, your workflow is in a good condition")
            && !lint.contains("Lints for"),
        "{lint}"
    );
    let snakefile = std::fs::read_to_string(dir.join("workflow/Snakefile")).unwrap();
    let solving: Vec<(String, String)> = rules(&snakefile)
        .into_iter()
        .filter(|(_, body)| body.contains("ribbar_stage(\"solve\""))
        .collect();
    assert!(!solving.is_empty(), "no rule runs the solve:\n{snakefile}");
    for (name, body) in &solving {
        for declared in ["threads:", "mem_mb=", "runtime="] {
            assert!(
                body.contains(declared),
                "rule {name} lacks {declared}:\n{body}"
            );
        }
    }
    // The floors under the estimate out of the way, the margins large
    // enough that the tiny scene's estimate shows.
    let config = dir.join("config/config.yaml");
    set_config(&config, "min_mem_mb", "1");
    set_config(&config, "min_runtime", "1");
    set_config(&config, "runtime_margin", "1000");
    ok(snakemake(&dir).args(["--cores", "2"]));
    let local = root.join("local");
    ok(ribbar()
        .args(["study", "tests/data/tiny-friction.yaml", "-q", "--work"])
        .arg(&local));
    let table = table_values(&work.join("tiny-friction/table.csv"));
    assert_eq!(table.len(), 3, "{table:?}");
    assert_eq!(table, table_values(&local.join("tiny-friction/table.csv")));
    // What the scheduler would be asked for: the jobs of a forced rerun.
    let dry = ok(snakemake(&dir).args(["-n", "--forcerun", "solve", "--cores", "4"]));
    let mut jobs = 0;
    for block in dry.split("\nrule solve:").skip(1) {
        let case = block
            .lines()
            .find_map(|l| l.trim().strip_prefix("wildcards: case="))
            .unwrap_or_else(|| panic!("{block}"));
        let estimate: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("results/estimates/{case}.json"))).unwrap(),
        )
        .unwrap();
        let memory = (1.5 * estimate["memory_bytes"].as_f64().unwrap() / 1e6).ceil();
        let runtime = (1000.0 * estimate["runtime_s"].as_f64().unwrap() / 60.0)
            .max(1.0)
            .ceil();
        assert!(memory > 1.0 && runtime > 1.0, "{estimate}");
        let resources = block
            .lines()
            .find(|l| l.trim().starts_with("resources:"))
            .unwrap();
        assert!(
            resources.contains(&format!("mem_mb={memory},"))
                && resources.contains(&format!("runtime={runtime},")),
            "{case}: {resources} (estimate {estimate})"
        );
        assert!(block.contains("threads: 2"), "{block}");
        jobs += 1;
    }
    assert_eq!(jobs, 2, "{dry}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// Issue 56: the workflow copied to another directory, with its work
/// directory and the ribbar binary elsewhere and only config.yaml changed,
/// runs unchanged to the same table.
#[test]
fn a_moved_workflow_runs_with_only_its_config_changed() {
    let root = work_dir("moved");
    let (work, dir) = (root.join("work"), root.join("here"));
    export("tests/data/tiny-friction.yaml", &work, &dir);
    ok(snakemake(&dir).args(["--cores", "2"]));
    let moved = root.join("elsewhere/study");
    std::fs::create_dir_all(moved.parent().unwrap()).unwrap();
    ok(Command::new("cp")
        .args(["-r", "--preserve=mode"])
        .arg(&dir)
        .arg(&moved));
    for leftover in [".snakemake", "results", "logs"] {
        std::fs::remove_dir_all(moved.join(leftover)).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let bin = root.join("opt/bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_ribbar"), bin.join("ribbar")).unwrap();
    let config = moved.join("config/config.yaml");
    let other_work = root.join("scratch/work");
    set_config(&config, "ribbar", &format!("{:?}", bin.join("ribbar")));
    set_config(&config, "work", &format!("{other_work:?}"));
    let out = ok(snakemake(&moved).args(["--cores", "2"]));
    let log = std::fs::read_to_string(moved.join("logs/solve/tiny-friction--0.log")).unwrap();
    assert!(
        log.contains(&bin.join("ribbar").display().to_string()),
        "{log}"
    );
    assert_eq!(
        table_values(&other_work.join("tiny-friction/table.csv")),
        table_values(&work.join("tiny-friction/table.csv")),
        "{out}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Issue 56: the workflow of a 200-case study is the same Snakefile as a
/// 2-case study's; only the case table grows, and the dry run has a mesh,
/// a solve and a post job for every case.
#[test]
fn a_200_case_study_exports_the_same_snakefile() {
    let root = work_dir("size");
    let base = repo().join("tests/data/tiny-smooth.yaml");
    let study = |n: usize| {
        let values: Vec<String> = (0..n)
            .map(|i| format!("{}", 0.1 + 0.001 * i as f64))
            .collect();
        let path = root.join(format!("s{n}.yaml"));
        std::fs::write(
            &path,
            format!(
                "name: s{n}\nbase: {}\nparameters:\n  materials.interface.mu: [{}]\n",
                base.display(),
                values.join(", ")
            ),
        )
        .unwrap();
        let dir = root.join(format!("wf{n}"));
        export(path.to_str().unwrap(), &root.join("work"), &dir);
        dir
    };
    let (small, large) = (study(2), study(200));
    for file in ["workflow/Snakefile", "workflow/rules/common.smk"] {
        assert_eq!(
            std::fs::read(small.join(file)).unwrap(),
            std::fs::read(large.join(file)).unwrap(),
            "{file}"
        );
    }
    let cases = std::fs::read_to_string(large.join("config/cases.tsv")).unwrap();
    assert_eq!(cases.lines().count(), 201);
    let dry = ok(snakemake(&large).args(["-n", "--quiet", "rules"]));
    let count = |rule: &str| -> usize {
        dry.lines()
            .find_map(|l| {
                let mut w = l.split_whitespace();
                (w.next() == Some(rule)).then(|| w.next()?.parse().ok())?
            })
            .unwrap_or_else(|| panic!("{rule}: {dry}"))
    };
    assert_eq!(
        (
            count("mesh"),
            count("solve"),
            count("post"),
            count("collect")
        ),
        (200, 200, 200, 1)
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Issue 56: a case whose solve stops early (here at its step limit) is
/// treated as `ribbar study` treats it: its job succeeds, its converged
/// steps and solve.json (`completed: false`) are kept, the workflow goes on
/// and the table holds every case, the same rows as `ribbar study`'s.
#[test]
fn a_stopped_case_is_kept_and_tabulated_as_ribbar_study_does() {
    let root = work_dir("stopped");
    let study = root.join("stops.yaml");
    std::fs::write(
        &study,
        format!(
            "name: stops\nbase: {}\nparameters:\n  solver.expert.max_steps: [3, 1000]\n",
            repo().join("tests/data/tiny-smooth.yaml").display()
        ),
    )
    .unwrap();
    let (work, dir) = (root.join("work"), root.join("workflow"));
    export(study.to_str().unwrap(), &work, &dir);
    let out = ok(snakemake(&dir).args(["--cores", "2"]));
    let solve: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(work.join("stops--0/solve.json")).unwrap())
            .unwrap();
    assert_eq!(solve["completed"], false, "{solve}");
    let curve = std::fs::read_to_string(work.join("stops--0/curve.csv")).unwrap();
    assert_eq!(curve.lines().count(), 1 + 3, "{curve}");
    let log = std::fs::read_to_string(dir.join("logs/collect.log")).unwrap();
    assert!(log.contains("[stops--0] stopped early"), "{log}\n{out}");
    let table = table_values(&work.join("stops/table.csv"));
    assert_eq!(table.len(), 3, "{table:?}");
    // `ribbar study` says the stopped case failed, and tabulates it.
    let local = root.join("local");
    let (o, text) = output(
        ribbar()
            .args(["study", study.to_str().unwrap(), "--work"])
            .arg(&local),
    );
    assert!(!o.status.success() && text.contains("[stops--0]"), "{text}");
    // Each runner keeps a case's log where it runs it (Snakemake under the
    // workflow's logs/, `ribbar study` under the study's): the log column
    // is the one that may differ.
    let without_logs = |t: Vec<Vec<String>>| -> Vec<Vec<String>> {
        t.into_iter()
            .map(|row| {
                row.into_iter()
                    .map(|c| {
                        if c.ends_with(".log") {
                            String::new()
                        } else {
                            c
                        }
                    })
                    .collect()
            })
            .collect()
    };
    assert_eq!(
        without_logs(table),
        without_logs(table_values(&local.join("stops/table.csv")))
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Waits until `done()`, at most `limit`; whether it came.
fn wait_for(done: &dyn Fn() -> bool, limit: Duration) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

/// The checkpoint of the scene's solve in progress, if one is written.
fn checkpoint_written(work: &Path) -> bool {
    std::fs::read_dir(work.join(".store/solve"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .any(|e| e.path().join("checkpoint.bin").is_file())
        })
        .unwrap_or(false)
}

/// A `ribbar solve` of `args` (ending in `--work`) into `work`, its mesh
/// made first, once it has written a checkpoint.
fn solving(args: &[&str], work: &Path) -> std::process::Child {
    ok(ribbar().arg("mesh").args(args).arg(work));
    let child = ribbar()
        .arg("solve")
        .args(args)
        .arg(work)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    assert!(
        wait_for(&|| checkpoint_written(work), Duration::from_secs(120)),
        "no checkpoint"
    );
    child
}

/// Issue 56: a solve sent SIGTERM (a scheduler's time limit, `scancel`)
/// stops at its next converged step with its checkpoint written and exits
/// 143 saying so; nothing is committed or published as its result; the
/// next run resumes from that very step to the uninterrupted curve, byte
/// for byte. A second SIGTERM ends a solve at once.
#[test]
fn a_sigterm_stops_the_solve_at_a_step_and_the_rerun_resumes_there() {
    let root = work_dir("sigterm");
    let slow = [
        "tests/data/tiny-smooth.yaml",
        "--set",
        "loading.max_step=2 um",
        "--set",
        "loading.initial_step=1 um",
        "-q",
        "--work",
    ];
    let reference = root.join("reference");
    ok(ribbar().arg("run").args(slow).arg(&reference));
    let expected = std::fs::read(reference.join("tiny-smooth/curve.csv")).unwrap();

    let work = root.join("work");
    let child = solving(&slow, &work);
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
    }
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(143), "{err}");
    let step: usize = err
        .split("stopped by SIGTERM after step ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert!(
        step > 0 && step < expected.iter().filter(|&&b| b == b'\n').count() - 1,
        "{err}"
    );
    assert!(!work.join("tiny-smooth/curve.csv").exists(), "{err}");
    let done: Vec<_> = std::fs::read_dir(work.join(".store/solve"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("stage.json").exists())
        .collect();
    assert!(done.is_empty(), "a stopped solve was committed");
    let out = ok(ribbar()
        .arg("run")
        .args(&slow[..slow.len() - 2])
        .arg("--work")
        .arg(&work));
    assert!(
        out.contains(&format!("resuming after step {step} ")),
        "{out}"
    );
    assert_eq!(
        std::fs::read(work.join("tiny-smooth/curve.csv")).unwrap(),
        expected
    );

    // Twice: the second one is not waited on.
    ok(ribbar().args(["clean", "--all", "--work"]).arg(&work));
    let child = solving(&slow, &work);
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
        libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
    }
    let o = child.wait_with_output().unwrap();
    // Either the second signal ended it, or the first stop came first.
    assert!(
        o.status.signal() == Some(libc::SIGTERM) || o.status.code() == Some(143),
        "{:?}",
        o.status
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Issue 56: two processes that need one stage at once take the store's
/// lock in turn: one computes the mesh, the other finds it done, and the
/// store holds it once.
#[test]
fn two_processes_compute_a_shared_stage_once() {
    let root = work_dir("lock");
    let spawn = |name: &str| {
        ribbar()
            .args(["mesh", "tests/data/tiny-smooth.yaml", "--set"])
            .arg(format!("name={name}"))
            .arg("--work")
            .arg(&root)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("a"), spawn("b"));
    let said: Vec<String> = [a, b]
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            let t = text(&o);
            assert!(o.status.success(), "{t}");
            t
        })
        .collect();
    let ran = said.iter().filter(|t| t.contains("mesh: done in")).count();
    let found = said
        .iter()
        .filter(|t| t.contains("mesh: up to date"))
        .count();
    assert_eq!((ran, found), (1, 1), "{said:?}");
    let meshes = std::fs::read_dir(root.join(".store/mesh"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("stage.json").is_file())
        .count();
    assert_eq!(meshes, 1);
    for scene in ["a", "b"] {
        assert!(root.join(scene).join("mesh.json").is_file());
    }
    std::fs::remove_dir_all(&root).unwrap();
}
