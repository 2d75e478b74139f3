//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996)
//! for elasticity, used as the preconditioner of conjugate gradients.
//!
//! * Matrices are block sparse rows ([`Bsr`]): 3×3 blocks per node on the
//!   finest level, 6×6 blocks per aggregate below, both triangles stored so
//!   the products parallelise over rows.
//! * Aggregation by node (greedy, three passes) on the block graph, with a
//!   strength threshold on the block Frobenius norms. A model tied across
//!   a cut gives each node a chart (its side of the cut): no aggregate, on
//!   any level, holds nodes of two sides, since the rigid-body modes are
//!   rigid within one side only.
//! * Tentative prolongator: per aggregate the QR factorisation of the
//!   near-null space (the 6 rigid-body modes from the node coordinates on
//!   the finest level, the R factors below); Q is the prolongator block, R
//!   the coarse near-null space. Dependent columns (small or constrained
//!   aggregates) become zero columns whose coarse diagonal is set to 1.
//! * One damped block-Jacobi step smooths the prolongator,
//!   P = (I − ω D⁻¹A) T with ω = 4 / (3 λ_max(D⁻¹A)); A_c = Pᵀ A P.
//! * V-cycle with Chebyshev smoothing on D⁻¹A (a polynomial in D⁻¹A:
//!   symmetric, so the cycle is a valid CG preconditioner, and parallel,
//!   unlike Gauss–Seidel); the coarsest level is solved by sparse Cholesky.
//!
//! Dirichlet DOFs must be eliminated symmetrically before the set-up (row
//! and column zero, diagonal 1) and their near-null-space rows zeroed, so
//! the prolongator never interpolates into them.

use crate::linalg::{Cholesky, LinearError, Ordering};
use rayon::prelude::*;

/// Block sparse rows: `rows` block rows of `br`×`bc` blocks (row-major
/// within a block), sorted block columns per row.
#[derive(Debug, Clone, PartialEq)]
pub struct Bsr {
    /// Block rows.
    pub rows: usize,
    /// Block columns.
    pub cols: usize,
    /// Rows per block.
    pub br: usize,
    /// Columns per block.
    pub bc: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<u32>,
    /// `br·bc` values per stored block.
    pub values: Vec<f64>,
}

impl Bsr {
    /// Stored blocks.
    pub fn blocks(&self) -> usize {
        self.col_idx.len()
    }

    /// Scalar entries of the stored blocks.
    pub fn entries(&self) -> usize {
        self.col_idx.len() * self.br * self.bc
    }

    /// Block (i, j) position in `col_idx`, if stored.
    pub fn find(&self, i: usize, j: usize) -> Option<usize> {
        let s = self.row_ptr[i];
        self.col_idx[s..self.row_ptr[i + 1]]
            .binary_search(&(j as u32))
            .ok()
            .map(|k| s + k)
    }

