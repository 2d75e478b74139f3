//! Timing of the solver's hot paths on a structured elastic cube of
//! n³ hexahedra split into tets (bottom face fixed): pattern build,
//! constitutive + assembly pass, METIS vs AMD symbolic analysis, numeric
//! Cholesky, one solve, 20 triangular-solve pairs in f64 and with L rounded
//! to f32 (sequential and on 2 threads), PCG on a perturbed matrix
//! preconditioned by the first factor in either precision, and the
//! multigrid's set-up and V-cycle (only that with
//! `RIBBAR_BENCH_MULTIGRID_ONLY` set). `RIBBAR_BENCH_N` sets n (default 30,
//! ≈ 89 k DOFs).

use mesh::{Model, Region};
use solve::assembly::{ElementLaws, Outputs, States, System, Tangents};
use solve::laws::elastic::LinearElastic;
use solve::laws::TangentKind;
use solve::linalg::amg::AmgParams;
use solve::linalg::multigrid::NodeBlockLayout;
use solve::linalg::{pcg, Cholesky, Ordering, Preconditioner, SymLower};
use std::time::Instant;

fn cube(n: usize) -> Model {
    let mut m = Model::default();
    let h = 1e-3;
    let id = |i: usize, j: usize, k: usize| (i + (n + 1) * (j + (n + 1) * k)) as u32;
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                m.nodes.push([i as f64 * h, j as f64 * h, k as f64 * h]);
                m.node_region.push(Region::Concrete);
            }
        }
    }
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ];
                for p in [[1, 2], [2, 3], [3, 7], [7, 4], [4, 5], [5, 1]] {
                    let mut t = [v[0], v[p[0]], v[p[1]], v[6]];
                    let x = |a: u32| m.nodes[a as usize];
                    let e = |a: u32| {
                        [
                            x(a)[0] - x(t[0])[0],
                            x(a)[1] - x(t[0])[1],
                            x(a)[2] - x(t[0])[2],
                        ]
                    };
                    let (a, b, c) = (e(t[1]), e(t[2]), e(t[3]));
                    let det = a[0] * (b[1] * c[2] - b[2] * c[1])
                        - a[1] * (b[0] * c[2] - b[2] * c[0])
                        + a[2] * (b[0] * c[1] - b[1] * c[0]);
                    if det < 0.0 {
                        t.swap(1, 2);
                    }
                    m.tets.push(t);
                    m.tet_region.push(Region::Concrete);
                }
            }
        }
    }
    m
}

