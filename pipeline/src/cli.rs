//! Command-line surface of `ribbar` (clap derive types only; validation of
//! what they carry happens where the values are used).

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "ribbar",
    version,
    about = "Rib-scale steel–concrete bond: parametric pull-out specimens, gmsh meshing, \
             interface elements, nonlinear solve, bond stress–slip curves",
    propagate_version = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Print nothing but errors.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Print more detail (per-iteration residuals, timings).
    #[arg(short, long, global = true)]
    pub verbose: bool,
}

/// Options shared by every stage command.
#[derive(Debug, Args, Clone)]
pub struct SceneArgs {
    /// Scene spec (YAML).
    pub spec: PathBuf,
    /// Work directory holding the artifact store and `<scene>/` results.
    #[arg(long, default_value = "ribbar-work")]
    pub work: PathBuf,
    /// Override a spec key, e.g. --set bar.ribs.angle="60 deg" (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
}

/// Options of the commands that run the solve.
#[derive(Debug, Args, Clone)]
pub struct RunArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Exit 0 when the solve stops before the end of the loading (a stall,
    /// the step limit): its converged steps are published as its result and
    /// solve.json records `"completed": false` and why. For workflow
    /// engines, which would otherwise delete the outputs of a failed job.
    #[arg(long)]
    pub allow_stopped: bool,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write the bar and specimen solid's OpenCASCADE script and its measures: specimen.geo and geometry.json.
    Geometry(SceneArgs),
    /// Build the solid in gmsh, check it against the geometry, mesh it and build the model with interface elements.
    Mesh(SceneArgs),
    /// Solve the pull-out: curve.csv, solve summary, fields.
    Solve(RunArgs),
    /// Plots, summary.json and fields from the solve.
    Post(RunArgs),
    /// Run every stale stage in order.
    Run(RunArgs),
    /// Show for each stage: up to date, stale (and which keys changed), or missing.
    Status(SceneArgs),
    /// What the scene's solve will take (memory, run time), from its mesh: JSON.
    Estimate(EstimateArgs),
    /// Remove what ribbar made of the scene's results and its in-progress stages (and, with --all, the whole store).
    Clean(CleanArgs),
    /// Check every stored result against its recorded digests (and a scene's results folder); move damaged ones aside.
    Verify(VerifyArgs),
    /// Drive one material point along a loading path (like MFront's mtest).
    Material(MaterialArgs),
    /// Run a study: a base spec with lists of values, or a convergence series over a mesh or step size.
    Study(StudyArgs),
    /// Benchmarks: run time against error, written as Markdown tables and plots.
    Bench(BenchArgs),
    /// Distance between two runs' σ_mb curves (relative L2) and their first peaks.
    Compare(CompareArgs),
    /// Print the JSON Schema of scene or study files (for editors and validators).
    Schema(SchemaArgs),
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum SchemaKind {
    /// A scene file (`ribbar run SCENE`).
    Scene,
    /// A study file (`ribbar study STUDY`).
    Study,
}

#[derive(Debug, Args)]
pub struct SchemaArgs {
    /// Which file's schema.
    #[arg(value_enum)]
    pub kind: SchemaKind,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum BenchKind {
    /// Linear-elastic perfect-bond pull-out: ribbar's linear solvers against CalculiX.
    Linear,
    /// Mesh series (h_interface 1.6 → 0.4 mm) on smooth-80 and R1 with GCI.
    MeshSeries,
    /// Solver settings on R1 at a fixed mesh against a small-step reference run.
    SolverSettings,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Which benchmark.
    #[arg(value_enum)]
    pub kind: BenchKind,
    /// Work directory for the benchmark's runs.
    #[arg(long, default_value = "ribbar-work")]
    pub work: PathBuf,
    /// Where the Markdown table and plots are written.
    #[arg(long, default_value = "docs/src/validation/bench")]
    pub out: PathBuf,
    /// Override a spec key of the benchmark's scenes (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
    /// Small scenes and coarse meshes (seconds; for tests and smoke runs).
    #[arg(long)]
    pub quick: bool,
    /// mesh-series: interface sizes in mm of one series, e.g.
    /// `--sizes R1=1.6,1.2,1.0,0.8` (repeatable; the other series keep
    /// 1.6, 1.2, 0.8, 0.4).
    #[arg(long = "sizes", value_name = "SERIES=MM,MM,...")]
    pub sizes: Vec<String>,
}

#[derive(Debug, Args)]
pub struct EstimateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Write the JSON to this file (atomically) instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct CleanArgs {
    /// Scene spec whose results are removed.
    pub spec: Option<PathBuf>,
    /// Work directory holding the artifact store and `<scene>/` results.
    #[arg(long, default_value = "ribbar-work")]
    pub work: PathBuf,
    /// Override a spec key, as for the stage commands (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
    /// Remove the whole work directory's store as well.
    #[arg(long)]
    pub all: bool,
}

#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Scene spec: check only its stages and results folder (default: the whole store).
    pub spec: Option<PathBuf>,
    #[arg(long, default_value = "ribbar-work")]
    pub work: PathBuf,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The run compared: its curve.csv (or the scene directory holding it).
    pub test: PathBuf,
    /// The reference run: its curve.csv (or the scene directory holding it).
    pub reference: PathBuf,
    /// Abscissa of the comparison: free-end displacement or imposed displacement.
    #[arg(long, value_enum, default_value = "fed")]
    pub along: CompareAxis,
    /// Compare curves that end far apart (one under 90 % of the other's
    /// range) over their common range instead of refusing them.
    #[arg(long)]
    pub common_range: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum CompareAxis {
    /// Free-end displacement (the plotted axis).
    Fed,
    /// Imposed displacement of the loaded end.
    U,
}

#[derive(Debug, Args)]
pub struct MaterialArgs {
    /// Material-point test file (YAML).
    pub test: PathBuf,
    /// Output CSV (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum ExportFormat {
    /// A Snakefile whose rules call the stage commands (`snakemake -s WORK/<study>/Snakefile`).
    Snakemake,
}

#[derive(Debug, Args)]
pub struct StudyArgs {
    /// Study file (YAML).
    pub study: PathBuf,
    /// Work directory holding the artifact store, the cases' and the study's results.
    #[arg(long, default_value = "ribbar-work")]
    pub work: PathBuf,
    /// Cases run at once.
    #[arg(long, short = 'j', default_value_t = 1)]
    pub jobs: usize,
    /// Memory bound for concurrently running cases, GiB.
    #[arg(long, default_value_t = 16.0)]
    pub memory_gib: f64,
    /// Write a workflow for an external engine instead of running.
    #[arg(long, value_enum)]
    pub export: Option<ExportFormat>,
    /// Where --export writes the workflow (default: WORK/<study>/snakemake).
    #[arg(long, value_name = "DIR", requires = "export")]
    pub export_dir: Option<PathBuf>,
    /// Run no case: only tabulate and plot the cases' published results
    /// (what an exported workflow's last step does).
    #[arg(long, conflicts_with = "export")]
    pub collect: bool,
}
