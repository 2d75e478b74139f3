//! A sensitivity study's indices from its cases' responses:
//! `sensitivity.csv` (Sobol': parameter, response, S1, S1_conf, ST,
//! ST_conf, rows; Morris: parameter, response, mu_star, sigma, mu,
//! mu_star_conf, effects), `sensitivity.md` (the same with the estimators,
//! the design and the cases left out, in words) and the bar plot.
//!
//! A case that failed or whose solve stopped early has no responses, and
//! neither has a completed case for a response it does not define: a
//! Saltelli row counts for a response only when all its d + 2 cases have
//! it, and a Morris elementary effect only when both of its points do.
//! Leaving them out keeps the estimators unbiased only if the failures do
//! not depend on the parameters; the counts say how many were left.

use crate::post::{self, Measure, SensitivityBars};
use crate::study::{display_unit, short_key, Design, Plan, Role};
use anyhow::Result;
use std::path::Path;

/// Writes the indices of every response; returns the lines the study
/// prints (one per response without indices, and where the files are).
pub fn write(
    design: &Design,
    responses: &[Vec<Option<f64>>],
    excluded: &[String],
    out: &Path,
) -> Result<Vec<String>> {
    let (table, bars, notes, estimator) = match design.plan {
        Plan::Sobol { seed, .. } => sobol(design, responses, seed)?,
        Plan::Morris { seed, .. } => morris(design, responses, seed),
        Plan::Sample { .. } => return Ok(Vec::new()),
    };
    table.write_csv(&out.join("sensitivity.csv"))?;
    let mut md = format!(
        "# Sensitivity\n\nDesign: {}.\n\n{estimator}\n\nA case that failed or whose solve \
         stopped early has no responses, nor has a completed case a response it does not \
         define (an energy to a FED its curve does not reach, a bond-law parameter its curve \
         does not determine): {}. The indices are unbiased only if such cases do not depend on \
         the parameters.\n\n",
        design.plan.describe(),
        match design.plan {
            Plan::Sobol { .. } =>
                "a row counts for a response only when all its d + 2 cases have it",
            _ => "an elementary effect counts only when both of its points have the response",
        }
    );
    if excluded.is_empty() {
        md.push_str("Every case completed.\n\n");
    } else {
        md.push_str("Cases left out:\n\n");
        for line in excluded {
            md.push_str(&format!("- {line}\n"));
        }
        md.push('\n');
    }
    for note in &notes {
        md.push_str(&format!("- {note}\n"));
    }
    md.push_str(&format!("\n{}", table.to_markdown()));
    crate::store::write_atomic(&out.join("sensitivity.md"), md.as_bytes())?;
    if !bars.is_empty() {
        let y_label = match design.plan {
            Plan::Sobol { .. } => "Sobol' index",
            _ => "μ*, σ (response per parameter range)",
        };
        let plots = out.join("plots");
        post::sensitivity_plot(
            y_label,
            &bars,
            &plots.join("sensitivity.png"),
            &plots.join("sensitivity.svg"),
        )?;
    }
    let mut lines: Vec<String> = notes.iter().map(|n| format!("sensitivity: {n}")).collect();
    lines.push(format!(
        "sensitivity: {} rows in {}",
        table.rows.len(),
        out.join("sensitivity.csv").display()
    ));
    Ok(lines)
}

type Outcome = (post::Table, Vec<SensitivityBars>, Vec<String>, String);

