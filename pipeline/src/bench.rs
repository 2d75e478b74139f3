//! `ribbar bench`: run time against error, written as Markdown tables and
//! plots (see docs/src/validation/performance.md).
//!
//! `ribbar bench linear`: the linear-elastic perfect-bond pull-out of
//! smooth-80 (SPEC §9) solved by each of ribbar's linear solvers, by
//! CalculiX `ccx` on the same nodes and tetrahedra and by PETSc's CG + GAMG
//! on ribbar's own system (`bench_petsc`). Every solve runs in its
//! own child process (ribbar re-invoked with a job in the environment), so
//! its wall time and peak resident memory (`wait4` rusage) are those of the
//! whole solve process, as SPEC §9 measured the peers.

use crate::cli::{BenchArgs, BenchKind};
use crate::commands::run_scene;
use crate::measure::{wait_measured, Measured};
use crate::progress::Printer;
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use mesh::Model;
use serde::{Deserialize, Serialize};
use solve::laws::elastic::LinearElastic;
use solve::linalg::amg::AmgParams;
use solve::problems::linear_elastic::{solve, ElasticSolver, PerfectBond};
use solve::spec::materials::{ConcreteModel, SteelModel};
use std::fmt::Write as _;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

pub fn run(args: &BenchArgs, printer: &Printer) -> Result<ExitCode> {
    match args.kind {
        BenchKind::Linear => {
            if let Ok(job) = std::env::var(JOB_ENV) {
                return linear_child(&job);
            }
            linear(args, printer)
        }
        BenchKind::MeshSeries => crate::bench_series::mesh_series(args, printer),
        BenchKind::SolverSettings => crate::bench_series::solver_settings(args, printer),
    }
}

/// Environment variable carrying a child solve's job (JSON).
const JOB_ENV: &str = "RIBBAR_BENCH_LINEAR_JOB";
/// The imposed displacement of the bar's loaded end, m (linear: any value
/// scales the reaction; 0.01 mm keeps the strains physical).
const U_IMPOSED: f64 = 1e-5;
/// Relative residual of the multigrid-preconditioned CG.
const CG_TOLERANCE: f64 = 1e-8;
/// Longest a single solve may run, s.
const TIMEOUT: f64 = 3600.0;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
enum SolverKind {
    Cholesky,
    AmgCg,
}

