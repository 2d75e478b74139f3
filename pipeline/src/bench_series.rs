//! Run time against error (issue 7): `ribbar bench mesh-series`, `ribbar
//! bench solver-settings`, and the table of the numerical-stability sweep
//! (`stress_report`, run by `scripts/stress-sweep.sh` after `ribbar study
//! specs/studies/stress-sweep.yaml`).
//!
//! Every run goes through the normal pipeline ([`run_scene`]) with its own
//! scene name, so the artifacts are cached: a second bench run reuses them
//! and reports the times recorded by the runs that made them (`summary.json`
//! `stage_wall_time_s`, `solver.summary.wall_time_s`), never the near-zero
//! time of a cache hit.

use crate::cli::BenchArgs;
use crate::commands::run_scene;
use crate::post::{self, CurveAxis, CurveRow, ErrorTimeSeries, GridResult};
use crate::progress::Printer;
use crate::scene::Scene;
use crate::study::Study;
use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// A spec shipped in the repository, found from the working directory or,
/// failing that, from the crate's source directory.
fn repo_file(rel: &str) -> PathBuf {
    let local = PathBuf::from(rel);
    if local.is_file() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
    }
}

/// What one pipeline run produced (SI).
#[derive(Debug, Clone, Default)]
pub struct RunRecord {
    pub name: String,
    pub completed: bool,
    /// Why the run did not complete (stopped solve or failed stage).
    pub reason: Option<String>,
    /// How a completed run ended: `completed` (the end of the loading),
    /// `limit_load` or `unloaded` (solve.json `ending.kind`).
    pub ending: Option<String>,
    /// Of a `brittle_failure`: concrete tets cracked through the cover
    /// (solve.json `ending.cracked_through_tets`).
    pub cracked_through_tets: Option<u64>,
    pub dofs: Option<u64>,
    pub steps: Option<u64>,
    pub iterations: Option<u64>,
    pub krylov_iterations: Option<u64>,
    /// Stage wall times, s.
    pub t_geometry: Option<f64>,
    pub t_mesh: Option<f64>,
    pub t_solve: Option<f64>,
    /// Solve phases, s: assembly, constitutive, factorisation, solve.
    pub solve_phases: Option<[f64; 4]>,
    /// Peak σ_mb, Pa.
    pub peak: Option<f64>,
    /// Energy under the σ_mb–FED curve, J/m².
    pub energy: Option<f64>,
    /// Largest |W_ext − W_int|/W_ext of the energy check.
    pub energy_imbalance: Option<f64>,
    pub energy_passed: Option<bool>,
    pub curve: Vec<CurveRow>,
}

impl RunRecord {
    /// Tets cracked through the cover of a completed run that ended with
    /// some (a `brittle_failure` whose cover split); `None` otherwise.
    pub fn cover_cracked(&self) -> Option<u64> {
        self.cracked_through_tets
            .filter(|&n| self.completed && n > 0)
    }

    /// Geometry + mesh + solve wall time, s (missing stages count 0).
    pub fn total_time(&self) -> Option<f64> {
        self.t_solve
            .map(|s| s + self.t_geometry.unwrap_or(0.0) + self.t_mesh.unwrap_or(0.0))
    }

