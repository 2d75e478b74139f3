//! Energy balance of a displacement-controlled run (issue 7): the work of
//! the imposed displacement equals the internal work, and the internal work
//! splits into a recoverable (stored) part and a dissipated part that never
//! decreases.
//!
//! All energies are in J for the whole specimen (a quarter model's values
//! are multiplied by its force factor, as its forces are).
//!
//! * **External work** W_ext = ∫ F dλ, trapezoidal over the converged
//!   steps from (λ, F) = (0, 0). Every other constrained DOF is held at a
//!   fixed value, so the loaded end's reaction is the only force that works.
//! * **Internal work** W_int = Σ_steps Σ_points ½ (σ_old + σ_new)·(ε_new −
//!   ε_old) V, the same trapezoid on every tet (one point, weight V) and on
//!   every interface node pair (traction · jump in the local frame, weight
//!   A/3). Summed over elements this is ½ (f_old + f_new)·Δu over all DOFs,
//!   so W_ext − W_int is the work of the residual force left on the free
//!   DOFs by the Newton tolerance, plus any inconsistency between the
//!   solver's measured force and its element forces.
//! * **Stored energy** (recoverable on unloading to zero force), as each
//!   law reports it (`BulkLaw::stored_energy`, `InterfaceLaw::stored_energy`):
//!   - bulk: ½ σ·(ε − ε_p) V. Mazars σ = (1 − D) C ε (no permanent strain):
//!     ½ ε·C_sec·ε; J2 σ = C (ε − ε_p): ½ (ε − ε_p)·C·(ε − ε_p); elastic ½ σ·ε.
//!   - interface: secant cohesive laws (Tvergaard, elastic) ½ t·u; the FCZM
//!     (paper eq. 15) ½ [P_n K_n u_n² + P_s K_s |u_s|²]
//!     (undamaged part, P = (1 − D)β, (1 − D)α) + D [½ K_n ⟨u_n⟩₋² +
//!     ½ |τ|²/K_s] (damaged part: the compressive normal spring and the
//!     elastic part τ = K_s (u_s − s) of the friction spring) =
//!     ½ t·u − ½ D τ·s; Coulomb ½ t_n u_n + ½ |t_s|²/K_s.
//! * **Dissipated** = W_int − stored: damage (Mazars, FCZM λ̃), frictional
//!   and plastic slip (FCZM/Coulomb slip s: the work τ·Δs), steel plastic
//!   strain (σ·Δε_p). Exact for the continuous path, non-negative; with the
//!   trapezoid a damage increment dissipates ½ ΔD ε_old·C·ε_new (≥ 0 unless
//!   the strain turns by more than 90° within a step) and a plastic one
//!   ½ (σ_old + σ_new)·Δε_p.
//!
//! The FCZM's undamaged part is not derived from a potential: its shear
//! weight α depends on the normal stress (eq. 26) without damage growth, so
//! a path that changes u_n under shear in a damaged state can give back or
//! take energy that no damage or slip accounts for. [`EnergyCheck`] reports
//! the smallest dissipation increment so that such a path shows.

use crate::assembly::{ElementLaws, States};
use crate::elements::interface::{InterfaceKernel, INTERFACE_POINTS};
use crate::elements::tet::{ElementError, TetGeometry};
use crate::laws::{BulkLaw, BulkState, InterfaceLaw, LawError, TangentKind};
use mesh::Model;
use nalgebra::{Vector3, Vector6};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Tolerance of the energy check, relative to W_ext.
///
/// Newton stops at ‖r‖ ≤ tol_r ‖reactions‖ (1e-4 by default). The residual
/// work of a step is r·Δu over the free DOFs, bounded by ‖r‖ ‖Δu_free‖;
/// ‖Δu_free‖/Δλ grows like the square root of the number of moving DOFs
/// (≈ 10² for the meshes here), so the Cauchy–Schwarz bound of the relative
/// imbalance is ≈ 1e-4 · 10² = 1e-2 per step. Residuals have no sign
/// pattern and the measured imbalances are far smaller, but 1 % is the
/// bound the stopping criterion itself guarantees.
pub const ENERGY_TOLERANCE: f64 = 1e-2;

/// Points evaluated per parallel task: a fixed chunking keeps the sums'
/// order, hence their bits, independent of the thread count (resumed runs
/// reproduce uninterrupted ones exactly).
const CHUNK: usize = 4096;