impl SolverKind {
    fn label(self) -> &'static str {
        match self {
            SolverKind::Cholesky => "ribbar: faer Cholesky, METIS",
            SolverKind::AmgCg => "ribbar: CG + smoothed-aggregation AMG",
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Job {
    model: PathBuf,
    solver: SolverKind,
    /// Worker threads of the solve (`RAYON_NUM_THREADS`); `None`: all cores.
    threads: Option<usize>,
    u_imposed: f64,
    concrete: LinearElastic,
    steel: LinearElastic,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct ChildResult {
    free_dofs: usize,
    reaction: f64,
    threads: usize,
    t_load: f64,
    t_assembly: f64,
    t_setup: f64,
    t_solve: f64,
    iterations: usize,
    detail: String,
}

/// The child side: load the model, build and solve, print the result.
fn linear_child(job: &str) -> Result<ExitCode> {
    let job: Job = serde_json::from_str(job).context("bench job")?;
    let t0 = Instant::now();
    let model = Model::load(&job.model)?;
    let problem = PerfectBond::from_model(&model, job.u_imposed)?;
    drop(model);
    let t_load = t0.elapsed().as_secs_f64();
    let solver = match job.solver {
        SolverKind::Cholesky => ElasticSolver::Cholesky,
        SolverKind::AmgCg => ElasticSolver::AmgCg {
            tolerance: CG_TOLERANCE,
            params: AmgParams::default(),
        },
    };
    let s = solve(&problem, &job.concrete, &job.steel, solver)?;
    let out = ChildResult {
        free_dofs: s.free_dofs,
        reaction: s.reaction,
        threads: rayon::current_num_threads(),
        t_load,
        t_assembly: s.t_assembly,
        t_setup: s.t_setup,
        t_solve: s.t_solve,
        iterations: s.iterations,
        detail: s.detail,
    };
    println!("{}", serde_json::to_string(&out)?);
    Ok(ExitCode::SUCCESS)
}

/// One row of the table.
struct Row {
    model: &'static str,
    h_interface: f64,
    dofs: usize,
    solver: String,
    threads: usize,
    wall: f64,
    phases: String,
    max_rss: u64,
    iterations: Option<usize>,
    reaction: f64,
}

fn run_ribbar_child(job: &Job, printer: &Printer) -> Result<(ChildResult, Measured)> {
    let exe = crate::child::self_exe()?;
    let start = Instant::now();
    let mut command = Command::new(exe);
    if let Some(n) = job.threads {
        command.env("RAYON_NUM_THREADS", n.to_string());
    }
    let mut child = command
        .args(["bench", "linear"])
        .env(JOB_ENV, serde_json::to_string(job)?)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .context("starting the solve process")?;
    let mut stdout = child.stdout.take().context("child stdout")?;
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let m = wait_measured(&mut child, start, TIMEOUT)?;
    let text = reader.join().unwrap_or_default();
    if !m.success {
        bail!(
            "{} failed{} after {:.1} s",
            job.solver.label(),
            if m.timed_out { " (timed out)" } else { "" },
            m.wall
        );
    }
    let r: ChildResult = serde_json::from_str(text.lines().last().unwrap_or(""))
        .with_context(|| format!("reading the result of {}: {text:?}", job.solver.label()))?;
    printer.line(&format!(
        "{}: {:.2} s, {:.0} MiB, F = {:.6e} N",
        job.solver.label(),
        m.wall,
        m.max_rss as f64 / 1048576.0,
        r.reaction
    ));
    Ok((r, m))
}

/// E and ν of the scene's materials (their elastic part).
fn elastic_materials(scene: &Scene) -> (LinearElastic, LinearElastic) {
    let concrete = match scene.materials.concrete {
        ConcreteModel::Mazars(m) => LinearElastic {
            young_modulus: m.young_modulus,
            poisson_ratio: m.poisson_ratio,
        },
        ConcreteModel::Elastic(e) => e,
    };
    let steel = match scene.materials.steel {
        SteelModel::J2(j) => LinearElastic {
            young_modulus: j.young_modulus,
            poisson_ratio: j.poisson_ratio,
        },
        SteelModel::Elastic(e) => e,
    };
    (concrete, steel)
}

fn smooth80_spec() -> PathBuf {
    let local = PathBuf::from("specs/smooth-80.yaml");
    if local.is_file() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs/smooth-80.yaml")
    }
}

/// Meshes the smooth-80 variant and returns (scene, model path).
fn mesh_variant(
    args: &BenchArgs,
    work: &Path,
    symmetry: &str,
    printer: &Printer,
) -> Result<(Scene, PathBuf)> {
    let mut overrides = args.overrides.clone();
    overrides.push(format!("specimen.symmetry={symmetry}"));
    overrides.push(format!("name=bench-linear-{symmetry}"));
    let scene = Scene::load(&smooth80_spec(), &overrides)?;
    run_scene(&scene, work, crate::stage::Stage::Mesh.up_to(), printer)?;
    let model = work.join(&scene.name).join(mesh::MODEL_FILE);
    Ok((scene, model))
}

fn linear(args: &BenchArgs, printer: &Printer) -> Result<ExitCode> {
    // The stages hand paths to gmsh, which runs in another directory.
    let work = std::path::absolute(&args.work)
        .with_context(|| format!("work directory {}", args.work.display()))?;
    let mut rows: Vec<Row> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    let mut ccx_force = None;
    for symmetry in ["full", "quarter"] {
        let (scene, model_path) = mesh_variant(args, &work, symmetry, printer)?;
        let (concrete, steel) = elastic_materials(&scene);
        let h = scene.mesh.h_interface;
        let label = if symmetry == "full" {
            "full"
        } else {
            "quarter"
        };
        // The AMG also on one thread, as PETSc runs (one process).
        let solvers: &[(SolverKind, Option<usize>)] = if symmetry == "full" {
            &[
                (SolverKind::Cholesky, None),
                (SolverKind::AmgCg, None),
                (SolverKind::AmgCg, Some(1)),
            ]
        } else {
            &[(SolverKind::AmgCg, None)]
        };
        for &(solver, threads) in solvers {
            let job = Job {
                model: model_path.clone(),
                solver,
                threads,
                u_imposed: U_IMPOSED,
                concrete,
                steel,
            };
            match run_ribbar_child(&job, printer) {
                Ok((r, m)) => rows.push(Row {
                    model: label,
                    h_interface: h,
                    dofs: r.free_dofs,
                    solver: solver.label().to_string(),
                    threads: r.threads,
                    wall: m.wall,
                    phases: format!(
                        "load {:.2} + assembly {:.2} + setup {:.2} + solve {:.2} s; {}",
                        r.t_load, r.t_assembly, r.t_setup, r.t_solve, r.detail
                    ),
                    max_rss: m.max_rss,
                    iterations: (solver == SolverKind::AmgCg).then_some(r.iterations),
                    reaction: r.reaction,
                }),
                Err(e) => {
                    printer.line(&format!("{label}: {e:#}"));
                    notes.push(format!("{label} model, {}: {e:#}", solver.label()));
                }
            }
        }
        if symmetry == "full" {
            let peers = Peers {
                work: &work,
                model_path: &model_path,
                label,
                h,
                concrete: &concrete,
                steel: &steel,
            };
            ccx_force = peer_rows(&peers, &mut rows, &mut notes, printer)?;
        }
    }
    let full_row = |prefix: &str| {
        rows.iter()
            .find(|r| r.model == "full" && r.solver.starts_with(prefix))
    };
    if let (Some(p), Some(a)) = (full_row("PETSc"), full_row(SolverKind::AmgCg.label())) {
        notes.push(format!(
            "PETSc's reaction against ribbar's AMG (same system, CG to {CG_TOLERANCE:e}): \
             {:+.2e} relative; wall time ribbar AMG / PETSc: {:.2} ({} threads), {:.2} (1 thread).",
            (p.reaction - a.reaction) / a.reaction.abs(),
            a.wall / p.wall,
            a.threads,
            rows.iter()
                .filter(|r| r.model == "full" && r.threads == 1 && r.solver == a.solver)
                .map(|r| r.wall / p.wall)
                .next()
                .unwrap_or(f64::NAN)
        ));
    }
    let table = linear_table(&rows, ccx_force, &notes, args);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let path = args.out.join("linear.md");
    let tmp = args
        .out
        .join(format!(".linear.md.tmp-{}", std::process::id()));
    std::fs::write(&tmp, &table).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    printer.finish();
    print!("{table}");
    printer.line(&format!("table: {}", path.display()));
    if rows.is_empty() {
        bail!("no solve succeeded");
    }
    Ok(ExitCode::SUCCESS)
}

/// The full model's external peers of one bench run.
struct Peers<'a> {
    work: &'a Path,
    model_path: &'a Path,
    label: &'static str,
    h: f64,
    concrete: &'a LinearElastic,
    steel: &'a LinearElastic,
}

/// CalculiX and PETSc on the full model: their rows, or a note saying why
/// not; returns CalculiX's reaction, the table's reference.
fn peer_rows(
    p: &Peers<'_>,
    rows: &mut Vec<Row>,
    notes: &mut Vec<String>,
    printer: &Printer,
) -> Result<Option<f64>> {
    let mut ccx_force = None;
    let model = Model::load(p.model_path)?;
    let problem = PerfectBond::from_model(&model, U_IMPOSED)?;
    drop(model);
    let dir = p.work.join("bench-linear-ccx");
    match ccx::run(&problem, p.concrete, p.steel, &dir, TIMEOUT, printer) {
        Ok(Some(c)) => {
            ccx_force = Some(c.reaction);
            rows.push(Row {
                model: p.label,
                h_interface: p.h,
                dofs: problem.free_dofs(),
                solver: format!("CalculiX ccx {} (C3D4)", c.version),
                threads: c.threads,
                wall: c.wall,
                phases: "whole run (input, SPOOLES solve, output)".into(),
                max_rss: c.max_rss,
                iterations: None,
                reaction: c.reaction,
            });
        }
        Ok(None) => notes.push(
            "CalculiX `ccx` is not installed (Debian package calculix-ccx): ribbar alone.".into(),
        ),
        Err(e) => {
            printer.line(&format!("ccx: {e:#}"));
            notes.push(format!("CalculiX failed: {e:#}"));
        }
    }
    let dir = p.work.join("bench-linear-petsc");
    match crate::bench_petsc::run(
        &problem,
        p.concrete,
        p.steel,
        CG_TOLERANCE,
        &dir,
        TIMEOUT,
        printer,
    ) {
        Ok(Some(r)) => rows.push(Row {
            model: p.label,
            h_interface: p.h,
            dofs: problem.free_dofs(),
            solver: format!("PETSc {}: CG + GAMG", r.version),
            threads: 1,
            wall: r.measured.wall,
            phases: r.phases,
            max_rss: r.measured.max_rss,
            iterations: Some(r.iterations),
            reaction: r.reaction,
        }),
        Ok(None) => notes.push(
            "petsc4py is not installed (Debian package python3-petsc4py): no PETSc row.".into(),
        ),
        Err(e) => {
            printer.line(&format!("PETSc: {e:#}"));
            notes.push(format!("PETSc failed: {e:#}"));
        }
    }
    Ok(ccx_force)
}

fn linear_table(
    rows: &[Row],
    ccx_force: Option<f64>,
    notes: &[String],
    args: &BenchArgs,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Linear-elastic perfect-bond pull-out (smooth-80)\n\n\
         Imposed displacement {} mm of the bar's loaded end; reaction F on that end \
         (whole specimen). Wall time and peak resident memory of the whole solve \
         process (reading the mesh included).\n",
        U_IMPOSED * 1e3
    );
    let mut cmd = String::from("ribbar bench linear");
    for o in &args.overrides {
        let _ = write!(cmd, " --set '{o}'");
    }
    let _ = writeln!(s, "Command: `{cmd}`\n");
    let _ = writeln!(
        s,
        "| model | h_interface (mm) | DOFs | solver | threads | wall time (s) | peak memory (MiB) | iterations | reaction F (N) | F vs ccx |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let diff = match ccx_force {
            Some(c) if c != 0.0 => format!("{:+.2e}", (r.reaction - c) / c.abs()),
            _ => "–".into(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.2} | {:.0} | {} | {:.6e} | {} |",
            r.model,
            r.h_interface * 1e3,
            r.dofs,
            r.solver,
            r.threads,
            r.wall,
            r.max_rss as f64 / 1048576.0,
            r.iterations
                .map(|i| i.to_string())
                .unwrap_or_else(|| "–".into()),
            r.reaction,
            diff
        );
    }
    let _ = writeln!(s, "\nPhases:\n");
    for r in rows {
        let _ = writeln!(s, "* {} model, {}: {}", r.model, r.solver, r.phases);
    }
    if !notes.is_empty() {
        let _ = writeln!(s, "\nNotes:\n");
        for n in notes {
            let _ = writeln!(s, "* {n}");
        }
    }
    s
}