fn sobol(design: &Design, responses: &[Vec<Option<f64>>], seed: u64) -> Result<Outcome> {
    let rows = saltelli_rows(design);
    let short: Vec<String> = design
        .axes
        .iter()
        .map(|a| short_key(&a.key, &design.axes))
        .collect();
    let (mut table, mut bars, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    for (r, response) in design.responses.iter().enumerate() {
        let y = |case: usize| responses[case][r];
        let complete: Vec<(f64, f64, Vec<f64>)> = rows
            .iter()
            .filter_map(|(a, b, ab)| {
                Some((
                    y(*a)?,
                    y(*b)?,
                    ab.iter().map(|&c| y(c)).collect::<Option<Vec<_>>>()?,
                ))
            })
            .collect();
        let name = response.name();
        let a: Vec<f64> = complete.iter().map(|c| c.0).collect();
        let b: Vec<f64> = complete.iter().map(|c| c.1).collect();
        let ab: Vec<Vec<f64>> = (0..design.axes.len())
            .map(|i| complete.iter().map(|c| c.2[i]).collect())
            .collect();
        let indices = match post::sobol_indices(&a, &b, &ab, post::BOOTSTRAP_RESAMPLES, seed) {
            Ok(i) => i,
            Err(e) => {
                notes.push(format!(
                    "{name}: no indices ({e}; {} of {} rows complete)",
                    complete.len(),
                    rows.len()
                ));
                continue;
            }
        };
        if complete.len() < rows.len() {
            notes.push(format!(
                "{name}: {} of {} rows complete",
                complete.len(),
                rows.len()
            ));
        }
        for (axis, index) in design.axes.iter().zip(&indices) {
            table.push((axis.key.clone(), name.clone(), *index, complete.len()));
        }
        bars.push(SensitivityBars {
            response: name,
            parameters: short.clone(),
            measures: vec![
                Measure {
                    name: "S1".into(),
                    bars: indices.iter().map(|i| (i.s1, Some(i.s1_conf))).collect(),
                },
                Measure {
                    name: "ST".into(),
                    bars: indices.iter().map(|i| (i.st, Some(i.st_conf))).collect(),
                },
            ],
        });
    }
    Ok((
        post::sobol_table(&table),
        bars,
        notes,
        format!(
            "Estimators: first-order S1 after Saltelli et al. (2010), total ST after Jansen \
             (1999), both on the variance of the responses at A and B; S1_conf and ST_conf are \
             95 % half-widths, 1.96 standard deviations over {} bootstrap resamples of the rows \
             (seed {seed}). `rows` is how many rows of A, B and AB_i the indices are from.",
            post::BOOTSTRAP_RESAMPLES
        ),
    ))
}

fn morris(design: &Design, responses: &[Vec<Option<f64>>], seed: u64) -> Outcome {
    let short: Vec<String> = design
        .axes
        .iter()
        .map(|a| short_key(&a.key, &design.axes))
        .collect();
    let (mut table, mut bars, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    let points = &design.points.points;
    for (r, response) in design.responses.iter().enumerate() {
        let mut effects = vec![Vec::new(); design.axes.len()];
        for k in 1..points.len() {
            let Role::Morris {
                moved: Some((i, delta)),
                ..
            } = points[k].role
            else {
                continue;
            };
            if let (Some(y1), Some(y0)) = (responses[k][r], responses[k - 1][r]) {
                effects[i].push((y1 - y0) / delta);
            }
        }
        let name = response.name();
        let indices = post::morris_indices(&effects, post::BOOTSTRAP_RESAMPLES, seed);
        if indices.iter().all(Option::is_none) {
            notes.push(format!(
                "{name}: no indices (fewer than 2 elementary effects per parameter)"
            ));
            continue;
        }
        let (scale, _) = display_unit(response.unit());
        let mut mu_star = Vec::new();
        let mut sigma = Vec::new();
        for (axis, index) in design.axes.iter().zip(&indices) {
            match index {
                Some(i) => {
                    table.push((axis.key.clone(), name.clone(), *i));
                    mu_star.push((i.mu_star * scale, Some(i.mu_star_conf * scale)));
                    sigma.push((i.sigma * scale, None));
                }
                None => {
                    notes.push(format!(
                        "{name}: {}: fewer than 2 elementary effects",
                        axis.key
                    ));
                    mu_star.push((0.0, None));
                    sigma.push((0.0, None));
                }
            }
        }
        let unit = display_unit(response.unit()).1;
        bars.push(SensitivityBars {
            response: if unit.is_empty() {
                name
            } else {
                format!("{name} ({unit})")
            },
            parameters: short.clone(),
            measures: vec![
                Measure {
                    name: "μ*".into(),
                    bars: mu_star,
                },
                Measure {
                    name: "σ".into(),
                    bars: sigma,
                },
            ],
        });
    }
    (
        post::morris_table(&table),
        bars,
        notes,
        format!(
            "Estimators: Morris's elementary effects EE = Δy / Δu along each trajectory, Δu \
             the step in the unit cube (so mu_star, sigma and mu are in the response's SI unit \
             per parameter range; log-scale ranges in their logarithm); mu_star = mean |EE| \
             (Campolongo et al. 2007), sigma their standard deviation, mu their mean; \
             mu_star_conf a 95 % half-width, 1.96 standard deviations over {} bootstrap \
             resamples of the effects (seed {seed}). `effects` is how many effects each row is \
             from.",
            post::BOOTSTRAP_RESAMPLES
        ),
    )
}

/// The case indices of each Saltelli row (A, B, AB_1 … AB_d) that the
/// design holds in full, by row.
fn saltelli_rows(design: &Design) -> Vec<(usize, usize, Vec<usize>)> {
    /// The cases of one row found so far.
    #[derive(Clone)]
    struct Row {
        a: Option<usize>,
        b: Option<usize>,
        ab: Vec<Option<usize>>,
    }
    let d = design.axes.len();
    let mut rows: Vec<Row> = Vec::new();
    for (k, p) in design.points.points.iter().enumerate() {
        let row = match p.role {
            Role::SobolA { row } | Role::SobolB { row } | Role::SobolAB { row, .. } => row,
            _ => continue,
        };
        if rows.len() <= row {
            rows.resize(
                row + 1,
                Row {
                    a: None,
                    b: None,
                    ab: vec![None; d],
                },
            );
        }
        match p.role {
            Role::SobolA { .. } => rows[row].a = Some(k),
            Role::SobolB { .. } => rows[row].b = Some(k),
            Role::SobolAB { parameter, .. } => rows[row].ab[parameter] = Some(k),
            _ => {}
        }
    }
    rows.into_iter()
        .filter_map(|r| Some((r.a?, r.b?, r.ab.into_iter().collect::<Option<Vec<_>>>()?)))
        .collect()
}
