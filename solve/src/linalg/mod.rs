//! Linear solvers for the symmetric tangent systems (lower triangle, CSC).
//!
//! * [`Cholesky`]: faer's sparse LLᵀ with the symbolic analysis (ordering,
//!   elimination tree, supernodes) done once per mesh and the numeric
//!   factorisation redone on new values. The fill-reducing ordering is METIS
//!   nested dissection on the node graph, expanded to each node's DOFs
//!   (SPEC §9: 3× faster and half the memory of faer's AMD at 285 k DOFs),
//!   or faer's AMD.
//! * [`pcg`]: conjugate gradients on the current matrix preconditioned by an
//!   older Cholesky factor, so one factorisation serves many iterations and
//!   steps while the tangent drifts slowly (damage, friction).

pub mod amg;
pub mod multigrid;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use serde::{Deserialize, Serialize};

/// Fill-reducing ordering of the Cholesky factor.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Ordering {
    /// METIS nested dissection on the node graph (METIS_NodeND).
    #[default]
    Metis,
    /// faer's approximate minimum degree.
    Amd,
}

/// Why a linear solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearError {
    #[error("matrix is not positive definite (non-positive pivot at permuted column {index})")]
    NotPositiveDefinite { index: usize },
    #[error("symbolic Cholesky analysis failed: {0}")]
    Symbolic(String),
    #[error("METIS ordering failed with status {0}")]
    Metis(i32),
    #[error("out of memory for the factorisation workspace")]
    OutOfMemory,
    #[error("conjugate gradients did not reach relative residual {tolerance:e} in {iterations} iterations (reached {reached:e})")]
    PcgNotConverged {
        iterations: usize,
        tolerance: f64,
        reached: f64,
    },
    #[error("GMRES did not reach relative residual {tolerance:e} in {iterations} iterations (reached {reached:e})")]
    KrylovNotConverged {
        iterations: usize,
        tolerance: f64,
        reached: f64,
    },
    #[error("non-finite value in the linear solve")]
    NonFinite,
}

/// A symmetric matrix given by its lower triangle in CSC form.
#[derive(Debug, Clone, Copy)]
pub struct SymLower<'a> {
    pub col_ptr: &'a [usize],
    pub row_idx: &'a [usize],
    pub values: &'a [f64],
}

impl SymLower<'_> {
    pub fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// y = A x.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..self.n() {
            let xj = x[j];
            let mut acc = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[k];
                let a = self.values[k];
                if i == j {
                    acc += a * xj;
                } else {
                    y[i] += a * xj;
                    acc += a * x[i];
                }
            }
            y[j] += acc;
        }
    }
}

/// METIS nested-dissection permutation of the DOFs: METIS_NodeND on the
/// graph of nodes (`dof_node[i]` = node of free DOF `i`, nondecreasing), each
/// node's DOFs kept together. Returns (forward, inverse) with
/// `forward[new] = old`.
pub fn metis_ordering(
    col_ptr: &[usize],
    row_idx: &[usize],
    dof_node: &[usize],
) -> Result<(Vec<usize>, Vec<usize>), LinearError> {
    let n = col_ptr.len() - 1;
    // Compress node ids to 0..m and record each node's first DOF.
    let mut node_first = Vec::new();
    let mut dof_cnode = vec![0usize; n];
    for i in 0..n {
        if i == 0 || dof_node[i] != dof_node[i - 1] {
            node_first.push(i);
        }
        dof_cnode[i] = node_first.len() - 1;
    }
    let m = node_first.len();
    node_first.push(n);
    let mut adj: Vec<Vec<i32>> = vec![Vec::new(); m];
    for j in 0..n {
        let b = dof_cnode[j];
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            let a = dof_cnode[i];
            if a != b {
                adj[a].push(b as i32);
                adj[b].push(a as i32);
            }
        }
    }
    let mut xadj = Vec::with_capacity(m + 1);
    let mut adjncy = Vec::new();
    xadj.push(0i32);
    for v in adj.iter_mut() {
        v.sort_unstable();
        v.dedup();
        adjncy.extend_from_slice(v);
        xadj.push(adjncy.len() as i32);
    }
    let mut perm = vec![0i32; m];
    let mut iperm = vec![0i32; m];
    if m > 1 {
        // METIS draws from one random generator shared by the whole
        // process (GKlib's), reseeded at each call: two calls at once
        // interleave its draws and order differently. One call at a
        // time keeps an ordering the same from run to run.
        static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
        let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
        let mut nv = m as i32;
        let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
        // SAFETY: arrays sized as METIS documents (xadj m+1, adjncy 2|E|, perm/iperm m).
        let status = unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            // C numbering (0-based) is the default.
            metis_sys::METIS_NodeND(
                &mut nv,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(LinearError::Metis(status));
        }
    }
    let mut fwd = Vec::with_capacity(n);
    for &node in &perm {
        let node = node as usize;
        fwd.extend(node_first[node]..node_first[node + 1]);
    }
    let mut inv = vec![0usize; n];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    Ok((fwd, inv))
}

