//! The `ribbar` command line. Library crates return typed errors; here they
//! are reported with their chain and a non-zero exit.

use anyhow::{Context, Result};
use clap::Parser;
use pipeline::cli::{Cli, Command, SceneArgs};
use pipeline::progress::{Printer, Verbosity};
use pipeline::scene::Scene;
use pipeline::stage::{self, Keys, Stage, StageStatus};
use pipeline::store::Store;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let verbosity = if cli.quiet {
        Verbosity::Quiet
    } else if cli.verbose {
        Verbosity::Verbose
    } else {
        Verbosity::Normal
    };
    let printer = Printer::new(verbosity);
    match dispatch(cli.command, &printer) {
        Ok(code) => code,
        Err(err) => {
            printer.finish();
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}

fn dispatch(command: Command, printer: &Printer) -> Result<ExitCode> {
    match command {
        Command::Geometry(a) => run_stages(&a, Stage::Geometry.up_to(), printer),
        Command::Mesh(a) => run_stages(&a, Stage::Mesh.up_to(), printer),
        Command::Solve(a) => run_stages(&a, Stage::Solve.up_to(), printer),
        Command::Post(a) | Command::Run(a) => run_stages(&a, &Stage::ALL, printer),
        Command::Status(a) => status(&a),
        Command::Clean(a) => pipeline::commands::clean(&a, printer),
        Command::Material(a) => pipeline::commands::material(&a),
        Command::Study(a) => pipeline::study_run::run(&a, printer),
        Command::Bench(a) => pipeline::bench::run(&a, printer),
    }
}

fn run_stages(args: &SceneArgs, stages: &[Stage], printer: &Printer) -> Result<ExitCode> {
    let scene = Scene::load(&args.spec, &args.overrides)?;
    pipeline::commands::run_scene(&scene, &args.work, stages, printer)?;
    Ok(ExitCode::SUCCESS)
}

fn status(args: &SceneArgs) -> Result<ExitCode> {
    let scene = Scene::load(&args.spec, &args.overrides)?;
    let gmsh = geom::gmsh::Gmsh::locate().context("status needs gmsh's version for the keys")?;
    let keys = Keys::of(&scene, gmsh.version());
    let store = Store::new(&args.work);
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
        println!("{:<9} {}", stage, text);
    }
    if all_done {
        println!("every stage is up to date");
    }
    Ok(ExitCode::SUCCESS)
}
