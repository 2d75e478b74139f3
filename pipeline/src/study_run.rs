//! Running a study: cases as child `ribbar` processes (a failing case cannot
//! take the others down), meshes first, then solves admitted under a memory
//! bound; then the study's table and plots from the cases' published files.
//! `--export snakemake` writes the same work as a Snakefile instead.

use crate::child::{CAUSE_PREFIX, ERROR_PREFIX};
use crate::cli::StudyArgs;
use crate::post::{self, ConvergenceStudy, CurveRow, GridResult, StudyCase};
use crate::progress::Printer;
use crate::study::{Case, Study, StudyKind};
use crate::study_outcome::{summary_line, CaseFailure, CaseOutcome};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::{Command, ExitCode, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};

use crate::estimate::estimated_solve_bytes;

fn case_args(study: &Study, case: &Case, work: &Path, command: &str) -> Vec<String> {
    let mut args = vec![
        command.to_string(),
        study.base.display().to_string(),
        "--work".into(),
        work.display().to_string(),
        "-q".into(),
    ];
    for o in &case.overrides {
        args.push("--set".into());
        args.push(o.clone());
    }
    args
}

fn run_child(exe: &Path, args: &[String], log: &Path) -> Result<bool> {
    let file = std::fs::File::create(log).with_context(|| format!("creating {}", log.display()))?;
    let status = Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(file.try_clone()?)
        .stderr(file)
        .status()
        .with_context(|| format!("starting {}", exe.display()))?;
    Ok(status.success())
}

/// The error a case's child reported last (the CLI ends a failed command
/// with `error: …`), so that a refused case says why in the study's own
/// output instead of only naming its log.
fn child_error(log: &Path) -> Option<String> {
    let text = std::fs::read_to_string(log).ok()?;
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().rposition(|l| l.starts_with(ERROR_PREFIX))?;
    let mut why = lines[at][ERROR_PREFIX.len()..].to_owned();
    for cause in lines[at + 1..]
        .iter()
        .map_while(|l| l.strip_prefix(CAUSE_PREFIX))
    {
        why.push_str(": ");
        why.push_str(cause);
    }
    Some(why)
}

/// Nodes of a case's mesh, from its published mesh.json.
fn case_dofs(work: &Path, case: &Case) -> Option<f64> {
    let path = work.join(&case.name).join("mesh.json");
    let text = geom::fsutil::read_capped(&path, geom::fsutil::MAX_RECORD_BYTES).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(3.0 * v.get("nodes")?.as_f64()?)
}

/// Runs `f` on every item with at most `jobs` at once and, when `cost` is
/// given, with the summed cost of running items under `budget` (one item
/// always runs, however large).
fn pool<T: Sync>(
    items: &[T],
    jobs: usize,
    cost: impl Fn(&T) -> f64 + Sync,
    budget: f64,
    f: impl Fn(&T) + Sync,
) {
    let next = AtomicUsize::new(0);
    let in_use = Mutex::new((0usize, 0.0f64));
    let freed = Condvar::new();
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(item) = items.get(i) else { break };
                let c = cost(item);
                {
                    let mut g = in_use.lock().unwrap_or_else(|e| e.into_inner());
                    while g.0 > 0 && g.1 + c > budget {
                        g = freed.wait(g).unwrap_or_else(|e| e.into_inner());
                    }
                    g.0 += 1;
                    g.1 += c;
                }
                f(item);
                let mut g = in_use.lock().unwrap_or_else(|e| e.into_inner());
                g.0 -= 1;
                g.1 -= c;
                freed.notify_all();
            });
        }
    });
}

/// What a study writes into `WORK/<study>/`, besides its cases' folders.
const STUDY_OUTPUTS: [&str; 11] = [
    "table.csv",
    "table.md",
    "bond_slip.png",
    "bond_slip.svg",
    "convergence.csv",
    "convergence.md",
    "curve_distances.csv",
    "error_vs_time.png",
    "error_vs_time.svg",
    "Snakefile",
    "logs",
];

