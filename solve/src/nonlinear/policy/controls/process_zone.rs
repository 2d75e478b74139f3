//! Process-zone control (`solver.path_following: process_zone`): once
//! interface points soften, each step prescribes how far the jumps of the
//! points that softened in the last step move on along their last
//! increments (their r.m.s. over the zone, m), and λ is an unknown: a local
//! arc-length (Geers, IJNME 46, 1999) that follows snap-backs in λ and in
//! the FED, and bounds the zone's jump increments, on which the IMPL-EX
//! interface's error depends.

use super::super::state::{PathView, Rules, Steps};
use super::displacement;
use super::landing::landing;
use super::plan::{Plan, Zone};
use crate::assembly::{ElementLaws, States};
use crate::elements::interface::INTERFACE_POINTS;
use crate::nonlinear::control::{ControlMode, Quantity};
use crate::nonlinear::problem::Dirichlet;
use mesh::Model;

/// Process-zone control takes over after a displacement step in which λ
/// grew and interface points softened (unless a load jump paused it), the
/// step converted by the zone's move over Δλ; it hands back to
/// displacement control after a step in which no point softened, at the
/// last step's |Δλ|.
pub fn take_over_or_hand_back(
    steps: &mut Steps,
    view: &PathView,
    zone: Option<Zone>,
    rules: &Rules,
) {
    let dl = view.lambda_increment;
    match (zone, steps.mode) {
        (Some(zone), ControlMode::Displacement) if dl > 0.0 && !steps.zone_paused => {
            steps.mode = ControlMode::ProcessZone;
            steps.next *= zone.moved / dl;
        }
        (None, ControlMode::ProcessZone) => {
            // No point softened in the last step: nothing for the zone's
            // constraint to hold; λ takes the steps again.
            steps.mode = ControlMode::Displacement;
            steps.next = displacement::lambda_step(view, rules.loading);
        }
        _ => {}
    }
}

/// A process-zone step: the zone's quantity `steps.next` further.
pub fn plan(steps: &Steps, view: &PathView, zone: Zone, rules: &Rules) -> Plan {
    let size = steps.next;
    let scale = size / zone.moved;
    landing(view, scale, rules).unwrap_or(Plan {
        mode: ControlMode::ProcessZone,
        size,
        target: zone.value + size,
        scale,
    })
}

/// The process zone's jump quantity and its value for the last increment
/// `du` (m), `None` when no interface point softened in the last step
/// (`states`: the committed ones). The zone is the node pairs whose λ̃ grew
/// in it; each pair's jump counts along its last increment Δ[u]_p, scaled
/// so that the quantity moves by the r.m.s. of |Δ[u]_p| over the zone
/// (pairs weighted by their area) in a step that repeats the last one:
/// q(u) = Σ_p w_p Δ[u]_p·[u]_p / (W · rms). The pairs moving fastest weigh
/// most; pairs outside the zone are free, and so is λ.
pub(crate) fn quantity(
    model: &Model,
    laws: &ElementLaws,
    states: &States,
    du: &[f64],
    dofs: &crate::assembly::DofMap,
    dirichlet: &Dirichlet,
) -> Option<(Quantity, f64)> {
    if du.is_empty() {
        return None;
    }
    let mut dense = vec![0.0; du.len()];
    let (mut area, mut squares) = (0.0, 0.0);
    for (e, (element, law)) in model.interfaces.iter().zip(&laws.interfaces).enumerate() {
        if law.is_none() {
            continue;
        }
        let weight = element.area / INTERFACE_POINTS as f64;
        for a in 0..INTERFACE_POINTS {
            if states.interface[e * INTERFACE_POINTS + a].lambda_increment <= 0.0 {
                continue;
            }
            let (s, c) = (
                3 * element.nodes[a] as usize,
                3 * element.nodes[a + INTERFACE_POINTS] as usize,
            );
            area += weight;
            for k in 0..3 {
                let jump = du[c + k] - du[s + k];
                squares += weight * jump * jump;
                dense[c + k] += weight * jump;
                dense[s + k] -= weight * jump;
            }
        }
    }
    if squares <= 0.0 || !squares.is_finite() {
        return None;
    }
    let rms = (squares / area).sqrt();
    let norm = area * rms;
    dense.iter_mut().for_each(|w| *w /= norm);
    Some((Quantity::from_dense(&dense, dofs, dirichlet), rms))
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::spec::solver::{PathFollowing, SolverSettings};

    /// The zone's control starts after a displacement step that grew λ and
    /// softened points (its step the zone's move scaled to the planned
    /// Δλ), not while a load jump pauses it, and hands back at the last
    /// |Δλ| when no point softened.
    #[test]
    fn the_zone_takes_over_when_points_soften_and_hands_back_when_none_do() {
        let loading = loading();
        let settings = SolverSettings {
            path_following: PathFollowing::ProcessZone,
            ..SolverSettings::default()
        };
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        let rows = [row(1, 1e-5, 10.0)];
        let v = view(&rows, [0.0, 0.0], [1e-5, 10.0]);
        let zone = Zone {
            value: 3e-6,
            moved: 2e-6,
        };
        let mut steps = Steps {
            next: 1e-5,
            ..Steps::start(&loading)
        };
        take_over_or_hand_back(&mut steps, &v, Some(zone), &rules);
        assert_eq!(steps.mode, ControlMode::ProcessZone);
        assert!((steps.next - 2e-6).abs() < 1e-18);
        let p = plan(&steps, &v, zone, &rules);
        assert_eq!((p.mode, p.scale), (ControlMode::ProcessZone, 1.0));
        assert!((p.target - 5e-6).abs() < 1e-18);
        take_over_or_hand_back(&mut steps, &v, None, &rules);
        assert_eq!(steps.mode, ControlMode::Displacement);
        assert!((steps.next - 1e-5).abs() < 1e-18);
        let mut paused = Steps {
            zone_paused: true,
            ..Steps::start(&loading)
        };
        take_over_or_hand_back(&mut paused, &v, Some(zone), &rules);
        assert_eq!(paused.mode, ControlMode::Displacement);
    }
}
