//! The smoothed-aggregation multigrid of [`super::amg`] as the kept
//! preconditioner of a system whose Dirichlet DOFs are eliminated (the
//! nonlinear driver's free-DOF numbering, lower triangle in CSC).
//!
//! The hierarchy works on whole nodes (3×3 blocks) with the constrained DOFs
//! as identity rows and zero near-null-space rows, as [`super::amg`]
//! requires; [`NodeBlockLayout`] holds, once per mesh, where each stored
//! lower entry lands in the node-block matrix, so a rebuild is a scatter and
//! the set-up. Unlike a Cholesky factor, nothing of the size of the fill is
//! stored: the hierarchy costs about twice the matrix.

use super::amg::{Amg, AmgError, AmgInfo, AmgParams, Bsr, Work};
use super::{LinearError, Preconditioner};
use rayon::prelude::*;
use std::sync::Mutex;

const NONE: u32 = u32::MAX;

/// Where the free-DOF lower triangle lands in node-block storage.
pub struct NodeBlockLayout {
    n_nodes: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<u32>,
    /// Per stored lower entry (i, j): positions of (i, j) and (j, i) in the
    /// block values (equal on the diagonal).
    positions: Vec<[u32; 2]>,
    /// Value positions of the diagonals of constrained DOFs (set to 1).
    constrained_diagonal: Vec<usize>,
    /// Global DOF (`3·node + component`) of each free DOF.
    free_to_global: Vec<u32>,
    /// Per global DOF its free index, [`NONE`] when constrained.
    global_to_free: Vec<u32>,
    /// Rigid-body modes, 6 per global DOF, zero on constrained DOFs.
    null_space: Vec<f64>,
    /// Per node, its side of a tied cut (empty: no cut); see
    /// [`Amg::with_charts`].
    charts: Vec<i8>,
}

impl NodeBlockLayout {
    /// The layout of the lower pattern `col_ptr`/`row_idx` on free DOFs,
    /// where `free_of[d]` is the free index of global DOF d (`None` when
    /// constrained), `nodes` the node coordinates (m) and `charts` each
    /// node's side of a tied cut (empty when nothing is tied).
    pub fn new(
        col_ptr: &[usize],
        row_idx: &[usize],
        free_of: impl Fn(usize) -> Option<usize>,
        nodes: &[[f64; 3]],
        charts: &[i8],
    ) -> Result<Self, LinearError> {
        let n_nodes = nodes.len();
        if !charts.is_empty() && charts.len() != n_nodes {
            return Err(LinearError::Symbolic(format!(
                "multigrid layout: {} node charts for {n_nodes} nodes",
                charts.len()
            )));
        }
        let n_free = col_ptr.len() - 1;
        let mut free_to_global = vec![NONE; n_free];
        let mut global_to_free = vec![NONE; 3 * n_nodes];
        for (d, free) in global_to_free.iter_mut().enumerate() {
            if let Some(f) = free_of(d) {
                free_to_global[f] = d as u32;
                *free = f as u32;
            }
        }
        if free_to_global.contains(&NONE) {
            return Err(LinearError::Symbolic(
                "multigrid layout: a free DOF has no node".into(),
            ));
        }
        let node_of = |f: usize| free_to_global[f] as usize / 3;
        let mut neighbours: Vec<Vec<u32>> = (0..n_nodes).map(|i| vec![i as u32]).collect();
        for j in 0..n_free {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                let (ni, nj) = (node_of(i), node_of(j));
                if ni != nj {
                    neighbours[ni].push(nj as u32);
                    neighbours[nj].push(ni as u32);
                }
            }
        }
        let mut row_ptr = Vec::with_capacity(n_nodes + 1);
        row_ptr.push(0);
        let mut col_idx = Vec::new();
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
            col_idx.extend_from_slice(list);
            row_ptr.push(col_idx.len());
            *list = Vec::new();
        }
        if 9 * col_idx.len() >= NONE as usize {
            return Err(LinearError::Symbolic(
                "multigrid layout: more than 4·10⁹ block entries".into(),
            ));
        }
        let block = |ni: usize, nj: usize| -> usize {
            let s = row_ptr[ni];
            s + col_idx[s..row_ptr[ni + 1]]
                .binary_search(&(nj as u32))
                .expect("every coupled node pair is in the pattern")
        };
        let mut positions = Vec::with_capacity(row_idx.len());
        for j in 0..n_free {
            let gj = free_to_global[j] as usize;
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                let gi = free_to_global[i] as usize;
                let (ni, ci, nj, cj) = (gi / 3, gi % 3, gj / 3, gj % 3);
                let ij = 9 * block(ni, nj) + 3 * ci + cj;
                let ji = 9 * block(nj, ni) + 3 * cj + ci;
                positions.push([ij as u32, ji as u32]);
            }
        }
        let constrained_diagonal = (0..3 * n_nodes)
            .filter(|&d| free_of(d).is_none())
            .map(|d| 9 * block(d / 3, d / 3) + 4 * (d % 3))
            .collect();
        let null_space = rigid_body_modes(nodes, |d| free_of(d).is_some());
        Ok(Self {
            n_nodes,
            row_ptr,
            col_idx,
            positions,
            constrained_diagonal,
            free_to_global,
            global_to_free,
            null_space,
            charts: charts.to_vec(),
        })
    }

    /// The node-block matrix (both triangles) of the lower values `lower`.
    pub fn matrix(&self, lower: &[f64]) -> Bsr {
        let mut values = vec![0.0; 9 * self.col_idx.len()];
        for (&[ij, ji], &v) in self.positions.iter().zip(lower) {
            values[ij as usize] = v;
            values[ji as usize] = v;
        }
        for &k in &self.constrained_diagonal {
            values[k] = 1.0;
        }
        Bsr {
            rows: self.n_nodes,
            cols: self.n_nodes,
            br: 3,
            bc: 3,
            row_ptr: self.row_ptr.clone(),
            col_idx: self.col_idx.clone(),
            values,
        }
    }

    /// The hierarchy of the symmetric matrix with lower values `lower`.
    pub fn build(&self, lower: &[f64], params: AmgParams) -> Result<FreeDofMultigrid, AmgError> {
        let amg = Amg::with_charts(self.matrix(lower), &self.null_space, &self.charts, params)?;
        let work = amg.workspace();
        Ok(FreeDofMultigrid {
            amg,
            free_to_global: self.free_to_global.clone(),
            global_to_free: self.global_to_free.clone(),
            scratch: Mutex::new(Scratch {
                work,
                r: vec![0.0; 3 * self.n_nodes],
                z: vec![0.0; 3 * self.n_nodes],
            }),
        })
    }
}

