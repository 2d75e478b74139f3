//! A study's results beyond its table: every case's bond laws
//! (`bond_laws.csv`); for a sampled or sensitivity study its design
//! (`designs.csv`, and the draws outside the design bounds in
//! `rejected.csv`), its responses (`responses.csv`) and their trends
//! against each parameter and f_R (`plots/trend_<response>.png|svg`); for
//! a sensitivity study the indices (`sensitivity.csv`, `sensitivity.md`,
//! `plots/sensitivity.png|svg`).
//!
//! A case counts in the trends and indices when its solve completed; a
//! case that failed or stopped early is left out, and so is a response a
//! completed case does not define (see [`Response::value`]).

use crate::post::{self, Cell, CurveRow, Table};
use crate::progress::Printer;
use crate::study::{display_unit, short_key, Axis, Design, Plan, Response, Study};
use anyhow::Result;
use serde_json::Value as Json;
use std::path::Path;

/// What a case left behind.
struct CaseResult {
    name: String,
    summary: Option<Json>,
    curve: Vec<CurveRow>,
    /// Why the case does not count in trends and indices, if it does not.
    excluded: Option<String>,
}

fn read_json(path: &Path) -> Option<Json> {
    serde_json::from_slice(&std::fs::read(path).ok()?).ok()
}

fn read_case(work: &Path, name: &str) -> CaseResult {
    let dir = work.join(name);
    let summary = read_json(&dir.join("summary.json"));
    let curve = post::read_curve_csv(&dir.join("curve.csv")).unwrap_or_default();
    let excluded = match (&summary, read_json(&dir.join("solve.json"))) {
        (None, _) | (_, None) => Some("no results (the case failed; see its log)".to_string()),
        (Some(_), Some(solve)) if solve.get("completed").and_then(Json::as_bool) != Some(true) => {
            Some(format!(
                "its solve stopped early: {}",
                solve
                    .get("stopped")
                    .and_then(Json::as_str)
                    .unwrap_or("no reason recorded")
            ))
        }
        _ => None,
    };
    CaseResult {
        name: name.to_string(),
        summary,
        curve,
        excluded,
    }
}

impl CaseResult {
    /// The response where the case counts and defines it.
    fn response(&self, r: &Response) -> Option<f64> {
        if self.excluded.is_some() {
            return None;
        }
        r.value(self.summary.as_ref()?, &self.curve)
    }

    fn f_r(&self) -> Option<f64> {
        self.summary.as_ref()?.pointer("/geometry/f_R")?.as_f64()
    }
}

/// Every output of this module for `study`'s cases in `work`, into `out`.
pub fn write(study: &Study, work: &Path, out: &Path, printer: &Printer) -> Result<()> {
    let cases: Vec<CaseResult> = study
        .cases
        .iter()
        .map(|c| read_case(work, &c.name))
        .collect();
    bond_law_table(study, &cases).write_csv(&out.join("bond_laws.csv"))?;
    let Some(design) = &study.design else {
        return Ok(());
    };
    write_design(study, design, out)?;
    responses_table(design, &cases).write_csv(&out.join("responses.csv"))?;
    let excluded: Vec<String> = cases
        .iter()
        .filter_map(|c| c.excluded.as_ref().map(|why| format!("{}: {why}", c.name)))
        .collect();
    for line in &excluded {
        printer.line(&format!("left out of the trends and indices: {line}"));
    }
    trend_plots(design, &cases, &out.join("plots"))?;
    if matches!(design.plan, Plan::Sobol { .. } | Plan::Morris { .. }) {
        for line in crate::study_sensitivity::write(
            design,
            &cases_responses(design, &cases),
            &excluded,
            out,
        )? {
            printer.line(&line);
        }
    }
    Ok(())
}

/// Each case's responses (`None` where it does not count or define one),
/// `[case][response]`.
fn cases_responses(design: &Design, cases: &[CaseResult]) -> Vec<Vec<Option<f64>>> {
    cases
        .iter()
        .map(|c| design.responses.iter().map(|r| c.response(r)).collect())
        .collect()
}

/// designs.csv and rejected.csv: every point of the design with its role,
/// its unit-cube coordinates and its values, and every draw outside the
/// design bounds with why. Written before the cases run, and again with
/// the results.
pub fn write_design(study: &Study, design: &Design, out: &Path) -> Result<()> {
    let mut columns = vec!["case".to_string(), "role".to_string()];
    columns.extend(design.axes.iter().map(|a| format!("u_{}", a.key)));
    columns.extend(design.axes.iter().map(|a| a.key.clone()));
    let rows = study
        .cases
        .iter()
        .zip(&design.points.points)
        .map(|(case, p)| {
            let mut row = vec![
                Cell::from(case.name.as_str()),
                Cell::from(p.role.label(&design.axes)),
            ];
            row.extend(p.unit.iter().map(|&u| Cell::Num(u)));
            row.extend(p.values.iter().map(|v| Cell::from(&yaml_to_json(&v.table))));
            row
        })
        .collect();
    Table { columns, rows }.write_csv(&out.join("designs.csv"))?;
    let mut columns = vec!["draw".to_string(), "reason".to_string()];
    columns.extend(design.axes.iter().map(|a| a.key.clone()));
    let rows = design
        .points
        .rejected
        .iter()
        .map(|r| {
            let mut row = vec![Cell::from(r.draw.as_str()), Cell::from(r.reason.as_str())];
            row.extend(r.values.iter().map(|v| Cell::from(&yaml_to_json(&v.table))));
            row
        })
        .collect();
    Table { columns, rows }.write_csv(&out.join("rejected.csv"))?;
    Ok(())
}

