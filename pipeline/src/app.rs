//! The `ribbar` command line as a function: the binary and the Python
//! package's entry point both run it. Library crates return typed errors;
//! here they are reported with their chain and a non-zero exit.

use crate::child::{CAUSE_PREFIX, ERROR_PREFIX};
use crate::cli::{Cli, Command, SceneArgs};
use crate::progress::{Printer, Verbosity};
use crate::scene::Scene;
use crate::stage::{self, Keys, Stage, StageStatus};
use crate::store::Store;
use anyhow::{Context, Result};
use clap::Parser;
use std::ffi::OsString;
use std::io::Write;
use std::process::ExitCode;

/// An error as the command line reports it: `error: ` and the message,
/// then one `  caused by: ` line per cause that the message above it does
/// not already end with.
pub fn error_report(err: &anyhow::Error) -> String {
    let lines = crate::child::error_lines(err);
    let mut text = format!("{ERROR_PREFIX}{}", lines[0]);
    for cause in &lines[1..] {
        text.push_str(&format!("\n{CAUSE_PREFIX}{cause}"));
    }
    text
}

/// Runs the command line `args` (the program name first) and returns the
/// process exit status: 0 on success, 1 on an error (reported on standard
/// error with its chain), clap's own status for usage errors and `--help`.
pub fn main_with_args<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(err) => {
            let _ = err.print();
            return u8::try_from(err.exit_code()).unwrap_or(2);
        }
    };
    let verbosity = if cli.quiet {
        Verbosity::Quiet
    } else if cli.verbose {
        Verbosity::Verbose
    } else {
        Verbosity::Normal
    };
    let printer = Printer::new(verbosity);
    // The command runs on a worker of rayon's pool rather than on the
    // calling thread. Every parallel loop called from outside the pool
    // hands its work to the workers and parks the caller until they
    // finish; the solve makes thousands of such calls per second (each
    // Krylov iteration, each assembly), and the hand-offs weighed on it
    // (docs/src/validation/performance.md, "r1-coarse end to end"). From a worker the
    // same loops split on its own deque, with the same results.
    let outcome = rayon::scope(|_| dispatch(cli.command, &printer));
    match outcome {
        Ok(code) if code == ExitCode::SUCCESS => 0,
        Ok(_) => 1,
        // A reader that closed the pipe (`ribbar status ... | head -1`)
        // wanted no more: stop quietly, as other command-line tools do.
        Err(err) if is_broken_pipe(&err) => 0,
        Err(err) => {
            printer.finish();
            eprintln!("{}", error_report(&err));
            1
        }
    }
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn dispatch(command: Command, printer: &Printer) -> Result<ExitCode> {
    match command {
        Command::Geometry(a) => run_stages(&a, Stage::Geometry.up_to(), false, printer),
        Command::Mesh(a) => run_stages(&a, Stage::Mesh.up_to(), false, printer),
        Command::Solve(a) => run_stages(&a.scene, Stage::Solve.up_to(), a.allow_stopped, printer),
        Command::Post(a) | Command::Run(a) => {
            run_stages(&a.scene, &Stage::ALL, a.allow_stopped, printer)
        }
        Command::Status(a) => status(&a),
        Command::Estimate(a) => crate::commands::estimate(&a),
        Command::Clean(a) => crate::commands::clean(&a, printer),
        Command::Verify(a) => crate::verify::run(&a, printer),
        Command::Material(a) => crate::commands::material(&a),
        Command::Study(a) => crate::study_run::run(&a, printer),
        Command::Bench(a) => crate::bench::run(&a, printer),
        Command::Compare(a) => crate::commands::compare(&a),
        Command::Schema(a) => crate::commands::schema(&a),
    }
}

/// Runs `stages` of the scene; a solve that stopped early is an error
/// unless `allow_stopped`, where it is said and the exit is 0.
fn run_stages(
    args: &SceneArgs,
    stages: &[Stage],
    allow_stopped: bool,
    printer: &Printer,
) -> Result<ExitCode> {
    let scene = Scene::load(&args.spec, &args.overrides)?;
    refuse_spec_among_outputs(args, &scene)?;
    match crate::commands::run_scene_stages(&scene, &args.work, stages, printer)? {
        None => {}
        Some(stopped) if allow_stopped => {
            // Said even under -q: the exit status no longer tells.
            eprintln!("stopped: {stopped} (exit 0: --allow-stopped)");
        }
        Some(stopped) => anyhow::bail!(stopped),
    }
    Ok(ExitCode::SUCCESS)
}

/// A spec inside the store, or at the place of one of the files its run
/// publishes, would be overwritten or removed by the run.
fn refuse_spec_among_outputs(args: &SceneArgs, scene: &Scene) -> Result<()> {
    let store = Store::new(&args.work);
    let dir = store.scene_dir(&scene.name);
    let published: Vec<std::path::PathBuf> = Stage::ALL
        .iter()
        .flat_map(|s| s.published_files().iter().map(|f| dir.join(f)))
        .chain([dir.join(crate::store::RECORD_FILE)])
        .collect();
    crate::inputs::refuse_input_among_outputs(
        "the spec",
        &args.spec,
        &[store.work.join(".store")],
        &published,
    )
}

fn status(args: &SceneArgs) -> Result<ExitCode> {
    let scene = Scene::load(&args.spec, &args.overrides)?;
    let gmsh = geom::gmsh::Gmsh::locate().context("status needs gmsh's version for the keys")?;
    let keys = Keys::of(&scene, gmsh.version());
    let store = Store::new(&args.work);
    let mut out = std::io::stdout().lock();
    for warning in crate::plausibility::warnings(&scene) {
        writeln!(out, "warning: {warning}")?;
    }
    let mut all_done = true;
    for (stage, st) in stage::status(&store, &scene, &keys)? {
        all_done &= st == StageStatus::UpToDate;
        writeln!(out, "{:<9} {}", stage, status_text(&st))?;
    }
    if all_done {
        writeln!(out, "every stage is up to date")?;
    }
    for line in stage::folder_report(&store, &scene, &keys)? {
        writeln!(out, "results   {line}")?;
    }
    Ok(ExitCode::SUCCESS)
}

fn status_text(st: &StageStatus) -> String {
    match st {
        StageStatus::UpToDate => "up to date".to_string(),
        StageStatus::Missing => "missing".to_string(),
        StageStatus::Interrupted => "interrupted: `ribbar run` resumes it".to_string(),
        StageStatus::Damaged(why) => {
            format!("damaged: {why}; `ribbar run` moves it to the quarantine and computes it again")
        }
        StageStatus::Stale(changed) if changed.is_empty() => "stale (upstream changed)".to_string(),
        StageStatus::Stale(changed) => format!(
            "stale: changed {}",
            changed
                .iter()
                .map(|k| if Stage::from_name(k).is_some() {
                    format!("{k} (upstream stage)")
                } else {
                    k.clone()
                })
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}