    /// y = A x (parallel over block rows).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.mul_with(&self.values, x, y);
    }

    /// y = A x with `values` (one per stored block entry, in place of
    /// `self.values`: a single-precision copy), summed in f64.
    pub fn mul_with<T: Copy + Into<f64> + Sync>(&self, values: &[T], x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(values.len(), self.col_idx.len() * self.br * self.bc);
        match (self.br, self.bc) {
            (3, 3) => self.mul_fixed::<3, 3, T>(values, x, y),
            (6, 6) => self.mul_fixed::<6, 6, T>(values, x, y),
            (3, 6) => self.mul_fixed::<3, 6, T>(values, x, y),
            (6, 3) => self.mul_fixed::<6, 3, T>(values, x, y),
            _ => self.mul_any(values, x, y),
        }
    }

    fn mul_fixed<const R: usize, const C: usize, T: Copy + Into<f64> + Sync>(
        &self,
        values: &[T],
        x: &[f64],
        y: &mut [f64],
    ) {
        self.rows_fixed::<R, C, T>(values, x, y, |_, yi, acc| *yi = acc);
    }

    /// Block row i of A x with `values`, summed in f64.
    #[inline(always)]
    fn row_product<const R: usize, const C: usize, T: Copy + Into<f64>>(
        &self,
        values: &[T],
        x: &[f64],
        i: usize,
    ) -> [f64; R] {
        let mut acc = [0.0f64; R];
        for k in self.row_ptr[i]..self.row_ptr[i + 1] {
            let j = self.col_idx[k] as usize;
            let blk = &values[k * R * C..(k + 1) * R * C];
            let xj = &x[j * C..(j + 1) * C];
            for r in 0..R {
                let mut s = 0.0;
                for c in 0..C {
                    s += blk[r * C + c].into() * xj[c];
                }
                acc[r] += s;
            }
        }
        acc
    }

    /// Block row i of A x with `values` (summed in f64), handed to
    /// `store(i, y_i, (A x)_i)`: the product and what is done with it in
    /// one pass over y, in parallel over chunks of block rows.
    fn rows_fixed<const R: usize, const C: usize, T: Copy + Into<f64> + Sync>(
        &self,
        values: &[T],
        x: &[f64],
        y: &mut [f64],
        store: impl Fn(usize, &mut [f64; R], [f64; R]) + Sync,
    ) {
        y.par_chunks_mut(R * 256)
            .enumerate()
            .for_each(|(chunk, ys)| {
                for (off, yi) in ys.chunks_exact_mut(R).enumerate() {
                    let i = chunk * 256 + off;
                    let acc = self.row_product::<R, C, T>(values, x, i);
                    // A fixed-size store: `copy_from_slice` on the
                    // chunk's runtime length became a `memcpy` call per
                    // row, 8 % of R1's solve (perf).
                    let yi: &mut [f64; R] = yi.try_into().expect("chunks of R");
                    store(i, yi, acc);
                }
            });
    }

    /// y += A x with `values` in one pass; the same bits as
    /// [`Bsr::mul_with`] into a vector and the sum after.
    pub fn mul_add_with<T: Copy + Into<f64> + Sync>(&self, values: &[T], x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(values.len(), self.col_idx.len() * self.br * self.bc);
        fn add<const R: usize>(_: usize, yi: &mut [f64; R], ax: [f64; R]) {
            for (v, a) in yi.iter_mut().zip(ax) {
                *v += a;
            }
        }
        match (self.br, self.bc) {
            (3, 3) => self.rows_fixed::<3, 3, T>(values, x, y, add::<3>),
            (6, 6) => self.rows_fixed::<6, 6, T>(values, x, y, add::<6>),
            (3, 6) => self.rows_fixed::<3, 6, T>(values, x, y, add::<3>),
            (6, 3) => self.rows_fixed::<6, 3, T>(values, x, y, add::<6>),
            _ => {
                let mut ax = vec![0.0; y.len()];
                self.mul_any(values, x, &mut ax);
                y.par_iter_mut().zip(&ax).for_each(|(v, a)| *v += a);
            }
        }
    }

    /// r = b − A x with `values` in one pass; the same bits as
    /// [`Bsr::mul_with`] into a vector and the difference after.
    pub fn residual_with<T: Copy + Into<f64> + Sync>(
        &self,
        values: &[T],
        b: &[f64],
        x: &[f64],
        r: &mut [f64],
    ) {
        debug_assert_eq!(values.len(), self.col_idx.len() * self.br * self.bc);
        fn square<const R: usize, T: Copy + Into<f64> + Sync>(
            a: &Bsr,
            values: &[T],
            (b, x, r): (&[f64], &[f64], &mut [f64]),
        ) {
            a.rows_fixed::<R, R, T>(values, x, r, |i, ri, ax| {
                for (k, (rk, q)) in ri.iter_mut().zip(ax).enumerate() {
                    *rk = b[R * i + k] - q;
                }
            });
        }
        if (self.br, self.bc) == (3, 3) {
            square::<3, T>(self, values, (b, x, r));
        } else if (self.br, self.bc) == (6, 6) {
            square::<6, T>(self, values, (b, x, r));
        } else {
            self.mul_with(values, x, r);
            r.par_iter_mut()
                .zip(b.par_iter())
                .for_each(|(ri, bi)| *ri = bi - *ri);
        }
    }

    fn mul_any<T: Copy + Into<f64> + Sync>(&self, values: &[T], x: &[f64], y: &mut [f64]) {
        let (br, bc) = (self.br, self.bc);
        y.par_chunks_mut(br).enumerate().for_each(|(i, yi)| {
            yi.iter_mut().for_each(|v| *v = 0.0);
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                let j = self.col_idx[k] as usize;
                let blk = &values[k * br * bc..(k + 1) * br * bc];
                for r in 0..br {
                    let mut s = 0.0;
                    for c in 0..bc {
                        s += blk[r * bc + c].into() * x[j * bc + c];
                    }
                    yi[r] += s;
                }
            }
        });
    }

    /// The transpose (blocks transposed).
    pub fn transpose(&self) -> Bsr {
        let (br, bc) = (self.br, self.bc);
        let mut count = vec![0usize; self.cols + 1];
        for &j in &self.col_idx {
            count[j as usize + 1] += 1;
        }
        for j in 0..self.cols {
            count[j + 1] += count[j];
        }
        let row_ptr = count.clone();
        let mut next = count;
        let nb = self.blocks();
        let mut col_idx = vec![0u32; nb];
        let mut values = vec![0.0; nb * br * bc];
        for i in 0..self.rows {
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                let j = self.col_idx[k] as usize;
                let dst = next[j];
                next[j] += 1;
                col_idx[dst] = i as u32;
                let src = &self.values[k * br * bc..(k + 1) * br * bc];
                let out = &mut values[dst * br * bc..(dst + 1) * br * bc];
                for r in 0..br {
                    for c in 0..bc {
                        out[c * br + r] = src[r * bc + c];
                    }
                }
            }
        }
        Bsr {
            rows: self.cols,
            cols: self.rows,
            br: bc,
            bc: br,
            row_ptr,
            col_idx,
            values,
        }
    }

    /// C = A B (block shapes must chain: `a.bc == b.br`), rows in parallel.
    pub fn product(a: &Bsr, b: &Bsr) -> Bsr {
        assert_eq!(a.bc, b.br, "block shapes do not chain");
        assert_eq!(a.cols, b.rows, "matrix shapes do not chain");
        let (br, bk, bc) = (a.br, a.bc, b.bc);
        let bsz = br * bc;
        let rows: Vec<(Vec<u32>, Vec<f64>)> = (0..a.rows)
            .into_par_iter()
            .map_init(
                || (vec![u32::MAX; b.cols], Vec::<u32>::new(), Vec::<f64>::new()),
                |(slot, cols, vals), i| {
                    cols.clear();
                    vals.clear();
                    for ka in a.row_ptr[i]..a.row_ptr[i + 1] {
                        let kk = a.col_idx[ka] as usize;
                        let ab = &a.values[ka * br * bk..(ka + 1) * br * bk];
                        for kb in b.row_ptr[kk]..b.row_ptr[kk + 1] {
                            let j = b.col_idx[kb] as usize;
                            let bb = &b.values[kb * bk * bc..(kb + 1) * bk * bc];
                            if slot[j] == u32::MAX {
                                slot[j] = cols.len() as u32;
                                cols.push(j as u32);
                                vals.extend(std::iter::repeat_n(0.0, bsz));
                            }
                            let s = slot[j] as usize;
                            let out = &mut vals[s * bsz..(s + 1) * bsz];
                            for r in 0..br {
                                for m in 0..bk {
                                    let arm = ab[r * bk + m];
                                    if arm == 0.0 {
                                        continue;
                                    }
                                    for c in 0..bc {
                                        out[r * bc + c] += arm * bb[m * bc + c];
                                    }
                                }
                            }
                        }
                    }
                    for &j in cols.iter() {
                        slot[j as usize] = u32::MAX;
                    }
                    // Sort the row's blocks by column.
                    let mut order: Vec<usize> = (0..cols.len()).collect();
                    order.sort_unstable_by_key(|&s| cols[s]);
                    let sc: Vec<u32> = order.iter().map(|&s| cols[s]).collect();
                    let mut sv = Vec::with_capacity(vals.len());
                    for &s in &order {
                        sv.extend_from_slice(&vals[s * bsz..(s + 1) * bsz]);
                    }
                    (sc, sv)
                },
            )
            .collect();
        let mut row_ptr = Vec::with_capacity(a.rows + 1);
        row_ptr.push(0);
        let total: usize = rows.iter().map(|r| r.0.len()).sum();
        let mut col_idx = Vec::with_capacity(total);
        let mut values = Vec::with_capacity(total * bsz);
        for (c, v) in rows {
            col_idx.extend_from_slice(&c);
            values.extend_from_slice(&v);
            row_ptr.push(col_idx.len());
        }
        Bsr {
            rows: a.rows,
            cols: b.cols,
            br,
            bc,
            row_ptr,
            col_idx,
            values,
        }
    }
}

/// Set-up parameters of the multigrid hierarchy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmgParams {
    /// Strength threshold θ (dimensionless): nodes i, j are strongly
    /// connected when ‖A_ij‖_F ≥ θ·√(‖A_ii‖_F ‖A_jj‖_F).
    pub strength: f64,
    /// Chebyshev polynomial degree of each pre- and post-smoothing.
    pub smoother_degree: usize,
    /// Lower end of the Chebyshev interval as a fraction of λ_max.
    pub smoother_range: f64,
    /// The coarsest level has at most this many DOFs (solved by Cholesky).
    pub coarse_dofs: usize,
    /// At most this many levels.
    pub max_levels: usize,
}

impl Default for AmgParams {
    fn default() -> Self {
        Self {
            strength: 0.0,
            smoother_degree: 2,
            smoother_range: 1.0 / 30.0,
            coarse_dofs: 3000,
            max_levels: 10,
        }
    }
}

