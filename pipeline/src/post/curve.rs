//! Reading the solver's `curve.csv` (its format: `solve::curve`).

use super::error::PostError;
use solve::curve::CurveCsvError;
pub use solve::curve::{CurveRow, CURVE_COLUMNS};
use std::path::Path;

/// Reads `curve.csv`; errors name the file and the 1-based line.
pub fn read_curve_csv(path: &Path) -> Result<Vec<CurveRow>, PostError> {
    let text = std::fs::read_to_string(path).map_err(|source| PostError::Io {
        action: "reading",
        path: path.to_path_buf(),
        source,
    })?;
    parse_curve_csv(&text, path)
}

/// Parses the text of a `curve.csv` (`solve::curve::parse_curve_csv`);
/// `path` is only used in error messages.
pub fn parse_curve_csv(text: &str, path: &Path) -> Result<Vec<CurveRow>, PostError> {
    let path = path.to_path_buf();
    solve::curve::parse_curve_csv(text).map_err(|e| match e {
        CurveCsvError::MissingColumn { column, expected } => PostError::MissingColumn {
            path,
            column,
            expected,
        },
        CurveCsvError::FieldCount {
            line,
            expected,
            found,
        } => PostError::FieldCount {
            path,
            line,
            expected,
            found,
        },
        CurveCsvError::BadValue {
            line,
            column,
            value,
            kind,
        } => PostError::BadValue {
            path,
            line,
            column,
            value,
            kind,
        },
        CurveCsvError::Empty => PostError::EmptyCsv { path },
    })
}