/// Sparse Cholesky with a reusable symbolic analysis.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    factor: Vec<f64>,
    /// L rounded to single precision for preconditioner applications, when
    /// enabled: the triangular solves are bound by memory traffic over L.
    factor_single: Option<Vec<f32>>,
    factored: bool,
}

impl Cholesky {
    /// Symbolic analysis of the lower-triangle pattern. `dof_node` (node of
    /// each DOF, nondecreasing) is needed for [`Ordering::Metis`].
    pub fn new(
        col_ptr: &[usize],
        row_idx: &[usize],
        ordering: Ordering,
        dof_node: &[usize],
    ) -> Result<Self, LinearError> {
        let n = col_ptr.len() - 1;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let perm;
        let ord = match ordering {
            Ordering::Amd => SymmetricOrdering::Amd,
            Ordering::Metis => {
                perm = metis_ordering(col_ptr, row_idx, dof_node)?;
                SymmetricOrdering::Custom(PermRef::new_checked(&perm.0, &perm.1, n))
            }
        };
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, ord, CholeskySymbolicParams::default())
                .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?;
        let len = symbolic.len_val();
        Ok(Self {
            symbolic,
            col_ptr: col_ptr.to_vec(),
            row_idx: row_idx.to_vec(),
            factor: vec![0.0; len],
            factor_single: None,
            factored: false,
        })
    }

    /// Number of stored entries of the factor L.
    pub fn factor_len(&self) -> usize {
        self.factor.len()
    }

    /// Whether a numeric factorisation is available.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Numeric factorisation of the matrix with the analysed pattern.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.factored = false;
        let n = self.col_ptr.len() - 1;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(sym, values);
        let par = faer::get_global_parallelism();
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut buf = MemBuffer::try_new(req).map_err(|_| LinearError::OutOfMemory)?;
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.factor,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buf),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    LinearError::NotPositiveDefinite { index }
                }
            })?;
        if let Some(single) = &mut self.factor_single {
            single.resize(self.factor.len(), 0.0);
            for (s, &d) in single.iter_mut().zip(&self.factor) {
                *s = d as f32;
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Keep (or drop) a single-precision copy of L for [`Self::precondition`]
    /// (takes effect at the next factorisation).
    pub fn set_single_precision_preconditioner(&mut self, on: bool) {
        self.factor_single = if on { Some(Vec::new()) } else { None };
        self.factored = false;
    }

    /// Applies the preconditioner (L Lᵀ)⁻¹ in place: with the single-precision
    /// copy of L when one is kept, else exactly like [`Self::solve_in_place`].
    pub fn precondition(&self, rhs: &mut [f64]) -> Result<(), LinearError> {
        let Some(single) = &self.factor_single else {
            return self.solve_in_place(rhs);
        };
        assert!(self.factored, "solve before factorize");
        // One thread: faer's parallel triangular solve with one right-hand
        // side hands small pieces of each supernode to the pool, which
        // costs more than it gains at the sizes this preconditioner is
        // chosen for (docs/src/validation/performance.md, "r1-coarse end to end"), and
        // its sums depended on the number of threads.
        let par = Par::Seq;
        let n = rhs.len();
        let llt = LltRef::<'_, usize, f32>::new(&self.symbolic, single);
        let req = self.symbolic.solve_in_place_scratch::<f32>(1, par);
        let mut buf = MemBuffer::try_new(req).map_err(|_| LinearError::OutOfMemory)?;
        let mut x: Vec<f32> = rhs.iter().map(|&v| v as f32).collect();
        let mat = MatMut::from_column_major_slice_mut(&mut x, n, 1);
        llt.solve_in_place_with_conj(Conj::No, mat, par, MemStack::new(&mut buf));
        for (r, &v) in rhs.iter_mut().zip(&x) {
            *r = v as f64;
        }
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearError::NonFinite)
        }
    }

    /// Solves L Lᵀ x = b in place (`rhs` holds b on entry, x on exit).
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), LinearError> {
        assert!(self.factored, "solve before factorize");
        let par: Par = faer::get_global_parallelism();
        let n = rhs.len();
        let llt = LltRef::<'_, usize, f64>::new(&self.symbolic, &self.factor);
        let req = self.symbolic.solve_in_place_scratch::<f64>(1, par);
        let mut buf = MemBuffer::try_new(req).map_err(|_| LinearError::OutOfMemory)?;
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        llt.solve_in_place_with_conj(Conj::No, mat, par, MemStack::new(&mut buf));
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearError::NonFinite)
        }
    }
}