/// Stress (Pa) and stored energy density (J/m³) of a bulk point at total
/// strain `strain` with committed state `state`: ½ σ·(ε − ε_p).
pub fn bulk_point(
    law: &dyn BulkLaw,
    state: &BulkState,
    strain: &Vector6<f64>,
) -> Result<(Vector6<f64>, f64), LawError> {
    let stress = law.stress(state, strain)?;
    Ok((stress, law.stored_energy(state, strain, &stress)))
}

/// Energies after a converged step, J (whole specimen).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct EnergyRow {
    /// External work ∫ F dλ.
    pub w_ext: f64,
    /// Internal work Σ ½ (σ_old + σ_new)·Δε V (+ interfaces).
    pub w_int: f64,
    /// Recoverable elastic energy.
    pub stored: f64,
    /// W_int − stored.
    pub dissipated: f64,
}

impl EnergyRow {
    fn is_finite(&self) -> bool {
        [self.w_ext, self.w_int, self.stored, self.dissipated]
            .iter()
            .all(|v| v.is_finite())
    }

    /// |W_ext − W_int| / W_ext: the share of the work the record leaves
    /// unbalanced (for W_ext > 0).
    pub fn relative_imbalance(&self) -> f64 {
        (self.w_ext - self.w_int).abs() / self.w_ext
    }

    /// dissipated / W_ext: the share of the work the record has dissipated,
    /// negative where it reports energy created.
    pub fn relative_dissipation(&self) -> f64 {
        self.dissipated / self.w_ext
    }

    /// (dissipated − `previous`'s dissipated) / W_ext: what the step added
    /// to the dissipated energy, negative where it gave some back.
    pub fn relative_dissipation_increment(&self, previous: &EnergyRow) -> f64 {
        (self.dissipated - previous.dissipated) / self.w_ext
    }

    /// Whether this step, after `previous`, keeps the measures of
    /// [`check`] within `tolerance`: the relative imbalance, the dissipated
    /// energy and its increment. A step with W_ext ≤ 0 has no scale and
    /// keeps them; a non-finite energy does not.
    pub fn keeps_check(&self, previous: &EnergyRow, tolerance: f64) -> bool {
        if !self.is_finite() {
            return false;
        }
        if self.w_ext <= 0.0 {
            return true;
        }
        self.relative_imbalance() <= tolerance
            && self.relative_dissipation_increment(previous) >= -tolerance
            && self.relative_dissipation() >= -tolerance
    }
}

/// The energy evaluation could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnergyError {
    #[error("energy: tet {tet}: {source}")]
    Geometry {
        tet: usize,
        #[source]
        source: ElementError,
    },
    #[error("energy: {what} {index}: {source}")]
    Law {
        what: &'static str,
        index: usize,
        #[source]
        source: LawError,
    },
    #[error("energy: {what} has {found} entries for a model needing {expected}")]
    Size {
        what: &'static str,
        found: usize,
        expected: usize,
    },
}

/// The converged state an energy record continues from.
pub struct EnergyStart<'s> {
    /// Displacement, m.
    pub u: &'s [f64],
    /// Committed integration-point states.
    pub states: &'s States,
    /// Energy rows of the steps before it.
    pub rows: Vec<EnergyRow>,
    /// Imposed displacement λ, m.
    pub lambda: f64,
    /// Force at λ (whole specimen), N.
    pub force: f64,
}

/// Accumulates the energies step by step (see the module doc).
pub struct EnergyTracker<'a> {
    model: &'a Model,
    laws: &'a ElementLaws,
    force_factor: f64,
    tets: Vec<TetGeometry>,
    kernels: Vec<InterfaceKernel>,
    rows: Vec<EnergyRow>,
    /// The last kept step, from which the next one's trapezoids start.
    old: Evaluated,
    /// The step of the last [`EnergyTracker::trial`], until it is
    /// accepted (it then becomes `old`) or another trial replaces it.
    trial: Evaluated,
    trial_row: Option<EnergyRow>,
}

/// One evaluated state: displacement, each point's stress or traction,
/// λ and the curve's force.
#[derive(Default)]
struct Evaluated {
    u: Vec<f64>,
    stress: Vec<[f64; 6]>,
    traction: Vec<[f64; 3]>,
    lambda: f64,
    force: f64,
}

impl<'a> EnergyTracker<'a> {
    /// A tracker at the unloaded state (u = 0, initial states).
    pub fn new(model: &'a Model, laws: &'a ElementLaws) -> Result<Self, EnergyError> {
        let u = vec![0.0; 3 * model.nodes.len()];
        let start = EnergyStart {
            u: &u,
            states: &States::initial(model),
            rows: Vec::new(),
            lambda: 0.0,
            force: 0.0,
        };
        Self::resume(model, laws, start)
    }

