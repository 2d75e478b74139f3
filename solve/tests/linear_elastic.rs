//! The perfect-bond elastic pull-out (SPEC §9 benchmark problem) and its
//! solvers on a small structured specimen built without gmsh.

use mesh::{Frame, InterfaceElement, InterfaceZone, Model, NodeSets, Region};
use solve::laws::elastic::LinearElastic;
use solve::linalg::amg::AmgParams;
use solve::problems::linear_elastic::{solve, ElasticSolution, ElasticSolver, PerfectBond};

const CONCRETE: LinearElastic = LinearElastic {
    young_modulus: 25e9,
    poisson_ratio: 0.2,
};
const STEEL: LinearElastic = LinearElastic {
    young_modulus: 200e9,
    poisson_ratio: 0.3,
};

/// A pull-out specimen on a grid: an `n`×`n`×`nz` block of hexahedra (6
/// tets each, cell size 2 mm) whose central 2×2 column is steel and sticks
/// out by one cell above the bearing face z = L; perfect bond (shared nodes).
fn specimen(n: usize, nz: usize) -> Model {
    let h = 2e-3;
    let (nx, nzt) = (n, nz + 1);
    let id = |i: usize, j: usize, k: usize| (k * (nx + 1) + j) * (nx + 1) + i;
    let c = n / 2;
    let is_bar = |i: usize, j: usize| (c - 1..=c).contains(&i) && (c - 1..=c).contains(&j);
    let mut used = vec![false; (nx + 1) * (nx + 1) * (nzt + 1)];
    let mut tets = Vec::new();
    let mut region = Vec::new();
    for k in 0..nzt {
        for j in 0..nx {
            for i in 0..nx {
                let bar = is_bar(i, j);
                if k == nz && !bar {
                    continue;
                }
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
                // Kuhn subdivision along the diagonal 0–6: conforming.
                for t in [
                    [0, 1, 2, 6],
                    [0, 2, 3, 6],
                    [0, 3, 7, 6],
                    [0, 7, 4, 6],
                    [0, 4, 5, 6],
                    [0, 5, 1, 6],
                ] {
                    tets.push(t.map(|a| v[a]));
                    region.push(if bar { Region::Steel } else { Region::Concrete });
                }
                v.iter().for_each(|&a| used[a] = true);
            }
        }
    }
    let mut new = vec![u32::MAX; used.len()];
    let mut nodes = Vec::new();
    for k in 0..=nzt {
        for j in 0..=nx {
            for i in 0..=nx {
                let a = id(i, j, k);
                if used[a] {
                    new[a] = nodes.len() as u32;
                    nodes.push([
                        (i as f64 - c as f64) * h,
                        (j as f64 - c as f64) * h,
                        k as f64 * h,
                    ]);
                }
            }
        }
    }
    let mut tets: Vec<[u32; 4]> = tets.iter().map(|t| t.map(|a| new[a])).collect();
    for t in tets.iter_mut() {
        let x = t.map(|a| nodes[a as usize]);
        let d = |p: usize| [x[p][0] - x[0][0], x[p][1] - x[0][1], x[p][2] - x[0][2]];
        let (a, b, e) = (d(1), d(2), d(3));
        let det = a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0])
            + a[2] * (b[0] * e[1] - b[1] * e[0]);
        if det < 0.0 {
            t.swap(1, 2);
        }
    }
    let zl = nz as f64 * h;
    let top = (nz + 1) as f64 * h;
    let at = |z: f64| -> Vec<u32> {
        (0..nodes.len() as u32)
            .filter(|&a| (nodes[a as usize][2] - z).abs() < 1e-12)
            .collect()
    };
    let mut in_concrete = vec![false; nodes.len()];
    for (t, r) in tets.iter().zip(&region) {
        if *r == Region::Concrete {
            t.iter().for_each(|&a| in_concrete[a as usize] = true);
        }
    }
    let bearing: Vec<u32> = at(zl)
        .into_iter()
        .filter(|&a| in_concrete[a as usize])
        .collect();
    let node_region = vec![Region::Concrete; nodes.len()];
    Model {
        tet_size: vec![h; tets.len()],
        node_sets: NodeSets {
            bar_loaded_end: at(top),
            bar_free_end: at(0.0),
            concrete_bearing_face: bearing,
            concrete_free_face: at(0.0),
            ..Default::default()
        },
        nodes,
        node_region,
        tets,
        tet_region: region,
        interfaces: Vec::new(),
        bar_diameter: 2.0 * h,
        adhesive_length: zl / 2.0,
        ..Default::default()
    }
}