/// The study file and its base spec must not be among what the study
/// writes (its own folder's outputs, the store).
fn refuse_inputs_among_outputs(study: &Study, args: &StudyArgs, out: &Path) -> Result<()> {
    let outputs: Vec<std::path::PathBuf> = STUDY_OUTPUTS.iter().map(|f| out.join(f)).collect();
    let store = [args.work.join(".store")];
    crate::inputs::refuse_input_among_outputs("the study file", &args.study, &store, &outputs)?;
    crate::inputs::refuse_input_among_outputs(
        "the study's base spec",
        &study.base,
        &store,
        &outputs,
    )
}

pub fn run(args: &StudyArgs, printer: &Printer) -> Result<ExitCode> {
    let study = Study::load(&args.study)?;
    let out = args.work.join(&study.name);
    refuse_inputs_among_outputs(&study, args, &out)?;
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    report_design(&study, &out, printer)?;
    if let Some(crate::cli::ExportFormat::Snakemake) = args.export {
        let dir = args
            .export_dir
            .clone()
            .unwrap_or_else(|| out.join("snakemake"));
        let ribbar = crate::child::self_exe()?;
        let ribbar = std::path::absolute(&ribbar).unwrap_or(ribbar);
        let done = crate::export::export_snakemake(&study, &args.study, &args.work, &ribbar, &dir)?;
        printer.line(&format!(
            "wrote the workflow of {} cases to {}; run it there with `snakemake --cores N`, \
             or `snakemake --executor slurm --profile profiles/slurm` on a Slurm cluster",
            done.cases,
            done.dir.display()
        ));
        return Ok(ExitCode::SUCCESS);
    }
    if args.collect {
        collect(&study, &args.work, &out, &[], printer)?;
        for case in &study.cases {
            let solve_json = args.work.join(&case.name).join("solve.json");
            if let Some(why) = crate::commands::incomplete_solve(&solve_json) {
                printer.line(&format!("[{}] stopped early: {why}", case.name));
            }
        }
        return Ok(ExitCode::SUCCESS);
    }
    let exe = crate::child::self_exe()?;
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).with_context(|| format!("creating {}", logs.display()))?;
    printer.line(&format!(
        "study {}: {} cases, {} at once",
        study.name,
        study.cases.len(),
        args.jobs
    ));

    let failed = Mutex::new(Vec::<(String, CaseFailure)>::new());
    let fail = |case: &Case, command: &str, log: &Path| {
        let failure = CaseFailure {
            command: command.to_string(),
            cause: child_error(log),
            log: log.to_path_buf(),
        };
        failed
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((case.name.clone(), failure));
    };
    // Meshes first: gmsh's memory is small, and the mesh sizes tell the
    // solves' memory.
    pool(
        &study.cases,
        args.jobs,
        |_| 0.0,
        f64::INFINITY,
        |case| {
            let log = logs.join(format!("{}.mesh.log", case.name));
            match run_child(&exe, &case_args(&study, case, &args.work, "mesh"), &log) {
                Ok(true) => printer.line(&format!("[{}] mesh ready", case.name)),
                _ => fail(case, "mesh", &log),
            }
        },
    );
    let meshed: Vec<&Case> = {
        let f = failed.lock().unwrap_or_else(|e| e.into_inner());
        study
            .cases
            .iter()
            .filter(|c| !f.iter().any(|(n, _)| *n == c.name))
            .collect()
    };
    let budget = args.memory_gib * (1u64 << 30) as f64;
    pool(
        &meshed,
        args.jobs,
        |case| {
            case_dofs(&args.work, case)
                .map(estimated_solve_bytes)
                .unwrap_or(0.0)
        },
        budget,
        |case| {
            let log = logs.join(format!("{}.run.log", case.name));
            match run_child(&exe, &case_args(&study, case, &args.work, "run"), &log) {
                Ok(true) => printer.line(&format!("[{}] done", case.name)),
                _ => fail(case, "run", &log),
            }
        },
    );
    let failed = failed.into_inner().unwrap_or_else(|e| e.into_inner());
    for (name, failure) in &failed {
        printer.line(&format!("[{name}] {}", failure.describe()));
    }
    let outcomes = collect(&study, &args.work, &out, &failed, printer)?;
    let unfinished = outcomes
        .iter()
        .filter(|o| matches!(o, CaseOutcome::Stopped { .. } | CaseOutcome::Failed { .. }))
        .count();
    if unfinished == 0 {
        Ok(ExitCode::SUCCESS)
    } else {
        bail!(
            "{unfinished} of {} cases failed or stopped early (their logs are named above and \
             in the table); the others' results are kept",
            study.cases.len()
        )
    }
}

