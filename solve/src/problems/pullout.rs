//! The pull-out test of SPEC §2: boundary conditions and measurements
//! from the model's node sets, for the nonlinear driver
//! ([`crate::nonlinear::run`]) and the linear benchmark alike:
//! * concrete bearing face (z = L): u_z = 0 on every node;
//! * lateral rigid-body modes of the concrete: of the bearing-face nodes
//!   nearest the line y = 0, the two extreme in x get u_y = 0; of those
//!   nearest x = 0, the one with the largest y gets u_x = 0 (removes x, y
//!   translation and rotation about z without opposing a mirror-symmetric
//!   deformation; the three other modes are held by u_z = 0 on the face);
//! * quarter models (`Symmetry::Quarter`): u_x = 0 on `symmetry_x`, u_y = 0
//!   on `symmetry_y` instead of the point constraints; forces × 4;
//! * half models (`Symmetry::Half`, y ≥ 0): u_y = 0 on `symmetry_y` (holds y
//!   translation and rotation about z) and the one point constraint on u_x
//!   of the whole model's three, which lies in the half; forces × 2;
//! * half-turn half models (`Symmetry::HalfTurn`, y ≥ 0 of a spiral bar):
//!   each cut-face node at x < 0 moves as the half-turn image of its twin,
//!   u = R u_twin with R = diag(−1, −1, 1) (DOF ties); axis nodes get
//!   u_x = u_y = 0; of the whole model's point constraints, u_y at the two
//!   line ends on y = 0 (twins of each other: one holds the rotation about
//!   z); the ties hold the x, y translations; forces × 2. A constrained DOF
//!   of a twin pair constrains its image with the image value;
//! * bar loaded end: u_z = λ (the imposed displacement), u_x = u_y = 0 (the
//!   machine's grip; it also holds the bar's lateral modes once the
//!   interface has lost its shear stiffness);
//! * F = Σ of the internal forces f_z over the loaded-end nodes (the pull,
//!   N); FED = mean u_z of `bar_free_end` − mean u_z of `concrete_free_face`
//!   (the whole z = 0 concrete face as the mesh gives it, m); in a part of
//!   a symmetric specimen each node weighs as many times as it appears in
//!   the whole (2 in a half, 4 in a quarter, halved per plane it lies on),
//!   so FED is the whole specimen's;
//!   σ_mb = F / (π d l_adh) (paper eq. 14, Pa).

use crate::assembly::{ElementLaws, Tie};
use crate::laws::BulkLaw;
use crate::nonlinear::{
    run, Checkpoint, Dirichlet, Measurement, Observer, Problem, RunResult, SolveError,
};
use crate::spec::solver::{Loading, SolverSettings};
use mesh::{Model, Symmetry};

/// Boundary conditions and measurement of the pull-out test (see module doc).
pub fn pullout_conditions(model: &Model) -> Result<(Dirichlet, Measurement), SolveError> {
    let sets = &model.node_sets;
    let need = |name: &str, v: &Vec<u32>| {
        if v.is_empty() {
            Err(SolveError::Model(format!("node set {name} is empty")))
        } else if v.iter().any(|&n| n as usize >= model.nodes.len()) {
            Err(SolveError::Model(format!(
                "node set {name} references a missing node"
            )))
        } else {
            Ok(())
        }
    };
    need("bar_loaded_end", &sets.bar_loaded_end)?;
    need("bar_free_end", &sets.bar_free_end)?;
    need("concrete_bearing_face", &sets.concrete_bearing_face)?;
    need("concrete_free_face", &sets.concrete_free_face)?;
    if !(model.bar_diameter > 0.0 && model.adhesive_length > 0.0) {
        return Err(SolveError::Model(format!(
            "bar_diameter {} m and adhesive_length {} m must be > 0",
            model.bar_diameter, model.adhesive_length
        )));
    }
    let mut dir = Dirichlet::default();
    let mut seen = vec![false; 3 * model.nodes.len()];
    let mut fix = |dir: &mut Dirichlet, dof: usize, rate: f64| {
        if !seen[dof] {
            seen[dof] = true;
            dir.push(dof, 0.0, rate);
        }
    };
    for &n in &sets.bar_loaded_end {
        let n = n as usize;
        fix(&mut dir, 3 * n, 0.0);
        fix(&mut dir, 3 * n + 1, 0.0);
        fix(&mut dir, 3 * n + 2, 1.0);
    }
    for &n in &sets.concrete_bearing_face {
        fix(&mut dir, 3 * n as usize + 2, 0.0);
    }
    if model.symmetry == Symmetry::Quarter {
        // The mirror planes hold the normal displacement; with the bearing
        // face's u_z = 0 they remove every rigid mode, so no point
        // constraints are added (they would over-constrain the quarter).
        need("symmetry_x", &sets.symmetry_x)?;
        need("symmetry_y", &sets.symmetry_y)?;
        for &n in &sets.symmetry_x {
            fix(&mut dir, 3 * n as usize, 0.0);
        }
        for &n in &sets.symmetry_y {
            fix(&mut dir, 3 * n as usize + 1, 0.0);
        }
        return Ok((dir, measurement(model)));
    }
    // Lateral rigid modes: points on (or nearest to) the mirror lines of
    // the bearing face, where a symmetric deformation has no displacement
    // across the line. Corner points (the earlier choice) pin the Poisson
    // expansion of the face and changed the elastic force by 0.45 % on a
    // mirrored test specimen.
    let x = |n: &u32| model.nodes[*n as usize];
    let nearest = |c: usize| line_ends(model, &sets.concrete_bearing_face, c);
    // Nearest the line y = 0: two points at both ends hold u_y (y
    // translation and rotation about z); nearest x = 0: one holds u_x.
    if model.symmetry == Symmetry::HalfTurn {
        need("symmetry_y", &sets.symmetry_y)?;
        let (a, b) = nearest(1);
        fix(&mut dir, 3 * a as usize + 1, 0.0);
        fix(&mut dir, 3 * b as usize + 1, 0.0);
        tie_half_turn(model, &mut dir)?;
        return Ok((dir, measurement(model)));
    }
    let (_, c) = nearest(0);
    if model.symmetry == Symmetry::Half {
        // The mirror plane y = 0 holds u_y; c (largest y) is in the half.
        need("symmetry_y", &sets.symmetry_y)?;
        for &n in &sets.symmetry_y {
            fix(&mut dir, 3 * n as usize + 1, 0.0);
        }
        fix(&mut dir, 3 * c as usize, 0.0);
        return Ok((dir, measurement(model)));
    }
    let (a, b) = nearest(1);
    if x(&b)[0] - x(&a)[0] <= 0.0 {
        return Err(SolveError::Model(
            "concrete_bearing_face has no extent in x: cannot remove the rotation about z".into(),
        ));
    }
    fix(&mut dir, 3 * a as usize + 1, 0.0);
    fix(&mut dir, 3 * b as usize + 1, 0.0);
    fix(&mut dir, 3 * c as usize, 0.0);
    Ok((dir, measurement(model)))
}

