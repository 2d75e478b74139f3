//! The damage passes and interface holds of a retried step (the
//! remedies of `policy::remedies`): the machinery that settles the points
//! a retry treated apart, and hands them back to their laws at the commit.

use super::control::Control;
use super::failure::{NotConverged, RegimeChanges};
use super::newton::Attempt;
use super::policy::remedies::{DAMAGE_PASSES, DAMAGE_SETTLED};
use super::summary::Summary;
use super::workspace::Workspace;
use crate::assembly::{AssemblyError, Outputs, States, System, Tangents};
use crate::laws::{HeldHistory, TangentKind};
use crate::linalg::norm;

/// An iterate of a step: its displacement, the step's size (in its
/// control's unit) and the control that holds it.
pub(crate) struct Iterate<'a> {
    pub(crate) u: Vec<f64>,
    pub(crate) size: f64,
    pub(crate) control: Control<'a>,
}

/// The points a retry treats apart: tets made explicit for the step, and
/// interface points held at a history.
#[derive(Debug, Default)]
pub(crate) struct Retried {
    pub(crate) tets: Vec<usize>,
    pub(crate) held: Vec<(usize, HeldHistory)>,
}

impl Retried {
    pub(crate) fn is_empty(&self) -> bool {
        self.tets.is_empty() && self.held.is_empty()
    }

    /// How many of `flipping` (tets of a failed attempt, the run's explicit
    /// ones excluded by `explicit`) are not explicit for the step yet.
    pub(crate) fn new_tets(&self, flipping: &[usize], explicit: &[bool]) -> usize {
        flipping
            .iter()
            .filter(|&&i| !explicit[i] && self.tets.binary_search(&i).is_err())
            .collect::<std::collections::BTreeSet<_>>()
            .len()
    }

    /// Makes `flipping`'s tets (but the run's explicit ones) explicit for
    /// the step.
    pub(crate) fn add_tets(&mut self, flipping: &[usize], explicit: &[bool]) {
        self.tets.extend(flipping.iter().filter(|&&i| !explicit[i]));
        self.tets.sort_unstable();
        self.tets.dedup();
    }

    /// How many of the interface points `flipping` are not held yet.
    pub(crate) fn new_points(&self, flipping: &[usize]) -> usize {
        let known: std::collections::HashSet<usize> = self.held.iter().map(|&(j, _)| j).collect();
        flipping
            .iter()
            .filter(|i| !known.contains(i))
            .collect::<std::collections::HashSet<_>>()
            .len()
    }
}

/// Fixed-point passes on the damage of the tets Newton could not settle:
/// those a retry made explicit, and those that kept switching between
/// damage growing and not in an attempt that ended on its best iterate.
/// Each pass gives them the damage their implicit history reached at the
/// converged displacement (never less than the damage already used) and
/// solves again, until no such tet's damage grows by more than
/// `DAMAGE_SETTLED` and no other tet chatters. The damage used only
/// grows, so the passes cannot cycle as Newton's consistent iterates did;
/// once settled, the stress of every such tet is the one its committed
/// state gives, and the converged state is in equilibrium under the
/// implicit law on the stated criteria. Without the passes the
/// extrapolated damage of a tet passing its threshold lagged the implicit
/// one by so much that committed states were out of balance by up to 95 %
/// of the reaction (docs/src/validation/solver.md, "Law switches: the explicit retry").
/// The interface points held for the step (or that chattered in an
/// attempt ending on its best iterate) are settled by the same passes: each
/// pass holds them at the history their law reached at the converged jump,
/// and the passes end once the displacement is in balance with that,
/// where a held point's traction is its law's (`InterfaceLaw::held_step`).
/// Their history need not grow monotonically; the passes are bounded by
/// `DAMAGE_PASSES` all the same.
/// Returns the last attempt: a failed pass fails the step; a step whose
/// damage has not settled after `DAMAGE_PASSES` is kept, its residual
/// under the implicit damage reported like IMPL-EX's.
pub(crate) fn settle(
    ws: &mut Workspace<'_>,
    start: &mut States,
    retried: &mut Retried,
    iterate: &mut Iterate<'_>,
    mut attempt: Attempt,
    summary: &mut Summary,
) -> Attempt {
    let Retried {
        tets: flipped,
        held,
    } = retried;
    let mut settled = false;
    for _ in 0..DAMAGE_PASSES {
        let mut changed = false;
        if attempt.force_only {
            for &i in &attempt.flipping {
                if start.bulk[i].explicit_damage.is_none() {
                    let state = &mut start.bulk[i];
                    state.explicit_damage = Some(state.damage.max(ws.trial.bulk[i].damage));
                    flipped.push(i);
                    changed = true;
                }
            }
        }
        for &i in flipped.iter() {
            let implicit = ws.trial.bulk[i].damage;
            let state = &mut start.bulk[i];
            let used = state.explicit_damage.unwrap_or(state.damage);
            if implicit > used + DAMAGE_SETTLED {
                state.explicit_damage = Some(implicit);
                changed = true;
            }
        }
        if attempt.force_only {
            let added = hold_pairs(held, &attempt.flipping_pairs, &ws.trial);
            summary.held_interface_points += added;
            changed |= added > 0;
        }
        // A held point takes the history its law reached at the converged
        // jump; the balance check below then decides whether that moved
        // the equilibrium.
        changed |= rehold(held, start, &ws.trial);
        if !changed {
            settled = true;
            break;
        }
        // Often the converged displacement is already in balance under the
        // updated damage (it grew by little): one force evaluation then
        // spares a Newton solve. An attempt that ended on its best iterate
        // has not met the energy criterion: it gets the solve.
        let balanced = if attempt.force_only {
            Ok((false, f64::INFINITY))
        } else {
            in_balance(ws, start, iterate)
        };
        match balanced {
            Ok((true, _)) => {
                settled = true;
                break;
            }
            Ok((false, _)) => {}
            Err(source) => {
                let why = NotConverged::Constitutive {
                    in_line_search: false,
                    source,
                };
                attempt.failure = Some(why);
                break;
            }
        }
        let pass = ws.newton(start, &mut iterate.u, iterate.size, &mut iterate.control);
        summary.total_iterations += pass.iterations;
        summary.damage_passes += 1;
        let iterations = attempt.iterations + pass.iterations;
        attempt = Attempt { iterations, ..pass };
        if attempt.failure.is_some() {
            break;
        }
    }
    // Damage only grows, so unsettled tets leave a bounded residual, which
    // is reported; held points can wander, so theirs fails the attempt.
    if !settled && attempt.failure.is_none() && !held.is_empty() {
        rehold(held, start, &ws.trial);
        match in_balance(ws, start, iterate) {
            Ok((true, _)) => {}
            Ok((false, relative_residual)) => {
                attempt.failure = Some(NotConverged::Unsettled {
                    points: held.len(),
                    passes: DAMAGE_PASSES,
                    relative_residual,
                    regimes: RegimeChanges::between(start, &ws.trial),
                })
            }
            Err(source) => {
                attempt.failure = Some(NotConverged::Constitutive {
                    in_line_search: false,
                    source,
                })
            }
        }
    }
    flipped.sort_unstable();
    flipped.dedup();
    attempt
}