/// Tables and plots of the study: a row for every case (`failures`: the
/// cases whose child failed), with how it ended, the results of each case
/// that has them; returns each case's outcome, in the study's order.
pub fn collect(
    study: &Study,
    work: &Path,
    out: &Path,
    failures: &[(String, CaseFailure)],
    printer: &Printer,
) -> Result<Vec<CaseOutcome>> {
    let mut curves: Vec<(String, Vec<CurveRow>)> = Vec::new();
    let mut cases: Vec<StudyCase> = Vec::new();
    let mut grids: Vec<(f64, serde_json::Value)> = Vec::new();
    let mut outcomes = Vec::new();
    for case in &study.cases {
        let dir = work.join(&case.name);
        let failure = failures
            .iter()
            .find(|(n, _)| *n == case.name)
            .map(|(_, f)| f);
        let outcome = CaseOutcome::of_case(work, &case.name, failure);
        let results = outcome.has_results().then(|| {
            let read = |name: &str| {
                geom::fsutil::read_capped(&dir.join(name), geom::fsutil::MAX_TABLE_BYTES)
            };
            (
                read("curve.csv").map(|text| post::parse_curve_csv(&text, &dir.join("curve.csv"))),
                read("summary.json"),
            )
        });
        let Some((Ok(Ok(rows)), Ok(summary))) = results else {
            let mut row =
                StudyCase::from_summary(&case.name, &case.parameters, &serde_json::Value::Null);
            outcome.prepend_to(&mut row);
            cases.push(row);
            outcomes.push(outcome);
            continue;
        };
        let summary: serde_json::Value = serde_json::from_str(&summary)
            .with_context(|| format!("{}: not valid JSON", dir.join("summary.json").display()))?;
        let label = post::parameters_label(&case.parameters);
        let mut row = StudyCase::from_summary(&case.name, &case.parameters, &summary);
        outcome.prepend_to(&mut row);
        cases.push(row);
        outcomes.push(outcome);
        if study.kind == StudyKind::Convergence {
            let (key, value) = &case.parameters[0];
            let h = crate::study::size_of(key, value).map_err(anyhow::Error::msg)?;
            grids.push((h, summary.clone()));
        }
        curves.push((label, rows));
    }
    post::write_study_tables(&cases, &out.join("table.csv"), &out.join("table.md"))?;
    printer.line(&summary_line(&study.name, &outcomes));
    if curves.is_empty() {
        let first = outcomes
            .iter()
            .find_map(|o| match o {
                CaseOutcome::Failed { stage, cause, log } => Some(format!(
                    "the first failed in {stage}: {cause} (log {})",
                    log.display()
                )),
                _ => None,
            })
            .unwrap_or_default();
        bail!(
            "no case of study {} has results; {first}; every case's row is in {}",
            study.name,
            out.join("table.csv").display()
        );
    }
    let refs: Vec<(&str, &[CurveRow])> = curves
        .iter()
        .map(|(l, r)| (l.as_str(), r.as_slice()))
        .collect();
    post::bond_slip_plot(
        &refs,
        &out.join("bond_slip.png"),
        &out.join("bond_slip.svg"),
    )?;
    if study.kind == StudyKind::Convergence {
        // Every case with results has its grid, in the same order.
        let grid_curves: Vec<(f64, &[CurveRow])> = grids
            .iter()
            .zip(&curves)
            .map(|((h, _), (_, rows))| (*h, rows.as_slice()))
            .collect();
        for line in convergence(&grids, &grid_curves, out)? {
            printer.line(&line);
        }
    }
    crate::study_results::write(study, work, out, printer)?;
    printer.line(&format!("study tables and plots: {}", out.display()));
    Ok(outcomes)
}

