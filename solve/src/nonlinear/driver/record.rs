//! What the driver hands out of a run: the summary's wall times and
//! reports, the checkpoint of its state, and its result so far.

use super::setup::Driver;
use crate::nonlinear::checkpoint::{Checkpoint, PreconditionerState, RunState};
use crate::nonlinear::report::RunResult;
use crate::nonlinear::summary::{CheckOff, Ending};
use crate::spec::solver::LinearSolverKind;

impl Driver<'_> {
    /// Brings the summary up to date: this invocation's wall times added to
    /// the run's so far, the peak memory, the interface holds' first step
    /// and the checks that were off.
    pub(crate) fn finish(&self, state: &mut RunState) {
        let summary = &mut state.summary;
        let mut w = self.previous_wall;
        let mut now = self.wall;
        now.total = self.started.elapsed().as_secs_f64();
        w.add(&now);
        summary.wall_time_s = w;
        // A resumed run reports the larger of its invocations' peaks.
        if let Some(rss) = peak_resident_mib() {
            summary.peak_rss_mib = summary.peak_rss_mib.max(rss);
        }
        summary.interface_holds_from_step = state.policy.holds_from_step;
        summary.checks_off = self.checks_off();
    }

    /// The checks of the policy that are off in this run, from which step
    /// and why.
    fn checks_off(&self) -> Vec<CheckOff> {
        let energy = |from_step, why: String| CheckOff {
            check: "energy".into(),
            from_step,
            why,
        };
        let explicit_tets = self.explicit.iter().filter(|&&e| e).count();
        if explicit_tets > 0 || self.explicit_interface {
            let what = match (explicit_tets, self.explicit_interface) {
                (0, _) => "the interface points are".to_string(),
                (n, false) => format!("{n} tets are"),
                (n, true) => format!("{n} tets and the interface points are"),
            };
            return vec![energy(
                1,
                format!(
                    "{what} integrated explicitly (IMPL-EX) for the whole run: their energy \
                     record carries the extrapolation's error, bounded by \
                     solver.impl_ex_tolerance, not a sign of a state off the path"
                ),
            )];
        }
        if self.settings.dissipation_tolerance == 0.0 {
            return vec![energy(
                1,
                "solver.expert.dissipation_tolerance is 0".to_string(),
            )];
        }
        match &self.energy {
            Err(why) => vec![energy(
                first_step_of(why),
                format!("the energy record is not available: {why}"),
            )],
            Ok(_) => Vec::new(),
        }
    }

    /// The checkpoint of the run's state `state`, with the kept
    /// preconditioner and the energy record.
    pub(crate) fn checkpoint(&self, state: &RunState) -> Checkpoint {
        let model = self.problem.model;
        let lin = &self.ws.lin;
        Checkpoint {
            n_nodes: model.nodes.len(),
            n_tets: model.tets.len(),
            n_interfaces: model.interfaces.len(),
            state: state.clone(),
            preconditioner: (self.settings.linear_solver != LinearSolverKind::Cholesky
                && lin.kept.is_ready())
            .then(|| PreconditionerState {
                values: lin.preconditioner.clone(),
                refactor: lin.refactor,
                wear: lin.wear,
            }),
            energy: self.energy_rows().unwrap_or_default(),
            record: Default::default(),
        }
    }

    /// The run's result so far, with the state to resume from.
    pub(crate) fn partial(&self, mut state: RunState) -> Box<RunResult> {
        self.finish(&mut state);
        let last = self.checkpoint(&state);
        Box::new(RunResult {
            rows: state.path.rows,
            summary: state.summary,
            last,
            ending: Ending::Completed,
            energy: self.energy_rows(),
        })
    }
}

/// The step an energy record's error names ("step 12: …", "going back to
/// step 3: …"), 1 if none.
fn first_step_of(why: &str) -> usize {
    why.split_once("step ")
        .map(|(_, rest)| {
            rest.chars()
                .take_while(char::is_ascii_digit)
                .collect::<String>()
        })
        .and_then(|n| n.parse().ok())
        .unwrap_or(1)
}

/// The process's peak resident memory so far, MiB (Linux `VmHWM`); `None`
/// where /proc is not available.
fn peak_resident_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The step an energy record's error names is read back, else 1.
    #[test]
    fn the_first_step_without_an_energy_record_is_read_from_its_error() {
        assert_eq!(first_step_of("step 12: non-finite energy"), 12);
        assert_eq!(first_step_of("going back to step 3: x"), 3);
        assert_eq!(first_step_of("the checkpoint's record holds 2 rows"), 1);
    }
}
