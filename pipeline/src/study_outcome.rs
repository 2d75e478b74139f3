//! How each case of a study ended, as its row of the study table says it
//! (`status`, `ending`, `cause`, `log`), and the study's summary line: a
//! case that failed or stopped has its row, with the cause and its log,
//! instead of being left out of the table.

use crate::post::{Cell, StudyCase};
use crate::store::{RunOutcome, Store};
use std::path::{Path, PathBuf};

/// A case whose child process did not succeed.
#[derive(Debug, Clone)]
pub struct CaseFailure {
    /// The command that failed (`mesh`, `run`).
    pub command: String,
    /// The error the child reported last, if it reported one.
    pub cause: Option<String>,
    pub log: PathBuf,
}

impl CaseFailure {
    /// `run failed: <cause> (log <path>)`, for the study's output.
    pub fn describe(&self) -> String {
        match &self.cause {
            Some(e) => format!("{} failed: {e} (log {})", self.command, self.log.display()),
            None => format!("{} failed, see {}", self.command, self.log.display()),
        }
    }
}

/// How a case ended.
#[derive(Debug, Clone, PartialEq)]
pub enum CaseOutcome {
    /// The loading reached its end.
    Completed,
    /// The solve ended another way (`limit_load`, `brittle_failure`,
    /// `unloaded`): its curve is a result.
    Ended { ending: String },
    /// The solve stopped early (a stall, the step limit): the converged
    /// steps are kept.
    Stopped {
        reason: String,
        log: Option<PathBuf>,
    },
    /// A stage failed: no results.
    Failed {
        stage: String,
        cause: String,
        log: PathBuf,
    },
}

impl CaseOutcome {
    /// The outcome of the case `name` from its results folder and, when
    /// its child failed, that failure.
    pub fn of_case(work: &Path, name: &str, failure: Option<&CaseFailure>) -> CaseOutcome {
        let store = Store::new(work);
        let run = store.read_record(name).ok().flatten().and_then(|r| r.run);
        if let Some(f) = failure {
            return match run.map(|r| r.outcome) {
                Some(RunOutcome::Stopped { reason }) => CaseOutcome::Stopped {
                    reason,
                    log: Some(f.log.clone()),
                },
                outcome => CaseOutcome::Failed {
                    stage: match outcome {
                        Some(RunOutcome::Failed { stage, .. }) => stage,
                        _ => f.command.clone(),
                    },
                    cause: f
                        .cause
                        .clone()
                        .unwrap_or_else(|| "no error reported".into()),
                    log: f.log.clone(),
                },
            };
        }
        let solve_json = work.join(name).join("solve.json");
        let solve: Option<serde_json::Value> =
            geom::fsutil::read_capped(&solve_json, geom::fsutil::MAX_RECORD_BYTES)
                .ok()
                .and_then(|text| serde_json::from_str(&text).ok());
        let Some(solve) = solve else {
            return CaseOutcome::Failed {
                stage: "solve".into(),
                cause: "no solve.json in its results folder".into(),
                log: PathBuf::new(),
            };
        };
        if solve.get("completed").and_then(|v| v.as_bool()) == Some(false) {
            return CaseOutcome::Stopped {
                reason: solve
                    .get("stopped")
                    .and_then(|v| v.as_str())
                    .unwrap_or("unknown")
                    .to_string(),
                log: None,
            };
        }
        match solve.pointer("/ending/kind").and_then(|v| v.as_str()) {
            None | Some("completed") => CaseOutcome::Completed,
            Some(kind) => CaseOutcome::Ended {
                ending: kind.to_string(),
            },
        }
    }

    /// `completed`, `ended`, `stopped` or `failed`.
    pub fn status(&self) -> &'static str {
        match self {
            CaseOutcome::Completed => "completed",
            CaseOutcome::Ended { .. } => "ended",
            CaseOutcome::Stopped { .. } => "stopped",
            CaseOutcome::Failed { .. } => "failed",
        }
    }

    /// Whether the case has a curve to tabulate.
    pub fn has_results(&self) -> bool {
        !matches!(self, CaseOutcome::Failed { .. })
    }

    /// The table columns `status`, `ending`, `cause`, `log`.
    pub fn entries(&self) -> Vec<(String, Cell)> {
        let (ending, cause, log): (Cell, Cell, Option<&PathBuf>) = match self {
            CaseOutcome::Completed => ("completed".into(), Cell::Empty, None),
            CaseOutcome::Ended { ending } => (ending.as_str().into(), Cell::Empty, None),
            CaseOutcome::Stopped { reason, log } => {
                ("stopped".into(), reason.as_str().into(), log.as_ref())
            }
            CaseOutcome::Failed { stage, cause, log } => (
                format!("failed in {stage}").into(),
                cause.as_str().into(),
                Some(log),
            ),
        };
        let log = log
            .filter(|p| !p.as_os_str().is_empty())
            .map_or(Cell::Empty, |p| p.display().to_string().into());
        vec![
            ("status".to_string(), self.status().into()),
            ("ending".to_string(), ending),
            ("cause".to_string(), cause),
            ("log".to_string(), log),
        ]
    }

    /// Puts the outcome's columns first among the case's summary columns.
    pub fn prepend_to(&self, case: &mut StudyCase) {
        let mut entries = self.entries();
        entries.append(&mut case.summary);
        case.summary = entries;
    }
}

/// `study S: N cases: a completed, b ended otherwise (…), c stopped, d failed`.
pub fn summary_line(study: &str, outcomes: &[CaseOutcome]) -> String {
    let count = |status: &str| outcomes.iter().filter(|o| o.status() == status).count();
    let mut endings: Vec<String> = Vec::new();
    for o in outcomes {
        if let CaseOutcome::Ended { ending } = o {
            if !endings.contains(ending) {
                endings.push(ending.clone());
            }
        }
    }
    let endings: Vec<String> = endings
        .iter()
        .map(|e| {
            let n = outcomes
                .iter()
                .filter(|o| matches!(o, CaseOutcome::Ended { ending } if ending == e))
                .count();
            format!("{n} {}", e.replace('_', " "))
        })
        .collect();
    let ended = if endings.is_empty() {
        format!("{} ended otherwise", count("ended"))
    } else {
        format!(
            "{} ended otherwise ({})",
            count("ended"),
            endings.join(", ")
        )
    };
    format!(
        "study {study}: {} cases: {} completed, {ended}, {} stopped, {} failed",
        outcomes.len(),
        count("completed"),
        count("stopped"),
        count("failed")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The summary line counts each status and names the endings.
    #[test]
    fn the_summary_line_counts_every_status() {
        let outcomes = [
            CaseOutcome::Completed,
            CaseOutcome::Ended {
                ending: "brittle_failure".into(),
            },
            CaseOutcome::Ended {
                ending: "brittle_failure".into(),
            },
            CaseOutcome::Stopped {
                reason: "step 3 did not converge".into(),
                log: None,
            },
            CaseOutcome::Failed {
                stage: "mesh".into(),
                cause: "gmsh".into(),
                log: PathBuf::from("logs/s--4.mesh.log"),
            },
        ];
        assert_eq!(
            summary_line("s", &outcomes),
            "study s: 5 cases: 1 completed, 2 ended otherwise (2 brittle failure), 1 stopped, 1 failed"
        );
        let failed = outcomes[4].entries();
        assert_eq!(failed[0], ("status".into(), "failed".into()));
        assert_eq!(failed[1].1, "failed in mesh".into());
        assert_eq!(failed[3].1, "logs/s--4.mesh.log".into());
    }
}