    /// A tracker continuing after the converged state `start`.
    pub fn resume(
        model: &'a Model,
        laws: &'a ElementLaws,
        start: EnergyStart<'_>,
    ) -> Result<Self, EnergyError> {
        let EnergyStart {
            u,
            states,
            rows,
            lambda,
            force,
        } = start;
        let tets = model
            .tets
            .iter()
            .enumerate()
            .map(|(i, t)| {
                TetGeometry::new(&t.map(|n| model.nodes[n as usize]))
                    .map_err(|source| EnergyError::Geometry { tet: i, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let kernels = model.interfaces.iter().map(InterfaceKernel::new).collect();
        let mut tracker = Self {
            model,
            laws,
            force_factor: model.symmetry.force_factor(),
            tets,
            kernels,
            rows,
            old: Evaluated {
                u: u.to_vec(),
                stress: vec![[0.0; 6]; model.tets.len()],
                traction: vec![[0.0; 3]; INTERFACE_POINTS * model.interfaces.len()],
                lambda,
                force,
            },
            trial: Evaluated::default(),
            trial_row: None,
        };
        tracker.check_sizes(u, states)?;
        // The old stresses of the next step: the converged state's own.
        tracker.sweep(u, states)?;
        tracker.take_trial_stresses();
        Ok(tracker)
    }

    /// Continues after the converged state `start` instead (a run that
    /// went back to an earlier step): its rows replace the tracker's.
    pub fn rewind(&mut self, start: EnergyStart<'_>) -> Result<(), EnergyError> {
        self.check_sizes(start.u, start.states)?;
        self.old.u = start.u.to_vec();
        self.old.lambda = start.lambda;
        self.old.force = start.force;
        self.rows = start.rows;
        self.sweep(start.u, start.states)?;
        self.take_trial_stresses();
        Ok(())
    }

    /// Makes the last sweep's stresses and tractions the old ones.
    fn take_trial_stresses(&mut self) {
        std::mem::swap(&mut self.old.stress, &mut self.trial.stress);
        std::mem::swap(&mut self.old.traction, &mut self.trial.traction);
        self.trial_row = None;
    }

    fn check_sizes(&self, u: &[f64], states: &States) -> Result<(), EnergyError> {
        let size = |what, found, expected| {
            if found == expected {
                Ok(())
            } else {
                Err(EnergyError::Size {
                    what,
                    found,
                    expected,
                })
            }
        };
        size("displacement", u.len(), 3 * self.model.nodes.len())?;
        size("bulk states", states.bulk.len(), self.model.tets.len())?;
        size(
            "interface states",
            states.interface.len(),
            INTERFACE_POINTS * self.model.interfaces.len(),
        )?;
        size("tet laws", self.laws.tets.len(), self.model.tets.len())?;
        size(
            "interface laws",
            self.laws.interfaces.len(),
            self.model.interfaces.len(),
        )
    }

    /// Evaluates every point at (`u`, `states`): returns (Σ trapezoid work
    /// from the stored old values, Σ stored energy), both on the model, and
    /// keeps the new stresses and tractions in the trial.
    fn sweep(&mut self, u: &[f64], states: &States) -> Result<(f64, f64), EnergyError> {
        let (model, laws, old) = (self.model, self.laws, &self.old);
        let u_old = &old.u;
        let tets = &self.tets;
        let trial = &mut self.trial;
        trial.stress.resize(old.stress.len(), [0.0; 6]);
        trial.traction.resize(old.traction.len(), [0.0; 3]);
        let bulk: Vec<Result<(f64, f64), EnergyError>> =
            trial
                .stress
                .par_chunks_mut(CHUNK)
                .zip(old.stress.par_chunks(CHUNK))
                .enumerate()
                .map(|(c, (chunk, olds))| {
                    let (mut work, mut stored) = (0.0, 0.0);
                    for (k, (new, old)) in chunk.iter_mut().zip(olds).enumerate() {
                        let i = c * CHUNK + k;
                        let nodes = model.tets[i];
                        let gather = |v: &[f64]| -> [f64; 12] {
                            std::array::from_fn(|j| v[3 * nodes[j / 3] as usize + j % 3])
                        };
                        let (eps, eps_old) =
                            (tets[i].strain(&gather(u)), tets[i].strain(&gather(u_old)));
                        let (sigma, psi) = bulk_point(&laws.tets[i], &states.bulk[i], &eps)
                            .map_err(|source| EnergyError::Law {
                                what: "tet",
                                index: i,
                                source,
                            })?;
                        let s_old = Vector6::from_column_slice(old);
                        let v = tets[i].volume;
                        work += 0.5 * (s_old + sigma).dot(&(eps - eps_old)) * v;
                        stored += psi * v;
                        new.copy_from_slice(sigma.as_slice());
                    }
                    Ok((work, stored))
                })
                .collect();
        let kernels = &self.kernels;
        let iface: Vec<Result<(f64, f64), EnergyError>> = trial
            .traction
            .par_chunks_mut(CHUNK * INTERFACE_POINTS)
            .zip(old.traction.par_chunks(CHUNK * INTERFACE_POINTS))
            .enumerate()
            .map(|(c, (chunk, old_chunk))| {
                let (mut work, mut stored) = (0.0, 0.0);
                for (k, (news, olds)) in chunk
                    .chunks_mut(INTERFACE_POINTS)
                    .zip(old_chunk.chunks(INTERFACE_POINTS))
                    .enumerate()
                {
                    let i = c * CHUNK + k;
                    let Some(law) = laws.interfaces[i].as_ref() else {
                        continue;
                    };
                    let kern = &kernels[i];
                    let states = &states.interface[INTERFACE_POINTS * i..];
                    let points = kern
                        .tractions(law, u, states, TangentKind::Secant)
                        .map_err(|e| EnergyError::Law {
                            what: "interface element",
                            index: i,
                            source: e.source,
                        })?;
                    let ue_old = kern.gather(u_old);
                    for (p, ((new, old), r)) in news.iter_mut().zip(olds).zip(&points).enumerate() {
                        let (jump, t) = (r.jump, r.law.traction);
                        let jump_old = kern.local_jump(&ue_old, p);
                        let psi = law.stored_energy(&states[p], &jump, &t);
                        let t_old = Vector3::from_column_slice(old);
                        work += 0.5 * (t_old + t).dot(&(jump - jump_old)) * kern.weight;
                        stored += psi * kern.weight;
                        new.copy_from_slice(t.as_slice());
                    }
                }
                Ok((work, stored))
            })
            .collect();
        let (mut work, mut stored) = (0.0, 0.0);
        for r in bulk.into_iter().chain(iface) {
            let (w, s) = r?;
            work += w;
            stored += s;
        }
        Ok((work, stored))
    }

    /// Adds a converged step: imposed displacement `lambda` (m), the
    /// curve's force `force` (N, whole specimen), the converged `u` and
    /// committed `states`.
    pub fn step(
        &mut self,
        lambda: f64,
        force: f64,
        u: &[f64],
        states: &States,
    ) -> Result<EnergyRow, EnergyError> {
        let row = self.trial(lambda, force, u, states)?;
        self.accept();
        Ok(row)
    }

    /// The energies the step to (`lambda`, `force`, `u`, `states`) would
    /// add, without adding it: [`EnergyTracker::accept`] does, and another
    /// trial replaces it (a step the solver rejects).
    pub fn trial(
        &mut self,
        lambda: f64,
        force: f64,
        u: &[f64],
        states: &States,
    ) -> Result<EnergyRow, EnergyError> {
        self.check_sizes(u, states)?;
        self.trial_row = None;
        let (work, stored) = self.sweep(u, states)?;
        let last = self.rows.last().copied().unwrap_or_default();
        let w_ext = last.w_ext + 0.5 * (self.old.force + force) * (lambda - self.old.lambda);
        let w_int = last.w_int + self.force_factor * work;
        let stored = self.force_factor * stored;
        let row = EnergyRow {
            w_ext,
            w_int,
            stored,
            dissipated: w_int - stored,
        };
        let trial = &mut self.trial;
        trial.u.clear();
        trial.u.extend_from_slice(u);
        (trial.lambda, trial.force) = (lambda, force);
        self.trial_row = Some(row);
        Ok(row)
    }

    /// Adds the last trial's step; without one, does nothing.
    pub fn accept(&mut self) {
        let Some(row) = self.trial_row.take() else {
            return;
        };
        std::mem::swap(&mut self.old, &mut self.trial);
        self.rows.push(row);
    }

    /// The rows of every step so far.
    pub fn rows(&self) -> &[EnergyRow] {
        &self.rows
    }
}

/// External work of a force–displacement curve from the origin, J:
/// trapezoidal Σ ½ (F_{k−1} + F_k)(λ_k − λ_{k−1}) with (λ, F) = (0, 0) first.
pub fn external_work(points: &[(f64, f64)]) -> Vec<f64> {
    let mut prev = (0.0, 0.0);
    let mut acc = 0.0;
    points
        .iter()
        .map(|&(l, f)| {
            acc += 0.5 * (prev.1 + f) * (l - prev.0);
            prev = (l, f);
            acc
        })
        .collect()
}

/// Outcome of the energy check over the converged steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnergyCheck {
    /// Tolerance relative to W_ext.
    pub tolerance: f64,
    /// max_k |W_ext − W_int| / W_ext over the steps with W_ext > 0.
    pub max_relative_imbalance: f64,
    /// Step (1-based) of that maximum, 0 without steps.
    pub step_of_max_imbalance: usize,
    /// min_k (dissipated_k − dissipated_{k−1}) / W_ext,k (0 without steps).
    pub min_dissipation_increment: f64,
    /// min_k dissipated_k / W_ext,k.
    pub min_dissipation: f64,
    /// Every measure within the tolerance.
    pub passed: bool,
    /// Steps checked.
    pub steps: usize,
}

/// Checks |W_ext − W_int| ≤ tol·W_ext, dissipated ≥ −tol·W_ext and
/// dissipated_k − dissipated_{k−1} ≥ −tol·W_ext at every step.
/// Steps with W_ext ≤ 0 (nothing loaded yet) have no scale and are skipped;
/// a non-finite energy fails the check.
pub fn check(rows: &[EnergyRow], tolerance: f64) -> EnergyCheck {
    let mut out = EnergyCheck {
        tolerance,
        max_relative_imbalance: 0.0,
        step_of_max_imbalance: 0,
        min_dissipation_increment: 0.0,
        min_dissipation: 0.0,
        passed: true,
        steps: rows.len(),
    };
    let mut prev = EnergyRow::default();
    for (k, r) in rows.iter().enumerate() {
        out.passed &= r.keeps_check(&prev, tolerance);
        if !r.is_finite() {
            out.max_relative_imbalance = f64::INFINITY;
            out.step_of_max_imbalance = k + 1;
            break;
        }
        if r.w_ext > 0.0 {
            let imbalance = r.relative_imbalance();
            if imbalance > out.max_relative_imbalance {
                out.max_relative_imbalance = imbalance;
                out.step_of_max_imbalance = k + 1;
            }
            out.min_dissipation_increment = out
                .min_dissipation_increment
                .min(r.relative_dissipation_increment(&prev));
            out.min_dissipation = out.min_dissipation.min(r.relative_dissipation());
        }
        prev = *r;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laws::fczm::{Fczm, DEFAULT_GAMMA};
    use crate::laws::j2::J2;
    use crate::laws::{InterfaceLaw, InterfaceState};
    use mesh::{Frame, InterfaceElement, InterfaceZone, Region};

    fn fczm() -> Fczm {
        Fczm {
            tensile_strength: 2e6,
            fracture_energy: 90.0,
            lambda0: 5e-5,
            delta_s: 0.5,
            friction: 0.3,
            zeta: 4.0,
            gamma: DEFAULT_GAMMA,
            min_damage: 0.0,
            contact_smoothing: 0.0,
        }
    }

    /// Drives one interface point along `path` (jumps) and returns the
    /// trapezoidal work and the final stored energy per area.
    fn drive(law: &Fczm, path: &[Vector3<f64>]) -> (f64, f64) {
        let (mut state, mut t_old, mut u_old) = (
            InterfaceState::default(),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        let mut work = 0.0;
        let mut stored = 0.0;
        for u in path {
            let r = law.step(&state, u, TangentKind::Secant).unwrap();
            state = r.state;
            let t = law.step(&state, u, TangentKind::Secant).unwrap().traction;
            let psi = law.stored_energy(&state, u, &t);
            work += 0.5 * (t + t_old).dot(&(u - u_old));
            (t_old, u_old, stored) = (t, *u, psi);
        }
        (work, stored)
    }

    fn ramp(from: Vector3<f64>, to: Vector3<f64>, n: usize) -> Vec<Vector3<f64>> {
        (1..=n)
            .map(|k| from + (to - from) * (k as f64 / n as f64))
            .collect()
    }

    /// FCZM pure opening to λ: the dissipated energy equals the closed form
    /// ½ f_t λ_0 + (f_t/c)(1 − q) − ½ q f_t λ with c = f_t/(ζ G_f), q = e^{−c(λ−λ_0)}
    /// (paper eqs. 22–25 with u_n ≥ 0: t_n = (1 − D) f_t beyond λ_0).
    #[test]
    fn fczm_opening_dissipation_matches_closed_form() {
        let law = fczm();
        let lam = 8e-4;
        let (work, stored) = drive(
            &law,
            &ramp(Vector3::zeros(), Vector3::new(lam, 0.0, 0.0), 20000),
        );
        let ft = law.tensile_strength;
        let c = ft / (law.zeta * law.fracture_energy);
        let q = (-c * (lam - law.lambda0)).exp();
        let expected_stored = 0.5 * q * ft * lam;
        let expected_dissipated = 0.5 * ft * law.lambda0 + ft / c * (1.0 - q) - expected_stored;
        assert!(
            (stored - expected_stored).abs() < 1e-9 * expected_stored,
            "{stored} vs {expected_stored}"
        );
        let d = work - stored;
        assert!(
            (d - expected_dissipated).abs() < 1e-5 * expected_dissipated,
            "{d} vs {expected_dissipated}"
        );
    }

    /// Fully damaged FCZM under a held compression u_n = −u_0, then sliding by
    /// U: the dissipation is the friction work μ K_n u_0 (U − u_stick) and the
    /// stored energy ½ K_n u_0² + ½ τ_y²/K_s (paper eqs. 16–21).
    #[test]
    fn friction_dissipation_matches_coulomb_work() {
        let law = Fczm {
            min_damage: 1.0,
            ..fczm()
        };
        let (kn, ks) = (law.normal_stiffness(), law.shear_stiffness());
        let u0 = 2e-5;
        let ty = law.friction * kn * u0;
        let stick = ty / ks;
        let big_u = 10.0 * stick;
        let mut path = ramp(Vector3::zeros(), Vector3::new(-u0, 0.0, 0.0), 10);
        // Increments that land on the stick limit keep the trapezoid exact.
        path.extend(ramp(
            Vector3::new(-u0, 0.0, 0.0),
            Vector3::new(-u0, stick, 0.0),
            10,
        ));
        path.extend(ramp(
            Vector3::new(-u0, stick, 0.0),
            Vector3::new(-u0, big_u, 0.0),
            90,
        ));
        let (work, stored) = drive(&law, &path);
        let expected_stored = 0.5 * kn * u0 * u0 + 0.5 * ty * ty / ks;
        assert!((stored - expected_stored).abs() < 1e-9 * expected_stored);
        let expected = ty * (big_u - stick);
        assert!(
            ((work - stored) - expected).abs() < 1e-9 * expected,
            "{} vs {expected}",
            work - stored
        );
    }

    /// J2 steel in simple shear beyond yield: the dissipation equals τ_y Δγ_p
    /// and the stored energy τ_y²/(2G) (von Mises, τ_y = σ_y/√3).
    #[test]
    fn j2_shear_dissipation_is_plastic_work() {
        let law = J2 {
            young_modulus: 200e9,
            poisson_ratio: 0.3,
            yield_stress: 365e6,
        };
        let g = law.young_modulus / (2.0 * (1.0 + law.poisson_ratio));
        let ty = law.yield_stress / 3f64.sqrt();
        let gy = ty / g;
        let mut state = BulkState::default();
        let (mut work, mut stored, mut s_old, mut e_old) =
            (0.0, 0.0, Vector6::zeros(), Vector6::zeros());
        let n = 40;
        for k in 1..=n {
            let gamma = gy
                * if k <= 10 {
                    k as f64 / 10.0
                } else {
                    1.0 + 4.0 * (k - 10) as f64 / 30.0
                };
            let e = Vector6::new(0.0, 0.0, 0.0, gamma, 0.0, 0.0);
            state = law.step(&state, &e, TangentKind::Consistent).unwrap().state;
            let (s, psi) = bulk_point(&law, &state, &e).unwrap();
            work += 0.5 * (s + s_old).dot(&(e - e_old));
            (s_old, e_old, stored) = (s, e, psi);
        }
        let expected_stored = ty * ty / (2.0 * g);
        assert!((stored - expected_stored).abs() < 1e-9 * expected_stored);
        let expected = ty * 4.0 * gy;
        assert!(((work - stored) - expected).abs() < 1e-9 * expected);
    }

    /// On a model (one interface element between two node triangles, tilted
    /// frame) the tracker's internal work, stored and dissipated energies
    /// equal the point-level closed form times the area, and W_ext from the
    /// element's own reaction balances W_int (issue 7 energy balance).
    #[test]
    fn tracker_balances_an_opening_interface() {
        let (c, s) = (0.6f64, 0.8f64);
        let n = [c, s, 0.0];
        let area = 2e-6;
        let mut model = Model {
            nodes: vec![[0.0; 3]; 6],
            node_region: vec![
                Region::Steel,
                Region::Steel,
                Region::Steel,
                Region::Concrete,
                Region::Concrete,
                Region::Concrete,
            ],
            interfaces: vec![InterfaceElement {
                nodes: [0, 1, 2, 3, 4, 5],
                zone: InterfaceZone::Adhesive,
                frame: Frame {
                    n,
                    t: [0.0, 0.0, 1.0],
                    h: [s, -c, 0.0],
                },
                area,
            }],
            ..Default::default()
        };
        model.symmetry = mesh::Symmetry::Quarter;
        let law = fczm();
        let laws = ElementLaws {
            tets: Vec::new(),
            interfaces: vec![Some(law.into())],
            nonlocal_length: None,
        };
        let mut tracker = EnergyTracker::new(&model, &laws).unwrap();
        let mut states = States::initial(&model);
        let steps = 4000;
        let lam_end = 4e-4;
        for k in 1..=steps {
            let lam = lam_end * k as f64 / steps as f64;
            let mut u = vec![0.0; 18];
            for p in 3..6 {
                for d in 0..3 {
                    u[3 * p + d] = lam * n[d];
                }
            }
            let jump = Vector3::new(lam, 0.0, 0.0);
            let r = law
                .step(&states.interface[0], &jump, TangentKind::Secant)
                .unwrap();
            for st in states.interface.iter_mut() {
                *st = r.state;
            }
            // The element's reaction: traction × area, × 4 for the quarter.
            let force = 4.0 * r.traction[0] * area;
            tracker.step(lam, force, &u, &states).unwrap();
        }
        let last = *tracker.rows().last().unwrap();
        let ft = law.tensile_strength;
        let cc = ft / (law.zeta * law.fracture_energy);
        let q = (-cc * (lam_end - law.lambda0)).exp();
        let stored = 4.0 * area * 0.5 * q * ft * lam_end;
        let dissipated = 4.0 * area * (0.5 * ft * law.lambda0 + ft / cc * (1.0 - q)) - stored;
        assert!((last.stored - stored).abs() < 1e-9 * stored);
        assert!(
            (last.dissipated - dissipated).abs() < 1e-4 * dissipated,
            "{} vs {dissipated}",
            last.dissipated
        );
        assert!((last.w_ext - last.w_int).abs() < 1e-9 * last.w_ext);
        let chk = check(tracker.rows(), ENERGY_TOLERANCE);
        assert!(chk.passed, "{chk:?}");
        assert!(chk.min_dissipation_increment >= -1e-12);
    }

    /// A tracker sent back to an earlier converged state (a run that
    /// discards steps after a stall) continues as one that never left it,
    /// and so does one that evaluates states it then refuses: neither the
    /// detour nor the refused trials leave anything in its sums.
    #[test]
    fn energy_tracker_rewound_equals_resumed() {
        let mut model = Model {
            nodes: vec![[0.0; 3]; 6],
            node_region: vec![Region::Steel; 3]
                .into_iter()
                .chain(vec![Region::Concrete; 3])
                .collect(),
            interfaces: vec![InterfaceElement {
                nodes: [0, 1, 2, 3, 4, 5],
                zone: InterfaceZone::Adhesive,
                frame: Frame {
                    n: [1.0, 0.0, 0.0],
                    t: [0.0, 0.0, 1.0],
                    h: [0.0, -1.0, 0.0],
                },
                area: 2e-6,
            }],
            ..Default::default()
        };
        model.symmetry = mesh::Symmetry::Full;
        let law = fczm();
        let laws = ElementLaws {
            tets: Vec::new(),
            interfaces: vec![Some(law.into())],
            nonlocal_length: None,
        };
        // The state at opening `lam` from `states`: displacement, states, force.
        let at = |lam: f64, states: &States| {
            let mut u = vec![0.0; 18];
            for p in 3..6 {
                u[3 * p] = lam;
            }
            let r = law
                .step(
                    &states.interface[0],
                    &Vector3::new(lam, 0.0, 0.0),
                    TangentKind::Secant,
                )
                .unwrap();
            let mut next = states.clone();
            next.interface.iter_mut().for_each(|st| *st = r.state);
            (u, next, r.traction[0] * 2e-6)
        };
        let path = |k: usize| 4e-4 * k as f64 / 400.0;
        let (mut straight, mut sent_back) = (
            EnergyTracker::new(&model, &laws).unwrap(),
            EnergyTracker::new(&model, &laws).unwrap(),
        );
        let mut states = States::initial(&model);
        let mut kept = None;
        for k in 1..=100 {
            let (u, next, f) = at(path(k), &states);
            straight.step(path(k), f, &u, &next).unwrap();
            sent_back.step(path(k), f, &u, &next).unwrap();
            states = next;
            kept = Some((u, states.clone(), f));
        }
        // A detour the run then discards: further open, then back.
        let mut detour = states.clone();
        for lam in [2e-4, 3e-4, 1e-4] {
            let (u, next, f) = at(lam, &detour);
            sent_back.step(lam, f, &u, &next).unwrap();
            detour = next;
        }
        let (u, kept_states, force) = kept.unwrap();
        let rows = straight.rows().to_vec();
        sent_back
            .rewind(EnergyStart {
                u: &u,
                states: &kept_states,
                rows,
                lambda: path(100),
                force,
            })
            .unwrap();
        for k in 101..=400 {
            if k % 7 == 0 {
                // A state the solver refuses: evaluated, never accepted.
                let (u, next, f) = at(1.5 * path(k), &states);
                let refused = sent_back.trial(1.5 * path(k), f, &u, &next).unwrap();
                assert_ne!(refused, *straight.rows().last().unwrap());
            }
            let (u, next, f) = at(path(k), &states);
            straight.step(path(k), f, &u, &next).unwrap();
            sent_back.step(path(k), f, &u, &next).unwrap();
            states = next;
        }
        assert_eq!(straight.rows(), sent_back.rows());
        assert!(check(sent_back.rows(), ENERGY_TOLERANCE).passed);
    }

    /// The check flags an imbalance above the tolerance and a dissipation
    /// that decreases (issue 7: energy balance within a stated tolerance).
    #[test]
    fn check_flags_imbalance_and_negative_dissipation() {
        let row = |w_ext: f64, w_int: f64, stored: f64| EnergyRow {
            w_ext,
            w_int,
            stored,
            dissipated: w_int - stored,
        };
        let good = [row(1.0, 1.0, 1.0), row(3.0, 3.001, 2.0), row(4.0, 4.0, 2.5)];
        assert!(check(&good, 1e-2).passed);
        let unbalanced = [row(1.0, 1.0, 1.0), row(3.0, 3.1, 2.0)];
        let c = check(&unbalanced, 1e-2);
        assert!(
            !c.passed
                && c.step_of_max_imbalance == 2
                && (c.max_relative_imbalance - 0.1 / 3.0).abs() < 1e-12
        );
        let healing = [row(1.0, 1.0, 0.5), row(2.0, 2.0, 1.9)];
        let c = check(&healing, 1e-2);
        assert!(!c.passed && c.min_dissipation_increment < -0.1);
        let nan = [row(1.0, f64::NAN, 0.5)];
        assert!(!check(&nan, 1e-2).passed);
        assert_eq!(external_work(&[(1.0, 2.0), (2.0, 4.0)]), vec![1.0, 4.0]);
    }

    /// A step keeps the check exactly when the run's check over the rows
    /// up to it passes, given that it passed before: the rule the solver
    /// refuses states by is the one solve.json reports.
    #[test]
    fn keeps_check_is_the_check_of_one_step() {
        let row = |w_ext: f64, w_int: f64, dissipated: f64| EnergyRow {
            w_ext,
            w_int,
            stored: w_int - dissipated,
            dissipated,
        };
        let start = row(2.0, 2.0, 0.5);
        let steps = [
            row(3.0, 3.02, 0.6),  // balanced to 0.67 %
            row(3.0, 3.04, 0.6),  // 1.3 % apart
            row(3.0, 2.96, 0.6),  // 1.3 % apart, the other way
            row(3.0, 3.0, 0.45),  // gives back 1.7 % of W_ext
            row(3.0, 3.0, 0.48),  // gives back 0.67 %
            row(0.0, 1e-3, -1.0), // nothing loaded: no scale
            row(3.0, f64::INFINITY, 0.6),
        ];
        for step in steps {
            let by_check = check(&[start, step], 1e-2).passed;
            assert_eq!(step.keeps_check(&start, 1e-2), by_check, "{step:?}");
        }
        assert!(steps[0].keeps_check(&start, 1e-2) && !steps[1].keeps_check(&start, 1e-2));
        assert!(!steps[3].keeps_check(&start, 1e-2) && steps[4].keeps_check(&start, 1e-2));
    }
}