/// Result of a Krylov solve (PCG or GMRES).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovInfo {
    pub iterations: usize,
    /// Final ‖b − A x‖ / ‖b‖ (for GMRES the Arnoldi estimate).
    pub relative_residual: f64,
}

/// Preconditioned conjugate gradients for A x = b from x = 0, with the
/// preconditioner `m` (a Cholesky factor of an earlier matrix). Stops at
/// ‖r‖ ≤ `tolerance`·‖b‖ or fails after `max_iterations`.
pub fn pcg(
    a: SymLower<'_>,
    m: &Cholesky,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<KrylovInfo, LinearError> {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let bnorm = norm(b);
    if bnorm == 0.0 {
        return Ok(KrylovInfo {
            iterations: 0,
            relative_residual: 0.0,
        });
    }
    let mut r = b.to_vec();
    let mut z = r.clone();
    m.precondition(&mut z)?;
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    let mut rel = 1.0;
    for it in 1..=max_iterations {
        a.mul(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            // Indefinite current matrix (or breakdown): CG cannot continue.
            return Err(if pap.is_finite() {
                LinearError::NotPositiveDefinite { index: it }
            } else {
                LinearError::NonFinite
            });
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        rel = norm(&r) / bnorm;
        if !rel.is_finite() {
            return Err(LinearError::NonFinite);
        }
        if rel <= tolerance {
            return Ok(KrylovInfo {
                iterations: it,
                relative_residual: rel,
            });
        }
        z.copy_from_slice(&r);
        m.precondition(&mut z)?;
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    Err(LinearError::PcgNotConverged {
        iterations: max_iterations,
        tolerance,
        reached: rel,
    })
}

/// Unknowns from which [`SplitMatrix::mul`] runs in parallel.
pub const PARALLEL_PRODUCT_DOFS: usize = 50_000;
/// Column ranges of a parallel [`SplitMatrix::mul`].
pub const PRODUCT_PARTS: usize = 4;

/// A general (possibly unsymmetric) square matrix in the symmetric pattern
/// of [`SymLower`]: `lower[k]` = A_ij and `upper[k]` = A_ji for the stored
/// position k = (i, j), i ≥ j (see `assembly::Outputs::upper`).
#[derive(Debug, Clone, Copy)]
pub struct SplitMatrix<'a> {
    pub col_ptr: &'a [usize],
    pub row_idx: &'a [usize],
    pub lower: &'a [f64],
    pub upper: &'a [f64],
}

impl SplitMatrix<'_> {
    pub fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// y = A x. From [`PARALLEL_PRODUCT_DOFS`] unknowns on, the columns are
    /// cut into [`PRODUCT_PARTS`] ranges of equal entries, each summed into
    /// its own vector in parallel, and the vectors added: a fixed cut, so
    /// the result does not depend on the number of threads.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n();
        if n < PARALLEL_PRODUCT_DOFS {
            y.iter_mut().for_each(|v| *v = 0.0);
            self.mul_columns(0..n, x, y);
            return;
        }
        use rayon::prelude::*;
        let nnz = self.col_ptr[n];
        let mut cuts = vec![0usize];
        for p in 1..PRODUCT_PARTS {
            let target = nnz * p / PRODUCT_PARTS;
            cuts.push(self.col_ptr.partition_point(|&c| c < target).min(n));
        }
        cuts.push(n);
        let parts: Vec<Vec<f64>> = cuts
            .par_windows(2)
            .map(|w| {
                let mut part = vec![0.0; n];
                self.mul_columns(w[0]..w[1], x, &mut part);
                part
            })
            .collect();
        y.par_iter_mut().enumerate().for_each(|(i, v)| {
            *v = parts.iter().map(|p| p[i]).sum();
        });
    }

    /// Adds the columns `columns` of A x to `y`.
    fn mul_columns(&self, columns: std::ops::Range<usize>, x: &[f64], y: &mut [f64]) {
        for j in columns {
            let xj = x[j];
            let mut acc = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[k];
                if i == j {
                    acc += self.lower[k] * xj;
                } else {
                    y[i] += self.lower[k] * xj;
                    acc += self.upper[k] * x[i];
                }
            }
            y[j] += acc;
        }
    }

    /// Lower values of the symmetric part (A + Aᵀ)/2.
    pub fn symmetric_part(&self, out: &mut [f64]) {
        for ((o, l), u) in out.iter_mut().zip(self.lower).zip(self.upper) {
            *o = 0.5 * (l + u);
        }
    }
}

