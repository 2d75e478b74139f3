//! The post stage: `summary.json` (curve quantities, the bond laws and the
//! design code's, the solver's counts and wall times, the upstream stages'
//! timings), `bond_law.json` and the plots, from the solve stage's files
//! (and the geometry's f_R) only.

use super::bond_law::BondLaws;
use super::ctx::Ctx;
use super::kinds::Stage;
use crate::outputs::PlotFormat;
use crate::post::{self, InterfaceProfile, InterfaceSample, SummaryOptions};
use anyhow::{Context, Result};
use serde_json::{json, Value};
use std::path::Path;

fn read_json(path: &Path) -> Result<Value> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_slice(&bytes).with_context(|| format!("{}: not valid JSON", path.display()))
}

/// Interface traction profiles written by the solve stage
/// (`interface_profile.csv`: `step,fed,z,normal,shear`, SI).
pub fn read_profiles(path: &Path) -> Result<Vec<InterfaceProfile>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut profiles: Vec<(u64, InterfaceProfile)> = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let f: Vec<f64> = line
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}:{}: not a row of numbers", path.display(), i + 1))?;
        anyhow::ensure!(
            f.len() == 5,
            "{}:{}: expected 5 columns",
            path.display(),
            i + 1
        );
        let step = f[0] as u64;
        if profiles.last().map(|(s, _)| *s) != Some(step) {
            profiles.push((
                step,
                InterfaceProfile {
                    label: format!("step {step}, FED = {:.3} mm", f[1] * 1e3),
                    samples: Vec::new(),
                },
            ));
        }
        let (_, p) = profiles.last_mut().expect("pushed above");
        p.samples.push(InterfaceSample {
            z: f[2],
            normal: f[3],
            shear: f[4],
        });
    }
    Ok(profiles.into_iter().map(|(_, p)| p).collect())
}

pub fn run(ctx: &Ctx, out: &Path) -> Result<()> {
    let solve_dir = ctx.done_dir(Stage::Solve);
    let solve_dir = solve_dir.as_path();
    let request = &ctx.scene.outputs.post;
    let rows = post::read_curve_csv(&solve_dir.join("curve.csv"))?;
    let solve = read_json(&solve_dir.join("solve.json"))?;
    let curve = post::summarize(
        &rows,
        &SummaryOptions {
            energy_fed_limit: Some(request.energy_fed_limit),
            residual_fraction: request.residual_fraction,
        },
    )?;
    let laws = BondLaws::of(ctx, &rows);
    crate::store::write_atomic(
        &out.join("bond_law.json"),
        &serde_json::to_vec_pretty(&laws.to_json())?,
    )?;
    let stage_time = |stage: Stage| -> Value {
        ctx.store
            .wall_time(ctx.keys.get(stage))
            .map_or(Value::Null, Value::from)
    };
    let summary = json!({
        "scene": ctx.scene.name,
        "units": "SI (Pa, m, N, J/m^2, s)",
        "curve": curve,
        "bond_law": laws.to_json(),
        "design_code": laws.design_summary(curve.peak_bond_stress),
        "geometry": {"f_R": laws.f_r},
        "solver": solve,
        "stage_wall_time_s": {
            "geometry": stage_time(Stage::Geometry),
            "mesh": stage_time(Stage::Mesh),
            "solve": solve.pointer("/summary/wall_time_s/total").cloned().unwrap_or(Value::Null),
        },
    });
    crate::store::write_atomic(
        &out.join("summary.json"),
        &serde_json::to_vec_pretty(&summary)?,
    )?;

    let plots = out.join("plots");
    if !request.plots.is_empty() {
        std::fs::create_dir_all(&plots).with_context(|| format!("creating {}", plots.display()))?;
    }
    let label = ctx.scene.name.as_str();
    let profiles_csv = solve_dir.join("interface_profile.csv");
    let profiles = if profiles_csv.is_file() {
        read_profiles(&profiles_csv)?
    } else {
        Vec::new()
    };
    let references = laws.references();
    for format in &request.plots {
        match format {
            PlotFormat::Png => {
                post::bond_slip_with_laws_png(
                    &[(label, &rows)],
                    &references,
                    &plots.join("bond_slip.png"),
                )?;
                if !profiles.is_empty() {
                    post::interface_line_png(&profiles, &plots.join("interface_profile.png"))?;
                }
            }
            PlotFormat::Svg => {
                post::bond_slip_with_laws_svg(
                    &[(label, &rows)],
                    &references,
                    &plots.join("bond_slip.svg"),
                )?;
                if !profiles.is_empty() {
                    post::interface_line_svg(&profiles, &plots.join("interface_profile.svg"))?;
                }
            }
        }
    }
    if profiles_csv.is_file() {
        std::fs::copy(&profiles_csv, out.join("interface_profile.csv"))
            .with_context(|| format!("copying {}", profiles_csv.display()))?;
    }
    ctx.printer.line(&format!(
        "post: first peak σ_mb {:.3} MPa at FED {:.4} mm, maximum {:.3} MPa, residual {}",
        curve.first_peak_bond_stress / 1e6,
        curve.fed_at_first_peak * 1e3,
        curve.peak_bond_stress / 1e6,
        curve
            .residual_bond_stress
            .map_or("n/a (no slip past the peak)".to_string(), |r| format!(
                "{:.3} MPa",
                r / 1e6
            ))
    ));
    ctx.printer.line(&laws.line());
    Ok(())
}
