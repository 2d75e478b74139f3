//! The pull-out curve and its file, `curve.csv`: one row per converged
//! step, with the energy balance's columns after the curve's when the run
//! tracked it, and the IMPL-EX error of each step after those when every
//! step integrated points explicitly. The column names live here only;
//! files are written with them and read back by name, so columns may be
//! reordered or added.

use crate::energy::EnergyRow;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// One converged load step of a pull-out (SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    /// Load step number (counts converged steps).
    pub step: usize,
    /// Imposed displacement λ at the loaded end, m.
    pub u_imposed: f64,
    /// Pull-out force (reaction at the loaded end, whole specimen), N.
    pub force: f64,
    /// Free-end displacement (slip of the unloaded bar end), m.
    pub fed: f64,
    /// Mean bond stress σ_mb = F / (π d l_b), Pa.
    pub bond_stress: f64,
    /// Newton iterations of the converged attempt.
    pub iterations: usize,
    /// The step's IMPL-EX error indicator (relative residual of its state
    /// under the implicit history, the quantity `solver.impl_ex_tolerance`
    /// bounds); `None` in a run without explicitly integrated points.
    pub impl_ex_error: Option<f64>,
}

impl CurveRow {
    /// A row from its values in column order (m, N, m, Pa).
    pub fn new(
        step: usize,
        u_imposed: f64,
        force: f64,
        fed: f64,
        bond_stress: f64,
        iterations: usize,
    ) -> Self {
        CurveRow {
            step,
            u_imposed,
            force,
            fed,
            bond_stress,
            iterations,
            impl_ex_error: None,
        }
    }
}

/// The curve's columns, in the order they are written.
pub const CURVE_COLUMNS: [&str; 6] = [
    "step",
    "u_imposed",
    "force",
    "fed",
    "bond_stress",
    "iterations",
];

/// The energy balance's columns (J, whole specimen), after the curve's.
pub const ENERGY_COLUMNS: [&str; 4] = ["w_ext", "w_int", "stored", "dissipated"];

/// The column of each step's IMPL-EX error, last, written when every row
/// has one.
pub const IMPL_EX_ERROR_COLUMN: &str = "impl_ex_error";

/// The text of `curve.csv`; with `energy` (one row per curve row) the
/// energy columns follow, then the IMPL-EX error when every row has one.
/// Reals in shortest round-trip scientific notation.
pub fn write_curve_csv(rows: &[CurveRow], energy: Option<&[EnergyRow]>) -> String {
    let energy = energy.filter(|e| e.len() == rows.len());
    let impl_ex = !rows.is_empty() && rows.iter().all(|r| r.impl_ex_error.is_some());
    let mut header: Vec<&str> = CURVE_COLUMNS.to_vec();
    if energy.is_some() {
        header.extend(ENERGY_COLUMNS);
    }
    if impl_ex {
        header.push(IMPL_EX_ERROR_COLUMN);
    }
    let mut out = header.join(",");
    out.push('\n');
    for (i, r) in rows.iter().enumerate() {
        let _ = write!(
            out,
            "{},{:e},{:e},{:e},{:e},{}",
            r.step, r.u_imposed, r.force, r.fed, r.bond_stress, r.iterations
        );
        if let Some(e) = energy {
            let e = &e[i];
            let _ = write!(
                out,
                ",{:e},{:e},{:e},{:e}",
                e.w_ext, e.w_int, e.stored, e.dissipated
            );
        }
        if let (true, Some(e)) = (impl_ex, r.impl_ex_error) {
            let _ = write!(out, ",{e:e}");
        }
        out.push('\n');
    }
    out
}

/// What is wrong with a `curve.csv` text; lines are 1-based.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CurveCsvError {
    #[error("header lacks column `{column}` (expected at least {expected})")]
    MissingColumn {
        column: &'static str,
        expected: String,
    },
    #[error("line {line}: expected {expected} fields, found {found}")]
    FieldCount {
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("line {line}: column `{column}`: cannot read `{value}` as {kind}")]
    BadValue {
        line: usize,
        column: &'static str,
        value: String,
        kind: &'static str,
    },
    #[error("no data rows")]
    Empty,
}