fn main() {
    let n: usize = std::env::var("RIBBAR_BENCH_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    let m = cube(n);
    let fixed: Vec<usize> = (0..(n + 1) * (n + 1))
        .flat_map(|v| [3 * v, 3 * v + 1, 3 * v + 2])
        .collect();
    let law: solve::laws::AnyBulkLaw = solve::laws::AnyBulkLaw::Elastic(LinearElastic {
        young_modulus: 30e9,
        poisson_ratio: 0.2,
    });
    let laws = ElementLaws {
        tets: vec![law; m.tets.len()],
        interfaces: vec![],
        nonlocal_length: None,
    };
    let t = Instant::now();
    let sys = System::new(&m, &fixed, &[], &[]).unwrap();
    println!(
        "tets {}  free DOFs {}  lower nnz {}",
        m.tets.len(),
        sys.dofs().n_free(),
        sys.nnz()
    );
    println!(
        "pattern + scatter maps      {:8.3} s",
        t.elapsed().as_secs_f64()
    );
    let mut u = vec![0.0; 3 * m.nodes.len()];
    for (i, p) in m.nodes.iter().enumerate() {
        u[3 * i + 2] = 1e-4 * p[2];
    }
    let st = States::initial(&m);
    let mut trial = st.clone();
    let mut f = vec![0.0; u.len()];
    let mut k = vec![0.0; sys.nnz()];
    // 20 evaluations: the scatter of one is a few ms.
    let (mut cons, mut scat) = (0.0, 0.0);
    let t = Instant::now();
    for _ in 0..20 {
        let e = sys
            .evaluate(
                &laws,
                &u,
                &st,
                &mut trial,
                Tangents::all(TangentKind::Consistent),
                Outputs::with_matrix(&mut f, &mut k),
            )
            .unwrap();
        cons += e.constitutive;
        scat += e.assembly;
    }
    println!(
        "20 × evaluate (K + f)       {:8.3} s  (constitutive+kernels {cons:.3}, scatter {scat:.3})",
        t.elapsed().as_secs_f64(),
    );
    let mut dof_node = vec![0; sys.dofs().n_free()];
    for d in 0..sys.dofs().n_total() {
        if let Some(i) = sys.dofs().free_index(d) {
            dof_node[i] = d / 3;
        }
    }
    let b: Vec<f64> = (0..dof_node.len())
        .map(|i| ((i % 7) as f64 - 3.0) * 1e3)
        .collect();
    multigrid(&m, &sys, &k, &b);
    if std::env::var_os("RIBBAR_BENCH_MULTIGRID_ONLY").is_some() {
        return;
    }
    let mut first = None;
    for ord in [Ordering::Metis, Ordering::Amd] {
        let t = Instant::now();
        let mut c = Cholesky::new(&sys.col_ptr, &sys.row_idx, ord, &dof_node).unwrap();
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        c.factorize(&k).unwrap();
        let tf = t.elapsed().as_secs_f64();
        let mut x = b.clone();
        let t = Instant::now();
        c.solve_in_place(&mut x).unwrap();
        let tsol = t.elapsed().as_secs_f64();
        println!(
            "{ord:?}: symbolic {ts:.3} s  numeric {tf:.3} s  solve {tsol:.4} s  factor entries {}",
            c.factor_len()
        );
        // `precondition` is `solve_in_place` unless the f32 copy of L is kept.
        for single in [false, true] {
            c.set_single_precision_preconditioner(single);
            c.factorize(&k).unwrap();
            for par in [faer::Par::Seq, faer::Par::rayon(2)] {
                faer::set_global_parallelism(par);
                let t = Instant::now();
                for _ in 0..20 {
                    let mut x = b.clone();
                    c.precondition(&mut x).unwrap();
                }
                println!(
                    "  20 {} solves {par:?}: {:.4} s",
                    if single { "f32" } else { "f64" },
                    t.elapsed().as_secs_f64()
                );
            }
        }
        if first.is_none() {
            first = Some(c);
        }
    }
    // PCG on 0.8 K + 0.2 diag(K) (SPD, a drifted tangent), preconditioned by the factor of K.
    let mut c = first.unwrap();
    let mut k2: Vec<f64> = k.iter().map(|v| 0.8 * v).collect();
    for j in 0..sys.col_ptr.len() - 1 {
        k2[sys.col_ptr[j]] += 0.2 * k[sys.col_ptr[j]];
    }
    for single in [false, true] {
        c.set_single_precision_preconditioner(single);
        c.factorize(&k).unwrap();
        let mut x = vec![0.0; b.len()];
        let t = Instant::now();
        let info = pcg(
            SymLower {
                col_ptr: &sys.col_ptr,
                row_idx: &sys.row_idx,
                values: &k2,
            },
            &c,
            &b,
            &mut x,
            1e-8,
            200,
        );
        println!(
            "PCG (reused factor{})  {:8.3} s  {:?}",
            if single { ", f32" } else { ", f64" },
            t.elapsed().as_secs_f64(),
            info
        );
    }
}

/// The multigrid hierarchy of K (rigid-body near-null space): set-up, and
/// 50 V-cycles applied to the right-hand side (the preconditioner of every
/// GMRES iteration of a multigrid run), with a checksum of the last.
fn multigrid(m: &Model, sys: &System, k: &[f64], b: &[f64]) {
    let dofs = sys.dofs();
    let t = Instant::now();
    let layout = NodeBlockLayout::new(
        &sys.col_ptr,
        &sys.row_idx,
        |d| dofs.free_index(d),
        &m.nodes,
        &[],
    )
    .unwrap();
    let mg = layout.build(k, AmgParams::default()).unwrap();
    let t_setup = t.elapsed().as_secs_f64();
    let mut z = b.to_vec();
    let t = Instant::now();
    // On a pool worker, as `ribbar` runs its commands.
    rayon::scope(|_| {
        for _ in 0..50 {
            z.copy_from_slice(b);
            mg.apply(&mut z).unwrap();
        }
    });
    let checksum: f64 = z.iter().map(|v| v.abs()).sum();
    println!(
        "multigrid: set-up {t_setup:.3} s  50 V-cycles {:.3} s  levels {:?}  checksum {checksum:.12e}",
        t.elapsed().as_secs_f64(),
        mg.info().level_dofs
    );
}
