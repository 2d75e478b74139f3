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
    let mut text = format!("{ERROR_PREFIX}{err}");
    let mut previous = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        // Errors that print their source as part of their own message
        // (`{path}: {source}`) would otherwise say it twice.
        if !previous.ends_with(&cause) {
            text.push_str(&format!("\n{CAUSE_PREFIX}{cause}"));
        }
        previous = cause;
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

fn status(args: &SceneArgs) -> Result<ExitCode> {
    let scene = Scene::load(&args.spec, &args.overrides)?;
    let gmsh = geom::gmsh::Gmsh::locate().context("status needs gmsh's version for the keys")?;
    let keys = Keys::of(&scene, gmsh.version());
    let store = Store::new(&args.work);
    let mut out = std::io::stdout().lock();
    let mut all_done = true;
    for (stage, st) in stage::status(&store, &scene, &keys)? {
        let text = match &st {
            StageStatus::UpToDate => "up to date".to_string(),
            StageStatus::Missing => "missing".to_string(),
            StageStatus::Interrupted => "interrupted: `ribbar run` resumes it".to_string(),
            StageStatus::Stale(changed) if changed.is_empty() => {
                "stale (upstream changed)".to_string()
            }
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
        };
        all_done &= st == StageStatus::UpToDate;
        writeln!(out, "{:<9} {}", stage, text)?;
    }
    if all_done {
        writeln!(out, "every stage is up to date")?;
    }
    Ok(ExitCode::SUCCESS)
}