/// Parses the text of a `curve.csv`.
///
/// Columns are found by header name, so extra columns (anywhere) are allowed.
/// Blank lines and lines starting with `#` are skipped. Every number must be
/// finite: a NaN in a curve is a solver failure that must not be plotted.
pub fn parse_curve_csv(text: &str) -> Result<Vec<CurveRow>, CurveCsvError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(CurveCsvError::Empty);
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut index = [0usize; CURVE_COLUMNS.len()];
    for (slot, column) in index.iter_mut().zip(CURVE_COLUMNS) {
        *slot = names.iter().position(|n| *n == column).ok_or_else(|| {
            CurveCsvError::MissingColumn {
                column,
                expected: CURVE_COLUMNS.join(","),
            }
        })?;
    }

    let impl_ex = names.iter().position(|n| *n == IMPL_EX_ERROR_COLUMN);

    let mut rows = Vec::new();
    for (line, content) in lines {
        let fields: Vec<&str> = content.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(CurveCsvError::FieldCount {
                line,
                expected: names.len(),
                found: fields.len(),
            });
        }
        let bad = |column, at: usize, kind| CurveCsvError::BadValue {
            line,
            column,
            value: fields[at].to_string(),
            kind,
        };
        let int = |k: usize| -> Result<usize, CurveCsvError> {
            fields[index[k]]
                .parse::<usize>()
                .map_err(|_| bad(CURVE_COLUMNS[k], index[k], "a non-negative integer"))
        };
        let finite = |column, at: usize| -> Result<f64, CurveCsvError> {
            match fields[at].parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(bad(column, at, "a finite number")),
            }
        };
        let real = |k: usize| finite(CURVE_COLUMNS[k], index[k]);
        let impl_ex_error = impl_ex
            .map(|at| finite(IMPL_EX_ERROR_COLUMN, at))
            .transpose()?;
        rows.push(CurveRow {
            step: int(0)?,
            u_imposed: real(1)?,
            force: real(2)?,
            fed: real(3)?,
            bond_stress: real(4)?,
            iterations: int(5)?,
            impl_ex_error,
        });
    }
    if rows.is_empty() {
        return Err(CurveCsvError::Empty);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What is written is read back exactly, with or without energies and
    /// IMPL-EX errors.
    #[test]
    fn written_curve_reads_back() {
        let implicit = vec![
            CurveRow::new(1, 1e-5, 120.5, 2.5e-6, 1.25e6, 4),
            CurveRow::new(2, 2.000000000000001e-5, 240.25, 5e-6, 2.5e6, 5),
        ];
        let mut explicit = implicit.clone();
        explicit[0].impl_ex_error = Some(3.25e-3);
        explicit[1].impl_ex_error = Some(0.0);
        let energy = vec![EnergyRow::default(); 2];
        for rows in [implicit, explicit] {
            for e in [None, Some(energy.as_slice())] {
                let text = write_curve_csv(&rows, e);
                assert_eq!(parse_curve_csv(&text).unwrap(), rows, "{text}");
                let header = text.lines().next().unwrap();
                assert_eq!(header.contains("w_ext"), e.is_some());
                assert_eq!(
                    header.ends_with(IMPL_EX_ERROR_COLUMN),
                    rows[0].impl_ex_error.is_some()
                );
            }
        }
    }

    /// A row without an IMPL-EX error leaves the column out rather than
    /// writing a value that is not there; a bad value is named.
    #[test]
    fn impl_ex_column_only_when_every_row_has_one() {
        let mut rows = vec![CurveRow::new(1, 1e-5, 1.0, 1e-6, 1e6, 1); 2];
        rows[0].impl_ex_error = Some(1e-2);
        assert!(!write_curve_csv(&rows, None).contains(IMPL_EX_ERROR_COLUMN));
        let text = "step,u_imposed,force,fed,bond_stress,iterations,impl_ex_error\n1,0,0,0,0,1,x\n";
        assert!(matches!(
            parse_curve_csv(text),
            Err(CurveCsvError::BadValue {
                column: IMPL_EX_ERROR_COLUMN,
                ..
            })
        ));
    }
}
