//! How a step holds its loading: displacement control (the load factor λ,
//! the imposed displacement, is prescribed) or indirect displacement
//! control, where λ is an unknown and a linear quantity of the
//! displacement that grows monotonically along the path (here the
//! free-end displacement, FED, or the jumps of the interface's process
//! zone) is prescribed instead.
//!
//! Under indirect control each Newton correction solves the bordered system
//!
//! ```text
//! [ K    k_λ ] [Δu]   [ r  ]
//! [ c_fᵀ c_λ ] [Δλ] = [ −g ]
//! ```
//!
//! with K the tangent, k_λ = ∂f_int/∂λ (the load column of the assembly),
//! c the quantity's weights on the free DOFs (c_f) and through the
//! Dirichlet values (c_λ = Σ c_i rate_i), g = c·u − target, by bordering:
//! a = K⁻¹ r and b = K⁻¹ k_λ with the same kept preconditioner, then
//! Δλ = (g + c_f·a) / (c_f·b − c_λ) and Δu = a − Δλ b. The constraint is
//! linear, so every iterate after a correction meets it exactly, whatever
//! the accuracy of the two Krylov solves.
//!
//! Where displacement control meets a local snap-back of the quasi-static
//! path (the bond softens faster than the elastic bar unloads), no
//! equilibrium exists at a slightly larger λ and Newton cycles; the FED
//! keeps growing through it, and λ may decrease (Crisfield, Non-linear
//! Finite Element Analysis of Solids and Structures, vol. 1, §9.5; de
//! Borst, IJNME 24, 1987, "indirect displacement control").

use super::problem::Dirichlet;
use crate::assembly::DofMap;
use crate::assembly::LoadDerivatives;
use crate::linalg::{dot, LinearError, Operator, Preconditioner};
use serde::{Deserialize, Serialize};

/// A linear quantity Σ w_i u_i of the global displacement.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Quantity {
    /// (global DOF, weight).
    weights: Vec<(usize, f64)>,
    /// (free index, weight) of the free DOFs among them.
    free: Vec<(usize, f64)>,
    /// d(quantity)/dλ through the Dirichlet values.
    per_lambda: f64,
}

impl Quantity {
    pub(crate) fn new(weights: Vec<(usize, f64)>, dofs: &DofMap, dirichlet: &Dirichlet) -> Self {
        let per_lambda = dirichlet
            .dofs
            .iter()
            .zip(&dirichlet.rate)
            .map(|(d, r)| {
                weights
                    .iter()
                    .filter(|(g, _)| g == d)
                    .map(|(_, w)| w * r)
                    .sum::<f64>()
            })
            .sum();
        Self::with_weights(weights, per_lambda, dofs)
    }
    /// The quantity whose weight on global DOF d is `dense[d]` (zeros
    /// skipped).
    pub(crate) fn from_dense(dense: &[f64], dofs: &DofMap, dirichlet: &Dirichlet) -> Self {
        let weights = dense
            .iter()
            .enumerate()
            .filter(|(_, &w)| w != 0.0)
            .map(|(d, &w)| (d, w))
            .collect();
        let per_lambda = dirichlet
            .dofs
            .iter()
            .zip(&dirichlet.rate)
            .map(|(&d, r)| dense[d] * r)
            .sum();
        Self::with_weights(weights, per_lambda, dofs)
    }
    fn with_weights(weights: Vec<(usize, f64)>, per_lambda: f64, dofs: &DofMap) -> Self {
        let free = weights
            .iter()
            .filter_map(|&(d, w)| dofs.signed_index(d).map(|(f, sign)| (f, sign * w)))
            .collect();
        Self {
            weights,
            free,
            per_lambda,
        }
    }
    /// The quantity's value for the global displacement `u`.
    pub(crate) fn value(&self, u: &[f64]) -> f64 {
        self.weights.iter().map(|&(d, w)| w * u[d]).sum()
    }
}

/// The loading of one Newton attempt.
pub(crate) enum Control<'a> {
    /// λ prescribed; its Dirichlet values are already in the iterate.
    Displacement,
    /// λ unknown; a constraint on the path holds the step.
    Indirect(Indirect<'a>),
}