/// A linear operator y = A x on vectors of length `n`.
pub trait Operator {
    fn n(&self) -> usize;
    fn mul(&self, x: &[f64], y: &mut [f64]);
}

/// An approximate inverse applied in place, z = M⁻¹ r.
pub trait Preconditioner {
    fn apply(&self, r: &mut [f64]) -> Result<(), LinearError>;
}

impl Operator for SplitMatrix<'_> {
    fn n(&self) -> usize {
        SplitMatrix::n(self)
    }
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        SplitMatrix::mul(self, x, y)
    }
}

impl Preconditioner for Cholesky {
    fn apply(&self, r: &mut [f64]) -> Result<(), LinearError> {
        self.precondition(r)
    }
}

/// Flexible GMRES (Saad 1993) for A x = b from x = 0, right-preconditioned
/// by `m`, e.g. the Cholesky factor of an SPD matrix close to A (A M⁻¹ y = b),
/// without restart: stops at ‖b − A x‖ ≤ `tolerance`·‖b‖ or fails after
/// `max_iterations` (storage: 2 `max_iterations` + 1 vectors). Right
/// preconditioning makes the monitored residual the true one, so the Newton
/// correction's accuracy does not depend on the preconditioner's quality.
pub fn gmres(
    a: &impl Operator,
    m: &impl Preconditioner,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<KrylovInfo, LinearError> {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let beta = norm(b);
    if beta == 0.0 {
        return Ok(KrylovInfo {
            iterations: 0,
            relative_residual: 0.0,
        });
    }
    if !beta.is_finite() {
        return Err(LinearError::NonFinite);
    }
    let kmax = max_iterations.max(1);
    let mut v: Vec<Vec<f64>> = Vec::with_capacity(kmax + 1);
    v.push(b.iter().map(|bi| bi / beta).collect());
    // Hessenberg columns after the Givens rotations (upper triangular R).
    let mut h: Vec<Vec<f64>> = Vec::with_capacity(kmax);
    let mut cs: Vec<f64> = Vec::with_capacity(kmax);
    let mut sn: Vec<f64> = Vec::with_capacity(kmax);
    let mut g = vec![beta];
    // Flexible GMRES keeps z_k = M⁻¹ v_k and builds x from them: the
    // single-precision preconditioner is not exactly linear, so x = M⁻¹ V y
    // would not be the vector the Arnoldi residual estimate describes.
    let mut zs: Vec<Vec<f64>> = Vec::with_capacity(kmax);
    let mut w = vec![0.0; n];
    let mut rel = 1.0;
    let mut k = 0;
    while k < kmax {
        let mut z = v[k].clone();
        m.apply(&mut z)?;
        a.mul(&z, &mut w);
        zs.push(z);
        let mut col = vec![0.0; k + 2];
        // Modified Gram–Schmidt.
        for (i, vi) in v.iter().enumerate() {
            let hij = dot(&w, vi);
            col[i] = hij;
            w.iter_mut().zip(vi).for_each(|(wj, vj)| *wj -= hij * vj);
        }
        let hnext = norm(&w);
        if !hnext.is_finite() {
            return Err(LinearError::NonFinite);
        }
        col[k + 1] = hnext;
        for i in 0..k {
            let (c, s) = (cs[i], sn[i]);
            let (p, q) = (col[i], col[i + 1]);
            col[i] = c * p + s * q;
            col[i + 1] = -s * p + c * q;
        }
        let r = col[k].hypot(col[k + 1]);
        let (c, s) = if r == 0.0 {
            (1.0, 0.0)
        } else {
            (col[k] / r, col[k + 1] / r)
        };
        cs.push(c);
        sn.push(s);
        col[k] = r;
        col.truncate(k + 1);
        h.push(col);
        g.push(-s * g[k]);
        g[k] *= c;
        k += 1;
        rel = g[k].abs() / beta;
        if rel <= tolerance || hnext == 0.0 {
            break;
        }
        v.push(w.iter().map(|wj| wj / hnext).collect());
    }
    // y = R⁻¹ g, x = Z y.
    let mut y = vec![0.0; k];
    for i in (0..k).rev() {
        let mut s = g[i];
        for (j, yj) in y.iter().enumerate().skip(i + 1) {
            s -= h[j][i] * yj;
        }
        if h[i][i] == 0.0 {
            return Err(LinearError::NonFinite);
        }
        y[i] = s / h[i][i];
    }
    for (zi, yi) in zs.iter().zip(&y) {
        x.iter_mut().zip(zi).for_each(|(xj, zj)| *xj += yi * zj);
    }
    if rel <= tolerance {
        Ok(KrylovInfo {
            iterations: k,
            relative_residual: rel,
        })
    } else {
        Err(LinearError::KrylovNotConverged {
            iterations: k,
            tolerance,
            reached: rel,
        })
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(crate) fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian chain with 3 DOFs per "node", lower CSC.
    fn laplacian(nodes: usize, shift: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>, Vec<usize>) {
        let n = 3 * nodes;
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for j in 0..n {
            ri.push(j);
            v.push(2.0 + shift);
            if j + 3 < n {
                ri.push(j + 3);
                v.push(-1.0);
            }
            cp.push(ri.len());
        }
        (cp, ri, v, (0..n).map(|i| i / 3).collect())
    }

    /// Both orderings solve an SPD system to round-off; PCG with the factor of
    /// a nearby matrix converges on the current one.
    #[test]
    fn cholesky_and_pcg_solve_spd_systems() {
        let (cp, ri, v, dn) = laplacian(40, 0.01);
        let n = cp.len() - 1;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        for ord in [Ordering::Metis, Ordering::Amd] {
            let mut c = Cholesky::new(&cp, &ri, ord, &dn).unwrap();
            c.factorize(&v).unwrap();
            let mut x = b.clone();
            c.solve_in_place(&mut x).unwrap();
            let mut ax = vec![0.0; n];
            SymLower {
                col_ptr: &cp,
                row_idx: &ri,
                values: &v,
            }
            .mul(&x, &mut ax);
            let err: f64 = ax
                .iter()
                .zip(&b)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{ord:?}: {err}");
        }
        let mut c = Cholesky::new(&cp, &ri, Ordering::Metis, &dn).unwrap();
        c.factorize(&v).unwrap();
        let (_, _, v2, _) = laplacian(40, 0.05);
        let a2 = SymLower {
            col_ptr: &cp,
            row_idx: &ri,
            values: &v2,
        };
        let mut x = vec![0.0; n];
        let info = pcg(a2, &c, &b, &mut x, 1e-10, 100).unwrap();
        assert!(info.iterations > 1 && info.relative_residual <= 1e-10);
        let mut neg = v.clone();
        neg[0] = -5.0;
        assert!(matches!(
            c.factorize(&neg),
            Err(LinearError::NotPositiveDefinite { .. })
        ));
    }

    /// The single-precision copy of L preconditions like the double one (to
    /// f32 round-off), and GMRES on an unsymmetric matrix reaches a tight
    /// tolerance with it: only the preconditioner is rounded, not the system.
    #[test]
    fn single_precision_preconditioner_keeps_gmres_exact() {
        let (cp, ri, v, dn) = laplacian(60, 0.01);
        let n = cp.len() - 1;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut c = Cholesky::new(&cp, &ri, Ordering::Metis, &dn).unwrap();
        c.set_single_precision_preconditioner(true);
        c.factorize(&v).unwrap();
        let mut exact = b.clone();
        c.solve_in_place(&mut exact).unwrap();
        let mut single = b.clone();
        c.precondition(&mut single).unwrap();
        let diff = norm(
            &exact
                .iter()
                .zip(&single)
                .map(|(p, q)| p - q)
                .collect::<Vec<_>>(),
        );
        assert!(diff > 0.0 && diff < 1e-4 * norm(&exact), "{diff}");
        // Unsymmetric perturbation of the matrix: upper values differ from lower.
        let (_, _, lower, _) = laplacian(60, 0.05);
        let upper: Vec<f64> = lower
            .iter()
            .enumerate()
            .map(|(k, x)| if k % 2 == 1 { 0.9 * x } else { *x })
            .collect();
        let a = SplitMatrix {
            col_ptr: &cp,
            row_idx: &ri,
            lower: &lower,
            upper: &upper,
        };
        let mut x = vec![0.0; n];
        let info = gmres(&a, &c, &b, &mut x, 1e-10, 60).unwrap();
        let mut ax = vec![0.0; n];
        a.mul(&x, &mut ax);
        let res: Vec<f64> = ax.iter().zip(&b).map(|(p, q)| p - q).collect();
        assert!(
            norm(&res) <= 1e-9 * norm(&b),
            "{info:?}: {}",
            norm(&res) / norm(&b)
        );
    }

    /// 7-point Laplacian (slightly shifted, SPD) on a side³ grid, one
    /// unknown per grid point, lower CSC with sorted rows.
    fn grid_laplacian(side: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let at = |i: usize, j: usize, k: usize| (i * side + j) * side + k;
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for i in 0..side {
            for j in 0..side {
                for k in 0..side {
                    ri.push(at(i, j, k));
                    v.push(6.01);
                    for (p, q, r) in [(i, j, k + 1), (i, j + 1, k), (i + 1, j, k)] {
                        if p < side && q < side && r < side {
                            ri.push(at(p, q, r));
                            v.push(-1.0);
                        }
                    }
                    cp.push(ri.len());
                }
            }
        }
        (cp, ri, v)
    }

    /// METIS orders a graph the same way when other threads call it at the
    /// same time (its random generator is shared by the process).
    #[test]
    fn concurrent_metis_calls_order_alike() {
        let (cp, ri, _) = grid_laplacian(16);
        let dof_node: Vec<usize> = (0..cp.len() - 1).collect();
        let alone = metis_ordering(&cp, &ri, &dof_node).unwrap();
        std::thread::scope(|s| {
            let runs: Vec<_> = (0..4)
                .map(|_| {
                    s.spawn(|| {
                        (0..10)
                            .map(|_| metis_ordering(&cp, &ri, &dof_node).unwrap())
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for run in runs {
                for ordering in run.join().unwrap() {
                    assert!(ordering == alone, "a concurrent call ordered differently");
                }
            }
        });
    }

    /// The factorisation and the single-precision preconditioner give the
    /// same bits whatever the number of threads, so a run's curve does
    /// not depend on the machine's cores (a 3D grid Laplacian, big enough
    /// for faer to split its supernodes among threads).
    #[test]
    fn the_preconditioner_does_not_depend_on_the_number_of_threads() {
        let (cp, ri, v) = grid_laplacian(22);
        let n = cp.len() - 1;
        let dof_node: Vec<usize> = (0..n).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let applied = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut x = b.clone();
            pool.install(|| {
                let mut c = Cholesky::new(&cp, &ri, Ordering::Metis, &dof_node).unwrap();
                c.set_single_precision_preconditioner(true);
                c.factorize(&v).unwrap();
                c.precondition(&mut x)
            })
            .unwrap();
            x
        };
        let one = applied(1);
        assert_eq!(one, applied(2));
        assert_eq!(one, applied(4));
    }

    /// The parallel product (column ranges summed apart) equals the serial
    /// one to round-off, on an unsymmetric banded matrix above the size
    /// where it starts, and does not depend on the number of threads.
    #[test]
    fn parallel_split_product_equals_the_serial_one() {
        let n = PARALLEL_PRODUCT_DOFS + 1234;
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for j in 0..n {
            for i in [j, j + 1, j + 7, j + 300].into_iter().filter(|&i| i < n) {
                row_idx.push(i);
            }
            col_ptr.push(row_idx.len());
        }
        let lower: Vec<f64> = (0..row_idx.len())
            .map(|k| ((k * 37) % 11) as f64 - 4.5)
            .collect();
        let upper: Vec<f64> = (0..row_idx.len())
            .map(|k| ((k * 13) % 7) as f64 - 2.5)
            .collect();
        let a = SplitMatrix {
            col_ptr: &col_ptr,
            row_idx: &row_idx,
            lower: &lower,
            upper: &upper,
        };
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut serial = vec![0.0; n];
        a.mul_columns(0..n, &x, &mut serial);
        let mut parallel = vec![1.0; n];
        a.mul(&x, &mut parallel);
        for (p, q) in parallel.iter().zip(&serial) {
            assert!((p - q).abs() <= 1e-12 * (1.0 + q.abs()), "{p} vs {q}");
        }
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut single = vec![0.0; n];
        one.install(|| a.mul(&x, &mut single));
        assert_eq!(single, parallel);
    }
}
