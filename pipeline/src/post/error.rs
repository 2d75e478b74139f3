use std::path::PathBuf;

/// Everything post-processing can refuse or fail at; each variant names the
/// file, line, field or input that is wrong.
#[derive(Debug, thiserror::Error)]
pub enum PostError {
    #[error("{action} {path}: {source}")]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: header lacks column `{column}` (expected at least {expected})")]
    MissingColumn {
        path: PathBuf,
        column: &'static str,
        expected: String,
    },
    #[error("{path}:{line}: expected {expected} fields, found {found}")]
    FieldCount {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("{path}:{line}: column `{column}`: cannot read `{value}` as {kind}")]
    BadValue {
        path: PathBuf,
        line: usize,
        column: &'static str,
        value: String,
        kind: &'static str,
    },
    #[error("{path}: no data rows")]
    EmptyCsv { path: PathBuf },
    #[error("{what}: {problem}")]
    InvalidInput { what: String, problem: String },
    #[error(
        "energy up to FED = {limit} m requested but the curve ends at FED = {final_fed} m \
         (max {max_fed} m)"
    )]
    FedLimitBeyondCurve {
        limit: f64,
        final_fed: f64,
        max_fed: f64,
    },
    #[error(
        "no TrueType font found for plot text (searched {searched}); \
         install the Debian package fonts-dejavu-core (apt-get install fonts-dejavu-core)"
    )]
    FontNotFound { searched: String },
    #[error("drawing {path}: {message}")]
    Plot { path: PathBuf, message: String },
    #[error("mesh convergence of `{quantity}`: {problem}")]
    Convergence { quantity: String, problem: String },
}

impl PostError {
    pub(crate) fn invalid(what: impl Into<String>, problem: impl Into<String>) -> Self {
        PostError::InvalidInput {
            what: what.into(),
            problem: problem.into(),
        }
    }
}