/// What went wrong in the set-up or a cycle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AmgError {
    #[error("near-null space has {got} values, expected {expected} (6 per DOF)")]
    NullSpace { got: usize, expected: usize },
    #[error("{got} node charts for {expected} nodes")]
    Charts { got: usize, expected: usize },
    #[error("matrix is not square with 3×3 blocks")]
    Shape,
    #[error("diagonal block of row {row} on level {level} is singular")]
    SingularDiagonal { level: usize, row: usize },
    #[error("coarsest level: {0}")]
    Coarse(#[from] LinearError),
    #[error("conjugate gradients did not reach relative residual {tolerance:e} in {iterations} iterations (reached {reached:e})")]
    NotConverged {
        iterations: usize,
        tolerance: f64,
        reached: f64,
    },
    #[error("non-finite value in conjugate gradients (iteration {iteration})")]
    NonFinite { iteration: usize },
}

/// One level of the hierarchy. The cycle reads the level's operators from
/// single-precision copies of their values (sums in f64): the products are
/// bound by memory traffic, which f32 values halve, and a preconditioner
/// needs no more than f32's 6e-8 relative rounding. The f64 values are
/// dropped after the set-up, except the finest matrix's ([`Amg::matrix`]).
struct Level {
    a: Bsr,
    a32: Vec<f32>,
    /// Inverse diagonal blocks.
    dinv: Vec<f64>,
    /// Chebyshev interval of D⁻¹A.
    lo: f64,
    hi: f64,
    p: Bsr,
    p32: Vec<f32>,
    r: Bsr,
    r32: Vec<f32>,
}

/// The single-precision copy of `m`'s values; `keep` false drops the f64
/// values.
fn single_precision(m: &mut Bsr, keep: bool) -> Vec<f32> {
    let v = m.values.iter().map(|&x| x as f32).collect();
    if !keep {
        m.values = Vec::new();
    }
    v
}

/// A smoothed-aggregation hierarchy.
pub struct Amg {
    levels: Vec<Level>,
    single: Option<Bsr>,
    coarse: Cholesky,
    coarse_n: usize,
    /// Stored entries of the coarsest matrix (both triangles).
    coarse_entries: usize,
    params: AmgParams,
}

/// Summary of a hierarchy.
#[derive(Debug, Clone, PartialEq)]
pub struct AmgInfo {
    /// DOFs per level, finest first (the coarsest is the Cholesky level).
    pub level_dofs: Vec<usize>,
    /// Σ entries of all level matrices / entries of the finest.
    pub operator_complexity: f64,
}

fn invert_small(m: &mut [f64], n: usize) -> bool {
    // Gauss–Jordan with partial pivoting on an n×n row-major block.
    let mut inv = vec![0.0; n * n];
    for i in 0..n {
        inv[i * n + i] = 1.0;
    }
    let scale = m.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    if !(scale > 0.0 && scale.is_finite()) {
        return false;
    }
    for c in 0..n {
        let p = (c..n)
            .max_by(|&a, &b| m[a * n + c].abs().total_cmp(&m[b * n + c].abs()))
            .unwrap_or(c);
        if m[p * n + c].abs() <= 1e-14 * scale {
            return false;
        }
        if p != c {
            for k in 0..n {
                m.swap(p * n + k, c * n + k);
                inv.swap(p * n + k, c * n + k);
            }
        }
        let d = 1.0 / m[c * n + c];
        for k in 0..n {
            m[c * n + k] *= d;
            inv[c * n + k] *= d;
        }
        for r in 0..n {
            if r != c {
                let f = m[r * n + c];
                if f != 0.0 {
                    for k in 0..n {
                        m[r * n + k] -= f * m[c * n + k];
                        inv[r * n + k] -= f * inv[c * n + k];
                    }
                }
            }
        }
    }
    m.copy_from_slice(&inv);
    true
}

fn block_diag_inverse(a: &Bsr, level: usize) -> Result<Vec<f64>, AmgError> {
    let b = a.br;
    let mut out = vec![0.0; a.rows * b * b];
    out.par_chunks_mut(b * b)
        .enumerate()
        .try_for_each(|(i, blk)| {
            let k = a
                .find(i, i)
                .ok_or(AmgError::SingularDiagonal { level, row: i })?;
            blk.copy_from_slice(&a.values[k * b * b..(k + 1) * b * b]);
            if invert_small(blk, b) {
                Ok(())
            } else {
                Err(AmgError::SingularDiagonal { level, row: i })
            }
        })?;
    Ok(out)
}

fn apply_dinv(dinv: &[f64], b: usize, r: &[f64], z: &mut [f64]) {
    z.par_chunks_mut(b)
        .zip(r.par_chunks(b))
        .zip(dinv.par_chunks(b * b))
        .for_each(|((zi, ri), d)| {
            for (row, zr) in zi.iter_mut().enumerate() {
                *zr = dinv_row(d, ri, row);
            }
        });
}

/// Row `row` of one block's D⁻¹ r: `block` (b×b, row-major) times `r_i`.
#[inline(always)]
fn dinv_row(block: &[f64], r_i: &[f64], row: usize) -> f64 {
    let b = r_i.len();
    let mut s = 0.0;
    for (c, rc) in r_i.iter().enumerate() {
        s += block[row * b + c] * rc;
    }
    s
}

/// One Chebyshev iteration after the first on `lev` (B×B blocks) with
/// coefficients (c1, c2), in one pass over the block rows: q = (A d)_i,
/// r_i −= q, z = D⁻¹_i r_i, next_i = c1 d_i + c2 z, x_i += next_i.
fn chebyshev_pass<const B: usize>(
    lev: &Level,
    (c1, c2): (f64, f64),
    d: &[f64],
    (next, r, x): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let rows = B * 256;
    next.par_chunks_mut(rows)
        .zip(r.par_chunks_mut(rows))
        .zip(x.par_chunks_mut(rows))
        .enumerate()
        .for_each(|(chunk, ((ns, rs), xs))| {
            let blocks = ns
                .chunks_exact_mut(B)
                .zip(rs.chunks_exact_mut(B))
                .zip(xs.chunks_exact_mut(B));
            for (off, ((ni, ri), xi)) in blocks.enumerate() {
                let i = chunk * 256 + off;
                let q = lev.a.row_product::<B, B, f32>(&lev.a32, d, i);
                for (rk, qk) in ri.iter_mut().zip(q) {
                    *rk -= qk;
                }
                let dm = &lev.dinv[i * B * B..(i + 1) * B * B];
                for row in 0..B {
                    let dn = c1 * d[i * B + row] + c2 * dinv_row(dm, ri, row);
                    ni[row] = dn;
                    xi[row] += dn;
                }
            }
        });
}

/// Dot product in parallel, with the same bits on any number of threads:
/// the chunks' sums are collected in order and added in order (rayon's own
/// `sum` adds them in a tree that follows how the work was split).
fn pdot(a: &[f64], b: &[f64]) -> f64 {
    let parts: Vec<f64> = a
        .par_chunks(4096)
        .zip(b.par_chunks(4096))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    parts.iter().sum()
}