/// A sampled or sensitivity study's design, before its cases run: how it
/// was drawn, and each draw outside the design bounds with the reason and
/// what replaced it (designs.csv and rejected.csv say the same).
fn report_design(study: &Study, out: &Path, printer: &Printer) -> Result<()> {
    let Some(design) = &study.design else {
        return Ok(());
    };
    crate::study_results::write_design(study, design, out)?;
    printer.line(&format!("design: {}", design.plan.describe()));
    for r in &design.points.rejected {
        let values: Vec<String> = design
            .axes
            .iter()
            .zip(&r.values)
            .map(|(a, v)| format!("{} = {}", a.key, a.show(v)))
            .collect();
        printer.line(&format!(
            "design: {} ({}) is outside the design bounds and was replaced by the next draw: {}",
            r.draw,
            values.join(", "),
            r.reason
        ));
    }
    Ok(())
}

/// The quantities a convergence study estimates, as (name, pointer into
/// summary.json). The largest σ_mb sits at the adhesion peak on some grids
/// and at the end of the curve on others, so the first (adhesion) peak is
/// estimated on its own.
const CONVERGENCE_QUANTITIES: [(&str, &str); 5] = [
    ("first_peak_bond_stress", "/curve/first_peak_bond_stress"),
    ("fed_at_first_peak", "/curve/fed_at_first_peak"),
    ("peak_bond_stress", "/curve/peak_bond_stress"),
    ("fed_at_peak", "/curve/fed_at_peak"),
    ("energy", "/curve/energy"),
];

/// The quantities of [`CONVERGENCE_QUANTITIES`] that may jump from one
/// point of the curve to another between grids.
const JUMPING_QUANTITIES: [&str; 2] = ["peak_bond_stress", "fed_at_peak"];

/// convergence.{csv,md}, curve_distances.csv and the error-against-time
/// plot of a convergence study's grids (size, summary.json) and curves;
/// returns a line per plotted quantity with the finest grid's error.
fn convergence(
    grids: &[(f64, serde_json::Value)],
    curves: &[(f64, &[CurveRow])],
    out: &Path,
) -> Result<Vec<String>> {
    let quantity = |pointer: &str| -> Vec<GridResult> {
        grids
            .iter()
            .filter_map(|(h, s)| {
                Some(GridResult {
                    h: *h,
                    value: s.pointer(pointer)?.as_f64()?,
                    dofs: s.pointer("/solver/summary/dofs").and_then(|v| v.as_u64()),
                    wall_time: s
                        .pointer("/solver/summary/wall_time_s/total")
                        .and_then(|v| v.as_f64()),
                })
            })
            .collect()
    };
    let studies: Vec<ConvergenceStudy> = CONVERGENCE_QUANTITIES
        .iter()
        .filter_map(|(name, p)| post::convergence_study(name, &quantity(p)).ok())
        .collect();
    post::convergence_table(&studies).write_csv(&out.join("convergence.csv"))?;
    let distances = curve_distance_table(curves);
    distances.write_csv(&out.join("curve_distances.csv"))?;
    let markdown = format!(
        "{}\n## Curves\n\nRelative L2 distance of σ_mb along FED from each grid's curve \
         to the next finer one's, over their common FED range.\n\n{}",
        post::convergence_markdown(&studies),
        distances.to_markdown()
    );
    crate::store::write_atomic(&out.join("convergence.md"), markdown.as_bytes())?;
    // The largest σ_mb and its FED sit at the adhesion peak on some grids
    // and at the end of the curve on others: their "errors" compare
    // different points, so they stay in the tables and out of the plot.
    let plotted: Vec<&ConvergenceStudy> = studies
        .iter()
        .filter(|s| !JUMPING_QUANTITIES.contains(&s.quantity.as_str()))
        .collect();
    let series: Vec<_> = plotted
        .iter()
        .map(|s| post::ErrorTimeSeries::from_study(s))
        .chain(
            plotted
                .iter()
                .map(|s| post::ErrorTimeSeries::uncertainty_from_study(s)),
        )
        .filter(|s| !s.points.is_empty())
        .collect();
    // Three grids whose triplet diverged have no error to plot; the
    // tables say why.
    if !series.is_empty() {
        post::error_vs_time_plot(
            &series,
            &out.join("error_vs_time.png"),
            &out.join("error_vs_time.svg"),
        )?;
    }
    Ok(plotted.iter().map(|s| finest_error_line(s)).collect())
}

