//! A pull-out run on a meshed model, for measuring the nonlinear solver:
//!
//! ```text
//! cargo bench -p solve --bench pullout_run -- SCENE.yaml MODEL.bin [key=value ...]
//! ```
//!
//! `SCENE.yaml` gives the `materials`, `loading` and `solver` sections (a
//! scene file of `specs/`), `MODEL.bin` the mesh stage's model; each
//! `key=value` overrides a `solver` key (e.g. `linear_solver=cholesky`,
//! `tangent=secant`) or, as `loading.key=value`, a `loading` key;
//! `bench.save_at=N bench.checkpoint=PATH` saves the state after step N
//! there, `bench.checkpoint=PATH` alone resumes from it, `bench.resume=PATH`
//! resumes from PATH in either case. Prints
//! every converged step, every cut-back, and the summary with the phase
//! times.

use mesh::Model;
use solve::nonlinear::{Checkpoint, CommittedView, Cutback, Observer, SolveError, StepReport};
use solve::problems::pullout::solve_pullout;
use solve::spec::materials::NonAdhesive;
use solve::spec::materials::RawMaterials;
use solve::spec::solver::{RawLoading, RawSolver};

/// The key the benchmark saves its checkpoints with and resumes them by.
const BENCH_KEY: &str = "pullout-run-bench";

/// Prints each step; the GMRES iterations and factorisations of a step come
/// from the running summary (read through a checkpoint, a few ms per step).
#[derive(Default)]
struct Print {
    krylov: usize,
    factorisations: usize,
    /// Save the checkpoint of this step to this file.
    save: Option<(usize, std::path::PathBuf)>,
}
impl Observer for Print {
    fn step_converged(&mut self, r: &StepReport, v: &CommittedView<'_>) {
        let w = r.times;
        let cp = (v.checkpoint)();
        if let Some((n, path)) = &self.save {
            if *n == r.row.step {
                cp.save(path, BENCH_KEY).expect("checkpoint");
            }
        }
        let s = cp.state.summary;
        let (kr, fa) = (
            s.krylov_iterations - self.krylov,
            s.factorisations - self.factorisations,
        );
        (self.krylov, self.factorisations) = (s.krylov_iterations, s.factorisations);
        println!(
            "step {:>4} u {:.4} mm FED {:.4} mm σ_mb {:.3} MPa it {:>2} gmres {kr:>3} fact {fa} h {:.2} µm | {:.2} s (const {:.2} asm {:.2} fact {:.2} solve {:.2})",
            r.row.step,
            r.row.u_imposed * 1e3,
            r.row.fed * 1e3,
            r.row.bond_stress / 1e6,
            r.row.iterations,
            r.step_size * 1e6,
            w.total,
            w.constitutive,
            w.assembly,
            w.factorisation,
            w.solve
        );
    }
    fn cutback(&mut self, c: &Cutback) {
        let h: Vec<String> = c
            .residual_history
            .iter()
            .map(|v| format!("{v:.1e}"))
            .collect();
        println!(
            "cut-back step {} u {:.4} mm: {} [{}]",
            c.step,
            c.u_imposed * 1e3,
            c.reason,
            h.join(" ")
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.len() < 2 {
        eprintln!("usage: pullout_run SCENE.yaml MODEL.bin [key=value ...]");
        return;
    }
    let text = std::fs::read_to_string(&args[0]).expect("scene file");
    let mut scene: serde_yaml::Value = serde_yaml::from_str(&text).expect("scene YAML");
    for kv in &args[2..] {
        let (k, v) = kv.split_once('=').expect("key=value");
        let (section, key) = k.split_once('.').unwrap_or(("solver", k));
        let map = scene
            .as_mapping_mut()
            .unwrap()
            .entry(section.into())
            .or_insert(serde_yaml::Value::Mapping(Default::default()));
        map.as_mapping_mut()
            .unwrap()
            .insert(key.into(), serde_yaml::from_str(v).unwrap());
    }
    let get = |k: &str| scene.get(k).cloned().unwrap_or(serde_yaml::Value::Null);
    let mats: RawMaterials = serde_yaml::from_value(get("materials")).expect("materials");
    let mats = mats.resolve().expect("materials");
    let loading: RawLoading = serde_yaml::from_value(get("loading")).unwrap_or_default();
    let solver: RawSolver = serde_yaml::from_value(get("solver")).unwrap_or_default();
    let loading = loading.resolve(&solver).expect("loading");
    let settings = solver.resolve().expect("solver");
    let model = Model::load(std::path::Path::new(&args[1])).expect("model");
    let non_adhesive: NonAdhesive = get("specimen")
        .get("non_adhesive")
        .map(|v| serde_yaml::from_value(v.clone()).expect("specimen.non_adhesive"))
        .unwrap_or_default();
    let laws = mats.element_laws(&model, non_adhesive).expect("laws");
    println!(
        "{} nodes, {} tets, {} interface elements; {settings:?}",
        model.nodes.len(),
        model.tets.len(),
        model.interfaces.len()
    );
    let opt = |k: &str| {
        scene
            .get("bench")
            .and_then(|b| b.get(k))
            .map(|v| serde_yaml::to_string(v).unwrap().trim().to_string())
    };
    let mut print = Print::default();
    let mut resume = None;
    match (opt("save_at"), opt("checkpoint")) {
        (Some(n), Some(p)) => print.save = Some((n.parse().expect("bench.save_at"), p.into())),
        (None, Some(p)) => {
            resume = Some(Checkpoint::load(p.as_ref(), BENCH_KEY).expect("checkpoint"))
        }
        _ => {}
    }
    if let Some(p) = opt("resume") {
        resume = Some(Checkpoint::load(p.as_ref(), BENCH_KEY).expect("bench.resume"));
    }
    let res = solve_pullout(&model, &laws, &loading, &settings, resume, &mut print);
    let summary = match &res {
        Ok(r) => r.summary.clone(),
        Err(SolveError::Stalled { partial, .. }) => {
            println!("stalled: {}", res.as_ref().err().unwrap());
            partial.summary.clone()
        }
        Err(e) => panic!("{e}"),
    };
    println!("{}", serde_json::to_string_pretty(&summary).unwrap());
}