/// Largest eigenvalue of D⁻¹A by power iteration (a few steps: the
/// Chebyshev interval and ω only need it to ~10 %, then it is enlarged).
fn lambda_max(a: &Bsr, dinv: &[f64]) -> f64 {
    let n = a.rows * a.br;
    let mut x: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0)
        .collect();
    let mut y = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut lam = 1.0;
    for _ in 0..15 {
        let nx = pdot(&x, &x).sqrt();
        x.par_iter_mut().for_each(|v| *v /= nx);
        a.mul(&x, &mut y);
        apply_dinv(dinv, a.br, &y, &mut z);
        // Rayleigh quotient in the A-inner product: (x, A D⁻¹A x)/(x, A x)
        // is the symmetric form of D⁻¹A's eigenproblem.
        let xax = pdot(&x, &y);
        let zaz = pdot(&y, &z);
        if xax > 0.0 {
            lam = zaz / xax;
        }
        std::mem::swap(&mut x, &mut z);
    }
    lam
}

/// Greedy aggregation of the block rows of `a`: `agg[i]` is the aggregate
/// of node i or `u32::MAX` for an isolated node (no strong neighbour:
/// fully constrained), which the prolongator leaves out.
///
/// `charts` (one per node, or empty: all 0) keeps apart nodes of opposite
/// non-zero charts: no aggregate holds both a +1 and a −1 node. A model
/// tied across a cut (a half-turn half) has rigid-body modes that are
/// rigid only within one side of the cut; an aggregate reaching across
/// would take a mode that jumps there into the coarse space. Returns also
/// each aggregate's chart (its members' non-zero chart, or 0), one per
/// aggregate: the charts of the next level.
fn aggregate(a: &Bsr, theta: f64, charts: &[i8]) -> (Vec<u32>, Vec<i8>) {
    let n = a.rows;
    let bsz = a.br * a.bc;
    let chart = |i: usize| charts.get(i).copied().unwrap_or(0);
    let fits = |c: i8, into: i8| c * into >= 0;
    let fro = |k: usize| {
        a.values[k * bsz..(k + 1) * bsz]
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
    };
    let diag: Vec<f64> = (0..n)
        .map(|i| a.find(i, i).map(fro).unwrap_or(0.0))
        .collect();
    let strong: Vec<Vec<u32>> = (0..n)
        .into_par_iter()
        .map(|i| {
            (a.row_ptr[i]..a.row_ptr[i + 1])
                .filter(|&k| {
                    let j = a.col_idx[k] as usize;
                    j != i && {
                        let f = fro(k);
                        f > 0.0 && f >= theta * (diag[i] * diag[j]).sqrt()
                    }
                })
                .map(|k| a.col_idx[k])
                .collect()
        })
        .collect();
    const NONE: u32 = u32::MAX;
    let mut agg = vec![NONE; n];
    let mut agg_chart: Vec<i8> = Vec::new();
    // Pass 1: a node whose strong neighbours are all free (and of one
    // chart with it) seeds an aggregate.
    for i in 0..n {
        if agg[i] != NONE || strong[i].is_empty() {
            continue;
        }
        let mut c = chart(i);
        let free = strong[i].iter().all(|&j| {
            let cj = chart(j as usize);
            let ok = agg[j as usize] == NONE && fits(cj, c);
            if ok && c == 0 {
                c = cj;
            }
            ok
        });
        if free {
            let id = agg_chart.len() as u32;
            agg[i] = id;
            for &j in &strong[i] {
                agg[j as usize] = id;
            }
            agg_chart.push(c);
        }
    }
    // Pass 2: join the neighbouring aggregate of strongest connection.
    let pass1 = agg.clone();
    for i in 0..n {
        if agg[i] != NONE || strong[i].is_empty() {
            continue;
        }
        let mut best = (0.0, NONE);
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            let j = a.col_idx[k] as usize;
            if j != i && pass1[j] != NONE && fits(chart(i), agg_chart[pass1[j] as usize]) {
                let f = fro(k);
                if f > best.0 {
                    best = (f, pass1[j]);
                }
            }
        }
        agg[i] = best.1;
        if best.1 != NONE && agg_chart[best.1 as usize] == 0 {
            agg_chart[best.1 as usize] = chart(i);
        }
    }
    // Pass 3: what is left forms aggregates with its free neighbours.
    for i in 0..n {
        if agg[i] != NONE || strong[i].is_empty() {
            continue;
        }
        let id = agg_chart.len() as u32;
        let mut c = chart(i);
        agg[i] = id;
        for &j in &strong[i] {
            let cj = chart(j as usize);
            if agg[j as usize] == NONE && fits(cj, c) {
                agg[j as usize] = id;
                if c == 0 {
                    c = cj;
                }
            }
        }
        agg_chart.push(c);
    }
    (agg, agg_chart)
}

/// Tentative prolongator (br = block size of `a`, bc = 6) and the coarse
/// near-null space (6 per coarse DOF), by a QR of each aggregate's rows of
/// `null` (6 values per fine DOF).
fn tentative(agg: &[u32], n_agg: usize, b: usize, null: &[f64]) -> (Bsr, Vec<f64>) {
    const K: usize = 6;
    let n = agg.len();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n_agg];
    for (i, &g) in agg.iter().enumerate() {
        if g != u32::MAX {
            members[g as usize].push(i);
        }
    }
    // Per aggregate: Q (|members|·b × 6) and R (6×6).
    let qr: Vec<(Vec<f64>, [f64; K * K])> = members
        .par_iter()
        .map(|mem| {
            let m = mem.len() * b;
            let mut q = vec![0.0; m * K];
            for (li, &i) in mem.iter().enumerate() {
                for c in 0..b {
                    let row = li * b + c;
                    q[row * K..(row + 1) * K]
                        .copy_from_slice(&null[(i * b + c) * K..(i * b + c + 1) * K]);
                }
            }
            let mut r = [0.0; K * K];
            // Modified Gram–Schmidt, column by column; a column left with
            // less than 1e-10 of its norm is dependent and set to zero.
            for j in 0..K {
                let orig: f64 = (0..m).map(|row| q[row * K + j].powi(2)).sum::<f64>().sqrt();
                for p in 0..j {
                    let d: f64 = (0..m).map(|row| q[row * K + p] * q[row * K + j]).sum();
                    r[p * K + j] = d;
                    for row in 0..m {
                        q[row * K + j] -= d * q[row * K + p];
                    }
                }
                let nrm: f64 = (0..m).map(|row| q[row * K + j].powi(2)).sum::<f64>().sqrt();
                if nrm > 1e-10 * orig && nrm > 0.0 {
                    r[j * K + j] = nrm;
                    for row in 0..m {
                        q[row * K + j] /= nrm;
                    }
                } else {
                    for row in 0..m {
                        q[row * K + j] = 0.0;
                    }
                }
            }
            (q, r)
        })
        .collect();
    let mut row_ptr = Vec::with_capacity(n + 1);
    row_ptr.push(0);
    let mut col_idx = Vec::new();
    let mut values = vec![0.0; 0];
    let mut local = vec![0usize; n];
    for mem in &members {
        for (li, &i) in mem.iter().enumerate() {
            local[i] = li;
        }
    }
    for i in 0..n {
        let g = agg[i];
        if g != u32::MAX {
            col_idx.push(g);
            let (q, _) = &qr[g as usize];
            let li = local[i];
            values.extend_from_slice(&q[li * b * K..(li + 1) * b * K]);
        }
        row_ptr.push(col_idx.len());
    }
    let mut coarse_null = vec![0.0; n_agg * K * K];
    for (g, (_, r)) in qr.iter().enumerate() {
        coarse_null[g * K * K..(g + 1) * K * K].copy_from_slice(r);
    }
    (
        Bsr {
            rows: n,
            cols: n_agg,
            br: b,
            bc: K,
            row_ptr,
            col_idx,
            values,
        },
        coarse_null,
    )
}