/// CalculiX: the same problem as an Abaqus-format input, run and parsed.
mod ccx {
    use super::Printer;
    use crate::measure::run_logged;
    use anyhow::{Context, Result};
    use solve::laws::elastic::LinearElastic;
    use solve::problems::linear_elastic::PerfectBond;
    use std::fmt::Write as _;
    use std::path::Path;
    use std::process::Command;

    pub struct CcxResult {
        pub reaction: f64,
        pub wall: f64,
        pub max_rss: u64,
        pub threads: usize,
        pub version: String,
    }

    const JOB: &str = "perfect_bond";

    /// The problem as a CalculiX input: C3D4 tets in two element sets,
    /// the constrained DOFs one by one (the same list ribbar eliminates),
    /// and the loaded end's total reaction printed to the `.dat` file.
    /// Coordinates with 13 significant digits (ccx rejects 17, SPEC §9).
    pub fn input(p: &PerfectBond, concrete: &LinearElastic, steel: &LinearElastic) -> String {
        let mut s = String::with_capacity(64 * (p.nodes.len() + p.tets.len()));
        s.push_str("*HEADING\nribbar perfect-bond pull-out, SI units\n*NODE\n");
        for (i, x) in p.nodes.iter().enumerate() {
            let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, x[0], x[1], x[2]);
        }
        for (name, region) in [
            ("ESTEEL", mesh::Region::Steel),
            ("ECONCRETE", mesh::Region::Concrete),
        ] {
            let _ = writeln!(s, "*ELEMENT, TYPE=C3D4, ELSET={name}");
            for (e, t) in p.tets.iter().enumerate() {
                if p.tet_region[e] == region {
                    let _ = writeln!(
                        s,
                        "{}, {}, {}, {}, {}",
                        e + 1,
                        t[0] + 1,
                        t[1] + 1,
                        t[2] + 1,
                        t[3] + 1
                    );
                }
            }
        }
        s.push_str("*NSET, NSET=NLOADED\n");
        for chunk in p.loaded_end.chunks(8) {
            let ids: Vec<String> = chunk.iter().map(|i| (i + 1).to_string()).collect();
            let _ = writeln!(s, "{},", ids.join(", "));
        }
        for (name, m) in [("STEEL", steel), ("CONCRETE", concrete)] {
            let _ = writeln!(
                s,
                "*MATERIAL, NAME={name}\n*ELASTIC\n{:.12e}, {:.12e}",
                m.young_modulus, m.poisson_ratio
            );
        }
        s.push_str("*SOLID SECTION, ELSET=ESTEEL, MATERIAL=STEEL\n");
        s.push_str("*SOLID SECTION, ELSET=ECONCRETE, MATERIAL=CONCRETE\n");
        s.push_str("*STEP\n*STATIC\n*BOUNDARY\n");
        for &(d, v) in &p.constrained {
            let (node, comp) = (d / 3 + 1, d % 3 + 1);
            let _ = writeln!(s, "{node}, {comp}, {comp}, {v:.12e}");
        }
        s.push_str("*NODE PRINT, NSET=NLOADED, TOTALS=ONLY\nRF\n*END STEP\n");
        s
    }

    /// The last "total force (fx,fy,fz) for set NLOADED" of a `.dat` file: fz.
    pub fn parse_total_fz(dat: &str) -> Option<f64> {
        let lines: Vec<&str> = dat.lines().collect();
        let mut found = None;
        for (i, l) in lines.iter().enumerate() {
            if l.contains("total force") && l.to_ascii_uppercase().contains("NLOADED") {
                let values = lines[i + 1..]
                    .iter()
                    .find(|l| !l.trim().is_empty())
                    .map(|l| {
                        l.split_whitespace()
                            .filter_map(|v| v.parse::<f64>().ok())
                            .collect::<Vec<_>>()
                    });
                if let Some(v) = values.filter(|v| v.len() >= 3) {
                    found = Some(v[2]);
                }
            }
        }
        found
    }

    fn locate() -> Option<std::path::PathBuf> {
        let path = std::env::var_os("PATH")?;
        std::env::split_paths(&path)
            .map(|d| d.join("ccx"))
            .find(|p| p.is_file())
    }

    /// Writes the input into `dir`, runs ccx with a timeout (s) and reads
    /// the reaction; `None` when ccx is not installed.
    pub fn run(
        p: &PerfectBond,
        concrete: &LinearElastic,
        steel: &LinearElastic,
        dir: &Path,
        timeout: f64,
        printer: &Printer,
    ) -> Result<Option<CcxResult>> {
        let Some(exe) = locate() else {
            printer.line("ccx not found on PATH: CalculiX skipped");
            return Ok(None);
        };
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let inp = dir.join(format!("{JOB}.inp"));
        std::fs::write(&inp, input(p, concrete, steel))
            .with_context(|| format!("writing {}", inp.display()))?;
        let dat = dir.join(format!("{JOB}.dat"));
        let _ = std::fs::remove_file(&dat);
        let version = Command::new(&exe)
            .arg("-v")
            .output()
            .ok()
            .and_then(|o| {
                String::from_utf8_lossy(&o.stdout)
                    .split_whitespace()
                    .find(|w| w.chars().next().is_some_and(|c| c.is_ascii_digit()))
                    .map(|w| w.trim_end_matches('.').to_string())
            })
            .unwrap_or_default();
        let threads = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1);
        printer.line(&format!(
            "CalculiX: {} nodes, {} tets",
            p.nodes.len(),
            p.tets.len()
        ));
        let m = run_logged(
            Command::new(&exe)
                .arg(JOB)
                .current_dir(dir)
                .env("OMP_NUM_THREADS", threads.to_string())
                .env("CCX_NPROC_EQUATION_SOLVER", threads.to_string()),
            &format!("ccx ({})", exe.display()),
            &dir.join("ccx.log"),
            timeout,
        )?;
        let text =
            std::fs::read_to_string(&dat).with_context(|| format!("reading {}", dat.display()))?;
        let reaction = parse_total_fz(&text)
            .with_context(|| format!("{}: no total force for set NLOADED", dat.display()))?;
        printer.line(&format!(
            "CalculiX: {:.2} s, {:.0} MiB, F = {:.6e} N",
            m.wall,
            m.max_rss as f64 / 1048576.0,
            reaction
        ));
        Ok(Some(CcxResult {
            reaction,
            wall: m.wall,
            max_rss: m.max_rss,
            threads,
            version,
        }))
    }

    #[cfg(test)]
    mod tests {
        /// The reaction is read from ccx's `.dat` totals block (format of CalculiX 2.x).
        #[test]
        fn parses_total_force_block() {
            let dat = "\n forces (fx,fy,fz) for set NLOADED and time  0.1000000E+01\n\n total force (fx,fy,fz) for set NLOADED and time  0.1000000E+01\n\n       -1.234500E-03  2.000000E-04  5.678900E+03\n";
            assert_eq!(super::parse_total_fz(dat), Some(5.6789e3));
            assert_eq!(super::parse_total_fz("nothing here"), None);
        }
    }
}
