//! The linear-elastic perfect-bond pull-out (SPEC §9 benchmark): the
//! mesh stage's model with every concrete interface twin merged back onto
//! its steel node (no interface elements: steel and concrete share the
//! interface nodes), P1 elasticity, the pull-out's boundary conditions
//! (SPEC §2: `pullout::pullout_conditions` itself, on the merged nodes) and the reaction
//! force on the bar's loaded end for an imposed displacement.
//!
//! Two linear solvers: faer's sparse Cholesky with METIS ordering
//! ([`crate::linalg::Cholesky`]) and conjugate gradients preconditioned by
//! smoothed-aggregation multigrid ([`crate::linalg::amg`]).

use crate::elements::tet::{ElementError, TetGeometry};
use crate::laws::elastic::LinearElastic;
use crate::linalg::amg::{amg_pcg, Amg, AmgError, AmgParams, Bsr};
use crate::linalg::{Cholesky, LinearError, Ordering};
use crate::problems::pullout::pullout_conditions;
use mesh::{Model, Region, Symmetry};
use rayon::prelude::*;
use std::time::Instant;

/// The model's nodes with every concrete interface twin merged onto its
/// steel node: the new id of each model node, and the merged coordinates.
fn merged_nodes(model: &Model) -> (Vec<u32>, Vec<[f64; 3]>) {
    let n = model.nodes.len();
    let mut target: Vec<u32> = (0..n as u32).collect();
    for e in &model.interfaces {
        for p in 0..3 {
            target[e.nodes[p + 3] as usize] = e.nodes[p];
        }
    }
    // Chains c → s → … cannot occur (a steel node is never a concrete
    // twin), but resolve them anyway so the map is idempotent.
    for i in 0..n {
        let mut t = target[i];
        while target[t as usize] != t {
            t = target[t as usize];
        }
        target[i] = t;
    }
    let mut kept = vec![u32::MAX; n];
    let mut nodes = Vec::new();
    for i in 0..n {
        if target[i] as usize == i {
            kept[i] = nodes.len() as u32;
            nodes.push(model.nodes[i]);
        }
    }
    let new_id = (0..n).map(|i| kept[target[i] as usize]).collect();
    (new_id, nodes)
}