    /// Reads a scene's published results from `dir`.
    pub fn read(name: &str, dir: &Path) -> RunRecord {
        let json = |f: &str| -> Option<Value> {
            serde_json::from_slice(&std::fs::read(dir.join(f)).ok()?).ok()
        };
        let summary = json("summary.json").unwrap_or(Value::Null);
        let solve = json("solve.json").unwrap_or(Value::Null);
        let f = |v: &Value, p: &str| v.pointer(p).and_then(Value::as_f64);
        let u = |v: &Value, p: &str| v.pointer(p).and_then(Value::as_u64);
        let stage = |key: &str| -> Option<f64> {
            let v = summary.pointer(&format!("/stage_wall_time_s/{key}"))?;
            match v {
                Value::Number(n) => n.as_f64(),
                Value::Object(m) => Some(m.values().filter_map(Value::as_f64).sum()),
                _ => None,
            }
        };
        let phases = ["assembly", "constitutive", "factorisation", "solve"]
            .map(|k| f(&solve, &format!("/summary/wall_time_s/{k}")));
        RunRecord {
            name: name.to_string(),
            completed: solve
                .get("completed")
                .and_then(Value::as_bool)
                .unwrap_or(false),
            reason: solve
                .get("stopped")
                .and_then(Value::as_str)
                .map(str::to_string),
            ending: solve
                .pointer("/ending/kind")
                .and_then(Value::as_str)
                .map(str::to_string),
            cracked_through_tets: u(&solve, "/ending/cracked_through_tets"),
            dofs: u(&solve, "/summary/dofs"),
            steps: u(&solve, "/summary/steps"),
            iterations: u(&solve, "/summary/total_iterations"),
            krylov_iterations: u(&solve, "/summary/krylov_iterations"),
            t_geometry: stage("geometry"),
            t_mesh: stage("mesh"),
            t_solve: f(&solve, "/summary/wall_time_s/total"),
            solve_phases: phases
                .iter()
                .all(Option::is_some)
                .then(|| phases.map(|p| p.unwrap_or(0.0))),
            peak: f(&summary, "/curve/peak_bond_stress"),
            energy: f(&summary, "/curve/energy"),
            energy_imbalance: f(&solve, "/energy_check/max_relative_imbalance"),
            energy_passed: solve
                .pointer("/energy_check/passed")
                .and_then(Value::as_bool),
            curve: post::read_curve_csv(&dir.join("curve.csv")).unwrap_or_default(),
        }
    }
}

/// Runs every stage of `spec` with `overrides` under the scene name `name`
/// and reads what it published; a failed or stopped run is recorded with
/// its reason rather than ending the benchmark.
pub fn run_and_read(
    spec: &Path,
    overrides: &[String],
    name: &str,
    work: &Path,
    printer: &Printer,
) -> RunRecord {
    let mut o = overrides.to_vec();
    o.push(format!("name={name}"));
    let outcome = Scene::load(spec, &o)
        .map_err(anyhow::Error::from)
        .and_then(|scene| run_scene(&scene, work, &crate::stage::Stage::ALL, printer));
    let mut rec = RunRecord::read(name, &work.join(name));
    if let Err(e) = outcome {
        printer.line(&format!("[{name}] {e:#}"));
        rec.completed = false;
        if rec.reason.is_none() {
            rec.reason = Some(format!("{e:#}"));
        }
    }
    rec
}

fn fmt_opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("–".into(), |x| format!("{:.*}", digits, x * scale))
}

fn fmt_rel(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{x:.2e}"))
}

fn command_line(kind: &str, args: &BenchArgs) -> String {
    let mut cmd = format!("ribbar bench {kind}");
    if args.quick {
        cmd.push_str(" --quick");
    }
    for o in &args.overrides {
        let _ = write!(cmd, " --set '{o}'");
    }
    for o in &args.sizes {
        let _ = write!(cmd, " --sizes {o}");
    }
    cmd
}