/// Ties each cut-face node at x < 0 of a half-turn half model to its twin
/// (u = R u_twin, R = diag(−1, −1, 1)) and holds u_x = u_y = 0 on the axis.
/// Where a pair has one DOF constrained (a face set, a point constraint),
/// the other is constrained to the image value instead of tied.
fn tie_half_turn(model: &Model, dir: &mut Dirichlet) -> Result<(), SolveError> {
    let twins = model
        .half_turn_twins()
        .map_err(|e| SolveError::Model(format!("half-turn cut plane: {e}")))?;
    let mut at: Vec<Option<usize>> = vec![None; 3 * model.nodes.len()];
    for (i, &d) in dir.dofs.iter().enumerate() {
        at[d] = Some(i);
    }
    for &n in &twins.axis {
        for c in 0..2 {
            let d = 3 * n as usize + c;
            if at[d].is_none() {
                at[d] = Some(dir.dofs.len());
                dir.push(d, 0.0, 0.0);
            }
        }
    }
    // The cut face's x < 0 half is glued to its x > 0 half, so x = 0
    // separates the sides on which the rigid-body modes stay rigid.
    dir.charts = model
        .nodes
        .iter()
        .map(|x| match x[0] {
            v if v > 0.0 => 1,
            v if v < 0.0 => -1,
            _ => 0,
        })
        .collect();
    for &n in &twins.axis {
        dir.charts[n as usize] = 0;
    }
    for &(image, source) in &twins.pairs {
        for c in 0..3 {
            let sign = if c < 2 { -1.0 } else { 1.0 };
            let (di, ds) = (3 * image as usize + c, 3 * source as usize + c);
            match (at[di], at[ds]) {
                (None, None) => dir.ties.push(Tie {
                    dof: di,
                    to: ds,
                    sign,
                }),
                (Some(_), Some(_)) => {}
                (None, Some(k)) => {
                    at[di] = Some(dir.dofs.len());
                    dir.push(di, sign * dir.base[k], sign * dir.rate[k]);
                }
                (Some(k), None) => {
                    at[ds] = Some(dir.dofs.len());
                    dir.push(ds, sign * dir.base[k], sign * dir.rate[k]);
                }
            }
        }
    }
    Ok(())
}