/// "quantity on h = … mm: GCI …, U …" for the finest grid of a study,
/// saying what is missing where an estimate is.
fn finest_error_line(study: &ConvergenceStudy) -> String {
    let finest = &study.rows()[0];
    let percent = |x: Option<f64>| match x {
        None => "none".to_string(),
        Some(x) if 100.0 * x >= 0.01 => format!("{:.3} %", 100.0 * x),
        Some(x) => format!("{:.1e} %", 100.0 * x),
    };
    let celik = match finest.gci {
        Some(_) => format!("GCI {}", percent(finest.gci)),
        None => format!("no GCI ({})", study.finest().kind.as_str()),
    };
    let fit = study.least_squares.as_ref().map_or(String::new(), |e| {
        format!(" ({}, F_s {})", e.fit.as_str(), e.safety_factor)
    });
    let h_mm = format!("{:.4}", finest.h * 1e3);
    format!(
        "convergence: {} on h = {} mm: {celik}; uncertainty U {}{fit}",
        study.quantity,
        h_mm.trim_end_matches('0').trim_end_matches('.'),
        percent(finest.uncertainty),
    )
}

/// For each grid but the finest: its size, the next finer one's (mm) and
/// the relative L2 distance of σ_mb along FED from its curve to that
/// grid's, over their common FED range: for a step-size series, the curve
/// error of a step against half of it. Where the distance is not defined
/// (a curve whose free end snaps back, curves with no common range) the
/// cell is empty and `why_none` says why.
fn curve_distance_table(curves: &[(f64, &[CurveRow])]) -> post::Table {
    let mut sorted = curves.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let rows = sorted
        .windows(2)
        .map(|pair| {
            let ((fine_h, fine), (h, coarse)) = (pair[0], pair[1]);
            let (distance, why_none) =
                match post::curve_distance(coarse, fine, post::CurveAxis::Fed, None) {
                    Ok(d) => (post::Cell::Num(d), post::Cell::Empty),
                    Err(e) => (post::Cell::Empty, post::Cell::Text(e.to_string())),
                };
            vec![
                post::Cell::Num(h * 1e3),
                post::Cell::Num(fine_h * 1e3),
                distance,
                why_none,
            ]
        })
        .collect();
    post::Table {
        columns: ["h_mm", "finer_h_mm", "relative_l2_along_fed", "why_none"]
            .map(String::from)
            .to_vec(),
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every quantity of a summary gets its rows, the first peak among
    /// them; a convergent series gets its extrapolation and error plot.
    #[test]
    fn convergence_tables_estimate_the_first_peak_and_the_energy() {
        let out = std::env::temp_dir().join(format!("ribbar-conv-{}", std::process::id()));
        std::fs::create_dir_all(&out).unwrap();
        let grids: Vec<(f64, serde_json::Value)> = [4e-4, 2e-4, 1e-4]
            .iter()
            .map(|&h: &f64| {
                let e = 1.0 + h * h * 1e6;
                let curve = serde_json::json!({
                    "first_peak_bond_stress": 5.7e6 * e,
                    "fed_at_first_peak": 3e-5 * e,
                    "peak_bond_stress": 6.0e6 * e,
                    "fed_at_peak": 1e-3 * e,
                    "energy": 3800.0 * e,
                });
                let solver =
                    serde_json::json!({"summary": {"dofs": 1000, "wall_time_s": {"total": 1.0}}});
                (h, serde_json::json!({"curve": curve, "solver": solver}))
            })
            .collect();
        let rows: Vec<(f64, Vec<CurveRow>)> = grids
            .iter()
            .map(|(h, _)| (*h, proportional_curve(*h)))
            .collect();
        let curves: Vec<(f64, &[CurveRow])> =
            rows.iter().map(|(h, r)| (*h, r.as_slice())).collect();
        convergence(&grids, &curves, &out).unwrap();
        let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
        for (name, _) in CONVERGENCE_QUANTITIES {
            assert!(
                csv.lines().any(|l| l.starts_with(&format!("{name},"))),
                "{name}: {csv}"
            );
        }
        let md = std::fs::read_to_string(out.join("convergence.md")).unwrap();
        let first_peak = md
            .lines()
            .find(|l| l.starts_with("| first_peak_bond_stress |") && l.contains("monotonic"))
            .unwrap_or_else(|| panic!("{md}"));
        // Second order in h, extrapolated to 5.7 MPa.
        let cells: Vec<f64> = first_peak
            .split('|')
            .filter_map(|c| c.trim().parse().ok())
            .collect();
        assert!((cells[0] - 2.0).abs() < 1e-3, "{first_peak}");
        assert!((cells[1] / 5.7e6 - 1.0).abs() < 1e-3, "{first_peak}");
        assert!(out.join("error_vs_time.png").is_file());
        // The curve distances go with the tables.
        assert!(md.contains("## Curves"), "{md}");
        assert!(out.join("curve_distances.csv").is_file());
        std::fs::remove_dir_all(&out).ok();
    }

    /// σ_mb proportional to the FED up to 1 mm, with the slope 1e9 (1 + 1000 h).
    fn proportional_curve(h: f64) -> Vec<CurveRow> {
        (1..=10)
            .map(|i| {
                let fed = 1e-4 * i as f64;
                CurveRow::new(i, 2.0 * fed, 0.0, fed, 1e9 * (1.0 + 1000.0 * h) * fed, 2)
            })
            .collect()
    }

    /// Each grid's curve is compared with the next finer one's: σ_mb
    /// proportional to the FED with a slope 1 + 1000 h gives distances
    /// |Δslope| / slope_fine, whatever order the cases came in.
    #[test]
    fn curve_distances_compare_each_grid_with_the_next_finer() {
        let slope = |h: f64| 1e9 * (1.0 + 1000.0 * h);
        let rows: Vec<(f64, Vec<CurveRow>)> = [2e-4, 4e-4, 1e-4]
            .iter()
            .map(|&h| (h, proportional_curve(h)))
            .collect();
        let curves: Vec<(f64, &[CurveRow])> =
            rows.iter().map(|(h, r)| (*h, r.as_slice())).collect();
        let table = curve_distance_table(&curves);
        assert_eq!(table.rows.len(), 2, "{}", table.to_markdown());
        for (row, (h, fine)) in table.rows.iter().zip([(2e-4, 1e-4), (4e-4, 2e-4)]) {
            let [post::Cell::Num(row_h), post::Cell::Num(row_fine), post::Cell::Num(d), post::Cell::Empty] =
                row.as_slice()
            else {
                panic!("{row:?}");
            };
            assert!((row_h - h * 1e3).abs() < 1e-12 && (row_fine - fine * 1e3).abs() < 1e-12);
            let expected = (slope(h) - slope(fine)) / slope(fine);
            assert!((d / expected - 1.0).abs() < 1e-3, "{row:?}");
        }
    }

    /// A grid whose free end snaps back has no distance along FED; its row
    /// says why instead of leaving the cell blank.
    #[test]
    fn a_curve_distance_that_is_not_defined_says_why() {
        let fine = proportional_curve(1e-4);
        let mut coarse = proportional_curve(2e-4);
        let last = coarse.len() - 1;
        coarse[last].fed = 0.5 * coarse[last - 1].fed;
        let curves: Vec<(f64, &[CurveRow])> = vec![(1e-4, &fine), (2e-4, &coarse)];
        let table = curve_distance_table(&curves);
        let [_, _, post::Cell::Empty, post::Cell::Text(why)] = table.rows[0].as_slice() else {
            panic!("{:?}", table.rows[0]);
        };
        assert!(why.contains("goes back") && why.contains("test"), "{why}");
    }
}