/// Applies the `--sizes SERIES=MM,MM,...` options to the plan.
fn apply_sizes(plan: &mut [Series], options: &[String]) -> Result<()> {
    for option in options {
        let Some((label, list)) = option.split_once('=') else {
            bail!("--sizes {option}: expected SERIES=MM,MM,... (e.g. R1=1.6,1.2,0.8)");
        };
        let Some(series) = plan
            .iter_mut()
            .find(|s| s.label.eq_ignore_ascii_case(label.trim()))
        else {
            let known: Vec<&str> = plan.iter().map(|s| s.label).collect();
            bail!(
                "--sizes {option}: no series `{label}` in this mesh series (series: {})",
                known.join(", ")
            );
        };
        let mut sizes = Vec::new();
        for item in list.split(',') {
            let mm: f64 = item
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--sizes {option}: `{item}` is not a size in mm"))?;
            if !(mm.is_finite() && mm > 0.0) {
                bail!("--sizes {option}: size {mm} mm must be positive");
            }
            sizes.push(mm * 1e-3);
        }
        if sizes.len() < 3 {
            bail!(
                "--sizes {option}: {} sizes given; the GCI needs at least 3",
                sizes.len()
            );
        }
        series.sizes = sizes;
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    crate::store::write_atomic(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// One scene of the mesh series: label, spec, interface sizes (m).
struct Series {
    label: &'static str,
    spec: PathBuf,
    sizes: Vec<f64>,
    extra: Vec<String>,
}

/// The settings every case of `specs/studies/NAME.yaml` shares (its `set:`),
/// as `--set` arguments: a series that shares the study's runs reads them
/// from the study instead of repeating them.
fn study_settings(name: &str) -> Result<Vec<String>> {
    let path = repo_file(&format!("specs/studies/{name}.yaml"));
    Ok(crate::study::Study::load(&path)?.shared)
}

fn mesh_series_plan(quick: bool) -> Result<Vec<Series>> {
    if quick {
        // Seconds per grid: the tiny smooth scene (tests, smoke runs).
        Ok(vec![Series {
            label: "tiny-smooth",
            spec: repo_file("tests/data/tiny-smooth.yaml"),
            sizes: vec![3e-3, 2.5e-3, 2e-3],
            extra: vec![
                "outputs.energy_fed_limit=\"0.2 mm\"".into(),
                "outputs.plots=[]".into(),
            ],
        }])
    } else {
        let sizes = vec![1.6e-3, 1.2e-3, 0.8e-3, 0.4e-3];
        Ok(vec![
            Series {
                label: "smooth-80",
                spec: repo_file("specs/smooth-80.yaml"),
                sizes: sizes.clone(),
                extra: vec![],
            },
            Series {
                label: "R1",
                spec: repo_file("specs/r1-coarse.yaml"),
                sizes,
                // The study's integration: the 0.4 mm grid needs IMPL-EX,
                // and one series one integration.
                extra: study_settings("r1-convergence")?,
            },
        ])
    }
}

/// `ribbar bench mesh-series`: see the module doc and docs/src/validation/performance.md.
pub fn mesh_series(args: &BenchArgs, printer: &Printer) -> Result<ExitCode> {
    let work = std::path::absolute(&args.work)
        .with_context(|| format!("work directory {}", args.work.display()))?;
    // Checked before anything runs.
    apply_sizes(&mut mesh_series_plan(args.quick)?, &args.sizes)?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Mesh series: run time against discretisation error\n\n\
         Command: `{}`\n\n\
         Per grid: free DOFs, wall time per stage (geometry, mesh, solve and the solve's phases: \
         assembly / constitutive / factorisation / solve, s), peak σ_mb and the energy under the \
         σ_mb–FED curve, each with its relative error against the Richardson extrapolation of the \
         finest triplet and its GCI (Celik et al. 2008, safety factor 1.25; docs/src/explanation/post.md), and the \
         solve's energy balance (largest |W_ext − W_int|/W_ext). Times are those of the runs that \
         produced the cached artifacts, on this 2-core machine shared with other jobs.\n",
        command_line("mesh-series", args)
    );
    let mut plan = mesh_series_plan(args.quick)?;
    apply_sizes(&mut plan, &args.sizes)?;
    let mut series_plot: Vec<ErrorTimeSeries> = Vec::new();
    let mut any = false;
    for s in plan {
        let records = run_series(&s, args, &work, printer);
        any |= records.iter().any(|(_, r)| !r.curve.is_empty());
        let studies = write_series(&mut md, &s, &records);
        for st in &studies {
            let mut e = ErrorTimeSeries::from_study(st);
            e.label = format!("{}: {}", s.label, st.quantity);
            if !e.points.is_empty() {
                series_plot.push(e);
            }
        }
    }
    if !series_plot.is_empty() {
        post::error_vs_time_plot(
            &series_plot,
            &args.out.join("mesh-series-error-vs-time.png"),
            &args.out.join("mesh-series-error-vs-time.svg"),
        )?;
        let _ = writeln!(
            md,
            "\n![error against wall time](mesh-series-error-vs-time.png)\n"
        );
    }
    let path = args.out.join("mesh-series.md");
    write_text(&path, &md)?;
    printer.finish();
    printer.line(&format!("table: {}", path.display()));
    if !any {
        bail!("no grid of the mesh series produced a curve");
    }
    Ok(ExitCode::SUCCESS)
}

/// Runs (or reads from the cache) every grid of one series.
fn run_series(
    s: &Series,
    args: &BenchArgs,
    work: &Path,
    printer: &Printer,
) -> Vec<(f64, RunRecord)> {
    let mut records = Vec::new();
    for &h in &s.sizes {
        let mut o = s.extra.clone();
        o.extend(args.overrides.iter().cloned());
        o.push(format!("mesh.h_interface=\"{} mm\"", h * 1e3));
        let name = format!("bench-mesh-{}-{:.0}um", s.label.to_lowercase(), h * 1e6);
        printer.line(&format!(
            "mesh series {}: h_interface = {} mm",
            s.label,
            h * 1e3
        ));
        let rec = run_and_read(&s.spec, &o, &name, work, printer);
        records.push((h, rec));
    }
    records
}

/// One series' section of the table: a row per grid, the triplets'
/// extrapolation and GCI, and the grids that did not complete; returns the
/// convergence studies (peak σ_mb, energy) that had three grids.
fn write_series(
    md: &mut String,
    s: &Series,
    records: &[(f64, RunRecord)],
) -> Vec<post::ConvergenceStudy> {
    let grid = |q: fn(&RunRecord) -> Option<f64>| -> Vec<GridResult> {
        records
            .iter()
            .filter_map(|(h, r)| {
                Some(GridResult {
                    h: *h,
                    value: q(r)?,
                    dofs: r.dofs,
                    wall_time: r.total_time(),
                })
            })
            .collect()
    };
    let peak = post::convergence_study("peak σ_mb", &grid(|r| r.peak)).ok();
    let energy = post::convergence_study("energy", &grid(|r| r.energy)).ok();
    let row_of = |study: &Option<post::ConvergenceStudy>, h: f64| {
        study
            .as_ref()
            .and_then(|s| s.rows().into_iter().find(|r| r.h == h))
    };
    let _ = writeln!(md, "## {} ({})\n", s.label, s.spec.display());
    let _ = writeln!(
        md,
        "| h_interface (mm) | DOFs | steps | completed | geometry (s) | mesh (s) | solve (s) | assembly / constitutive / factorisation / solve (s) | peak σ_mb (MPa) | error | GCI | energy (J/m²) | error | GCI | energy imbalance |"
    );
    let _ = writeln!(
        md,
        "|---:|---:|---:|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for (h, r) in records {
        let (pr, er) = (row_of(&peak, *h), row_of(&energy, *h));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            h * 1e3,
            r.dofs.map_or("–".into(), |d| d.to_string()),
            r.steps.map_or("–".into(), |d| d.to_string()),
            if r.completed { "yes" } else { "no" },
            fmt_opt(r.t_geometry, 1.0, 2),
            fmt_opt(r.t_mesh, 1.0, 2),
            fmt_opt(r.t_solve, 1.0, 1),
            r.solve_phases.map_or("–".into(), |p| format!(
                "{:.1} / {:.1} / {:.1} / {:.1}",
                p[0], p[1], p[2], p[3]
            )),
            fmt_opt(r.peak, 1e-6, 4),
            fmt_rel(pr.as_ref().and_then(|x| x.rel_error_vs_extrapolated)),
            fmt_rel(pr.as_ref().and_then(|x| x.gci)),
            fmt_opt(r.energy, 1.0, 1),
            fmt_rel(er.as_ref().and_then(|x| x.rel_error_vs_extrapolated)),
            fmt_rel(er.as_ref().and_then(|x| x.gci)),
            fmt_rel(r.energy_imbalance),
        );
    }
    let studies: Vec<post::ConvergenceStudy> = [peak, energy].into_iter().flatten().collect();
    if studies.is_empty() {
        let _ = writeln!(
            md,
            "\nNo quantity has three grids with a value: no extrapolation.\n"
        );
    } else {
        let _ = writeln!(
            md,
            "\nTriplets (finest first):\n\n{}",
            post::convergence_order_table(&studies).to_markdown()
        );
    }
    for (h, r) in records {
        if let Some(why) = &r.reason {
            let _ = writeln!(
                md,
                "- h = {} mm did not complete: {}\n",
                h * 1e3,
                truncate(why, 400)
            );
        }
    }
    studies
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(n).collect::<String>())
    }
}