fn yaml_to_json(v: &serde_yaml::Value) -> Json {
    serde_json::to_value(v).unwrap_or(Json::Null)
}

/// responses.csv: per case whether it counts, its f_R and its responses,
/// SI.
fn responses_table(design: &Design, cases: &[CaseResult]) -> Table {
    let mut columns = vec!["case".to_string(), "counted".to_string(), "f_R".to_string()];
    columns.extend(design.responses.iter().map(Response::name));
    let rows = cases
        .iter()
        .map(|c| {
            let mut row = vec![
                Cell::from(c.name.as_str()),
                Cell::from(if c.excluded.is_none() { "yes" } else { "no" }),
                Cell::from(c.f_r()),
            ];
            row.extend(design.responses.iter().map(|r| Cell::from(c.response(r))));
            row
        })
        .collect();
    Table { columns, rows }
}

/// bond_laws.csv: every case's fitted MC2010 law and piecewise law and the
/// design code's law, SI; empty cells where a case has none.
fn bond_law_table(study: &Study, cases: &[CaseResult]) -> Table {
    const FIELDS: [(&str, &str); 19] = [
        ("mc2010_tau_max", "/bond_law/mc2010/tau_max"),
        ("mc2010_s1", "/bond_law/mc2010/s1"),
        ("mc2010_s2", "/bond_law/mc2010/s2"),
        ("mc2010_s3", "/bond_law/mc2010/s3"),
        ("mc2010_alpha", "/bond_law/mc2010/alpha"),
        ("mc2010_tau_f", "/bond_law/mc2010/tau_f"),
        ("mc2010_fit_error", "/bond_law/mc2010/fit_error"),
        ("mc2010_unidentified", "/bond_law/mc2010/unidentified"),
        (
            "piecewise_fit_error",
            "/bond_law/piecewise_linear/fit_error",
        ),
        ("piecewise_points", "/bond_law/piecewise_linear/points"),
        ("code_tau_max", "/design_code/tau_max"),
        ("code_s1", "/design_code/s1"),
        ("code_s2", "/design_code/s2"),
        ("code_s3", "/design_code/s3"),
        ("code_tau_f", "/design_code/tau_f"),
        ("fcm", "/design_code/fcm"),
        ("fcm_source", "/design_code/fcm_source"),
        ("tau_max_ratio", "/design_code/tau_max_ratio"),
        ("f_R", "/geometry/f_R"),
    ];
    let mut columns = vec!["case".to_string()];
    columns.extend(study.keys.iter().cloned());
    columns.extend(FIELDS.iter().map(|(n, _)| n.to_string()));
    let rows = study
        .cases
        .iter()
        .zip(cases)
        .map(|(case, result)| {
            let mut row = vec![Cell::from(case.name.as_str())];
            row.extend(
                case.parameters
                    .iter()
                    .map(|(_, v)| Cell::from(&yaml_to_json(v))),
            );
            row.extend(FIELDS.iter().map(|(name, pointer)| {
                match result.summary.as_ref().and_then(|s| s.pointer(pointer)) {
                    Some(Json::Array(a)) if *name == "mc2010_unidentified" => Cell::from(
                        a.iter()
                            .filter_map(Json::as_str)
                            .collect::<Vec<_>>()
                            .join(" "),
                    ),
                    Some(v @ Json::Array(_)) => Cell::from(v.to_string()),
                    Some(v) => Cell::from(v),
                    None => Cell::Empty,
                }
            }));
            row
        })
        .collect();
    Table { columns, rows }
}

fn with_unit(name: &str, unit: &str) -> String {
    match display_unit(unit).1 {
        "" => name.to_string(),
        u => format!("{name} ({u})"),
    }
}

/// One trend plot per response: a panel per numeric parameter and one for
/// f_R, each with the counted cases and their least-squares line.
fn trend_plots(design: &Design, cases: &[CaseResult], plots: &Path) -> Result<()> {
    let numeric: Vec<(usize, &Axis)> = design
        .axes
        .iter()
        .enumerate()
        .filter(|(_, a)| a.is_numeric())
        .collect();
    for response in &design.responses {
        let (y_scale, _) = display_unit(response.unit());
        let mut panels = Vec::new();
        for &(i, axis) in &numeric {
            let (x_scale, _) = display_unit(axis.unit());
            let points: Vec<(f64, f64)> = design
                .points
                .points
                .iter()
                .zip(cases)
                .filter_map(|(p, c)| {
                    Some((
                        p.values[i].table.as_f64()? * x_scale,
                        c.response(response)? * y_scale,
                    ))
                })
                .collect();
            panels.push(post::TrendPanel {
                x_label: with_unit(&short_key(&axis.key, &design.axes), axis.unit()),
                trend: post::trend_line(&points, axis.is_log()),
                points,
            });
        }
        let f_r: Vec<(f64, f64)> = cases
            .iter()
            .filter_map(|c| Some((c.f_r()?, c.response(response)? * y_scale)))
            .collect();
        if f_r.iter().any(|p| (p.0 - f_r[0].0).abs() > 1e-12) {
            panels.push(post::TrendPanel {
                x_label: "relative rib area f_R".into(),
                trend: post::trend_line(&f_r, false),
                points: f_r,
            });
        }
        if panels.iter().all(|p| p.points.is_empty()) {
            continue;
        }
        let name = response.name();
        post::trend_plot(
            &with_unit(&name, response.unit()),
            &panels,
            &plots.join(format!("trend_{name}.png")),
            &plots.join(format!("trend_{name}.svg")),
        )?;
    }
    Ok(())
}