/// What an indirectly controlled step holds.
pub(crate) enum Constraint<'a> {
    /// The linear quantity c·u (m) at `target`.
    Quantity { quantity: &'a Quantity, target: f64 },
    /// The energy released since the last converged state (λ_0, F_0),
    /// G = ½(F_0 λ − F λ_0) (J), at `target`: the dissipation of the step
    /// when the structure unloads secantly, as damage does (Gutiérrez,
    /// IJNME 59, 2004). F = Σ rate_a f_int,a is the generalised load.
    Energy {
        rates: &'a [(usize, f64)],
        force0: f64,
        lambda0: f64,
        target: f64,
    },
}

impl Constraint<'_> {
    /// The constraint's residual g at an iterate (m or J).
    pub(crate) fn residual(&self, u: &[f64], lambda: f64, f_int: &[f64]) -> f64 {
        match *self {
            Constraint::Quantity { quantity, target } => quantity.value(u) - target,
            Constraint::Energy {
                rates,
                force0,
                lambda0,
                target,
            } => 0.5 * (force0 * lambda - generalised_load(rates, f_int) * lambda0) - target,
        }
    }
    /// The constraint's gradient: ∂g/∂u on the free DOFs into `row`,
    /// returns ∂g/∂λ.
    pub(crate) fn gradient(&self, load: &LoadDerivatives, row: &mut [f64]) -> f64 {
        match *self {
            Constraint::Quantity { quantity, .. } => {
                row.iter_mut().for_each(|v| *v = 0.0);
                for &(f, w) in &quantity.free {
                    row[f] += w;
                }
                quantity.per_lambda
            }
            Constraint::Energy {
                force0, lambda0, ..
            } => {
                row.iter_mut()
                    .zip(&load.row)
                    .for_each(|(v, r)| *v = -0.5 * lambda0 * r);
                0.5 * force0 - 0.5 * lambda0 * load.diagonal
            }
        }
    }
    /// How closely the constraint must hold at convergence (m or J),
    /// relative tolerance `tol`, for a step of size `size`.
    pub(crate) fn tolerance(&self, tol: f64, size: f64) -> f64 {
        match *self {
            Constraint::Quantity { .. } => tol * size,
            Constraint::Energy { target, .. } => tol * target.abs(),
        }
    }
}

/// F = Σ rate_a f_int,a: the load conjugate to λ (N).
pub(crate) fn generalised_load(rates: &[(usize, f64)], f_int: &[f64]) -> f64 {
    rates.iter().map(|&(d, r)| r * f_int[d]).sum()
}

/// Indirect control of one attempt.
pub(crate) struct Indirect<'a> {
    pub(crate) constraint: Constraint<'a>,
    pub(crate) dirichlet: &'a Dirichlet,
    /// The current iterate's λ, m.
    pub(crate) lambda: f64,
    /// Δλ of the last correction (followed by the line search).
    pub(crate) increment: f64,
}

impl Control<'_> {
    /// Moves λ by `s` times the last correction's Δλ and sets the Dirichlet
    /// values of `u` accordingly (no-op under displacement control).
    pub(crate) fn advance(&mut self, s: f64, u: &mut [f64]) {
        if let Control::Indirect(c) = self {
            c.lambda += s * c.increment;
            c.dirichlet.apply(c.lambda, u);
        }
    }
    /// The work scale of a step of size `size` under force scale `force`
    /// (N): force × size for steps in a length, the step's energy itself
    /// under dissipation control (J).
    pub(crate) fn work_scale(&self, force: f64, size: f64) -> f64 {
        match self {
            Control::Indirect(Indirect {
                constraint: Constraint::Energy { target, .. },
                ..
            }) => *target,
            _ => force * size,
        }
    }
    /// λ of the iterate, if it is an unknown.
    pub(crate) fn lambda(&self) -> Option<f64> {
        match self {
            Control::Displacement => None,
            Control::Indirect(c) => Some(c.lambda),
        }
    }
}

