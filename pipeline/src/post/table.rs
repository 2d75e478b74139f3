//! Study and convergence tables, written as CSV (full precision, for
//! machines) and Markdown (four significant digits, for people).

use super::convergence::ConvergenceStudy;
use super::error::PostError;
use super::fsutil::write_atomic;
use std::path::Path;

pub use super::cell::Cell;

impl From<&serde_yaml::Value> for Cell {
    /// A parameter value as written in a study file: numbers stay numbers,
    /// strings (often quantities with units, "60 deg") text.
    fn from(v: &serde_yaml::Value) -> Self {
        match v {
            serde_yaml::Value::Null => Cell::Empty,
            serde_yaml::Value::Number(n) => match n.as_i64() {
                Some(i) => Cell::Int(i),
                None => Cell::Num(n.as_f64().unwrap_or(f64::NAN)),
            },
            serde_yaml::Value::String(s) => Cell::Text(s.clone()),
            serde_yaml::Value::Bool(b) => Cell::Text(b.to_string()),
            other => Cell::Text(value_label(other)),
        }
    }
}

/// A case's varied parameters as they read in a legend or a table row:
/// `key=value, …`, each key by the shortest dotted suffix no other of them
/// ends with (`mu`, but `interface.ft` and `concrete.ft` when both vary).
pub fn parameters_label(parameters: &[(String, serde_yaml::Value)]) -> String {
    let keys: Vec<&str> = parameters.iter().map(|(k, _)| k.as_str()).collect();
    parameters
        .iter()
        .map(|(k, v)| format!("{}={}", short_key(k, &keys), value_label(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The shortest dotted suffix of `key` that no other of `keys` ends with.
fn short_key<'k>(key: &'k str, keys: &[&str]) -> &'k str {
    let starts = key.match_indices('.').map(|(i, _)| i + 1);
    let mut suffixes = starts.rev().map(|i| &key[i..]);
    suffixes
        .find(|suffix| {
            keys.iter()
                .filter(|&&other| other != key)
                .all(|other| !other.ends_with(&format!(".{suffix}")) && *other != *suffix)
        })
        .unwrap_or(key)
}

/// A study parameter's value as it reads in a table cell or a legend: one
/// line, strings unquoted, mappings (a whole law, say) as `k: v, k: v`.
pub fn value_label(v: &serde_yaml::Value) -> String {
    use serde_yaml::Value;
    match v {
        Value::Null => String::new(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => s.clone(),
        Value::Sequence(items) => format!(
            "[{}]",
            items.iter().map(value_label).collect::<Vec<_>>().join(", ")
        ),
        Value::Mapping(m) => m
            .iter()
            .map(|(k, v)| format!("{}: {}", value_label(k), value_label(v)))
            .collect::<Vec<_>>()
            .join(", "),
        Value::Tagged(t) => value_label(&t.value),
    }
}

impl Cell {
    fn is_numeric(&self) -> bool {
        matches!(self, Cell::Int(_) | Cell::Num(_))
    }

    fn csv(&self) -> String {
        match self {
            Cell::Int(i) => i.to_string(),
            Cell::Num(x) => csv_number(*x),
            Cell::Text(s) => {
                if s.contains([',', '"', '\n', '\r']) {
                    format!("\"{}\"", s.replace('"', "\"\""))
                } else {
                    s.clone()
                }
            }
            Cell::Empty => String::new(),
        }
    }

    fn markdown(&self) -> String {
        match self {
            Cell::Int(i) => i.to_string(),
            Cell::Num(x) => significant(*x, 4),
            Cell::Text(s) => md_escape(s),
            Cell::Empty => String::new(),
        }
    }
}

/// Shortest text that reads back to the same f64.
fn csv_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` rounded to `digits` significant digits, trailing zeros dropped;
/// scientific outside [1e-3, 1e6).
fn significant(x: f64, digits: usize) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    let mag = x.abs().log10().floor() as i32;
    // Trailing zeros only add noise to parameter values such as μ = 0.001.
    let trim = |s: &str| s.trim_end_matches('0').trim_end_matches('.').to_string();
    if (-3..6).contains(&mag) {
        let decimals = (digits as i32 - 1 - mag).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            trim(&s)
        } else {
            s
        }
    } else {
        let s = format!("{x:.prec$e}", prec = digits - 1);
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = if mantissa.contains('.') {
            trim(mantissa)
        } else {
            mantissa.to_string()
        };
        format!("{mantissa}e{exp}")
    }
}

fn md_escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// A rectangular table with named columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub columns: Vec<String>,
    /// Each row has one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// RFC 4180 CSV: a header line then one line per row.
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        let header: Vec<String> = self
            .columns
            .iter()
            .map(|c| Cell::Text(c.clone()).csv())
            .collect();
        out.push_str(&header.join(","));
        out.push('\n');
        for row in &self.rows {
            let cells: Vec<String> = row.iter().map(Cell::csv).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// A GitHub-flavoured Markdown table; numeric columns right-aligned.
    pub fn to_markdown(&self) -> String {
        let mut out = String::new();
        let header: Vec<String> = self.columns.iter().map(|c| md_escape(c)).collect();
        out.push_str(&format!("| {} |\n", header.join(" | ")));
        let align: Vec<&str> = (0..self.columns.len())
            .map(|j| {
                let mut cells = self
                    .rows
                    .iter()
                    .map(|r| &r[j])
                    .filter(|c| **c != Cell::Empty);
                let numeric = cells.clone().next().is_some() && cells.all(Cell::is_numeric);
                if numeric {
                    "---:"
                } else {
                    "---"
                }
            })
            .collect();
        out.push_str(&format!("| {} |\n", align.join(" | ")));
        for row in &self.rows {
            let cells: Vec<String> = row.iter().map(Cell::markdown).collect();
            out.push_str(&format!("| {} |\n", cells.join(" | ")));
        }
        out
    }

    /// Writes the CSV form to `path` (atomically; parent directories created).
    pub fn write_csv(&self, path: &Path) -> Result<(), PostError> {
        write_atomic(path, self.to_csv().as_bytes())
    }

    /// Writes the Markdown form to `path` (atomically; parent directories created).
    pub fn write_markdown(&self, path: &Path) -> Result<(), PostError> {
        write_atomic(path, self.to_markdown().as_bytes())
    }
}

/// One case of a parameter study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyCase {
    /// Case name (unique within the study).
    pub label: String,
    /// The study's varied parameters for this case, as (spec key, value).
    pub params: Vec<(String, Cell)>,
    /// Summary quantities, as (name with unit, value), e.g. from
    /// [`CurveSummary::table_entries`](super::summary::CurveSummary::table_entries).
    pub summary: Vec<(String, Cell)>,
}

impl StudyCase {
    /// A case from its swept parameters (spec key, value as written in the
    /// study file) and its `summary.json`. Summary columns: the entries of
    /// [`CurveSummary::table_entries`](super::summary::CurveSummary::table_entries)
    /// from the `curve` object, the bond-law columns of
    /// [`bond_law_entries`](super::bond_law::bond_law_entries), then `dofs` and
    /// `solve_wall_time_s` when the
    /// summary has `solver.summary.dofs` and `solver.summary.wall_time_s.total`.
    /// A summary without a readable `curve` object gives only what is found.
    pub fn from_summary(
        label: &str,
        params: &[(String, serde_yaml::Value)],
        summary: &serde_json::Value,
    ) -> StudyCase {
        let mut entries = summary
            .get("curve")
            .and_then(|c| serde_json::from_value::<super::summary::CurveSummary>(c.clone()).ok())
            .map(|c| c.table_entries())
            .unwrap_or_default();
        entries.extend(super::bond_law::bond_law_entries(summary));
        for (name, pointer) in [
            ("dofs", "/solver/summary/dofs"),
            ("solve_wall_time_s", "/solver/summary/wall_time_s/total"),
        ] {
            if let Some(v) = summary.pointer(pointer) {
                entries.push((name.to_string(), Cell::from(v)));
            }
        }
        StudyCase {
            label: label.to_string(),
            params: params
                .iter()
                .map(|(k, v)| (k.clone(), Cell::from(v)))
                .collect(),
            summary: entries,
        }
    }
}

/// Keys in order of first appearance over all cases.
fn union_keys<'a>(lists: impl Iterator<Item = &'a [(String, Cell)]>) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for list in lists {
        for (k, _) in list {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    keys
}

fn lookup(list: &[(String, Cell)], key: &str) -> Cell {
    list.iter()
        .find(|(k, _)| k == key)
        .map_or(Cell::Empty, |(_, c)| c.clone())
}

/// The study table: `case`, then parameter columns, then summary columns,
/// each group in order of first appearance over the cases (so the order is
/// fixed by the study, not by hashing); missing values are empty cells.
pub fn study_table(cases: &[StudyCase]) -> Table {
    let params = union_keys(cases.iter().map(|c| c.params.as_slice()));
    let summary = union_keys(cases.iter().map(|c| c.summary.as_slice()));
    let mut columns = vec!["case".to_string()];
    columns.extend(params.iter().cloned());
    columns.extend(summary.iter().cloned());
    let rows = cases
        .iter()
        .map(|c| {
            let mut row = vec![Cell::Text(c.label.clone())];
            row.extend(params.iter().map(|k| lookup(&c.params, k)));
            row.extend(summary.iter().map(|k| lookup(&c.summary, k)));
            row
        })
        .collect();
    Table { columns, rows }
}

/// Writes [`study_table`] as CSV and Markdown.
pub fn write_study_tables(cases: &[StudyCase], csv: &Path, md: &Path) -> Result<(), PostError> {
    let table = study_table(cases);
    table.write_csv(csv)?;
    table.write_markdown(md)
}

/// Per-grid lines of every quantity: quantity, h (mm), DOFs, value, relative
/// error against the finest-triplet Richardson extrapolation, GCI, the
/// least-squares uncertainty (relative), wall time (s).
pub fn convergence_table(studies: &[ConvergenceStudy]) -> Table {
    let columns = [
        "quantity",
        "h_mm",
        "dofs",
        "value",
        "rel_error_vs_extrapolated",
        "gci",
        "uncertainty",
        "wall_time_s",
    ]
    .map(String::from)
    .to_vec();
    let mut rows = Vec::new();
    for s in studies {
        for r in s.rows() {
            rows.push(vec![
                Cell::Text(s.quantity.clone()),
                Cell::Num(r.h * 1e3),
                r.dofs.into(),
                Cell::Num(r.value),
                r.rel_error_vs_extrapolated.into(),
                r.gci.into(),
                r.uncertainty.into(),
                r.wall_time.into(),
            ]);
        }
    }
    Table { columns, rows }
}

/// One line per triplet of every quantity (finest triplet first): the grid
/// sizes, behaviour, observed order, extrapolated value, e_a^21, e_ext^21,
/// GCI_fine^21.
pub fn convergence_order_table(studies: &[ConvergenceStudy]) -> Table {
    let columns = [
        "quantity",
        "h_mm",
        "behaviour",
        "order_p",
        "extrapolated",
        "e_a21",
        "e_ext21",
        "gci_fine21",
    ]
    .map(String::from)
    .to_vec();
    let mut rows = Vec::new();
    for s in studies {
        for t in &s.triplets {
            let hs: Vec<String> = t.h.iter().map(|h| significant(h * 1e3, 4)).collect();
            rows.push(vec![
                Cell::Text(s.quantity.clone()),
                Cell::Text(hs.join(" / ")),
                Cell::Text(t.kind.as_str().into()),
                t.order.into(),
                t.extrapolated.into(),
                t.approx_rel_error.into(),
                t.extrap_rel_error.into(),
                t.gci_fine.into(),
            ]);
        }
    }
    Table { columns, rows }
}

/// One line per quantity with four grids or more: the least-squares fit the
/// uncertainty comes from, its order, extrapolated value, standard
/// deviation, data range, safety factor and the finest grid's uncertainty
/// (absolute and relative).
pub fn uncertainty_table(studies: &[ConvergenceStudy]) -> Table {
    let columns = [
        "quantity",
        "fit",
        "order_p",
        "extrapolated",
        "std_dev",
        "data_range",
        "safety_factor",
        "u_finest",
        "u_finest_rel",
    ]
    .map(String::from)
    .to_vec();
    let rows = studies
        .iter()
        .filter_map(|s| {
            let e = s.least_squares.as_ref()?;
            let fit = format!(
                "{}{}",
                e.fit.as_str(),
                if e.weighted { ", weighted" } else { "" }
            );
            Some(vec![
                Cell::Text(s.quantity.clone()),
                Cell::Text(fit),
                e.order.into(),
                Cell::Num(e.extrapolated),
                Cell::Num(e.standard_deviation),
                Cell::Num(e.data_range),
                Cell::Num(e.safety_factor),
                Cell::Num(e.uncertainty[0]),
                e.relative(0, s.grids[0].value).into(),
            ])
        })
        .collect();
    Table { columns, rows }
}

/// Writes [`convergence_table`] as CSV, and the Markdown of
/// [`convergence_markdown`].
pub fn write_convergence_tables(
    studies: &[ConvergenceStudy],
    csv: &Path,
    md: &Path,
) -> Result<(), PostError> {
    convergence_table(studies).write_csv(csv)?;
    write_atomic(md, convergence_markdown(studies).as_bytes())
}

/// The Markdown of [`write_convergence_tables`]: the per-grid table,
/// [`convergence_order_table`] and, from four grids on,
/// [`uncertainty_table`], each under its heading.
pub fn convergence_markdown(studies: &[ConvergenceStudy]) -> String {
    let mut markdown = format!(
        "## Grids\n\nErrors, GCI and uncertainty are fractions of the value (0.01 is 1 %; \
         the study's console line gives them in percent); the error is against the \
         Richardson extrapolation of the three finest grids, the uncertainty is the \
         least-squares estimate of all grids (below).\n\n{}\n## Observed order and \
         extrapolation (Celik et al. 2008, safety factor 1.25)\n\n{}",
        convergence_table(studies).to_markdown(),
        convergence_order_table(studies).to_markdown()
    );
    let uncertainty = uncertainty_table(studies);
    if !uncertainty.rows.is_empty() {
        markdown.push_str(&format!(
            "\n## Uncertainty from all grids (least squares after Eça & Hoekstra 2014)\n\n\
             The fit of the error estimate, its order p (of the fit a h^p, blank where no \
             positive order fits; a fixed-order fit is taken where p < 0.5), the value \
             at h = 0, the fit's standard deviation σ, the data range Δ, the safety \
             factor (1.25 where 0.5 ≤ p < 2.1 and σ < Δ, 3 otherwise) and the finest \
             grid's uncertainty U, in the quantity's unit and relative.\n\n{}",
            uncertainty.to_markdown()
        ));
    }
    markdown
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_labels_are_the_shortest_unique_suffixes() {
        let keys = [
            "materials.interface.ft",
            "materials.concrete.ft",
            "materials.interface.mu",
            "mesh.h_interface",
        ];
        let labels: Vec<&str> = keys.iter().map(|k| short_key(k, &keys)).collect();
        assert_eq!(labels, ["interface.ft", "concrete.ft", "mu", "h_interface"]);
        assert_eq!(short_key("a.b", &["a.b", "b"]), "a.b");
        let v = |t: &str| serde_yaml::Value::String(t.into());
        let parameters = [
            ("materials.interface.ft".to_string(), v("2 MPa")),
            ("materials.concrete.ft".to_string(), v("3 MPa")),
            ("materials.interface.mu".to_string(), v("0.3")),
        ];
        assert_eq!(
            parameters_label(&parameters),
            "interface.ft=2 MPa, concrete.ft=3 MPa, mu=0.3"
        );
    }

    #[test]
    fn a_whole_law_as_a_parameter_reads_on_one_line() {
        let v: serde_yaml::Value =
            serde_yaml::from_str("{law: tvergaard, ft: 1.8 MPa, delta_s: 0.3}").unwrap();
        assert_eq!(value_label(&v), "law: tvergaard, ft: 1.8 MPa, delta_s: 0.3");
        assert_eq!(Cell::from(&v), Cell::Text(value_label(&v)));
        let q: serde_yaml::Value = serde_yaml::from_str("[1, 2.5]").unwrap();
        assert_eq!(value_label(&q), "[1, 2.5]");
    }
}
