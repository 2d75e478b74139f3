//! What the driver is given: proportional Dirichlet conditions and the
//! measurement recorded per converged step.

/// Proportional Dirichlet conditions: u[dofs[i]] = base[i] + λ·rate[i].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Dirichlet {
    /// Global DOFs (3·node + component).
    pub dofs: Vec<usize>,
    /// Value at λ = 0, m.
    pub base: Vec<f64>,
    /// Value per unit λ (dimensionless: λ is a length, m).
    pub rate: Vec<f64>,
    /// Free DOFs that move as ± another free DOF (a half-turn half model's
    /// cut face).
    pub ties: Vec<crate::assembly::Tie>,
    /// Per node, its side of the cut the ties join (+1, −1, or 0 on the
    /// cut's axis; empty without ties): the multigrid's aggregates stay on
    /// one side, where the rigid-body modes are rigid.
    pub charts: Vec<i8>,
}

impl Dirichlet {
    /// Adds DOF `dof` with value `base + λ·rate`.
    pub fn push(&mut self, dof: usize, base: f64, rate: f64) {
        self.dofs.push(dof);
        self.base.push(base);
        self.rate.push(rate);
    }
    /// The DOFs that move with λ and their rates.
    pub fn load_rates(&self) -> Vec<(usize, f64)> {
        self.dofs
            .iter()
            .zip(&self.rate)
            .filter(|(_, r)| **r != 0.0)
            .map(|(d, r)| (*d, *r))
            .collect()
    }
    pub(crate) fn apply(&self, lambda: f64, u: &mut [f64]) {
        for i in 0..self.dofs.len() {
            u[self.dofs[i]] = self.base[i] + lambda * self.rate[i];
        }
    }
}

/// What is recorded per converged step.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// Force = Σ f_int over these global DOFs, N.
    pub force_dofs: Vec<usize>,
    /// Relative displacement = mean u over `plus` − mean u over `minus`, m.
    pub plus_dofs: Vec<usize>,
    pub minus_dofs: Vec<usize>,
    /// Weights of those means, one per DOF (empty: equal weights). A part
    /// of a symmetric specimen weights each node by the number of its
    /// images in the whole, so the means are the whole specimen's.
    pub plus_weights: Vec<f64>,
    pub minus_weights: Vec<f64>,
    /// Stress = force · this factor (1/m²), e.g. 1/(π d l_adh) (applied
    /// after `force_factor`).
    pub stress_per_force: f64,
    /// Whole-specimen force per force summed on the model (1, or 4 for a
    /// quarter model: `Symmetry::force_factor`), dimensionless.
    pub force_factor: f64,
}

impl Default for Measurement {
    fn default() -> Self {
        Self {
            force_dofs: Vec::new(),
            plus_dofs: Vec::new(),
            minus_dofs: Vec::new(),
            plus_weights: Vec::new(),
            minus_weights: Vec::new(),
            stress_per_force: 0.0,
            force_factor: 1.0,
        }
    }
}

impl Measurement {
    /// The relative displacement as weights on global DOFs (mean over
    /// `plus` minus mean over `minus`).
    pub fn relative_weights(&self) -> Vec<(usize, f64)> {
        let mut w = Vec::new();
        for (ds, ws, sign) in [
            (&self.plus_dofs, &self.plus_weights, 1.0),
            (&self.minus_dofs, &self.minus_weights, -1.0),
        ] {
            let total = weight_sum(ds, ws);
            w.extend(
                ds.iter()
                    .enumerate()
                    .map(|(i, &d)| (d, sign * ws.get(i).copied().unwrap_or(1.0) / total)),
            );
        }
        w
    }

    /// (force N, relative displacement m, stress Pa) of a state.
    pub(crate) fn eval(&self, u: &[f64], f_int: &[f64]) -> (f64, f64, f64) {
        let force: f64 = self.force_factor * self.force_dofs.iter().map(|&d| f_int[d]).sum::<f64>();
        let mean = |ds: &[usize], ws: &[f64]| {
            if ds.is_empty() {
                0.0
            } else if ws.is_empty() {
                ds.iter().map(|&d| u[d]).sum::<f64>() / ds.len() as f64
            } else {
                ds.iter().zip(ws).map(|(&d, w)| w * u[d]).sum::<f64>() / weight_sum(ds, ws)
            }
        };
        let rel =
            mean(&self.plus_dofs, &self.plus_weights) - mean(&self.minus_dofs, &self.minus_weights);
        (force, rel, force * self.stress_per_force)
    }
}

/// Σ of the weights of `ds` (their count when `ws` is empty).
fn weight_sum(ds: &[usize], ws: &[f64]) -> f64 {
    if ws.is_empty() {
        ds.len() as f64
    } else {
        ws.iter().sum()
    }
}