/// P = T − ω D⁻¹ (A T), row by row.
fn smooth_prolongator(a: &Bsr, dinv: &[f64], t: &Bsr, omega: f64) -> Bsr {
    let at = Bsr::product(a, t);
    let (b, k) = (t.br, t.bc);
    let bsz = b * k;
    // Rows are independent: P_i = T_i − ω D_i⁻¹ (AT)_i; T_i's block is in
    // AT's row pattern (A_ii T_i contributes to it) unless A_ii T_i = 0.
    let rows: Vec<(Vec<u32>, Vec<f64>)> = (0..at.rows)
        .into_par_iter()
        .map(|i| {
            let d = &dinv[i * b * b..(i + 1) * b * b];
            let mut cols: Vec<u32> = at.col_idx[at.row_ptr[i]..at.row_ptr[i + 1]].to_vec();
            let mut vals = Vec::with_capacity(cols.len() * bsz);
            for kk in at.row_ptr[i]..at.row_ptr[i + 1] {
                let blk = &at.values[kk * bsz..(kk + 1) * bsz];
                for r in 0..b {
                    for c in 0..k {
                        let mut s = 0.0;
                        for m in 0..b {
                            s += d[r * b + m] * blk[m * k + c];
                        }
                        vals.push(-omega * s);
                    }
                }
            }
            for kt in t.row_ptr[i]..t.row_ptr[i + 1] {
                let g = t.col_idx[kt];
                let tb = &t.values[kt * bsz..(kt + 1) * bsz];
                match cols.binary_search(&g) {
                    Ok(s) => {
                        for (v, x) in vals[s * bsz..(s + 1) * bsz].iter_mut().zip(tb) {
                            *v += x;
                        }
                    }
                    Err(s) => {
                        cols.insert(s, g);
                        let tail = vals.split_off(s * bsz);
                        vals.extend_from_slice(tb);
                        vals.extend_from_slice(&tail);
                    }
                }
            }
            (cols, vals)
        })
        .collect();
    let mut row_ptr = vec![0];
    let mut col_idx = Vec::new();
    let mut vals = Vec::new();
    for (c, v) in rows {
        col_idx.extend_from_slice(&c);
        vals.extend_from_slice(&v);
        row_ptr.push(col_idx.len());
    }
    Bsr {
        rows: t.rows,
        cols: t.cols,
        br: b,
        bc: k,
        row_ptr,
        col_idx,
        values: vals,
    }
}