/// Holds each held point at the history its law reached in `trial` (at
/// the converged jump), in `held` and in `start`; whether any moved.
pub(crate) fn rehold(
    held: &mut [(usize, HeldHistory)],
    start: &mut States,
    trial: &States,
) -> bool {
    let mut moved = false;
    for (i, h) in held.iter_mut() {
        let implicit = HeldHistory::of(&trial.interface[*i]);
        if implicit != *h {
            *h = implicit;
            moved = true;
        }
        start.interface[*i].held = Some(*h);
    }
    moved
}

/// Hands the points a retry treated apart back to their laws. A tet made
/// explicit for this step only goes back to the implicit integration,
/// keeping the damage its stress used where that is the larger: the state
/// then matches the equilibrium just found, and the energy it released
/// stays dissipated. A held interface point likewise keeps the history its
/// implicit update reached (the hold's, once settled).
pub(crate) fn release_retried(committed: &mut States, explicit: &[bool]) {
    for (s, &always) in committed.bulk.iter_mut().zip(explicit) {
        if !always {
            if let Some(used) = s.explicit_damage.take() {
                s.damage = s.damage.max(used);
            }
        }
    }
    for s in &mut committed.interface {
        if let Some(h) = s.held.take() {
            s.damage = s.damage.max(h.damage);
        }
    }
}

/// Adds the interface points `flipping` not held yet to `held`, each held
/// at the history of its last iterate in `trial`; returns how many.
pub(crate) fn hold_pairs(
    held: &mut Vec<(usize, HeldHistory)>,
    flipping: &[usize],
    trial: &States,
) -> usize {
    let before = held.len();
    // At the paper's mesh tens of thousands of points flip in one iterate:
    // a scan of `held` per point would be quadratic.
    let mut known: std::collections::HashSet<usize> = held.iter().map(|&(j, _)| j).collect();
    for &i in flipping {
        if known.insert(i) {
            held.push((i, HeldHistory::of(&trial.interface[i])));
        }
    }
    held.len() - before
}

/// Whether `u` meets the force criterion (and the control's constraint)
/// from the start states `start`, and its relative residual; leaves the
/// trial states and internal forces of `u` in the workspace.
fn in_balance(
    ws: &mut Workspace<'_>,
    start: &States,
    iterate: &Iterate<'_>,
) -> Result<(bool, f64), AssemblyError> {
    let (u, control) = (&iterate.u, &iterate.control);
    let system: &System = ws.system;
    system.evaluate(
        ws.laws,
        u,
        start,
        &mut ws.trial,
        Tangents::all(TangentKind::Secant),
        Outputs::forces_of_stresses(&mut ws.f_int),
    )?;
    let mut r = vec![0.0; system.dofs().n_free()];
    ws.residual(&mut r);
    let scale = ws.force_scale();
    let tolerance = ws.settings.residual_tolerance;
    let held = match control {
        Control::Displacement => true,
        Control::Indirect(c) => {
            c.constraint.residual(u, c.lambda, &ws.f_int).abs()
                <= c.constraint.tolerance(tolerance, iterate.size)
        }
    };
    let relative = norm(&r) / scale;
    Ok((held && relative <= tolerance, relative))
}
