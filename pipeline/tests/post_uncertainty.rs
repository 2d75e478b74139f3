//! Least-squares uncertainty of a grid series (after Eça & Hoekstra 2014):
//! the fitted order and value at h = 0 of a manufactured series, the
//! safety factors, and an uncertainty for series that Celik's three-grid
//! procedure calls divergent.

use pipeline::post::{
    convergence_study, least_squares_uncertainty, ConvergenceKind, ErrorFit, GridResult,
};

fn grids(h: &[f64], values: &[f64]) -> Vec<GridResult> {
    h.iter()
        .zip(values)
        .map(|(&h, &value)| GridResult {
            h,
            value,
            dofs: None,
            wall_time: None,
        })
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// An exact power law φ0 + C h^p on five unevenly spaced grids gives back
/// p and φ0, no scatter, the factor 1.25 for 0.5 ≤ p < 2.1 and 3 beyond,
/// and U_i = F_s |φ_i − φ0|.
#[test]
fn exact_power_law_gives_its_order_and_limit() {
    let h: [f64; 5] = [0.2e-3, 0.28e-3, 0.4e-3, 0.57e-3, 0.8e-3];
    for &(p, c, factor) in &[
        (1.0, 2.0e3, 1.25),
        (1.5, -4.0e4, 1.25),
        (0.7, 50.0, 1.25),
        (2.0, 1.0e6, 1.25),
        (3.0, 5.0e9, 3.0),
    ] {
        let phi0 = 4.0;
        let values: Vec<f64> = h.iter().map(|h| phi0 + c * h.powf(p)).collect();
        let e = least_squares_uncertainty(&h, &values).unwrap();
        assert_eq!(e.fit, ErrorFit::FittedOrder, "p = {p}: {e:?}");
        assert!((e.order.unwrap() - p).abs() < 1e-5, "p = {p}: {e:?}");
        assert!(rel(e.extrapolated, phi0) < 1e-7, "p = {p}: {e:?}");
        assert!(e.standard_deviation < 1e-6 * e.data_range, "p = {p}: {e:?}");
        assert_eq!(e.safety_factor, factor, "p = {p}");
        for (u, v) in e.uncertainty.iter().zip(&values) {
            assert!(rel(*u, factor * (v - phi0).abs()) < 1e-4, "p = {p}: {e:?}");
        }
    }
}

/// Scatter on top of a first-order series: the uncertainty of every grid
/// still covers the exact limit, and a σ beyond the data range switches
/// to the factor 3 and the σ/Δ form.
#[test]
fn scattered_series_are_covered() {
    let h: [f64; 5] = [0.25, 0.35, 0.5, 0.7, 1.0];
    let noise = [0.004, -0.006, 0.005, -0.003, 0.002];
    let values: Vec<f64> = h
        .iter()
        .zip(&noise)
        .map(|(h, n)| 1.0 + 0.1 * h + n)
        .collect();
    let e = least_squares_uncertainty(&h, &values).unwrap();
    assert!(e.standard_deviation > 0.0 && e.standard_deviation < e.data_range);
    for (u, v) in e.uncertainty.iter().zip(&values) {
        assert!((v - 1.0).abs() <= *u, "{u} does not cover {v}: {e:?}");
    }
    // Values that zig-zag with no trend: the fit misses them by more than
    // their spread per grid.
    let zigzag = [1.0, 1.3, 0.95, 1.25, 1.05];
    let e = least_squares_uncertainty(&h, &zigzag).unwrap();
    assert_eq!(e.safety_factor, 3.0, "{e:?}");
    for (u, v) in e.uncertainty.iter().zip(&zigzag) {
        assert!(*u >= (v - e.extrapolated).abs(), "{e:?}");
    }
}

/// R1's energy to FED 1 mm with the paper's local damage law on 1.6, 1.2,
/// 0.8 and 0.4 mm (docs/src/validation/results/studies/r1-convergence.csv): Celik's
/// finest triplet is divergent, the least-squares estimate falls back to
/// a fixed-order fit with the factor 3, and its uncertainty on the 0.4 mm
/// grid covers the next grid of the fine series (3 753 J/m² on 0.28 mm,
/// r1-convergence-fine.csv), which none of the four grids saw.
#[test]
fn divergent_local_damage_series_gets_an_uncertainty() {
    let h = [1.6e-3, 1.2e-3, 0.8e-3, 0.4e-3];
    let energy = [4047.65, 4039.83, 4008.62, 3857.63];
    let s = convergence_study("energy", &grids(&h, &energy)).unwrap();
    assert_eq!(s.finest().kind, ConvergenceKind::Divergent);
    assert!(s.finest().gci_fine.is_none());
    let e = s.least_squares.as_ref().unwrap();
    assert!(e.order.is_none_or(|p| p < 0.5), "{e:?}");
    assert_ne!(e.fit, ErrorFit::FittedOrder);
    assert_eq!(e.safety_factor, 3.0);
    let finest = e.uncertainty[0];
    assert!((3857.63 - 3753.0) < finest, "{e:?}");
    let rows = s.rows();
    assert!(rel(rows[0].uncertainty.unwrap(), finest / 3857.63) < 1e-12);
}

/// Fewer than four grids give no estimate (three parameters and no
/// scatter left to measure); equal values give zero uncertainty.
#[test]
fn too_few_grids_and_equal_values() {
    let h = [1.0, 2.0, 4.0];
    assert!(least_squares_uncertainty(&h, &[1.0, 2.0, 3.0]).is_none());
    let s = convergence_study("x", &grids(&h, &[1.0, 2.0, 3.0])).unwrap();
    assert!(s.least_squares.is_none() && s.rows().iter().all(|r| r.uncertainty.is_none()));
    let h = [1.0, 2.0, 4.0, 8.0];
    let e = least_squares_uncertainty(&h, &[5.0; 4]).unwrap();
    assert!(e.uncertainty.iter().all(|u| *u == 0.0), "{e:?}");
}
