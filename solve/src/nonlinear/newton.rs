//! Newton iterations at fixed Dirichlet values: line search, stagnation
//! handling and the convergence criteria of SPEC §6.
//!
//! Convergence needs both criteria after at least one correction:
//! ‖r‖ ≤ tol_r·‖reactions‖ and |Δu_k·r_{k−1}| ≤ tol_e·E_ref, where E_ref is
//! the largest |Δu·r| of the step's corrections, or the work scale
//! ‖reactions‖·h of the step (size h) when larger: after an exact predictor
//! every correction is round-off, relative to itself. A reference taken
//! from the first correction alone made tiny steps unconvergeable: after a
//! cut-back to a step of a few nm, the first correction carries only the
//! tiny imposed increment, and the leftover imbalance of the previous step
//! (converged to tol_r, not to zero) then looks like a large energy.

use super::control::Control;
use super::correction::{forcing_term, Request};
use super::failure::{NotConverged, RegimeChanges};
use super::workspace::Workspace;
use crate::assembly::{LoadDerivatives, States, Tangents};
use crate::laws::{InterfaceState, TangentKind};
use crate::linalg::{dot, norm};
use crate::spec::solver::SolverSettings;

/// Shortest line-search step kept; below it the full Newton step is taken.
const LINE_SEARCH_MIN_STEP: f64 = 0.25;

/// Outcome of one Newton attempt.
pub(crate) struct Attempt {
    pub(crate) iterations: usize,
    /// Relative residual of each iterate (the predictor first).
    pub(crate) history: Vec<f64>,
    pub(crate) failure: Option<NotConverged>,
    /// Converged on the force criterion only (see `Summary::force_only_steps`).
    pub(crate) force_only: bool,
    /// Of a failed attempt, or one that ended on its best iterate: the
    /// tets whose damage switched between growing and not at least twice
    /// between iterates (the points Newton could not settle). Tets whose
    /// history the iterates defer (IMPL-EX) are not among them: their
    /// damage does not enter the iterates.
    pub(crate) flipping: Vec<usize>,
    /// Likewise the interface points whose regime switched at least twice:
    /// damage growing or not, sliding or sticking, or their slip in the
    /// step reversed its direction.
    pub(crate) flipping_pairs: Vec<usize>,
}

impl Attempt {
    fn converged(iterations: usize, history: Vec<f64>, force_only: bool) -> Self {
        Self {
            iterations,
            history,
            failure: None,
            force_only,
            flipping: Vec::new(),
            flipping_pairs: Vec::new(),
        }
    }
    fn failed(iterations: usize, history: Vec<f64>, why: NotConverged) -> Self {
        Self {
            iterations,
            history,
            failure: Some(why),
            force_only: false,
            flipping: Vec::new(),
            flipping_pairs: Vec::new(),
        }
    }
}

fn constitutive(
    in_line_search: bool,
) -> impl FnOnce(crate::assembly::AssemblyError) -> NotConverged {
    move |source| NotConverged::Constitutive {
        in_line_search,
        source,
    }
}

/// What a line search searches along: the full correction, g0 = d·r
/// before it, and the residual norm the correction started from.
#[derive(Clone, Copy)]
struct Search<'a> {
    direction: &'a [f64],
    g0: f64,
    r_prev: f64,
}

/// The running record of one Newton attempt.
struct Record {
    /// Relative residual of each iterate.
    history: Vec<f64>,
    /// The largest |Δu·r| of the attempt's corrections, and the last one
    /// (scaled by the line search's step).
    energy_ref: f64,
    last_energy: f64,
    /// ‖r‖ of the first iterate.
    first_norm: f64,
    /// Forcing term of the last correction and the residual it started from.
    eta_prev: f64,
    r_prev: f64,
    /// Tangent kinds of the tets and of the interface elements: a
    /// stagnating consistent-tangent Newton continues with the secant
    /// matrix, from iteration `window`.
    kinds: Tangents,
    window: usize,
    /// The iterate with the smallest relative residual (a stagnating
    /// attempt may end on it).
    best_rel: f64,
    best_u: Vec<f64>,
    best_lambda: Option<f64>,
    /// Per tet: whether its damage grows at the last iterate, and how
    /// often that changed between iterates.
    growing: Vec<bool>,
    flips: Vec<u8>,
    /// Per interface point: its regime at the last iterate, and how often
    /// that changed between iterates; tracked only when the step may
    /// hold such points (`Workspace::holds_pairs`).
    holds_pairs: bool,
    regimes: Vec<PairRegime>,
    pair_flips: Vec<u8>,
}