/// Lower triangle (CSC) of a square Bsr and the node of each DOF.
fn to_lower_csc(a: &Bsr) -> (Vec<usize>, Vec<usize>, Vec<f64>, Vec<usize>) {
    let b = a.br;
    let n = a.rows * b;
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    col_ptr.push(0);
    // Symmetric: column j's lower part equals row j's entries with i ≥ j.
    for bj in 0..a.rows {
        for cj in 0..b {
            let j = bj * b + cj;
            for k in a.row_ptr[bj]..a.row_ptr[bj + 1] {
                let bi = a.col_idx[k] as usize;
                for ci in 0..b {
                    let i = bi * b + ci;
                    if i >= j {
                        // Row j, column i of A = A_ij by symmetry.
                        row_idx.push(i);
                        values.push(a.values[k * b * b + cj * b + ci]);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    (col_ptr, row_idx, values, (0..n).map(|i| i / b).collect())
}

impl Amg {
    /// Builds the hierarchy for the symmetric positive definite `a` (3×3
    /// blocks, both triangles) with the near-null space `null` (6 values per
    /// DOF, row-major: DOF i's row is `null[6i..6i+6]`).
    pub fn new(a: Bsr, null: &[f64], params: AmgParams) -> Result<Self, AmgError> {
        Self::with_charts(a, null, &[], params)
    }

    /// As [`Amg::new`] for a matrix tied across a cut: `charts` gives each
    /// node's side of the cut (+1 or −1; 0 for either, and for all nodes
    /// when empty), and no aggregate on any level reaches across (the
    /// near-null space `null` is rigid within one side only).
    pub fn with_charts(
        a: Bsr,
        null: &[f64],
        charts: &[i8],
        params: AmgParams,
    ) -> Result<Self, AmgError> {
        if !charts.is_empty() && charts.len() != a.rows {
            return Err(AmgError::Charts {
                got: charts.len(),
                expected: a.rows,
            });
        }
        if a.br != 3 || a.bc != 3 || a.rows != a.cols {
            return Err(AmgError::Shape);
        }
        let expected = 6 * a.rows * 3;
        if null.len() != expected {
            return Err(AmgError::NullSpace {
                got: null.len(),
                expected,
            });
        }
        let mut levels = Vec::new();
        let mut a = a;
        let mut null = null.to_vec();
        let mut charts = charts.to_vec();
        loop {
            let level = levels.len();
            let n = a.rows * a.br;
            if n <= params.coarse_dofs || level + 1 >= params.max_levels {
                break;
            }
            let dinv = block_diag_inverse(&a, level)?;
            let lam = lambda_max(&a, &dinv);
            let (agg, coarse_charts) = aggregate(&a, params.strength, &charts);
            let n_agg = coarse_charts.len();
            if n_agg == 0 || 6 * n_agg >= n {
                break;
            }
            let (t, coarse_null) = tentative(&agg, n_agg, a.br, &null);
            let omega = 4.0 / (3.0 * lam);
            let p = smooth_prolongator(&a, &dinv, &t, omega);
            drop(t);
            let r = p.transpose();
            let ap = Bsr::product(&a, &p);
            let mut ac = Bsr::product(&r, &ap);
            drop(ap);
            // Zero columns of P (dependent near-null-space columns) leave
            // zero rows in A_c: make them identity rows.
            for i in 0..ac.rows {
                let k = match ac.find(i, i) {
                    Some(k) => k,
                    None => continue,
                };
                for c in 0..6 {
                    let d = k * 36 + c * 6 + c;
                    if ac.values[d] == 0.0 {
                        ac.values[d] = 1.0;
                    }
                }
            }
            let hi = 1.1 * lam;
            let mut fine = std::mem::replace(&mut a, ac);
            let (mut p, mut r) = (p, r);
            levels.push(Level {
                a32: single_precision(&mut fine, level == 0),
                a: fine,
                dinv,
                lo: hi * params.smoother_range,
                hi,
                p32: single_precision(&mut p, false),
                p,
                r32: single_precision(&mut r, false),
                r,
            });
            null = coarse_null;
            charts = coarse_charts;
        }
        let (cp, ri, v, dn) = to_lower_csc(&a);
        let mut coarse = Cholesky::new(&cp, &ri, Ordering::Metis, &dn)?;
        coarse.factorize(&v)?;
        let coarse_n = a.rows * a.br;
        let coarse_entries = a.entries();
        // With one level the matrix is kept for the Krylov products.
        let single = levels.is_empty().then_some(a);
        Ok(Self {
            levels,
            single,
            coarse,
            coarse_n,
            coarse_entries,
            params,
        })
    }

    /// Level sizes and operator complexity.
    pub fn info(&self) -> AmgInfo {
        let mut level_dofs: Vec<usize> = self.levels.iter().map(|l| l.a.rows * l.a.br).collect();
        level_dofs.push(self.coarse_n);
        let fine = self.matrix().entries().max(1) as f64;
        let total: usize =
            self.levels.iter().map(|l| l.a.entries()).sum::<usize>() + self.coarse_entries;
        AmgInfo {
            level_dofs,
            operator_complexity: total as f64 / fine,
        }
    }

    /// Chebyshev smoothing of level `l` (degree `smoother_degree`) from x,
    /// or from zero. Each iteration is one pass over the block rows: the
    /// product A d of the row, then r −= A d, z = D⁻¹ r, the next d and
    /// x += d, with the next d written beside the current one (the row's
    /// product reads its neighbours' current d). The same bits as the
    /// iteration written as separate vector operations: the cycle's
    /// vectors are passed over once instead of five times.
    fn chebyshev(&self, l: usize, b: &[f64], x: &mut [f64], zero_start: bool, ws: &mut Work) {
        let lev = &self.levels[l];
        let (r, d, next) = (&mut ws.r[l], &mut ws.d[l], &mut ws.ad[l]);
        let theta = 0.5 * (lev.hi + lev.lo);
        let delta = 0.5 * (lev.hi - lev.lo);
        let sigma = theta / delta;
        let mut rho = 1.0 / sigma;
        let bs = lev.a.br;
        if zero_start {
            r.copy_from_slice(b);
            x.par_iter_mut().for_each(|v| *v = 0.0);
        } else {
            lev.a.residual_with(&lev.a32, b, x, r);
        }
        // The first iteration: d = D⁻¹ r / θ, x += d.
        d.par_chunks_mut(bs)
            .zip(x.par_chunks_mut(bs))
            .zip(r.par_chunks(bs))
            .zip(lev.dinv.par_chunks(bs * bs))
            .for_each(|(((di, xi), ri), dm)| {
                for (row, (dr, xr)) in di.iter_mut().zip(xi.iter_mut()).enumerate() {
                    *dr = dinv_row(dm, ri, row) / theta;
                    *xr += *dr;
                }
            });
        for _ in 1..self.params.smoother_degree.max(1) {
            let rho_new = 1.0 / (2.0 * sigma - rho);
            let c = (rho_new * rho, 2.0 * rho_new / delta);
            match bs {
                3 => chebyshev_pass::<3>(lev, c, d, (next, r, x)),
                6 => chebyshev_pass::<6>(lev, c, d, (next, r, x)),
                _ => unreachable!("levels have 3×3 or 6×6 blocks"),
            }
            std::mem::swap(d, next);
            rho = rho_new;
        }
    }

    fn cycle(&self, l: usize, b: &[f64], x: &mut [f64], ws: &mut Work) -> Result<(), AmgError> {
        if l == self.levels.len() {
            x.copy_from_slice(b);
            self.coarse.solve_in_place(x)?;
            return Ok(());
        }
        let lev = &self.levels[l];
        self.chebyshev(l, b, x, true, ws);
        lev.a.residual_with(&lev.a32, b, x, &mut ws.res[l]);
        let mut bc = std::mem::take(&mut ws.bc[l]);
        let mut xc = std::mem::take(&mut ws.xc[l]);
        lev.r.mul_with(&lev.r32, &ws.res[l], &mut bc);
        self.cycle(l + 1, &bc, &mut xc, ws)?;
        lev.p.mul_add_with(&lev.p32, &xc, x);
        ws.bc[l] = bc;
        ws.xc[l] = xc;
        self.chebyshev(l, b, x, false, ws);
        Ok(())
    }

    /// The finest-level matrix (the system matrix).
    pub fn matrix(&self) -> &Bsr {
        match (&self.single, self.levels.first()) {
            (Some(a), _) => a,
            (None, Some(l)) => &l.a,
            (None, None) => unreachable!("a hierarchy has at least one matrix"),
        }
    }

    /// Work vectors for [`Amg::apply`].
    pub fn workspace(&self) -> Work {
        let sizes: Vec<usize> = self.levels.iter().map(|l| l.a.rows * l.a.br).collect();
        let coarse: Vec<usize> = sizes
            .iter()
            .skip(1)
            .copied()
            .chain(std::iter::once(self.coarse_n))
            .collect();
        let v = |s: &[usize]| s.iter().map(|&n| vec![0.0; n]).collect::<Vec<_>>();
        Work {
            r: v(&sizes),
            d: v(&sizes),
            ad: v(&sizes),
            res: v(&sizes),
            bc: v(&coarse),
            xc: v(&coarse),
        }
    }

    /// One V-cycle: z ≈ A⁻¹ r.
    pub fn apply(&self, r: &[f64], z: &mut [f64], ws: &mut Work) -> Result<(), AmgError> {
        self.cycle(0, r, z, ws)
    }
}

/// Work vectors of the V-cycle, one set per level.
pub struct Work {
    r: Vec<Vec<f64>>,
    d: Vec<Vec<f64>>,
    ad: Vec<Vec<f64>>,
    res: Vec<Vec<f64>>,
    bc: Vec<Vec<f64>>,
    xc: Vec<Vec<f64>>,
}

/// Result of [`amg_pcg`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgInfo {
    pub iterations: usize,
    /// Final ‖b − A x‖ / ‖b‖ (recursively updated residual).
    pub relative_residual: f64,
}

/// Conjugate gradients on the hierarchy's finest matrix preconditioned by
/// one V-cycle per iteration, from x = 0, until ‖r‖ ≤ `tolerance`·‖b‖.
pub fn amg_pcg(
    amg: &Amg,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<CgInfo, AmgError> {
    let a = amg.matrix();
    let n = b.len();
    x.par_iter_mut().for_each(|v| *v = 0.0);
    let bnorm = pdot(b, b).sqrt();
    if bnorm == 0.0 {
        return Ok(CgInfo {
            iterations: 0,
            relative_residual: 0.0,
        });
    }
    let mut ws = amg.workspace();
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    amg.apply(&r, &mut z, &mut ws)?;
    let mut p = z.clone();
    let mut rz = pdot(&r, &z);
    let mut ap = vec![0.0; n];
    let mut rel = 1.0;
    for it in 1..=max_iterations {
        a.mul(&p, &mut ap);
        let pap = pdot(&p, &ap);
        if !(pap.is_finite() && pap > 0.0) {
            return Err(AmgError::NonFinite { iteration: it });
        }
        let alpha = rz / pap;
        x.par_iter_mut()
            .zip(p.par_iter())
            .for_each(|(xi, pi)| *xi += alpha * pi);
        r.par_iter_mut()
            .zip(ap.par_iter())
            .for_each(|(ri, ai)| *ri -= alpha * ai);
        rel = pdot(&r, &r).sqrt() / bnorm;
        if !rel.is_finite() {
            return Err(AmgError::NonFinite { iteration: it });
        }
        if rel <= tolerance {
            return Ok(CgInfo {
                iterations: it,
                relative_residual: rel,
            });
        }
        amg.apply(&r, &mut z, &mut ws)?;
        let rz_new = pdot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_iter_mut()
            .zip(z.par_iter())
            .for_each(|(pi, zi)| *pi = zi + beta * *pi);
    }
    Err(AmgError::NotConverged {
        iterations: max_iterations,
        tolerance,
        reached: rel,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(a: &Bsr) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; a.cols * a.bc]; a.rows * a.br];
        for i in 0..a.rows {
            for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                let j = a.col_idx[k] as usize;
                for r in 0..a.br {
                    for c in 0..a.bc {
                        d[i * a.br + r][j * a.bc + c] = a.values[k * a.br * a.bc + r * a.bc + c];
                    }
                }
            }
        }
        d
    }

    fn sample(rows: usize, cols: usize, br: usize, bc: usize, seed: usize) -> Bsr {
        let mut row_ptr = vec![0];
        let mut col_idx = Vec::new();
        let mut values = Vec::new();
        for i in 0..rows {
            for j in 0..cols {
                if !(i * 7 + j * 3 + seed).is_multiple_of(3) {
                    col_idx.push(j as u32);
                    for q in 0..br * bc {
                        values.push(((i * 31 + j * 17 + q * 5 + seed) % 11) as f64 - 5.0);
                    }
                }
            }
            row_ptr.push(col_idx.len());
        }
        Bsr {
            rows,
            cols,
            br,
            bc,
            row_ptr,
            col_idx,
            values,
        }
    }

    /// The block products, transposes and matrix–vector products used by the
    /// set-up and the cycle agree with dense arithmetic.
    #[test]
    fn block_kernels_match_dense() {
        let a = sample(5, 4, 3, 6, 1);
        let b = sample(4, 3, 6, 6, 2);
        let c = Bsr::product(&a, &b);
        let (da, db, dc) = (dense(&a), dense(&b), dense(&c));
        for i in 0..15 {
            for j in 0..18 {
                let e: f64 = (0..24).map(|k| da[i][k] * db[k][j]).sum();
                assert!(
                    (e - dc[i][j]).abs() < 1e-9,
                    "({i},{j}): {e} vs {}",
                    dc[i][j]
                );
            }
        }
        let t = dense(&a.transpose());
        for i in 0..15 {
            for j in 0..24 {
                assert_eq!(t[j][i], da[i][j]);
            }
        }
        let x: Vec<f64> = (0..24).map(|i| (i as f64).sin()).collect();
        let mut y = vec![0.0; 15];
        a.mul(&x, &mut y);
        for i in 0..15 {
            let e: f64 = (0..24).map(|k| da[i][k] * x[k]).sum();
            assert!((e - y[i]).abs() < 1e-9);
        }
        // The 6×3 kernel (the restriction's blocks), and the products with
        // single-precision values, which round each value once.
        let at = a.transpose();
        let xt: Vec<f64> = (0..15).map(|i| (i as f64).cos()).collect();
        let mut yt = vec![0.0; 24];
        at.mul(&xt, &mut yt);
        let dt = dense(&at);
        for i in 0..24 {
            let e: f64 = (0..15).map(|k| dt[i][k] * xt[k]).sum();
            assert!((e - yt[i]).abs() < 1e-9);
        }
        let sample32 = |m: &Bsr| {
            m.values
                .iter()
                .map(|&v| v as f32 + 0.25)
                .collect::<Vec<f32>>()
        };
        for (m, x) in [(&a, &x), (&at, &xt)] {
            let v32 = sample32(m);
            let mut shifted = m.clone();
            shifted.values = v32.iter().map(|&v| v as f64).collect();
            let (mut y64, mut y32) = (vec![0.0; m.rows * m.br], vec![0.0; m.rows * m.br]);
            shifted.mul(x, &mut y64);
            m.mul_with(&v32, x, &mut y32);
            assert_eq!(y64, y32);
        }
        let mut m = vec![4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let orig = m.clone();
        assert!(invert_small(&mut m, 3));
        for i in 0..3 {
            for j in 0..3 {
                let e: f64 = (0..3).map(|k| orig[3 * i + k] * m[3 * k + j]).sum();
                assert!((e - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        assert!(!invert_small(&mut [0.0; 9], 3));
    }

    /// A grid of nx × ny nodes with 3×3 blocks: −w·I between grid
    /// neighbours, the diagonal their sum plus a small shift (SPD), and
    /// each node's chart the sign of its column's offset from the middle.
    fn grid(nx: usize, ny: usize) -> (Bsr, Vec<i8>, Vec<f64>) {
        let id = |i: usize, j: usize| i * ny + j;
        let mut row_ptr = vec![0];
        let mut col_idx = Vec::new();
        let mut values = Vec::new();
        let mut nodes = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                let mut row: Vec<(usize, f64)> = Vec::new();
                let mut sum = 1e-3;
                for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (p, q) = (i as i64 + di, j as i64 + dj);
                    if p >= 0 && q >= 0 && (p as usize) < nx && (q as usize) < ny {
                        let w = 1.0 + 0.1 * ((i + j) % 3) as f64;
                        row.push((id(p as usize, q as usize), -w));
                        sum += w;
                    }
                }
                row.push((id(i, j), sum));
                row.sort_by_key(|e| e.0);
                for (c, v) in row {
                    col_idx.push(c as u32);
                    for r in 0..3 {
                        for k in 0..3 {
                            values.push(if r == k { v } else { 0.0 });
                        }
                    }
                }
                row_ptr.push(col_idx.len());
                nodes.push([i as f64 - (nx / 2) as f64, j as f64, 0.0]);
            }
        }
        let charts = nodes.iter().map(|x| (x[0] as i64).signum() as i8).collect();
        let a = Bsr {
            rows: nx * ny,
            cols: nx * ny,
            br: 3,
            bc: 3,
            row_ptr,
            col_idx,
            values,
        };
        let null = crate::linalg::multigrid::rigid_body_modes(&nodes, |_| true);
        (a, charts, null)
    }

    /// The hierarchy (its smoothers' eigenvalue estimates) and the
    /// preconditioned CG built on it give the same bits on 1, 2 and 4
    /// threads, so a run's curve does not depend on the machine's cores.
    #[test]
    fn the_multigrid_does_not_depend_on_the_number_of_threads() {
        let (a, charts, null) = grid(120, 100);
        let b: Vec<f64> = (0..3 * a.rows)
            .map(|i| ((i * 7) % 5) as f64 - 2.0)
            .collect();
        let solved = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let amg =
                    Amg::with_charts(a.clone(), &null, &charts, AmgParams::default()).unwrap();
                let mut x = vec![0.0; b.len()];
                amg_pcg(&amg, &b, &mut x, 1e-10, 200).unwrap();
                x
            })
        };
        let one = solved(1);
        assert_eq!(one, solved(2));
        assert_eq!(one, solved(4));
    }

    /// No aggregate holds nodes of two opposite charts, every node of a
    /// non-zero chart lands in an aggregate of its chart, and without charts
    /// the same matrix aggregates across the middle (so the rule is what
    /// keeps the sides apart).
    #[test]
    fn aggregates_stay_on_one_side_of_a_cut() {
        let (a, charts, null) = grid(15, 9);
        let (agg, coarse) = aggregate(&a, 0.0, &charts);
        let mut sides = vec![[false; 2]; coarse.len()];
        for (i, &g) in agg.iter().enumerate() {
            assert_ne!(g, u32::MAX, "node {i} left out");
            match charts[i] {
                1 => sides[g as usize][0] = true,
                -1 => sides[g as usize][1] = true,
                _ => {}
            }
            if charts[i] != 0 {
                assert_eq!(coarse[g as usize], charts[i], "node {i}");
            }
        }
        assert!(sides.iter().all(|s| !(s[0] && s[1])));
        let (free_agg, free_coarse) = aggregate(&a, 0.0, &[]);
        assert!(free_coarse.iter().all(|&c| c == 0));
        let mut mixed = vec![[false; 2]; free_coarse.len()];
        for (i, &g) in free_agg.iter().enumerate() {
            match charts[i] {
                1 => mixed[g as usize][0] = true,
                -1 => mixed[g as usize][1] = true,
                _ => {}
            }
        }
        assert!(mixed.iter().any(|s| s[0] && s[1]));
        // Deeper levels keep the rule, and the hierarchy still solves.
        let params = AmgParams {
            coarse_dofs: 30,
            ..AmgParams::default()
        };
        let amg = Amg::with_charts(a.clone(), &null, &charts, params).unwrap();
        assert!(amg.info().level_dofs.len() >= 3);
        let b: Vec<f64> = (0..3 * a.rows)
            .map(|i| ((i * 7) % 5) as f64 - 2.0)
            .collect();
        let mut x = vec![0.0; b.len()];
        amg_pcg(&amg, &b, &mut x, 1e-10, 200).unwrap();
        let mut ax = vec![0.0; b.len()];
        a.mul(&x, &mut ax);
        let err: f64 = ax
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(err < 1e-8 * b.iter().map(|v| v * v).sum::<f64>().sqrt());
        assert!(matches!(
            Amg::with_charts(a, &null, &charts[1..], params),
            Err(AmgError::Charts { .. })
        ));
    }

    /// The fused products (r = b − A x, y += A x) give the bits of the
    /// product into a vector and the difference or sum after, on every
    /// block shape, with f64 and f32 values.
    #[test]
    fn fused_products_give_the_bits_of_the_separate_ones() {
        for (k, (br, bc)) in [(3, 3), (6, 6), (3, 6), (6, 3), (2, 5)]
            .into_iter()
            .enumerate()
        {
            let mut m = sample(600, 500, br, bc, k);
            m.values
                .iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v = (*v + 0.3 * i as f64).sin());
            let v32: Vec<f32> = m.values.iter().map(|&v| v as f32).collect();
            let x: Vec<f64> = (0..500 * bc).map(|i| (0.7 * i as f64).cos()).collect();
            let b: Vec<f64> = (0..600 * br).map(|i| (1.3 * i as f64).sin()).collect();
            let mut ax = vec![0.0; b.len()];
            m.mul_with(&v32, &x, &mut ax);
            let mut r = vec![f64::NAN; b.len()];
            m.residual_with(&v32, &b, &x, &mut r);
            let expected: Vec<f64> = b.iter().zip(&ax).map(|(p, q)| p - q).collect();
            assert_eq!(r, expected, "{br}×{bc} residual");
            let mut y = b.clone();
            m.mul_add_with(&m.values, &x, &mut y);
            m.mul(&x, &mut ax);
            let expected: Vec<f64> = b.iter().zip(&ax).map(|(p, q)| p + q).collect();
            assert_eq!(y, expected, "{br}×{bc} sum");
        }
    }

    /// The Chebyshev smoothing, one pass over the block rows per
    /// iteration, gives the bits of the iteration written as separate
    /// vector operations, on every level, from zero and from an iterate.
    #[test]
    fn the_fused_smoothing_gives_the_bits_of_the_vector_operations() {
        let (a, charts, null) = grid(40, 30);
        let params = AmgParams {
            smoother_degree: 3,
            coarse_dofs: 200,
            ..AmgParams::default()
        };
        let amg = Amg::with_charts(a, &null, &charts, params).unwrap();
        assert!(amg.levels.len() >= 2);
        let reference = |lev: &Level, b: &[f64], x: &mut [f64], zero_start: bool| {
            let n = b.len();
            let (mut r, mut d, mut z, mut ad) =
                (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let theta = 0.5 * (lev.hi + lev.lo);
            let delta = 0.5 * (lev.hi - lev.lo);
            let sigma = theta / delta;
            let mut rho = 1.0 / sigma;
            if zero_start {
                r.copy_from_slice(b);
                x.iter_mut().for_each(|v| *v = 0.0);
            } else {
                lev.a.mul_with(&lev.a32, x, &mut ad);
                r.iter_mut()
                    .zip(b.iter().zip(&ad))
                    .for_each(|(ri, (bi, ai))| *ri = bi - ai);
            }
            apply_dinv(&lev.dinv, lev.a.br, &r, &mut z);
            d.iter_mut().zip(&z).for_each(|(di, zi)| *di = zi / theta);
            for k in 0..3 {
                x.iter_mut().zip(&d).for_each(|(xi, di)| *xi += di);
                if k == 2 {
                    break;
                }
                lev.a.mul_with(&lev.a32, &d, &mut ad);
                r.iter_mut().zip(&ad).for_each(|(ri, ai)| *ri -= ai);
                apply_dinv(&lev.dinv, lev.a.br, &r, &mut z);
                let rho_new = 1.0 / (2.0 * sigma - rho);
                let (c1, c2) = (rho_new * rho, 2.0 * rho_new / delta);
                d.iter_mut()
                    .zip(&z)
                    .for_each(|(di, zi)| *di = c1 * *di + c2 * zi);
                rho = rho_new;
            }
        };
        let mut ws = amg.workspace();
        for (l, lev) in amg.levels.iter().enumerate() {
            let n = lev.a.rows * lev.a.br;
            let b: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
            for zero_start in [true, false] {
                let start: Vec<f64> = (0..n).map(|i| (0.11 * i as f64).cos()).collect();
                let (mut fused, mut plain) = (start.clone(), start);
                amg.chebyshev(l, &b, &mut fused, zero_start, &mut ws);
                reference(lev, &b, &mut plain, zero_start);
                assert_eq!(fused, plain, "level {l}, zero start {zero_start}");
            }
        }
    }
}
