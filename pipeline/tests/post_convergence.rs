//! Mesh-convergence estimates: observed order, Richardson extrapolation and
//! GCI after Celik et al. (2008), J. Fluids Eng. 130(7) 078001 (SPEC §7
//! "Mesh convergence"; issue 6 `convergence` study).

use pipeline::post::{
    convergence_study, three_grid_estimate, ConvergenceKind, GridResult, PostError,
    GCI_SAFETY_FACTOR,
};

fn grids(h: &[f64], f: impl Fn(f64) -> f64) -> Vec<GridResult> {
    h.iter()
        .map(|&h| GridResult {
            h,
            value: f(h),
            dofs: Some((1e-9 / (h * h * h)) as u64),
            wall_time: Some(1e-6 / (h * h)),
        })
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// With a constant refinement ratio, a manufactured f(h) = f0 + C h^p gives
/// back p and f0 exactly, and the GCI equals 1.25 e_a/(r^p − 1)
/// (Celik et al. 2008, Eqs. 3–8).
#[test]
fn manufactured_constant_ratio() {
    let (f0, c, p) = (7.5e6, 3.0e12, 2.0);
    let h = [0.4e-3, 0.8e-3, 1.6e-3];
    let f = |h: f64| f0 + c * h.powf(p);
    let t = three_grid_estimate(h, h.map(f)).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Monotonic);
    assert!((t.order.unwrap() - p).abs() < 1e-10, "{t:?}");
    assert!(rel(t.extrapolated.unwrap(), f0) < 1e-13, "{t:?}");
    let ea = rel(f(h[1]), f(h[0]));
    assert!(rel(t.approx_rel_error.unwrap(), ea) < 1e-12);
    assert!(rel(t.extrap_rel_error.unwrap(), rel(f(h[0]), f0)) < 1e-9);
    assert!(rel(t.gci_fine.unwrap(), GCI_SAFETY_FACTOR * ea / 3.0) < 1e-9);
    // For an exact power law the fine-grid GCI is 1.25 × the true relative error (w.r.t. φ1).
    let true_err = ((f(h[0]) - f0) / f(h[0])).abs();
    assert!(rel(t.gci_fine.unwrap(), 1.25 * true_err) < 1e-9);
}

/// Non-constant refinement ratios (the fixed-point iteration for p), four
/// grids and values approaching from below: every consecutive triplet
/// recovers p and f0 to high precision.
#[test]
fn manufactured_non_constant_ratio_four_grids() {
    for &(p, c) in &[(1.7, -4.0e5), (0.8, 2.0e2), (3.2, 1.0e9)] {
        let f0 = 12.25;
        let f = |h: f64| f0 + c * h.powf(p);
        // Deliberately unsorted input.
        let h = [0.9e-3, 0.4e-3, 1.6e-3, 0.55e-3];
        let s = convergence_study("peak", &grids(&h, f)).unwrap();
        assert_eq!(
            s.grids.iter().map(|g| g.h).collect::<Vec<_>>(),
            vec![0.4e-3, 0.55e-3, 0.9e-3, 1.6e-3]
        );
        assert_eq!(s.triplets.len(), 2);
        for t in &s.triplets {
            assert_eq!(t.kind, ConvergenceKind::Monotonic, "{t:?}");
            assert!((t.order.unwrap() - p).abs() < 1e-9, "p = {p}: {t:?}");
            assert!(rel(t.extrapolated.unwrap(), f0) < 1e-11, "p = {p}: {t:?}");
        }
        assert!((s.finest().r21 - 1.375).abs() < 1e-12);
    }
}

/// Strongly unequal ratios, where the plain fixed-point iteration does not
/// contract, still give the manufactured order (bisection fallback).
#[test]
fn manufactured_strongly_unequal_ratios() {
    for &(h, p) in &[
        ([1.0, 1.02, 8.0], 0.6),
        ([1.0, 6.0, 6.3], 1.4),
        ([1.0, 1.05, 40.0], 2.5),
        ([1.0, 30.0, 31.0], 0.3),
    ] {
        let f = |x: f64| 1.0 + 0.01 * x.powf(p);
        let t = three_grid_estimate(h, h.map(f)).unwrap();
        assert!((t.order.unwrap() - p).abs() < 1e-8, "h {h:?} p {p}: {t:?}");
        assert!(rel(t.extrapolated.unwrap(), 1.0) < 1e-10, "{t:?}");
    }
}

/// Celik et al. (2008) Table 1, first column: N = 18000, 8000, 4500 cells in
/// 2-D (h = N^(−1/2)), φ = 6.063, 5.972, 5.863 give p = 1.53,
/// φ_ext = 6.1685, e_a = 1.5 %, e_ext = 1.7 %, GCI_fine = 2.2 % at the
/// precision printed in the paper.
#[test]
fn celik_table_1_example() {
    let h = [18000.0f64, 8000.0, 4500.0].map(|n| n.powf(-0.5));
    let t = three_grid_estimate(h, [6.063, 5.972, 5.863]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Monotonic);
    assert!((t.r21 - 1.5).abs() < 1e-12 && (t.r32 - 4.0 / 3.0).abs() < 1e-12);
    assert_eq!(format!("{:.2}", t.order.unwrap()), "1.53");
    assert_eq!(format!("{:.4}", t.extrapolated.unwrap()), "6.1685");
    assert_eq!(format!("{:.1}", 100.0 * t.approx_rel_error.unwrap()), "1.5");
    assert_eq!(format!("{:.1}", 100.0 * t.extrap_rel_error.unwrap()), "1.7");
    assert_eq!(format!("{:.1}", 100.0 * t.gci_fine.unwrap()), "2.2");
}