/// Why the perfect-bond problem could not be built or solved.
#[derive(Debug, thiserror::Error)]
pub enum LinearElasticError {
    #[error("model: {0}")]
    Model(String),
    #[error("tetrahedron {index}: {source}")]
    Element {
        index: usize,
        #[source]
        source: ElementError,
    },
    #[error("Cholesky: {0}")]
    Linear(#[from] LinearError),
    #[error("multigrid-preconditioned CG: {0}")]
    Amg(#[from] AmgError),
}

/// A conforming elastic pull-out problem.
#[derive(Debug, Clone, PartialEq)]
pub struct PerfectBond {
    /// Node coordinates, m.
    pub nodes: Vec<[f64; 3]>,
    /// Tetrahedra (positively oriented) and their regions.
    pub tets: Vec<[u32; 4]>,
    pub tet_region: Vec<Region>,
    /// Steel nodes of the bar's loaded end (imposed u_z, u_x = u_y = 0).
    pub loaded_end: Vec<u32>,
    /// Constrained global DOFs (3·node + component), sorted, unique, and
    /// their values (m) for the imposed displacement `u_imposed`: the
    /// pull-out's conditions (`pullout::pullout_conditions`) on the merged
    /// nodes.
    pub constrained: Vec<(usize, f64)>,
    /// Imposed displacement of the loaded end, m.
    pub u_imposed: f64,
    /// Whole-specimen force per force on the model (4 for a quarter).
    pub force_factor: f64,
    pub symmetry: Symmetry,
}

impl PerfectBond {
    /// Merges the interface twins of `model` (each concrete node `c_i` of an
    /// interface element onto its steel node `s_i`), renumbers the nodes
    /// densely and applies the pull-out conditions with the loaded end's
    /// u_z = `u_imposed` (m).
    pub fn from_model(model: &Model, u_imposed: f64) -> Result<Self, LinearElasticError> {
        model.check().map_err(LinearElasticError::Model)?;
        if !u_imposed.is_finite() {
            return Err(LinearElasticError::Model(format!(
                "imposed displacement {u_imposed} m is not finite"
            )));
        }
        let (new_id, nodes) = merged_nodes(model);
        let map = |i: u32| new_id[i as usize];
        let tets: Vec<[u32; 4]> = model.tets.iter().map(|t| t.map(map)).collect();
        let mut loaded_end: Vec<u32> = model
            .node_sets
            .bar_loaded_end
            .iter()
            .map(|&i| map(i))
            .collect();
        loaded_end.sort_unstable();
        loaded_end.dedup();
        let (dirichlet, _) =
            pullout_conditions(model).map_err(|e| LinearElasticError::Model(e.to_string()))?;
        // The first condition on a merged DOF wins (the grip over the
        // bearing face where they meet), as in the pull-out.
        let mut seen = vec![false; 3 * nodes.len()];
        let mut constrained = Vec::with_capacity(dirichlet.dofs.len());
        for ((&dof, &base), &rate) in dirichlet
            .dofs
            .iter()
            .zip(&dirichlet.base)
            .zip(&dirichlet.rate)
        {
            let d = 3 * map((dof / 3) as u32) as usize + dof % 3;
            if !seen[d] {
                seen[d] = true;
                constrained.push((d, base + u_imposed * rate));
            }
        }
        constrained.sort_unstable_by_key(|c| c.0);
        Ok(Self {
            nodes,
            tets,
            tet_region: model.tet_region.clone(),
            loaded_end,
            constrained,
            u_imposed,
            force_factor: model.symmetry.force_factor(),
            symmetry: model.symmetry,
        })
    }

    /// Total DOFs (3 per node, constrained included).
    pub fn dofs(&self) -> usize {
        3 * self.nodes.len()
    }

    /// Free (unknown) DOFs.
    pub fn free_dofs(&self) -> usize {
        self.dofs() - self.constrained.len()
    }
}

/// Which linear solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElasticSolver {
    /// faer sparse LLᵀ with METIS nested dissection.
    Cholesky,
    /// CG preconditioned by smoothed-aggregation AMG, to the relative
    /// residual `tolerance`.
    AmgCg { tolerance: f64, params: AmgParams },
}

/// The solution and what it cost.
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticSolution {
    /// Global displacement (3 per node), m.
    pub u: Vec<f64>,
    /// Reaction force on the loaded end along z, whole specimen, N.
    pub reaction: f64,
    /// Free DOFs.
    pub free_dofs: usize,
    /// Wall times, s.
    pub t_assembly: f64,
    /// Ordering + symbolic + numeric factorisation, or the AMG set-up.
    pub t_setup: f64,
    pub t_solve: f64,
    /// CG iterations (0 for Cholesky).
    pub iterations: usize,
    /// Factor entries (Cholesky) or DOFs per level (AMG), for the report.
    pub detail: String,
}

/// Assembles K (3×3 blocks per node, both triangles, all DOFs) of the
/// perfect-bond problem with `concrete` and `steel`.
pub fn assemble(
    p: &PerfectBond,
    concrete: &LinearElastic,
    steel: &LinearElastic,
) -> Result<Bsr, LinearElasticError> {
    let n = p.nodes.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &p.tets {
        if t.iter().any(|&i| i as usize >= n) {
            return Err(LinearElasticError::Model(format!(
                "a tetrahedron references a node ≥ {n}"
            )));
        }
        for &a in t {
            adj[a as usize].extend_from_slice(t);
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
    });
    let mut row_ptr = Vec::with_capacity(n + 1);
    row_ptr.push(0);
    let mut col_idx = Vec::new();
    for v in &adj {
        col_idx.extend_from_slice(v);
        row_ptr.push(col_idx.len());
    }
    drop(adj);
    let mut k = Bsr {
        rows: n,
        cols: n,
        br: 3,
        bc: 3,
        row_ptr,
        col_idx,
        values: Vec::new(),
    };
    k.values = vec![0.0; 9 * k.blocks()];
    let (dc, ds) = (concrete.stiffness(), steel.stiffness());
    const CHUNK: usize = 16384;
    let mut buf = vec![[0.0f64; 144]; CHUNK.min(p.tets.len())];
    for (c, tets) in p.tets.chunks(CHUNK).enumerate() {
        let start = c * CHUNK;
        buf[..tets.len()]
            .par_iter_mut()
            .zip(tets.par_iter())
            .enumerate()
            .try_for_each(|(off, (ke, t))| {
                let index = start + off;
                let x = t.map(|i| p.nodes[i as usize]);
                let g = TetGeometry::new(&x)
                    .map_err(|source| LinearElasticError::Element { index, source })?;
                let d = match p.tet_region[index] {
                    Region::Concrete => &dc,
                    Region::Steel => &ds,
                };
                g.stiffness(d, ke);
                Ok::<(), LinearElasticError>(())
            })?;
        for (off, t) in tets.iter().enumerate() {
            let ke = &buf[off];
            for (a, &na) in t.iter().enumerate() {
                for (b, &nb) in t.iter().enumerate() {
                    let pos = k
                        .find(na as usize, nb as usize)
                        .expect("pattern from the tets");
                    let blk = &mut k.values[9 * pos..9 * pos + 9];
                    for r in 0..3 {
                        for s in 0..3 {
                            blk[3 * r + s] += ke[12 * (3 * a + r) + 3 * b + s];
                        }
                    }
                }
            }
        }
    }
    Ok(k)
}

/// Symmetric elimination of the constrained DOFs: returns the right-hand
/// side (−K_fc u_c on free rows, zero on constrained rows, so the solution
/// is zero there and Krylov residuals stay zero there) and turns
/// constrained rows and columns into identity ones.
pub fn apply_dirichlet(k: &mut Bsr, constrained: &[(usize, f64)]) -> Vec<f64> {
    let nd = 3 * k.rows;
    let mut fixed = vec![false; nd];
    let mut uc = vec![0.0; nd];
    for &(d, v) in constrained {
        fixed[d] = true;
        uc[d] = v;
    }
    let mut rhs = vec![0.0; nd];
    k.mul(&uc, &mut rhs);
    rhs.iter_mut().for_each(|v| *v = -*v);
    let row_ptr = &k.row_ptr;
    let col_idx = &k.col_idx;
    // Row by row in parallel: each row's blocks are its own.
    let rows: Vec<(usize, usize)> = (0..k.rows).map(|i| (row_ptr[i], row_ptr[i + 1])).collect();
    let mut chunks: Vec<&mut [f64]> = Vec::with_capacity(k.rows);
    let mut rest: &mut [f64] = &mut k.values;
    for &(s, e) in &rows {
        let (head, tail) = rest.split_at_mut(9 * (e - s));
        chunks.push(head);
        rest = tail;
    }
    chunks.into_par_iter().enumerate().for_each(|(i, vals)| {
        for (kk, blk) in vals.chunks_mut(9).enumerate() {
            let j = col_idx[rows[i].0 + kk] as usize;
            for r in 0..3 {
                for s in 0..3 {
                    let (gi, gj) = (3 * i + r, 3 * j + s);
                    if fixed[gi] || fixed[gj] {
                        blk[3 * r + s] = if gi == gj { 1.0 } else { 0.0 };
                    }
                }
            }
        }
    });
    for &(d, _) in constrained {
        rhs[d] = 0.0;
    }
    rhs
}

/// The six rigid-body modes at the nodes (6 values per DOF), zero on the
/// constrained DOFs; coordinates relative to the centroid.
pub fn rigid_body_modes(p: &PerfectBond) -> Vec<f64> {
    let mut fixed = vec![false; 3 * p.nodes.len()];
    for &(d, _) in &p.constrained {
        fixed[d] = true;
    }
    crate::linalg::multigrid::rigid_body_modes(&p.nodes, |d| !fixed[d])
}

/// Reaction on the loaded end along z (whole specimen, N): Σ of the
/// element internal forces K_e u_e at the loaded-end nodes.
pub fn reaction(
    p: &PerfectBond,
    concrete: &LinearElastic,
    steel: &LinearElastic,
    u: &[f64],
) -> Result<f64, LinearElasticError> {
    let mut loaded = vec![false; p.nodes.len()];
    for &i in &p.loaded_end {
        loaded[i as usize] = true;
    }
    let (dc, ds) = (concrete.stiffness(), steel.stiffness());
    let f: f64 = p
        .tets
        .par_iter()
        .enumerate()
        .filter(|(_, t)| t.iter().any(|&i| loaded[i as usize]))
        .map(|(index, t)| {
            let x = t.map(|i| p.nodes[i as usize]);
            let g = TetGeometry::new(&x)
                .map_err(|source| LinearElasticError::Element { index, source })?;
            let d = match p.tet_region[index] {
                Region::Concrete => &dc,
                Region::Steel => &ds,
            };
            let ue: [f64; 12] = std::array::from_fn(|k| u[3 * t[k / 3] as usize + k % 3]);
            let stress = d * g.strain(&ue);
            let mut fe = [0.0; 12];
            g.internal_force(&stress, &mut fe);
            Ok((0..4)
                .filter(|&a| loaded[t[a] as usize])
                .map(|a| fe[3 * a + 2])
                .sum::<f64>())
        })
        .collect::<Result<Vec<f64>, LinearElasticError>>()?
        .iter()
        .sum();
    Ok(p.force_factor * f)
}

/// Solves the perfect-bond problem with `solver`.
pub fn solve(
    p: &PerfectBond,
    concrete: &LinearElastic,
    steel: &LinearElastic,
    solver: ElasticSolver,
) -> Result<ElasticSolution, LinearElasticError> {
    let t0 = Instant::now();
    let mut k = assemble(p, concrete, steel)?;
    let rhs = apply_dirichlet(&mut k, &p.constrained);
    let t_assembly = t0.elapsed().as_secs_f64();
    let nd = p.dofs();
    let mut u = vec![0.0; nd];
    let (t_setup, t_solve, iterations, detail);
    match solver {
        ElasticSolver::Cholesky => {
            let t1 = Instant::now();
            let mut fixed = vec![false; nd];
            for &(d, _) in &p.constrained {
                fixed[d] = true;
            }
            let mut free_id = vec![usize::MAX; nd];
            let mut dof_node = Vec::new();
            for d in 0..nd {
                if !fixed[d] {
                    free_id[d] = dof_node.len();
                    dof_node.push(d / 3);
                }
            }
            let nf = dof_node.len();
            // Lower triangle of the free block; K is symmetric, so column j's
            // lower part is row j's entries with i ≥ j.
            let mut col_ptr = Vec::with_capacity(nf + 1);
            let mut row_idx = Vec::new();
            let mut vals = Vec::new();
            col_ptr.push(0);
            for bj in 0..k.rows {
                for cj in 0..3 {
                    let Some(&j) = Some(&free_id[3 * bj + cj]).filter(|&&j| j != usize::MAX) else {
                        continue;
                    };
                    for kk in k.row_ptr[bj]..k.row_ptr[bj + 1] {
                        let bi = k.col_idx[kk] as usize;
                        for ci in 0..3 {
                            let i = free_id[3 * bi + ci];
                            if i != usize::MAX && i >= j {
                                row_idx.push(i);
                                vals.push(k.values[9 * kk + 3 * cj + ci]);
                            }
                        }
                    }
                    col_ptr.push(row_idx.len());
                }
            }
            drop(k);
            let mut b: Vec<f64> = (0..nd).filter(|&d| !fixed[d]).map(|d| rhs[d]).collect();
            let mut chol = Cholesky::new(&col_ptr, &row_idx, Ordering::Metis, &dof_node)?;
            drop((col_ptr, row_idx));
            chol.factorize(&vals)?;
            drop(vals);
            t_setup = t1.elapsed().as_secs_f64();
            let t2 = Instant::now();
            chol.solve_in_place(&mut b)?;
            t_solve = t2.elapsed().as_secs_f64();
            for d in 0..nd {
                if !fixed[d] {
                    u[d] = b[free_id[d]];
                }
            }
            iterations = 0;
            detail = format!("{} factor entries", chol.factor_len());
        }
        ElasticSolver::AmgCg { tolerance, params } => {
            let t1 = Instant::now();
            let null = rigid_body_modes(p);
            let amg = Amg::new(k, &null, params)?;
            drop(null);
            t_setup = t1.elapsed().as_secs_f64();
            let t2 = Instant::now();
            let info = amg_pcg(&amg, &rhs, &mut u, tolerance, 1000)?;
            t_solve = t2.elapsed().as_secs_f64();
            iterations = info.iterations;
            let ai = amg.info();
            detail = format!(
                "levels {:?} DOFs, operator complexity {:.2}, residual {:.1e}",
                ai.level_dofs, ai.operator_complexity, info.relative_residual
            );
        }
    }
    for &(d, v) in &p.constrained {
        u[d] = v;
    }
    let reaction = reaction(p, concrete, steel, &u)?;
    Ok(ElasticSolution {
        u,
        reaction,
        free_dofs: p.free_dofs(),
        t_assembly,
        t_setup,
        t_solve,
        iterations,
        detail,
    })
}
