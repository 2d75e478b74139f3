//! The post stage's bond laws: `bond_law.json` (the MC2010 form and a
//! piecewise-linear law fitted to the curve, the design code's law for the
//! scene's concrete), what summary.json says of them, and the laws drawn
//! beside the curve.

use super::ctx::Ctx;
use super::kinds::Stage;
use crate::post::{
    self, CurveRow, DesignCodeLaw, FcmSource, FittedMc2010, Mc2010Law, PiecewiseLaw, ReferenceCurve,
};
use serde_json::{json, Value};
use solve::spec::materials::ConcreteModel;

/// The laws of one run.
pub struct BondLaws {
    pub mc2010: Result<FittedMc2010, String>,
    pub piecewise: Result<PiecewiseLaw, String>,
    pub design: Result<DesignCodeLaw, String>,
    /// The relative rib area of the scene's bar (geometry.json), if ribbed.
    pub f_r: Option<f64>,
    /// The curve's largest slip, m.
    pub slip_range: f64,
}

/// The scene's f_cm, given or derived from its concrete's tensile strength.
fn fcm(ctx: &Ctx) -> Result<(f64, FcmSource), String> {
    if let Some(fcm) = ctx.scene.materials.concrete_fcm {
        return Ok((fcm, FcmSource::Given));
    }
    match &ctx.scene.materials.concrete {
        ConcreteModel::Mazars(m) => Ok((
            post::fcm_from_tensile_strength(m.tensile_strength()),
            FcmSource::DerivedFromTensileStrength,
        )),
        ConcreteModel::Elastic(_) => Err(
            "the concrete is elastic and has no tensile strength to derive f_cm from; \
             give materials.concrete.fcm"
                .into(),
        ),
    }
}

fn design_law(ctx: &Ctx) -> Result<DesignCodeLaw, String> {
    let ribs = ctx.scene.bar.ribs.as_ref().ok_or_else(|| {
        "MC2010's pull-out law (Table 6.1-1) is that of ribbed bars; this bar is smooth".to_string()
    })?;
    let (fcm, source) = fcm(ctx)?;
    Ok(DesignCodeLaw::new(
        fcm,
        source,
        ctx.scene.outputs.post.bond_conditions,
        post::clear_rib_spacing(&ribs.transverse),
    ))
}

/// f_R as the geometry stage measured it.
fn relative_rib_area(ctx: &Ctx) -> Option<f64> {
    let path = ctx.done_dir(Stage::Geometry).join("geometry.json");
    let v: Value = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
    v.get("f_R")?.as_f64()
}

impl BondLaws {
    pub fn of(ctx: &Ctx, rows: &[CurveRow]) -> BondLaws {
        let slip_range = rows.iter().map(|r| r.fed).fold(0.0, f64::max);
        BondLaws {
            mc2010: post::fit_mc2010(rows).map_err(|e| e.to_string()),
            piecewise: post::fit_piecewise(rows, ctx.scene.outputs.post.bond_law_points)
                .map_err(|e| e.to_string()),
            design: design_law(ctx),
            f_r: ctx.scene.bar.ribs.as_ref().and(relative_rib_area(ctx)),
            slip_range,
        }
    }

    /// bond_law.json: each law or why there is none.
    pub fn to_json(&self) -> Value {
        let either = |r: Result<Value, &String>| match r {
            Ok(v) => v,
            Err(why) => json!({ "none": why }),
        };
        json!({
            "units": "SI (m, Pa)",
            "slip": "free-end displacement (FED), held at its running maximum where the free end moves back",
            "slip_range": self.slip_range,
            "fit_error": "relative L2 distance along the slip over [0, slip_range]: ‖τ_law − σ_mb‖ / ‖σ_mb‖",
            "mc2010": either(self.mc2010.as_ref().map(|f| {
                let mut v = serde_json::to_value(f).unwrap_or(Value::Null);
                v["form"] = json!("tau_max (s/s1)^alpha up to s1, tau_max to s2, linear to tau_f at s3, tau_f after");
                v["bounds"] = json!(post::FIT_BOUNDS);
                v
            })),
            "piecewise_linear": either(self.piecewise.as_ref().map(|p| {
                let mut v = serde_json::to_value(p).unwrap_or(Value::Null);
                v["count"] = json!(p.points.len());
                v["form"] = json!("linear between the points, from the origin; the last point's tau after it");
                v
            })),
            "design_code": either(self.design.as_ref().map(|d| serde_json::to_value(d).unwrap_or(Value::Null))),
        })
    }

    /// summary.json's `design_code`: the code's law, and the fitted τ_max
    /// and the largest σ_mb as shares of 2.5 √f_cm.
    pub fn design_summary(&self, peak_bond_stress: f64) -> Value {
        match &self.design {
            Err(why) => json!({ "none": why }),
            Ok(d) => {
                let mut v = serde_json::to_value(d).unwrap_or(Value::Null);
                v["tau_max_ratio"] = self
                    .mc2010
                    .as_ref()
                    .map_or(Value::Null, |f| json!(d.strength_ratio(f.law.tau_max)));
                v["peak_bond_stress_ratio"] = json!(d.strength_ratio(peak_bond_stress));
                v["ratio"] = json!("stress / (2.5 sqrt(f_cm)), f_cm in MPa: the share of MC2010's good-bond pull-out strength");
                v
            }
        }
    }

    /// The fitted and the design code's MC2010 laws as lines over the
    /// curve's slip range.
    pub fn references(&self) -> Vec<ReferenceCurve> {
        let mut lines = Vec::new();
        if let Ok(fit) = &self.mc2010 {
            lines.push(ReferenceCurve {
                label: format!("MC2010 form fitted (error {:.1} %)", 100.0 * fit.fit_error),
                points: law_points(&fit.law, self.slip_range),
            });
        }
        if let Ok(d) = &self.design {
            let conditions = match d.bond_conditions {
                post::BondConditions::Good => "good bond",
                post::BondConditions::Other => "other bond conditions",
            };
            lines.push(ReferenceCurve {
                label: format!("MC2010, {conditions}, f_cm {:.1} MPa", d.fcm / 1e6),
                points: law_points(&d.law, self.slip_range),
            });
        }
        lines
    }

    /// The post line that reports the laws.
    pub fn line(&self) -> String {
        let fit = match &self.mc2010 {
            Ok(f) => format!(
                "MC2010 fit τ_max {:.3} MPa, s1 {:.3} mm, α {:.2}, error {:.1} %",
                f.law.tau_max / 1e6,
                f.law.s1 * 1e3,
                f.law.alpha,
                100.0 * f.fit_error
            ),
            Err(why) => format!("no MC2010 fit ({why})"),
        };
        let code = match &self.design {
            Ok(d) => format!(
                "; MC2010 code τ_max {:.2} MPa (f_cm {:.1} MPa{})",
                d.law.tau_max / 1e6,
                d.fcm / 1e6,
                match d.fcm_source {
                    FcmSource::Given => "",
                    FcmSource::DerivedFromTensileStrength => ", derived from ft",
                }
            ),
            Err(_) => String::new(),
        };
        format!("post: {fit}{code}")
    }
}

/// The law at 200 slips over [0, x] and at its kinks inside.
fn law_points(law: &Mc2010Law, x: f64) -> Vec<(f64, f64)> {
    let mut s: Vec<f64> = (0..=200).map(|i| x * i as f64 / 200.0).collect();
    s.extend([law.s1, law.s2, law.s3].into_iter().filter(|&k| k < x));
    s.sort_by(f64::total_cmp);
    s.into_iter().map(|s| (s, law.stress(s))).collect()
}