/// The same specimen with the mesh stage's topology: every node shared by
/// steel and concrete duplicated, the concrete tets re-pointed to the twins
/// and the node pairs listed in (pair-only) interface elements.
fn duplicated(m: &Model) -> Model {
    let n = m.nodes.len();
    let mut steel = vec![false; n];
    let mut conc = vec![false; n];
    for (t, r) in m.tets.iter().zip(&m.tet_region) {
        for &a in t {
            match r {
                Region::Steel => steel[a as usize] = true,
                Region::Concrete => conc[a as usize] = true,
            }
        }
    }
    let mut out = m.clone();
    let mut twin = vec![u32::MAX; n];
    let mut pairs = Vec::new();
    for a in 0..n {
        if steel[a] && conc[a] {
            twin[a] = out.nodes.len() as u32;
            out.nodes.push(m.nodes[a]);
            out.node_region.push(Region::Concrete);
            pairs.push((a as u32, twin[a]));
        }
    }
    for (t, r) in out.tets.iter_mut().zip(&m.tet_region) {
        if *r == Region::Concrete {
            for a in t.iter_mut() {
                if twin[*a as usize] != u32::MAX {
                    *a = twin[*a as usize];
                }
            }
        }
    }
    // The bearing face's ring nodes belong to the concrete side.
    for a in out.node_sets.concrete_bearing_face.iter_mut() {
        if twin[*a as usize] != u32::MAX {
            *a = twin[*a as usize];
        }
    }
    let frame = Frame {
        n: [1.0, 0.0, 0.0],
        t: [0.0, 0.0, 1.0],
        h: [0.0, -1.0, 0.0],
    };
    for ch in pairs.chunks(3) {
        let p = |k: usize| ch[k.min(ch.len() - 1)];
        out.interfaces.push(InterfaceElement {
            nodes: [p(0).0, p(1).0, p(2).0, p(0).1, p(1).1, p(2).1],
            zone: InterfaceZone::Adhesive,
            frame,
            area: 1e-6,
        });
    }
    out
}

fn amg(tolerance: f64) -> ElasticSolver {
    ElasticSolver::AmgCg {
        tolerance,
        params: AmgParams {
            coarse_dofs: 200,
            ..Default::default()
        },
    }
}

fn run(m: &Model, solver: ElasticSolver) -> ElasticSolution {
    let p = PerfectBond::from_model(m, 1e-5).unwrap();
    solve(&p, &CONCRETE, &STEEL, solver).unwrap()
}

/// Issue 7: ribbar's multigrid-preconditioned CG gives the direct solver's
/// reaction force to 1e-8 relative on a multi-level hierarchy.
#[test]
fn amg_cg_matches_cholesky_reaction() {
    let m = specimen(10, 12);
    let direct = run(&m, ElasticSolver::Cholesky);
    let iterative = run(&m, amg(1e-12));
    assert!(
        direct.reaction > 0.0,
        "pull gives a positive reaction: {}",
        direct.reaction
    );
    let rel = (iterative.reaction - direct.reaction).abs() / direct.reaction;
    assert!(
        rel < 1e-8,
        "AMG-CG {} vs Cholesky {} (rel {rel:e})",
        iterative.reaction,
        direct.reaction
    );
    // A real hierarchy: the fine level and at least two coarser ones.
    let d = &iterative.detail;
    let levels = d[d.find('[').unwrap() + 1..d.find(']').unwrap()]
        .split(',')
        .count();
    assert!(levels >= 3, "{d}");
    assert!(
        iterative.iterations > 0 && iterative.iterations < 60,
        "{} iterations",
        iterative.iterations
    );
    let umax = direct
        .u
        .iter()
        .zip(&iterative.u)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(umax < 1e-8 * 1e-5, "displacements differ by {umax:e} m");
}