/// Rigid-body modes of the nodes about their centroid, 6 per global DOF,
/// zero where `free(d)` is false.
pub fn rigid_body_modes(nodes: &[[f64; 3]], free: impl Fn(usize) -> bool) -> Vec<f64> {
    let n = nodes.len().max(1) as f64;
    let mut c = [0.0; 3];
    for x in nodes {
        for k in 0..3 {
            c[k] += x[k] / n;
        }
    }
    let mut b = vec![0.0; 18 * nodes.len()];
    for (i, x) in nodes.iter().enumerate() {
        let (x, y, z) = (x[0] - c[0], x[1] - c[1], x[2] - c[2]);
        let rows = [
            [1.0, 0.0, 0.0, 0.0, z, -y],
            [0.0, 1.0, 0.0, -z, 0.0, x],
            [0.0, 0.0, 1.0, y, -x, 0.0],
        ];
        for (k, row) in rows.iter().enumerate() {
            if free(3 * i + k) {
                b[(3 * i + k) * 6..(3 * i + k + 1) * 6].copy_from_slice(row);
            }
        }
    }
    b
}

struct Scratch {
    work: Work,
    r: Vec<f64>,
    z: Vec<f64>,
}

/// One V-cycle of a hierarchy built on node blocks, applied to free-DOF
/// vectors.
pub struct FreeDofMultigrid {
    amg: Amg,
    free_to_global: Vec<u32>,
    /// Per global DOF its free index, [`NONE`] when constrained.
    global_to_free: Vec<u32>,
    scratch: Mutex<Scratch>,
}

impl FreeDofMultigrid {
    /// Level sizes and operator complexity.
    pub fn info(&self) -> AmgInfo {
        self.amg.info()
    }
}

impl Preconditioner for FreeDofMultigrid {
    fn apply(&self, r: &mut [f64]) -> Result<(), LinearError> {
        let mut guard = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        let s = &mut *guard;
        let free = &*r;
        s.r.par_iter_mut()
            .zip(&self.global_to_free)
            .for_each(|(v, &f)| *v = if f == NONE { 0.0 } else { free[f as usize] });
        self.amg
            .apply(&s.r, &mut s.z, &mut s.work)
            .map_err(|_| LinearError::NonFinite)?;
        let z = &s.z;
        r.par_iter_mut()
            .zip(&self.free_to_global)
            .for_each(|(v, &g)| *v = z[g as usize]);
        if r.par_iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearError::NonFinite)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{gmres, SplitMatrix};

    /// Lower CSC of the free system, free index of each global DOF, nodes.
    type Chain = (
        Vec<usize>,
        Vec<usize>,
        Vec<f64>,
        Vec<Option<usize>>,
        Vec<[f64; 3]>,
    );