/// The variants of the solver-settings benchmark: (label, overrides). The
/// first is the reference: the default tolerances with steps of at most
/// 10 µm (a fifth of R1 coarse's 50 µm). Tighter force tolerances do not
/// get through R1 coarse: with 1e-7 (strict) its steps were cut to 0.1 µm
/// by u = 0.024 mm after 8 minutes, with 1e-6 (steps in a threshold
/// two-cycle ending within 1e-4) they crawled at u = 0.218 mm after 7
/// minutes; the two-cycles' residual is ~1e-4 (docs/src/validation/solver.md). Steps of
/// 5 µm with energy 1e-10 and GMRES 1e-8 took 10-15 s each on the shared
/// machine (some 45 minutes for the curve). `solver.expert.linear_solver:
/// cholesky` and `pcg` are not variants: on the symmetric part of the
/// consistent tangent they needed so many iterations and cut-backs that R1
/// coarse reached u = 0.035 mm in 26 steps (Cholesky) and 0.040 mm in 34
/// steps (PCG) after 6 minutes each.
pub fn solver_variants() -> Vec<(&'static str, Vec<&'static str>)> {
    vec![
        (
            "reference: max step 10 µm",
            vec![
                "loading.max_step=\"10 um\"",
                "loading.initial_step=\"2 um\"",
            ],
        ),
        ("defaults", vec![]),
        ("residual 1e-3", vec!["solver.residual_tolerance=1e-3"]),
        ("residual 1e-5", vec!["solver.residual_tolerance=1e-5"]),
        ("energy 1e-6", vec!["solver.expert.energy_tolerance=1e-6"]),
        (
            "krylov 1e-6, fixed forcing",
            vec![
                "solver.expert.krylov_tolerance=1e-6",
                "solver.expert.forcing=fixed",
            ],
        ),
        ("initial step 10 µm", vec!["loading.initial_step=\"10 um\""]),
        ("max step 40 µm", vec!["loading.max_step=\"40 um\""]),
        ("growth 1.2", vec!["solver.expert.growth=1.2"]),
        ("growth 2", vec!["solver.expert.growth=2"]),
        (
            "constant predictor",
            vec!["solver.expert.predictor=constant"],
        ),
        ("tangent secant", vec!["solver.expert.tangent=secant"]),
        ("no line search", vec!["solver.expert.line_search=false"]),
        (
            "strict stagnation rule",
            vec!["solver.expert.stagnation_acceptance=1"],
        ),
        (
            "double-precision preconditioner",
            vec!["solver.expert.preconditioner_precision=double"],
        ),
        (
            "IMPL-EX concrete (tolerance 1e-2)",
            vec!["solver.concrete_integration=impl_ex"],
        ),
        (
            "IMPL-EX concrete, tolerance 3e-2",
            vec![
                "solver.concrete_integration=impl_ex",
                "solver.impl_ex_tolerance=3e-2",
            ],
        ),
        (
            "IMPL-EX concrete, no step control",
            vec![
                "solver.concrete_integration=impl_ex",
                "solver.impl_ex_tolerance=1e9",
            ],
        ),
    ]
}

