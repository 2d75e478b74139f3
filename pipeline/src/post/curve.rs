//! Reading the solver's `curve.csv`.

use super::PostError;
use std::path::Path;

/// Columns every `curve.csv` carries, in this order; more may follow and are
/// ignored here.
pub const CURVE_COLUMNS: [&str; 6] = [
    "step",
    "u_imposed",
    "force",
    "fed",
    "bond_stress",
    "iterations",
];

/// One converged load step of a pull-out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveRow {
    /// Load step number (counts converged steps).
    pub step: u64,
    /// Imposed displacement at the loaded end, m.
    pub u_imposed: f64,
    /// Pull-out force (reaction at the loaded end), N.
    pub force: f64,
    /// Free-end displacement (slip of the unloaded bar end), m.
    pub fed: f64,
    /// Mean bond stress σ_mb = F / (π d l_b), Pa.
    pub bond_stress: f64,
    /// Newton iterations taken by this step.
    pub iterations: u64,
}

impl CurveRow {
    /// A row from its fields in `curve.csv` order (m, N, m, Pa).
    pub fn new(
        step: u64,
        u_imposed: f64,
        force: f64,
        fed: f64,
        bond_stress: f64,
        iterations: u64,
    ) -> Self {
        CurveRow {
            step,
            u_imposed,
            force,
            fed,
            bond_stress,
            iterations,
        }
    }
}

/// Reads `curve.csv`; errors name the file and the 1-based line.
pub fn read_curve_csv(path: &Path) -> Result<Vec<CurveRow>, PostError> {
    let text = std::fs::read_to_string(path).map_err(|source| PostError::Io {
        action: "reading",
        path: path.to_path_buf(),
        source,
    })?;
    parse_curve_csv(&text, path)
}

/// Parses the text of a `curve.csv`; `path` is only used in error messages.
///
/// Columns are found by header name, so extra columns (anywhere) are allowed.
/// Blank lines and lines starting with `#` are skipped. Every number must be
/// finite: a NaN in a curve is a solver failure that must not be plotted.
pub fn parse_curve_csv(text: &str, path: &Path) -> Result<Vec<CurveRow>, PostError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(PostError::EmptyCsv {
            path: path.to_path_buf(),
        });
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut index = [0usize; 6];
    for (slot, column) in index.iter_mut().zip(CURVE_COLUMNS) {
        *slot =
            names
                .iter()
                .position(|n| *n == column)
                .ok_or_else(|| PostError::MissingColumn {
                    path: path.to_path_buf(),
                    column,
                    expected: CURVE_COLUMNS.join(","),
                })?;
    }

    let mut rows = Vec::new();
    for (line, content) in lines {
        let fields: Vec<&str> = content.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(PostError::FieldCount {
                path: path.to_path_buf(),
                line,
                expected: names.len(),
                found: fields.len(),
            });
        }
        let int = |k: usize| -> Result<u64, PostError> {
            let v = fields[index[k]];
            v.parse::<u64>().map_err(|_| PostError::BadValue {
                path: path.to_path_buf(),
                line,
                column: CURVE_COLUMNS[k],
                value: v.to_string(),
                kind: "a non-negative integer",
            })
        };
        let real = |k: usize| -> Result<f64, PostError> {
            let v = fields[index[k]];
            match v.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(PostError::BadValue {
                    path: path.to_path_buf(),
                    line,
                    column: CURVE_COLUMNS[k],
                    value: v.to_string(),
                    kind: "a finite number",
                }),
            }
        };
        rows.push(CurveRow {
            step: int(0)?,
            u_imposed: real(1)?,
            force: real(2)?,
            fed: real(3)?,
            bond_stress: real(4)?,
            iterations: int(5)?,
        });
    }
    if rows.is_empty() {
        return Err(PostError::EmptyCsv {
            path: path.to_path_buf(),
        });
    }
    Ok(rows)
}