    /// A chain of nodes joined by axial and transverse springs, the first
    /// node clamped and one DOF of the last constrained: the lower triangle
    /// on the free DOFs.
    fn chain(n_nodes: usize) -> Chain {
        let constrained = |d: usize| d < 3 || d == 3 * n_nodes - 1;
        let mut free_of = vec![None; 3 * n_nodes];
        let mut n_free = 0;
        for (d, f) in free_of.iter_mut().enumerate() {
            if !constrained(d) {
                *f = Some(n_free);
                n_free += 1;
            }
        }
        let mut dense = vec![vec![0.0; 3 * n_nodes]; 3 * n_nodes];
        for e in 0..n_nodes - 1 {
            for c in 0..3 {
                let k = [3.0, 1.0, 2.0][c] * (1.0 + 0.1 * e as f64);
                let (a, b) = (3 * e + c, 3 * (e + 1) + c);
                dense[a][a] += k;
                dense[b][b] += k;
                dense[a][b] -= k;
                dense[b][a] -= k;
            }
            // A coupling between components so the blocks are full.
            let (a, b) = (3 * e, 3 * (e + 1) + 1);
            dense[a][a] += 0.5;
            dense[b][b] += 0.5;
            dense[a][b] -= 0.5;
            dense[b][a] -= 0.5;
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for gj in 0..3 * n_nodes {
            let Some(j) = free_of[gj] else { continue };
            for gi in 0..3 * n_nodes {
                if let Some(i) = free_of[gi] {
                    if i >= j && dense[gi][gj] != 0.0 {
                        row_idx.push(i);
                        values.push(dense[gi][gj]);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
        let nodes = (0..n_nodes).map(|i| [0.0, 0.0, i as f64 * 0.01]).collect();
        (col_ptr, row_idx, values, free_of, nodes)
    }

    #[test]
    fn the_block_matrix_holds_the_free_system_and_identity_rows() {
        let (cp, ri, v, free_of, nodes) = chain(5);
        let layout = NodeBlockLayout::new(&cp, &ri, |d| free_of[d], &nodes, &[]).unwrap();
        let b = layout.matrix(&v);
        let at = |gi: usize, gj: usize| {
            b.find(gi / 3, gj / 3)
                .map_or(0.0, |k| b.values[9 * k + 3 * (gi % 3) + gj % 3])
        };
        for j in 0..cp.len() - 1 {
            for k in cp[j]..cp[j + 1] {
                let (gi, gj) = (
                    layout.free_to_global[ri[k]] as usize,
                    layout.free_to_global[j] as usize,
                );
                assert_eq!(at(gi, gj), v[k]);
                assert_eq!(at(gj, gi), v[k]);
            }
        }
        for d in [0, 1, 2, 14] {
            assert_eq!(at(d, d), 1.0);
            for e in 0..15 {
                if e != d {
                    assert_eq!(at(d, e), 0.0, "constrained DOF {d} coupled to {e}");
                }
            }
        }
    }

    /// With and without charts (the chain's halves as the two sides of a
    /// cut), the preconditioned GMRES solves the free system.
    #[test]
    fn preconditioned_gmres_solves_the_free_system() {
        let (cp, ri, _, free_of, nodes) = chain(40);
        let halves: Vec<i8> = (0..40).map(|i| if i < 20 { -1 } else { 1 }).collect();
        for charts in [&[][..], &halves[..]] {
            solves_with(charts);
        }
        let short = NodeBlockLayout::new(&cp, &ri, |d| free_of[d], &nodes, &halves[1..]);
        assert!(matches!(short, Err(LinearError::Symbolic(m)) if m.contains("charts")));
    }

    fn solves_with(charts: &[i8]) {
        let (cp, ri, v, free_of, nodes) = chain(40);
        let layout = NodeBlockLayout::new(&cp, &ri, |d| free_of[d], &nodes, charts).unwrap();
        let params = AmgParams {
            coarse_dofs: 12,
            ..AmgParams::default()
        };
        let mg = layout.build(&v, params).unwrap();
        let a = SplitMatrix {
            col_ptr: &cp,
            row_idx: &ri,
            lower: &v,
            upper: &v,
        };
        let n = cp.len() - 1;
        let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        let mut x = vec![0.0; n];
        let info = gmres(&a, &mg, &b, &mut x, 1e-10, 200).unwrap();
        let mut ax = vec![0.0; n];
        a.mul(&x, &mut ax);
        let err = ax
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            .sqrt();
        let bn = b.iter().map(|q| q * q).sum::<f64>().sqrt();
        assert!(err <= 1e-9 * bn, "residual {err:e} of {bn:e}");
        assert!(
            info.iterations < n,
            "{} iterations for {n} unknowns",
            info.iterations
        );
    }
}