/// What an interface point did in the step up to an iterate.
#[derive(Clone, Copy, PartialEq)]
struct PairRegime {
    damage_grows: bool,
    /// Its slip in the step (zero: sticking).
    slip: [f64; 2],
}

impl PairRegime {
    fn of(start: &InterfaceState, trial: &InterfaceState) -> Self {
        Self {
            damage_grows: trial.damage > start.damage,
            slip: [trial.slip[0] - start.slip[0], trial.slip[1] - start.slip[1]],
        }
    }
    /// Whether going from `self` to `next` switched damage growth, stick
    /// and slip, or the direction of the slip.
    fn switched(&self, next: &Self) -> bool {
        let sliding = |r: &Self| r.slip != [0.0, 0.0];
        let along = self.slip[0] * next.slip[0] + self.slip[1] * next.slip[1];
        self.damage_grows != next.damage_grows
            || sliding(self) != sliding(next)
            || (sliding(self) && along < 0.0)
    }
}

impl Record {
    fn new(settings: &SolverSettings, holds_pairs: bool, u: &[f64], control: &Control<'_>) -> Self {
        Self {
            history: Vec::new(),
            energy_ref: 0.0,
            last_energy: f64::INFINITY,
            first_norm: 0.0,
            eta_prev: 0.0,
            r_prev: 0.0,
            kinds: Tangents::all(settings.tangent),
            window: 0,
            best_rel: f64::INFINITY,
            best_u: vec![0.0; u.len()],
            best_lambda: control.lambda(),
            growing: Vec::new(),
            flips: Vec::new(),
            holds_pairs,
            regimes: Vec::new(),
            pair_flips: Vec::new(),
        }
    }
    fn failed(mut self, iterations: usize, why: NotConverged) -> Attempt {
        self.failed_ref(iterations, why)
    }
    fn failed_ref(&mut self, iterations: usize, why: NotConverged) -> Attempt {
        let mut attempt = Attempt::failed(iterations, std::mem::take(&mut self.history), why);
        attempt.flipping = self.flipping();
        attempt.flipping_pairs = self.flipping_pairs();
        attempt
    }
    fn flipping(&self) -> Vec<usize> {
        (0..self.flips.len())
            .filter(|&i| self.flips[i] >= 2)
            .collect()
    }
    fn flipping_pairs(&self) -> Vec<usize> {
        (0..self.pair_flips.len())
            .filter(|&i| self.pair_flips[i] >= 2)
            .collect()
    }
    /// Counts the interface points whose regime changed since the last
    /// iterate.
    fn track_pairs(&mut self, start: &States, trial: &States) {
        let regime = |i: usize| PairRegime::of(&start.interface[i], &trial.interface[i]);
        if self.regimes.is_empty() {
            self.regimes = (0..trial.interface.len()).map(regime).collect();
            self.pair_flips = vec![0; trial.interface.len()];
            return;
        }
        for (i, (r, f)) in self
            .regimes
            .iter_mut()
            .zip(&mut self.pair_flips)
            .enumerate()
        {
            let now = regime(i);
            if r.switched(&now) {
                *f = f.saturating_add(1);
            }
            *r = now;
        }
    }
    /// Counts the tets whose damage growth, and (when tracked) the
    /// interface points whose regime, changed since the last iterate.
    fn track(&mut self, start: &States, trial: &States) {
        if self.holds_pairs {
            self.track_pairs(start, trial);
        }
        let grows = |i: usize| trial.bulk[i].damage > start.bulk[i].damage;
        if self.growing.is_empty() {
            self.growing = (0..trial.bulk.len()).map(grows).collect();
            self.flips = vec![0; trial.bulk.len()];
            return;
        }
        for (i, (g, f)) in self.growing.iter_mut().zip(&mut self.flips).enumerate() {
            let now = grows(i);
            if now != *g {
                *g = now;
                *f = f.saturating_add(1);
            }
        }
    }
}