/// SPEC §9 "perfect bond": merging the interface twins of the mesh stage's
/// model gives the conforming problem (same DOFs and the same reaction).
#[test]
fn merging_twins_restores_the_conforming_problem() {
    let m = specimen(6, 6);
    let d = duplicated(&m);
    assert!(d.nodes.len() > m.nodes.len() && !d.interfaces.is_empty());
    let pm = PerfectBond::from_model(&m, 1e-5).unwrap();
    let pd = PerfectBond::from_model(&d, 1e-5).unwrap();
    assert_eq!(pm.nodes.len(), pd.nodes.len());
    assert_eq!(pm.constrained.len(), pd.constrained.len());
    let a = solve(&pm, &CONCRETE, &STEEL, ElasticSolver::Cholesky).unwrap();
    let b = solve(&pd, &CONCRETE, &STEEL, ElasticSolver::Cholesky).unwrap();
    let rel = (a.reaction - b.reaction).abs() / a.reaction;
    assert!(rel < 1e-12, "{} vs {}", a.reaction, b.reaction);
}

/// SPEC §2 boundary conditions: the loaded end holds u_z = λ and u_x = u_y = 0,
/// the bearing face u_z = 0, and the full model adds 3 lateral point
/// constraints, exactly those of the nonlinear pull-out; the response is
/// linear in λ.
#[test]
fn conditions_and_linearity() {
    let m = specimen(6, 6);
    let p = PerfectBond::from_model(&m, 2e-5).unwrap();
    let loaded = p.loaded_end.len();
    let bearing = m.node_sets.concrete_bearing_face.len();
    assert_eq!(p.constrained.len(), 3 * loaded + bearing + 3);
    // The conforming specimen has no twins: the pull-out's DOFs as they are.
    let (dir, _) = solve::problems::pullout::pullout_conditions(&m).unwrap();
    let mut expected: Vec<(usize, f64)> = dir
        .dofs
        .iter()
        .zip(dir.base.iter().zip(&dir.rate))
        .map(|(&d, (&b, &r))| (d, b + 2e-5 * r))
        .collect();
    expected.sort_unstable_by_key(|c| c.0);
    assert_eq!(p.constrained, expected);
    for &n in &p.loaded_end {
        let d = 3 * n as usize;
        let v = |dof: usize| p.constrained.iter().find(|c| c.0 == dof).map(|c| c.1);
        assert_eq!(
            (v(d), v(d + 1), v(d + 2)),
            (Some(0.0), Some(0.0), Some(2e-5))
        );
    }
    let f2 = solve(&p, &CONCRETE, &STEEL, ElasticSolver::Cholesky)
        .unwrap()
        .reaction;
    let f1 = run(&m, ElasticSolver::Cholesky).reaction;
    assert!((f2 / f1 - 2.0).abs() < 1e-10, "F(2λ)/F(λ) = {}", f2 / f1);
}

/// Bad input gives a typed error, not a panic: a model without a loaded end.
#[test]
fn empty_loaded_end_is_an_error() {
    let mut m = specimen(4, 4);
    m.node_sets.bar_loaded_end.clear();
    let e = PerfectBond::from_model(&m, 1e-5).unwrap_err().to_string();
    assert!(e.contains("bar_loaded_end"), "{e}");
}

/// A coarse bearing face may have a single node nearest the line y = 0: the
/// two u_y supports then take the nearest node on each side of the axis, so
/// the rotation about z is still held (a coarse R1 failed before its first
/// step with "no extent in x").
#[test]
fn lateral_supports_hold_on_a_face_with_one_node_nearest_the_line() {
    let mut m = specimen(6, 6);
    // Distinct offsets in y: no two bearing-face nodes share |y|.
    for (k, &n) in m.node_sets.concrete_bearing_face.clone().iter().enumerate() {
        m.nodes[n as usize][1] += 1e-6 * (1.0 + k as f64 / 1000.0);
    }
    let (dir, _) = solve::problems::pullout::pullout_conditions(&m).unwrap();
    let bearing: std::collections::HashSet<u32> =
        m.node_sets.concrete_bearing_face.iter().copied().collect();
    let uy: Vec<usize> = dir
        .dofs
        .iter()
        .filter(|&&d| d % 3 == 1 && bearing.contains(&((d / 3) as u32)))
        .map(|&d| d / 3)
        .collect();
    assert_eq!(uy.len(), 2, "{uy:?}");
    let (xa, xb) = (m.nodes[uy[0]][0], m.nodes[uy[1]][0]);
    assert!(xa * xb < 0.0, "u_y supports at x = {xa} and {xb}");
}
