//! Gradient-enhanced averaging of the concrete's equivalent strain (the
//! implicit gradient model of Peerlings, de Borst, Brekelmans & de Vree,
//! IJNME 39, 1996): the averaged strain ε̄ solves
//!
//!   ε̄ − ℓ² ∇²ε̄ = ε_eq  in the concrete,  ∇ε̄ · n = 0  on its boundary,
//!
//! with ℓ the internal length (`materials.concrete.nonlocal_length`).
//! Mazars' κ then follows ε̄ instead of the point's own ε_eq, and a damage
//! zone takes a width set by ℓ rather than by the elements, which is what
//! lets a mesh-convergence series converge.
//!
//! Discretisation: ε̄ is linear on the concrete tets (one value per concrete
//! node; the duplicated interface nodes keep steel out), ε_eq constant per
//! tet (one integration point), so the system is (M + ℓ² K) ε̄ = f with the
//! consistent mass M_ab = V (1 + δ_ab)/20, the Laplacian K_ab = V ∇N_a·∇N_b
//! and f_a = V ε_eq / 4 summed over the tets; a tet's ε̄ is the mean of
//! its four nodal values (its centroid's). The matrix depends on the mesh
//! only: it is factored once.
//!
//! The solver averages once per converged step, staggered (`nonlinear`):
//! with IMPL-EX the stress of a step uses damage extrapolated from the
//! committed history, so equilibrium does not depend on the averaged strain
//! of the step itself, and the implicit history is updated from it after
//! convergence; the IMPL-EX error indicator then measures the extrapolation
//! against that nonlocal history.

use crate::elements::tet::TetGeometry;
use crate::linalg::{Cholesky, LinearError, Ordering};
use crate::spec::solver::ConcreteIntegration;

/// What the averaging asks of the concrete's integration, said where a
/// scene or a run does not give it (after the key `nonlocal_length`).
pub const NEEDS_IMPL_EX: &str = "needs solver.concrete_integration: impl_ex (the averaged \
     strain updates the damage history after each converged step, which only the \
     extrapolated damage leaves out of the step's equilibrium)";

/// Whether a gradient-enhanced damage of length `nonlocal_length` (if any)
/// can run with `integration`: only staggered under IMPL-EX.
pub fn admits(nonlocal_length: Option<f64>, integration: ConcreteIntegration) -> bool {
    nonlocal_length.is_none() || integration == ConcreteIntegration::ImplEx
}

/// The factored averaging operator of a set of tets.
pub struct GradientAveraging {
    /// The averaged tets (indices into the model's tets).
    tets: Vec<usize>,
    /// Their nodes, numbered among the averaged tets' nodes.
    nodes: Vec<[u32; 4]>,
    volumes: Vec<f64>,
    n_nodes: usize,
    factor: Cholesky,
}

impl GradientAveraging {
    /// The operator of internal length `length` (m) over the tets
    /// `averaged` of a mesh whose tets are `tets` with geometry `geometry`.
    pub fn new(
        tets: &[[u32; 4]],
        geometry: &[TetGeometry],
        averaged: impl Fn(usize) -> bool,
        length: f64,
    ) -> Result<Self, LinearError> {
        let chosen: Vec<usize> = (0..tets.len()).filter(|&i| averaged(i)).collect();
        let n_global = tets
            .iter()
            .flat_map(|t| t.iter())
            .map(|&n| n as usize + 1)
            .max()
            .unwrap_or(0);
        let mut number = vec![u32::MAX; n_global];
        let mut n_nodes = 0u32;
        let nodes: Vec<[u32; 4]> = chosen
            .iter()
            .map(|&i| {
                tets[i].map(|n| {
                    let slot = &mut number[n as usize];
                    if *slot == u32::MAX {
                        *slot = n_nodes;
                        n_nodes += 1;
                    }
                    *slot
                })
            })
            .collect();
        let n = n_nodes as usize;
        // Lower-triangle pattern, column-major.
        let mut entries: Vec<(u32, u32)> = Vec::with_capacity(10 * nodes.len());
        for t in &nodes {
            for a in 0..4 {
                for b in 0..4 {
                    if t[a] >= t[b] {
                        entries.push((t[b], t[a]));
                    }
                }
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(c, _) in &entries {
            col_ptr[c as usize + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let row_idx: Vec<usize> = entries.iter().map(|&(_, r)| r as usize).collect();
        let mut values = vec![0.0; row_idx.len()];
        let c = length * length;
        for (t, &i) in nodes.iter().zip(&chosen) {
            let g = &geometry[i];
            for a in 0..4 {
                for b in 0..4 {
                    let (row, col) = (t[a] as usize, t[b] as usize);
                    // The lower triangle: each pair of nodes once.
                    if row < col {
                        continue;
                    }
                    let mass = g.volume * if a == b { 0.1 } else { 0.05 };
                    let grad = g.grad[a]
                        .iter()
                        .zip(&g.grad[b])
                        .map(|(x, y)| x * y)
                        .sum::<f64>();
                    let column = &row_idx[col_ptr[col]..col_ptr[col + 1]];
                    let k =
                        col_ptr[col] + column.binary_search(&row).expect("entry in the pattern");
                    values[k] += mass + c * g.volume * grad;
                }
            }
        }
        let mut factor = Cholesky::new(&col_ptr, &row_idx, Ordering::Amd, &[])?;
        factor.factorize(&values)?;
        let volumes = chosen.iter().map(|&i| geometry[i].volume).collect();
        Ok(Self {
            tets: chosen,
            nodes,
            volumes,
            n_nodes: n,
            factor,
        })
    }

    /// The averaged tets, in the order [`Self::average`] takes and gives
    /// their values.
    pub fn tets(&self) -> &[usize] {
        &self.tets
    }

    /// The averaged strain ε̄ at each averaged tet's centroid from the
    /// tets' own equivalent strains `local` (same order as [`Self::tets`]).
    pub fn average(&self, local: &[f64]) -> Result<Vec<f64>, LinearError> {
        let mut rhs = vec![0.0; self.n_nodes];
        for ((t, &v), &e) in self.nodes.iter().zip(&self.volumes).zip(local) {
            for &a in t {
                rhs[a as usize] += 0.25 * v * e;
            }
        }
        self.factor.solve_in_place(&mut rhs)?;
        Ok(self
            .nodes
            .iter()
            .map(|t| 0.25 * t.iter().map(|&a| rhs[a as usize]).sum::<f64>())
            .collect())
    }
}
