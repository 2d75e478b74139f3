//! The sensitivity estimators on test functions whose indices are known:
//! Sobol' indices of the Ishigami function from Saltelli's design on the
//! study's own Sobol' points, and a Morris screening of the Sobol' g
//! function on the study's own trajectories.

use pipeline::post::{morris_indices, sobol_indices, BOOTSTRAP_RESAMPLES};
use pipeline::study::{morris, saltelli, Axis, AxisValue, Role, Verdict};
use std::f64::consts::PI;

fn unit_axes(n: usize) -> Vec<Axis> {
    (0..n)
        .map(|i| {
            Axis::parse(
                &format!("x{i}"),
                &serde_yaml::from_str("{range: [0, 1]}").unwrap(),
            )
            .unwrap()
        })
        .collect()
}

fn valid(_: &[AxisValue]) -> Result<Verdict, String> {
    Ok(Verdict::Valid)
}

/// Ishigami's function (a = 7, b = 0.1) on [−π, π]³.
fn ishigami(u: &[f64]) -> f64 {
    let x: Vec<f64> = u.iter().map(|u| -PI + 2.0 * PI * u).collect();
    x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
}

/// Its indices in closed form: (S1, ST) of x1, x2, x3.
fn ishigami_indices() -> [(f64, f64); 3] {
    let (a, b) = (7.0f64, 0.1f64);
    let v1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2);
    let v2 = a * a / 8.0;
    let v13 = b * b * PI.powi(8) * (1.0 / 18.0 - 1.0 / 50.0);
    let v = v1 + v2 + v13;
    [((v1) / v, (v1 + v13) / v), (v2 / v, v2 / v), (0.0, v13 / v)]
}

/// The Sobol' estimators reproduce Ishigami's first-order and total
/// indices within their bootstrap confidence intervals, and those
/// intervals are narrow enough for the check to mean something.
#[test]
fn sobol_indices_of_the_ishigami_function() {
    let axes = unit_axes(3);
    let n = 8192;
    let design = saltelli(&axes, n, 11, &valid).unwrap();
    let y: Vec<f64> = design.points.iter().map(|p| ishigami(&p.unit)).collect();
    let (mut a, mut b, mut ab) = (Vec::new(), Vec::new(), vec![Vec::new(); 3]);
    for (p, &y) in design.points.iter().zip(&y) {
        match p.role {
            Role::SobolA { .. } => a.push(y),
            Role::SobolB { .. } => b.push(y),
            Role::SobolAB { parameter, .. } => ab[parameter].push(y),
            _ => unreachable!(),
        }
    }
    let indices = sobol_indices(&a, &b, &ab, BOOTSTRAP_RESAMPLES, 5).unwrap();
    for (i, (got, (s1, st))) in indices.iter().zip(ishigami_indices()).enumerate() {
        assert!(
            (got.s1 - s1).abs() <= got.s1_conf,
            "x{}: S1 {got:?} vs {s1}",
            i + 1
        );
        assert!(
            (got.st - st).abs() <= got.st_conf,
            "x{}: ST {got:?} vs {st}",
            i + 1
        );
        assert!(
            got.s1_conf < 0.04 && got.st_conf < 0.04,
            "x{}: {got:?}",
            i + 1
        );
    }
}

/// The Sobol' g function with a = (0, 1, 4.5, 9, 99, 99): each x_i's
/// importance falls as a_i grows, x5 and x6 hardly matter.
fn g_function(u: &[f64]) -> f64 {
    let a = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0];
    u.iter()
        .zip(a)
        .map(|(u, a)| ((4.0 * u - 2.0).abs() + a) / (1.0 + a))
        .product()
}

/// A Morris screening of the g function ranks its parameters in the
/// order of their importance by μ*, and puts the two that hardly matter
/// last.
#[test]
fn morris_ranks_the_parameters_of_the_g_function() {
    let axes = unit_axes(6);
    let design = morris(&axes, 20, 4, 3, &valid).unwrap();
    let y: Vec<f64> = design.points.iter().map(|p| g_function(&p.unit)).collect();
    let mut effects = vec![Vec::new(); 6];
    for k in 1..y.len() {
        if let Role::Morris {
            moved: Some((i, delta)),
            ..
        } = design.points[k].role
        {
            effects[i].push((y[k] - y[k - 1]) / delta);
        }
    }
    let m: Vec<f64> = morris_indices(&effects, 200, 0)
        .iter()
        .map(|i| i.unwrap().mu_star)
        .collect();
    assert!(m[0] > m[1] && m[1] > m[2] && m[2] > m[3], "{m:?}");
    assert!(m[3] > m[4].max(m[5]), "{m:?}");
    assert!(m[4].max(m[5]) < 0.05 * m[0], "{m:?}");
}