/// The constraint row that borders the tangent under indirect control:
/// the load column k_λ, the constraint's gradient (row ∂g/∂u on the free
/// DOFs, ∂g/∂λ), and the factor that scales the constraint row to the size
/// of the force rows (GMRES measures the residual of both in one norm).
pub(crate) struct Border<'a> {
    pub(crate) column: &'a [f64],
    pub(crate) row: &'a [f64],
    pub(crate) row_lambda: f64,
    pub(crate) scale: f64,
}

impl Border<'_> {
    /// The augmented operator [K k_λ; s gᵤᵀ s g_λ] for the tangent `k`.
    pub(crate) fn operator<'b, K: Operator>(&'b self, k: &'b K) -> BorderedOperator<'b, K> {
        BorderedOperator { k, border: self }
    }
}

/// [K k_λ; s gᵤᵀ s g_λ] acting on (Δu, Δλ).
pub(crate) struct BorderedOperator<'a, K> {
    k: &'a K,
    border: &'a Border<'a>,
}

impl<K: Operator> Operator for BorderedOperator<'_, K> {
    fn n(&self) -> usize {
        self.k.n() + 1
    }
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.k.n();
        let b = self.border;
        self.k.mul(&x[..n], &mut y[..n]);
        let xl = x[n];
        y[..n]
            .iter_mut()
            .zip(b.column)
            .for_each(|(yi, ci)| *yi += ci * xl);
        y[n] = b.scale * (dot(b.row, &x[..n]) + b.row_lambda * xl);
    }
}

/// The exact inverse of [M k_λ; s gᵤᵀ s g_λ] by bordering with M⁻¹ (a
/// preconditioner of K): with q = M⁻¹ k_λ computed once,
/// z_λ = (v_λ/s − gᵤ·M⁻¹v_u)/(g_λ − gᵤ·q), z_u = M⁻¹v_u − z_λ q.
/// Regular where the Schur complement g_λ − gᵤ·q is not zero: M is SPD
/// (the symmetric part or the secant matrix), so this holds wherever the
/// constraint responds to λ under M, even where K itself is singular at a
/// turning point of λ.
pub(crate) struct BorderedPreconditioner<'a, M> {
    m: &'a M,
    border: &'a Border<'a>,
    q: Vec<f64>,
    schur: f64,
}

impl<'a, M: Preconditioner> BorderedPreconditioner<'a, M> {
    pub(crate) fn new(m: &'a M, border: &'a Border<'a>) -> Result<Self, LinearError> {
        let mut q = border.column.to_vec();
        m.apply(&mut q)?;
        let schur = border.row_lambda - dot(border.row, &q);
        if !(schur.is_finite() && schur != 0.0) {
            return Err(LinearError::NonFinite);
        }
        Ok(Self {
            m,
            border,
            q,
            schur,
        })
    }
}

impl<M: Preconditioner> Preconditioner for BorderedPreconditioner<'_, M> {
    fn apply(&self, r: &mut [f64]) -> Result<(), LinearError> {
        let n = self.q.len();
        let (ru, rl) = r.split_at_mut(n);
        self.m.apply(ru)?;
        let b = self.border;
        let zl = (rl[0] / b.scale - dot(b.row, ru)) / self.schur;
        ru.iter_mut().zip(&self.q).for_each(|(v, qi)| *v -= zl * qi);
        rl[0] = zl;
        Ok(())
    }
}

/// What the steps of a run prescribe at the moment (the unit of its step
/// size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ControlMode {
    /// λ, the imposed displacement.
    #[default]
    Displacement,
    /// The free-end displacement (indirect displacement control).
    FreeEnd,
    /// The energy released by the step (dissipation control), J.
    Energy,
    /// The r.m.s. jump increment of the interface points that softened in
    /// the last step, along their last increments (a local arc-length on
    /// the process zone), m.
    ProcessZone,
}

impl ControlMode {
    /// The unit of a step size in this mode.
    pub fn step_unit(self) -> &'static str {
        match self {
            ControlMode::Displacement | ControlMode::FreeEnd | ControlMode::ProcessZone => "m",
            ControlMode::Energy => "J",
        }
    }
}