impl Workspace<'_> {
    /// Newton iterations from the iterate `u` (Dirichlet values already
    /// set) and the step's start states `start`, for a step of size
    /// `step_size` (m), with the loading held by `control`. On return `u`,
    /// `trial`, `f_int` and the control's λ hold the last (or the
    /// accepted) iterate.
    pub(crate) fn newton(
        &mut self,
        start: &States,
        u: &mut [f64],
        step_size: f64,
        control: &mut Control<'_>,
    ) -> Attempt {
        let mut attempt = self.iterate(start, u, step_size, control);
        // The iterates deferred the history of the IMPL-EX tets; the last
        // one's trial states are the attempt's answer.
        if let Err(e) = self.update_history(start, u) {
            if attempt.failure.is_none() {
                attempt.failure = Some(constitutive(false)(e));
            }
        }
        if let Some(regimes) = attempt.failure.as_mut().and_then(NotConverged::regimes_mut) {
            *regimes = RegimeChanges::between(start, &self.trial);
        }
        attempt
    }

    /// [`Workspace::newton`]'s iterations; the trial states of the tets
    /// whose history is deferred stay as they were.
    fn iterate(
        &mut self,
        start: &States,
        u: &mut [f64],
        step_size: f64,
        control: &mut Control<'_>,
    ) -> Attempt {
        let settings = self.settings;
        let dofs = self.system.dofs();
        let n_free = dofs.n_free();
        let mut rec = Record::new(settings, self.holds_pairs, u, control);
        let mut r = vec![0.0; n_free];
        let mut du = vec![0.0; n_free];
        // Correction of the previous iteration (for the line search).
        let mut prev: Option<(Vec<f64>, f64)> = None;
        for k in 0..=settings.max_iterations {
            if let Err(e) = self.evaluate(start, u, rec.kinds) {
                return rec.failed(k, constitutive(false)(e));
            }
            rec.track(start, &self.trial);
            self.residual(&mut r);
            if let (true, Some((d, g0))) = (settings.line_search, prev.as_ref()) {
                let line = Search {
                    direction: d.as_slice(),
                    g0: *g0,
                    r_prev: rec.r_prev,
                };
                match self.line_search(start, u, &mut *control, rec.kinds, line, &mut r) {
                    Ok(s) => rec.last_energy *= s,
                    Err(e) => return rec.failed(k, e),
                }
            }
            let rnorm = norm(&r);
            if !rnorm.is_finite() {
                return rec.failed(k, NotConverged::NonFiniteResidual);
            }
            let scale = self.force_scale();
            rec.history.push(rnorm / scale);
            // The predictor (k = 0) counts: at a threshold the first correction
            // can cross to the worse side of the cycle (R1 with δ_s = 0.02 and
            // 1: predictor 1.8e-4, best later iterate 2.2e-4).
            if rnorm / scale < rec.best_rel {
                rec.best_rel = rnorm / scale;
                rec.best_u.copy_from_slice(u);
                rec.best_lambda = control.lambda();
            }
            if k == 0 {
                rec.first_norm = rnorm;
            }
            let held = match control {
                Control::Displacement => true,
                Control::Indirect(c) => {
                    c.constraint.residual(u, c.lambda, &self.f_int).abs()
                        <= c.constraint
                            .tolerance(settings.residual_tolerance, step_size)
                }
            };
            if k > 0
                && rnorm <= settings.residual_tolerance * scale
                && rec.last_energy
                    <= settings.energy_tolerance
                        * rec.energy_ref.max(control.work_scale(scale, step_size))
                && held
            {
                return Attempt::converged(k, rec.history, false);
            }
            if k == settings.max_iterations {
                break;
            }
            if let Some(end) = self.stagnation(k, &mut rec, rnorm / scale, start, u, control) {
                return end;
            }
            if rnorm > 1e8 * rec.first_norm.max(scale) {
                let regimes = RegimeChanges::between(start, &self.trial);
                let why = NotConverged::Diverging {
                    residual: rnorm,
                    regimes,
                };
                return rec.failed(k, why);
            }
            let eta = forcing_term(settings, k, rnorm, rec.r_prev, rec.eta_prev, scale);
            rec.eta_prev = eta;
            rec.r_prev = rnorm;
            let g0 = match self.newton_correction(start, u, &mut *control, &r, &mut du, eta) {
                Ok(g0) => g0,
                Err(why) => return rec.failed(k, why),
            };
            if k == 0 && g0 == 0.0 {
                return Attempt::converged(1, rec.history, false);
            }
            rec.energy_ref = rec.energy_ref.max(g0.abs());
            rec.last_energy = g0.abs();
            dofs.scatter_add(&du, 1.0, u);
            control.advance(1.0, u);
            prev = Some((du.clone(), g0));
        }
        let why = NotConverged::IterationLimit {
            iterations: settings.max_iterations,
            relative_residual: rec.history.last().copied().unwrap_or(f64::NAN),
            regimes: RegimeChanges::between(start, &self.trial),
        };
        rec.failed(settings.max_iterations, why)
    }

    /// Stagnation (switching stick/slip or loading/unloading points that
    /// Newton cannot settle): from iteration `window` + 8 on, the last 4
    /// residuals all above half the best before them. The attempt then
    /// ends on its best iterate if that one is within
    /// `stagnation_acceptance` × the force tolerance (points flipping
    /// between law branches hold Newton in a cycle whose best iterate is
    /// nearly in equilibrium; checked before the secant switch), else the
    /// consistent tangent gives way to the secant matrix (which does not
    /// jump between iterates), else the attempt fails (a cut-back is
    /// cheaper than more iterations). docs/src/validation/solver.md, Stagnation.
    fn stagnation(
        &mut self,
        k: usize,
        rec: &mut Record,
        relative: f64,
        start: &States,
        u: &mut [f64],
        control: &mut Control<'_>,
    ) -> Option<Attempt> {
        let settings = self.settings;
        if k < rec.window + 8 {
            return None;
        }
        let history = &rec.history;
        let best_before = history[rec.window..k - 3]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if !history[k - 3..].iter().all(|&v| v > 0.5 * best_before) {
            return None;
        }
        if rec.best_rel <= settings.stagnation_acceptance * settings.residual_tolerance {
            if relative > rec.best_rel {
                u.copy_from_slice(&rec.best_u);
                if let (Control::Indirect(c), Some(l)) = (&mut *control, rec.best_lambda) {
                    c.lambda = l;
                }
                if let Err(e) = self.evaluate(start, u, rec.kinds) {
                    return Some(rec.failed_ref(k, constitutive(false)(e)));
                }
            }
            let mut accepted = Attempt::converged(k, std::mem::take(&mut rec.history), true);
            accepted.flipping = rec.flipping();
            accepted.flipping_pairs = rec.flipping_pairs();
            return Some(accepted);
        }
        if rec.kinds != Tangents::all(TangentKind::Secant) {
            rec.kinds = Tangents::all(TangentKind::Secant);
            rec.window = k;
            return None;
        }
        let why = NotConverged::Stagnating {
            relative_residual: relative,
            regimes: RegimeChanges::between(start, &self.trial),
        };
        Some(rec.failed_ref(k, why))
    }

    /// The Newton correction `du` of residual `r` (bordered under indirect
    /// control, whose Δλ it stores in the control); returns Δu·r.
    /// The tangent predictor of a displacement-controlled step of size
    /// `increment` with no previous increment to extrapolate (the first
    /// step, or a resume without one): from the start displacement `u`
    /// (Dirichlet values of the start), the linear response
    /// K Δu = r − (∂f_int/∂λ) Δλ of the start states. The Dirichlet-only
    /// iterate strains the single layer of elements next to the loaded end
    /// by the whole increment (5 µm over a 1 mm tet yields a 365 MPa bar)
    /// and Newton then starts from plastic states the converged step never
    /// reaches (docs/src/validation/solver.md, "First step"). Leaves `u` unchanged and
    /// returns false where the linear solve fails.
    pub(crate) fn tangent_predictor(
        &mut self,
        start: &States,
        u: &mut [f64],
        increment: f64,
    ) -> bool {
        let n_free = self.system.dofs().n_free();
        let kept = self.load.replace(LoadDerivatives::new(n_free));
        let evaluated = self.evaluate(start, u, Tangents::all(self.settings.tangent));
        let load = std::mem::replace(&mut self.load, kept).expect("set above");
        if evaluated.is_err() {
            return false;
        }
        let mut rhs = vec![0.0; n_free];
        self.residual(&mut rhs);
        rhs.iter_mut()
            .zip(&load.column)
            .for_each(|(r, c)| *r -= c * increment);
        let mut du = vec![0.0; n_free];
        let eta = self.settings.krylov_tolerance;
        if self
            .correction(
                start,
                u,
                Request {
                    rhs: &rhs,
                    eta,
                    border: None,
                },
                &mut du,
            )
            .is_err()
            || du.iter().any(|v| !v.is_finite())
        {
            return false;
        }
        self.system.dofs().scatter_add(&du, 1.0, u);
        true
    }

    fn newton_correction(
        &mut self,
        start: &States,
        u: &[f64],
        control: &mut Control<'_>,
        r: &[f64],
        du: &mut [f64],
        eta: f64,
    ) -> Result<f64, NotConverged> {
        let n_free = r.len();
        let solved = match control {
            Control::Displacement => self.correction(
                start,
                u,
                Request {
                    rhs: r,
                    eta,
                    border: None,
                },
                du,
            ),
            Control::Indirect(c) => {
                let mut both = vec![0.0; n_free + 1];
                let solved = self.bordered_correction(start, u, c, r, &mut both, eta);
                du.copy_from_slice(&both[..n_free]);
                c.increment = both[n_free];
                solved
            }
        };
        if let Err(source) = solved {
            let regimes = RegimeChanges::between(start, &self.trial);
            return Err(NotConverged::LinearSolve { source, regimes });
        }
        let g0 = dot(du, r);
        if !g0.is_finite() {
            return Err(NotConverged::NonFiniteCorrection);
        }
        Ok(g0)
    }

    /// After a full correction `d` (with g0 = d·r before it): if it
    /// overshot the energy minimum along its direction and did not reduce
    /// the residual (‖r‖ above `r_prev`), tries the secant root (λ follows
    /// the correction's Δλ under indirect control). The
    /// unsymmetric tangent has no potential, so a shorter step is kept only
    /// if its residual is smaller than the full step's; and a step shorter
    /// than [`LINE_SEARCH_MIN_STEP`] is never kept (docs/src/validation/solver.md, "The
    /// softening-branch stall"). Returns the step length kept; `u`, the
    /// workspace's iterate and `r` are left at it.
    fn line_search(
        &mut self,
        start: &States,
        u: &mut [f64],
        control: &mut Control<'_>,
        kinds: Tangents,
        search: Search<'_>,
        r: &mut [f64],
    ) -> Result<f64, NotConverged> {
        let Search {
            direction: d,
            g0,
            r_prev,
        } = search;
        let dofs = self.system.dofs();
        let mut s = 1.0;
        let mut g = dot(d, r);
        let full_norm = norm(r);
        let mut best = (1.0, full_norm);
        let mut tries = 0;
        while g < 0.0 && g.abs() > 0.5 * g0 && full_norm > r_prev && tries < 4 {
            let s_new = (s * g0 / (g0 - g)).clamp(0.1 * s, 0.9 * s);
            dofs.scatter_add(d, s_new - s, u);
            control.advance(s_new - s, u);
            s = s_new;
            self.evaluate(start, u, kinds).map_err(constitutive(true))?;
            self.residual(r);
            let n = norm(r);
            if n < best.1 {
                best = (s, n);
            }
            g = dot(d, r);
            tries += 1;
        }
        if best.0 < LINE_SEARCH_MIN_STEP {
            best = (1.0, full_norm);
        }
        if s != best.0 {
            dofs.scatter_add(d, best.0 - s, u);
            control.advance(best.0 - s, u);
            s = best.0;
            self.evaluate(start, u, kinds).map_err(constitutive(true))?;
            self.residual(r);
        }
        Ok(s)
    }
}