/// Every solver-settings run stops after this many converged steps (the
/// reference needs about 250): a setting that makes R1 coarse crawl is
/// reported as not completed instead of holding the bench for hours.
const SETTINGS_MAX_STEPS: &str = "solver.expert.max_steps=600";

/// `ribbar bench solver-settings`: see the module doc and docs/src/validation/performance.md.
pub fn solver_settings(args: &BenchArgs, printer: &Printer) -> Result<ExitCode> {
    let work = std::path::absolute(&args.work)
        .with_context(|| format!("work directory {}", args.work.display()))?;
    let (label, spec, mut base) = if args.quick {
        (
            "tiny-smooth",
            repo_file("tests/data/tiny-smooth.yaml"),
            vec!["outputs.plots=[]".to_string()],
        )
    } else {
        ("R1 coarse", repo_file("specs/r1-coarse.yaml"), vec![])
    };
    base.push(SETTINGS_MAX_STEPS.to_string());
    base.extend(args.overrides.iter().cloned());
    let variants = solver_variants();
    let mut records: Vec<(&str, RunRecord)> = Vec::new();
    for (i, (name, o)) in variants.iter().enumerate() {
        let mut all = base.clone();
        all.extend(o.iter().map(|s| s.to_string()));
        printer.line(&format!("solver settings: {name}"));
        let scene_name = format!(
            "bench-settings-{}-{i:02}",
            if args.quick { "quick" } else { "r1" }
        );
        records.push((name, run_and_read(&spec, &all, &scene_name, &work, printer)));
    }
    let reference = records[0].1.clone();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Solver settings: run time against curve error ({label})\n\n\
         Command: `{}`\n\n\
         One mesh ({}), one run per setting; the first row is the reference (10 µm steps; docs/src/validation/performance.md). \
         Curve error: relative L2 distance of σ_mb along the imposed displacement to the \
         reference's, over their common range (`post::curve_distance`); peak error: relative \
         difference of the peak σ_mb. Solve wall time of the run (2 shared cores).\n",
        command_line("solver-settings", args),
        spec.display()
    );
    let _ = writeln!(md, "| setting | completed | solve (s) | steps | Newton iterations | GMRES iterations | final u (mm) | peak σ_mb (MPa) | curve error | peak error | energy imbalance |");
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut points = Vec::new();
    for (name, r) in &records {
        let dist = (!r.curve.is_empty() && !reference.curve.is_empty())
            .then(|| {
                post::curve_distance(
                    &r.curve,
                    &reference.curve,
                    CurveAxis::ImposedDisplacement,
                    None,
                )
                .ok()
            })
            .flatten();
        let peak_err = match (r.peak, reference.peak) {
            (Some(a), Some(b)) if b != 0.0 => Some(((a - b) / b).abs()),
            _ => None,
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            name,
            if r.completed { "yes" } else { "no" },
            fmt_opt(r.t_solve, 1.0, 1),
            r.steps.map_or("–".into(), |d| d.to_string()),
            r.iterations.map_or("–".into(), |d| d.to_string()),
            r.krylov_iterations.map_or("–".into(), |d| d.to_string()),
            fmt_opt(r.curve.last().map(|c| c.u_imposed), 1e3, 4),
            fmt_opt(r.peak, 1e-6, 4),
            fmt_rel(dist),
            fmt_rel(peak_err),
            fmt_rel(r.energy_imbalance),
        );
        if let (Some(t), Some(d)) = (r.t_solve, dist) {
            if !std::ptr::eq(r, &records[0].1) {
                points.push((t, d));
            }
        }
    }
    for (name, r) in &records {
        if let Some(why) = &r.reason {
            let _ = writeln!(md, "\n- {name}: did not complete: {}", truncate(why, 400));
        }
    }
    if !points.is_empty() {
        post::error_vs_time_plot(
            &[ErrorTimeSeries {
                label: "curve error vs reference".into(),
                points,
            }],
            &args.out.join("solver-settings-error-vs-time.png"),
            &args.out.join("solver-settings-error-vs-time.svg"),
        )?;
        let _ = writeln!(
            md,
            "\n![curve error against solve time](solver-settings-error-vs-time.png)\n"
        );
    }
    let path = args.out.join("solver-settings.md");
    write_text(&path, &md)?;
    printer.finish();
    printer.line(&format!("table: {}", path.display()));
    if reference.curve.is_empty() {
        bail!(
            "the reference run produced no curve: {}",
            reference.reason.unwrap_or_default()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// One case of the stress sweep, as checked by [`stress_report`].
#[derive(Debug, Clone)]
pub struct StressCase {
    pub name: String,
    /// The swept values, `key=value`.
    pub parameters: String,
    pub record: RunRecord,
    /// The run's log shows a Rust panic.
    pub panicked: bool,
    /// `curve.csv` holds a value that is not a finite number (any column),
    /// or cannot be read.
    pub non_finite: bool,
    /// The run failed before solving (no `solve.json`): the log's last line.
    pub failure: Option<String>,
}

impl StressCase {
    /// Completed, or stopped with a recorded reason and without NaN or panic.
    pub fn explained(&self) -> bool {
        !self.panicked
            && !self.non_finite
            && (self.record.completed || self.record.reason.is_some() || self.failure.is_some())
    }
}

/// Whether every value of every row of a `curve.csv` text is finite.
fn curve_all_finite(text: &str) -> bool {
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .all(|l| {
            l.split(',')
                .all(|v| v.trim().parse::<f64>().is_ok_and(f64::is_finite))
        })
}

impl StressCase {
    /// One case's record, its logs (`logs/<case>.mesh.log`, `.run.log`) and
    /// curve read back from a study's work dir.
    fn read(case: &crate::study::Case, work: &Path, logs: &Path) -> StressCase {
        let dir = work.join(&case.name);
        let record = RunRecord::read(&case.name, &dir);
        let log_text: String = ["mesh", "run"]
            .iter()
            .filter_map(|k| {
                std::fs::read_to_string(logs.join(format!("{}.{k}.log", case.name))).ok()
            })
            .collect::<Vec<_>>()
            .join("\n");
        let panicked = log_text.contains("panicked at");
        let non_finite = match std::fs::read_to_string(dir.join("curve.csv")) {
            Ok(t) => !curve_all_finite(&t),
            Err(_) => false,
        };
        let failure = (!dir.join("solve.json").is_file()).then(|| {
            log_text
                .lines()
                .rev()
                .find(|l| l.starts_with("error:"))
                .unwrap_or("no solve.json and no error in the log")
                .to_string()
        });
        let parameters = crate::post::parameters_label(&case.parameters);
        StressCase {
            name: case.name.clone(),
            parameters,
            record,
            panicked,
            non_finite,
            failure,
        }
    }
}

/// Checks every case of a study run by `ribbar study` in `work` and writes
/// the results table `out` (Markdown): case, parameters, completed, steps,
/// peak σ_mb, energy imbalance and check, NaN, panic, reason if stopped.
/// Damage monotonicity is not re-checked here: every law keeps D as the
/// maximum of its committed and trial values (laws' tests).
pub fn stress_report(
    study_file: &Path,
    work: &Path,
    out: &Path,
    command: &str,
) -> Result<Vec<StressCase>> {
    let study = Study::load(study_file)?;
    let logs = work.join(&study.name).join("logs");
    let mut cases = Vec::new();
    for case in &study.cases {
        cases.push(StressCase::read(case, work, &logs));
    }
    let n = cases.len();
    let completed = cases.iter().filter(|c| c.record.completed).count();
    let ended = |kind: &str| {
        cases
            .iter()
            .filter(|c| c.record.completed && c.record.ending.as_deref() == Some(kind))
            .count()
    };
    let (limit_loads, unloaded, brittle) = (
        ended("limit_load"),
        ended("unloaded"),
        ended("brittle_failure"),
    );
    let cracked = cases
        .iter()
        .filter(|c| c.record.cover_cracked().is_some())
        .count();
    let panics = cases.iter().filter(|c| c.panicked).count();
    let nans = cases.iter().filter(|c| c.non_finite).count();
    let unexplained = cases.iter().filter(|c| !c.explained()).count();
    let energy_fail = cases
        .iter()
        .filter(|c| c.record.energy_passed == Some(false))
        .count();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Numerical-stability stress sweep\n\n\
         Command: `{command}`\n\n\
         Study `{}` ({}): {n} cases; {completed} completed ({limit_loads} of them at the \
         bar's limit load, {brittle} at a brittle failure (the cube splits at its peak; \
         {cracked} of them with the cover cracked through), \
         {unloaded} unloaded: split through or pulled free; \
         docs/src/validation/solver.md, \"How a run ends\"), {} stopped with a reason, \
         {panics} panics, {nans} with a non-finite value in curve.csv, {unexplained} unexplained, \
         {energy_fail} failing the energy check (tolerance {} of W_ext on the converged steps).\n\n\
         Energy imbalance: max over the converged steps of |W_ext − W_int|/W_ext; dissipation \
         increment: min over the steps of ΔW_diss/W_ext (docs/src/validation/stress.md).\n",
        study.name,
        study_file.display(),
        n - completed,
        solve::energy::ENERGY_TOLERANCE,
    );
    let _ = writeln!(md, "| case | parameters | completed | ending | steps | final u (mm) | peak σ_mb (MPa) | energy imbalance | energy check | NaN/inf | panic | reason if stopped |");
    let _ = writeln!(md, "|---|---|---|---|---:|---:|---:|---:|---|---|---|---|");
    for c in &cases {
        let r = &c.record;
        let reason = r
            .reason
            .clone()
            .or_else(|| c.failure.clone())
            .unwrap_or_default();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            c.parameters,
            if r.completed { "yes" } else { "no" },
            match (r.completed, r.cover_cracked()) {
                (false, _) => "–".to_string(),
                (true, Some(n)) => format!(
                    "{} (cover cracked: {n} tets)",
                    r.ending.as_deref().unwrap_or("–")
                ),
                (true, None) => r.ending.as_deref().unwrap_or("–").to_string(),
            },
            r.steps.map_or("–".into(), |d| d.to_string()),
            fmt_opt(r.curve.last().map(|x| x.u_imposed), 1e3, 4),
            fmt_opt(r.peak, 1e-6, 3),
            fmt_rel(r.energy_imbalance),
            match r.energy_passed {
                Some(true) => "pass",
                Some(false) => "FAIL",
                None => "–",
            },
            if c.non_finite { "YES" } else { "no" },
            if c.panicked { "YES" } else { "no" },
            truncate(&reason.replace('|', "/"), 220),
        );
    }
    write_text(out, &md)?;
    Ok(cases)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Vec<Series> {
        mesh_series_plan(false).unwrap()
    }

    #[test]
    fn sizes_option_replaces_one_series_sizes() {
        let mut p = plan();
        apply_sizes(&mut p, &["r1=1.6, 1.2,1.0,0.8".into()]).unwrap();
        let r1 = p.iter().find(|s| s.label == "R1").unwrap();
        assert!(
            r1.extra
                .iter()
                .any(|a| a.starts_with("solver.concrete_integration=")),
            "the R1 series takes the study's integration: {:?}",
            r1.extra
        );
        assert_eq!(r1.sizes.len(), 4);
        assert!((r1.sizes[2] - 1.0e-3).abs() < 1e-15);
        let smooth = p.iter().find(|s| s.label == "smooth-80").unwrap();
        assert!((smooth.sizes[3] - 0.4e-3).abs() < 1e-15);
    }

    #[test]
    fn sizes_option_names_what_is_wrong() {
        let err = |o: &str| {
            apply_sizes(&mut plan(), &[o.to_string()])
                .unwrap_err()
                .to_string()
        };
        assert!(err("R1").contains("expected SERIES=MM"));
        assert!(err("R2=1,2,3").contains("no series `R2`"));
        assert!(err("R1=1.6,x,0.8").contains("`x` is not a size"));
        assert!(err("R1=1.6,-1,0.8").contains("must be positive"));
        assert!(err("R1=1.6,0.8").contains("at least 3"));
    }
}