/// The two bearing-face nodes at the ends of the line of face nodes
/// nearest the plane x_c = 0 (c = 0: x, 1: y), ordered by the other
/// coordinate; `face` is non-empty.
fn line_ends(model: &Model, face: &[u32], c: usize) -> (u32, u32) {
    let x = |n: &u32| model.nodes[*n as usize];
    let d = face
        .iter()
        .map(|n| x(n)[c].abs())
        .fold(f64::INFINITY, f64::min);
    let span = face
        .iter()
        .map(|n| x(n)[1 - c].abs())
        .fold(0.0f64, f64::max);
    let line: Vec<u32> = face
        .iter()
        .copied()
        .filter(|n| x(n)[c].abs() <= d + 1e-9 * span)
        .collect();
    let lo = line
        .iter()
        .copied()
        .min_by(|p, q| x(p)[1 - c].total_cmp(&x(q)[1 - c]))
        .expect("checked non-empty");
    let hi = line
        .iter()
        .copied()
        .max_by(|p, q| x(p)[1 - c].total_cmp(&x(q)[1 - c]))
        .expect("checked non-empty");
    if lo != hi {
        return (lo, hi);
    }
    // A coarse face may have a single node nearest the line: take the
    // node nearest it on each side of the axis instead (off the line by
    // up to an element size, so their u_y holds a little of the face's
    // Poisson expansion; used only where the line has no second node).
    let side = |negative: bool| {
        face.iter()
            .copied()
            .filter(|n| (x(n)[1 - c] < 0.0) == negative && x(n)[1 - c] != 0.0)
            .min_by(|p, q| x(p)[c].abs().total_cmp(&x(q)[c].abs()))
    };
    match (side(true), side(false)) {
        (Some(a), Some(b)) => (a, b),
        _ => (lo, hi),
    }
}

/// σ_y × the bar's section over its loaded overhang (whole specimen, N),
/// when the steel there has a yield limit: the mean section (steel volume
/// between the bearing face and the loaded end, divided by that length),
/// which ribs crossing it raise a few per cent above the smallest section;
/// the nominal π d²/4 when there is no overhang.
pub fn bar_yield_force(model: &Model, laws: &ElementLaws) -> Option<f64> {
    let z = |n: &u32| model.nodes[*n as usize][2];
    let sets = &model.node_sets;
    let z_end = sets
        .bar_loaded_end
        .iter()
        .map(z)
        .fold(f64::NEG_INFINITY, f64::max);
    let z_face = sets
        .concrete_bearing_face
        .iter()
        .map(z)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut volume = 0.0;
    let mut sigma_y: Option<f64> = None;
    for (i, t) in model.tets.iter().enumerate() {
        if model.tet_region[i] != mesh::Region::Steel {
            continue;
        }
        let p = t.map(|n| model.nodes[n as usize]);
        if p.iter().all(|q| q[2] >= z_face - 1e-12) {
            volume += mesh::build::tet_volume(p).abs();
            let s = laws.tets[i].yield_stress()?;
            sigma_y = Some(sigma_y.map_or(s, |m: f64| m.min(s)));
        }
    }
    let length = z_end - z_face;
    let area = if length > 0.0 && volume > 0.0 {
        volume / length
    } else {
        std::f64::consts::PI * model.bar_diameter * model.bar_diameter
            / 4.0
            / model.symmetry.force_factor()
    };
    let sigma_y = match sigma_y {
        Some(s) => s,
        None => laws
            .tets
            .iter()
            .zip(&model.tet_region)
            .find(|(_, r)| **r == mesh::Region::Steel)?
            .0
            .yield_stress()?,
    };
    Some(sigma_y * area * model.symmetry.force_factor())
}

/// Force on the loaded end (times the symmetry factor), FED and σ_mb.
fn measurement(model: &Model) -> Measurement {
    let sets = &model.node_sets;
    let uz = |set: &[u32]| set.iter().map(|&n| 3 * n as usize + 2).collect();
    // Whole-specimen means: each node counts as often as it appears in the
    // whole (force_factor, halved per plane set it lies on: its image in
    // that plane is itself, or its twin, which the part holds too).
    let mut planes = vec![0i32; model.nodes.len()];
    for &n in sets.symmetry_x.iter().chain(&sets.symmetry_y) {
        planes[n as usize] += 1;
    }
    let weights = |set: &[u32]| -> Vec<f64> {
        if model.symmetry == Symmetry::Full {
            return Vec::new();
        }
        set.iter()
            .map(|&n| model.symmetry.force_factor() / 2f64.powi(planes[n as usize]))
            .collect()
    };
    Measurement {
        force_dofs: uz(&sets.bar_loaded_end),
        plus_dofs: uz(&sets.bar_free_end),
        minus_dofs: uz(&sets.concrete_free_face),
        plus_weights: weights(&sets.bar_free_end),
        minus_weights: weights(&sets.concrete_free_face),
        stress_per_force: 1.0 / (std::f64::consts::PI * model.bar_diameter * model.adhesive_length),
        force_factor: model.symmetry.force_factor(),
    }
}

/// Runs the pull-out test of SPEC §2 (see [`run`]).
pub fn solve_pullout(
    model: &Model,
    laws: &ElementLaws,
    loading: &Loading,
    settings: &SolverSettings,
    checkpoint: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<RunResult, SolveError> {
    let (dir, meas) = pullout_conditions(model)?;
    let problem = Problem {
        model,
        laws,
        dirichlet: &dir,
        measurement: &meas,
        yield_force: bar_yield_force(model, laws),
    };
    run(&problem, loading, settings, checkpoint, observer)
}