/// Oscillatory, divergent, grid-independent and indeterminate series are
/// classified and carry no invented numbers (Celik et al. 2008, §"oscillatory
/// convergence"; SPEC §8 never a misleading result).
#[test]
fn classifies_non_monotone_series() {
    let h = [1e-3, 2e-3, 4e-3];

    let t = three_grid_estimate(h, [1.0, 1.1, 0.8]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Oscillatory);
    assert!((t.half_range - 0.15).abs() < 1e-12);
    if let Some(p) = t.order {
        assert!(p.is_finite() && p > 0.0);
        assert!(t.extrapolated.unwrap().is_finite() && t.gci_fine.unwrap().is_finite());
    }

    // Oscillation that grows under refinement: no positive order exists.
    let t = three_grid_estimate(h, [1.0, 1.4, 1.2]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Oscillatory);
    assert_eq!(
        (t.order, t.extrapolated, t.gci_fine),
        (None, None, None),
        "{t:?}"
    );

    // Differences grow as h shrinks: divergent, nothing extrapolated.
    let t = three_grid_estimate(h, [1.0, 1.5, 1.75]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Divergent);
    assert_eq!(
        (t.order, t.extrapolated, t.gci_fine, t.extrap_rel_error),
        (None, None, None, None)
    );
    assert!(t.approx_rel_error.is_some());

    let t = three_grid_estimate(h, [2.0, 2.0, 2.0]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::GridIndependent);
    assert_eq!((t.extrapolated, t.gci_fine), (Some(2.0), Some(0.0)));

    let t = three_grid_estimate(h, [1.0, 1.0, 1.2]).unwrap();
    assert_eq!(t.kind, ConvergenceKind::Indeterminate);
    assert_eq!((t.order, t.extrapolated, t.gci_fine), (None, None, None));
}

/// Per-grid rows: error against the finest-triplet extrapolation and the
/// GCI of each grid, with DOFs and wall time carried through.
#[test]
fn rows_of_a_four_grid_study() {
    let (f0, c, p) = (5.0, 2.0e3, 2.0);
    let f = |h: f64| f0 + c * h.powf(p);
    let h = [0.4e-3, 0.8e-3, 1.2e-3, 1.6e-3];
    let s = convergence_study("energy_J_per_m2", &grids(&h, f)).unwrap();
    let rows = s.rows();
    assert_eq!(rows.len(), 4);
    for (r, &hh) in rows.iter().zip(&h) {
        assert_eq!(r.h, hh);
        assert!(rel(r.rel_error_vs_extrapolated.unwrap(), rel(f(hh), f0)) < 1e-9);
        assert_eq!(r.wall_time, Some(1e-6 / (hh * hh)));
        assert!(r.dofs.is_some());
    }
    assert_eq!(rows[0].gci, s.triplets[0].gci_fine);
    assert_eq!(rows[1].gci, s.triplets[1].gci_fine);
    assert_eq!(rows[2].gci, s.triplets[1].gci_medium);
    assert_eq!(rows[3].gci, None);
    // GCI of the medium grid of the coarsest triplet: 1.25 e_a^32 / (r32^p − 1).
    let ea32 = rel(f(h[3]), f(h[2]));
    let r32: f64 = 1.6 / 1.2;
    assert!(rel(rows[2].gci.unwrap(), 1.25 * ea32 / (r32.powf(p) - 1.0)) < 1e-9);
}

/// Unusable series are refused with the quantity named.
#[test]
fn refuses_bad_series() {
    let ok = |h: f64, v: f64| GridResult {
        h,
        value: v,
        dofs: None,
        wall_time: None,
    };
    let cases = [
        vec![ok(1e-3, 1.0), ok(2e-3, 2.0)],
        vec![ok(1e-3, 1.0), ok(1e-3, 2.0), ok(2e-3, 3.0)],
        vec![ok(1e-3, 1.0), ok(2e-3, f64::NAN), ok(4e-3, 3.0)],
        vec![ok(-1e-3, 1.0), ok(2e-3, 2.0), ok(4e-3, 3.0)],
        vec![
            ok(1e-3, 1.0),
            ok(2e-3, 2.0),
            GridResult {
                wall_time: Some(-1.0),
                ..ok(4e-3, 3.0)
            },
        ],
    ];
    for grids in cases {
        let e = convergence_study("fed_at_peak_mm", &grids).unwrap_err();
        assert!(matches!(e, PostError::Convergence { .. }), "{e}");
        assert!(e.to_string().contains("fed_at_peak_mm"), "{e}");
    }
    assert!(three_grid_estimate([2e-3, 1e-3, 4e-3], [1.0, 2.0, 3.0]).is_err());
}
