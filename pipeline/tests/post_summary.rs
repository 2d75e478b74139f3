//! Reading `curve.csv` and the scalar summary of a σ_mb–FED curve
//! (SPEC §7 outputs; issue 6 "summary.json").

use pipeline::post::{
    curve_distance, energy_to_fed, parse_curve_csv, peak_bond_stress, read_curve_csv,
    residual_bond_stress, summarize, CurveAxis, CurveRow, PostError, SummaryOptions,
};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("post_summary")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Rows from (FED in mm, σ_mb in MPa) pairs.
fn rows_mm_mpa(points: &[(f64, f64)]) -> Vec<CurveRow> {
    points
        .iter()
        .enumerate()
        .map(|(i, &(fed, s))| {
            CurveRow::new(i + 1, 2.0 * fed * 1e-3, s * 1e3, fed * 1e-3, s * 1e6, 3)
        })
        .collect()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

/// A curve.csv with the documented header (plus an extra column) is read
/// back exactly; SPEC §7 "CSV curves".
#[test]
fn reads_curve_csv_with_extra_columns() {
    let dir = scratch("read");
    let path = dir.join("curve.csv");
    std::fs::write(
        &path,
        "step,u_imposed,force,fed,bond_stress,iterations,wall_s\n\
         1,1e-5,120.5,2.5e-6,1.25e6,4,0.1\n\
         \n\
         2,2e-5,240.25,5e-6,2.5e6,5,0.2\n",
    )
    .unwrap();
    let rows = read_curve_csv(&path).unwrap();
    assert_eq!(
        rows,
        vec![
            CurveRow::new(1, 1e-5, 120.5, 2.5e-6, 1.25e6, 4),
            CurveRow::new(2, 2e-5, 240.25, 5e-6, 2.5e6, 5)
        ]
    );
}

/// Columns are found by name, not position.
#[test]
fn reads_columns_by_name() {
    let text = "fed,step,bond_stress,force,iterations,u_imposed\n1e-4,7,3e6,10,2,2e-4\n";
    let rows = parse_curve_csv(text, Path::new("x.csv")).unwrap();
    assert_eq!(rows, vec![CurveRow::new(7, 2e-4, 10.0, 1e-4, 3e6, 2)]);
}

/// Bad input is refused with the file and line named (SPEC §8 bad input).
#[test]
fn csv_errors_name_file_and_line() {
    let p = Path::new("runs/a/curve.csv");
    let header = "step,u_imposed,force,fed,bond_stress,iterations\n";

    let e = parse_curve_csv(&format!("{header}1,0,0,0,0,1\n2,0,0,abc,0,1\n"), p).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            PostError::BadValue {
                line: 3,
                column: "fed",
                ..
            }
        ),
        "{msg}"
    );
    assert!(
        msg.contains("runs/a/curve.csv:3") && msg.contains("abc"),
        "{msg}"
    );

    let e = parse_curve_csv(&format!("{header}1,0,0,NaN,0,1\n"), p).unwrap_err();
    assert!(matches!(e, PostError::BadValue { line: 2, .. }), "{e}");

    let e = parse_curve_csv(&format!("{header}1,0,0,0,0\n"), p).unwrap_err();
    assert!(
        matches!(
            e,
            PostError::FieldCount {
                line: 2,
                expected: 6,
                found: 5,
                ..
            }
        ),
        "{e}"
    );

    let e = parse_curve_csv("step,u_imposed,force,bond_stress,iterations\n", p).unwrap_err();
    assert!(
        matches!(e, PostError::MissingColumn { column: "fed", .. }),
        "{e}"
    );

    let e = parse_curve_csv(header, p).unwrap_err();
    assert!(matches!(e, PostError::EmptyCsv { .. }), "{e}");

    let e = parse_curve_csv(&format!("{header}-1,0,0,0,0,1\n"), p).unwrap_err();
    assert!(
        matches!(e, PostError::BadValue { column: "step", .. }),
        "{e}"
    );

    let e = read_curve_csv(Path::new("/nonexistent/curve.csv")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/curve.csv"), "{e}");
}

/// Peak, energy (trapezoid from the unloaded state, interpolated at the
/// limit) and residual (FED-weighted tail mean) on a polyline whose answers
/// are known by hand; issue 6 summary quantities.
#[test]
fn summary_of_polyline_by_hand() {
    // FED mm, σ MPa.
    let rows = rows_mm_mpa(&[(0.5, 5.0), (1.0, 10.0), (2.0, 4.0), (3.0, 4.0)]);
    let (peak, fed, step) = peak_bond_stress(&rows).unwrap();
    assert_eq!((peak, fed, step), (10e6, 1e-3, 2));
    // 0→0.5: 1250; 0.5→1: 3750; 1→1.5 (σ(1.5) = 7 MPa): 4250 J/m².
    assert!(close(energy_to_fed(&rows, 1.5e-3).unwrap(), 9250.0, 1e-12));
    // The whole curve: 1250 + 3750 + 7000 + 4000.
    assert!(close(energy_to_fed(&rows, 3e-3).unwrap(), 16000.0, 1e-12));
    // Window [2, 3] mm: constant 4 MPa.
    assert!(close(
        residual_bond_stress(&rows, 1.0 / 3.0).unwrap(),
        4e6,
        1e-12
    ));
    // Window [1.5, 3] mm: (2.75 + 4) MPa·mm / 1.5 mm = 4.5 MPa.
    assert!(close(
        residual_bond_stress(&rows, 0.5).unwrap(),
        4.5e6,
        1e-12
    ));

    let s = summarize(
        &rows,
        &SummaryOptions {
            energy_fed_limit: Some(1.5e-3),
            residual_fraction: 0.5,
        },
    )
    .unwrap();
    assert_eq!(s.peak_bond_stress, 10e6);
    assert_eq!(s.fed_at_peak, 1e-3);
    assert!(close(s.energy.unwrap(), 9250.0, 1e-12));
    assert!(close(s.residual_bond_stress.unwrap(), 4.5e6, 1e-12));
    assert_eq!(s.final_fed, 3e-3);
    assert_eq!(s.steps, 4);
    assert_eq!(s.total_iterations, 12);
}

/// The energy of a smooth, non-uniformly sampled analytic curve
/// σ = A (s/s0) e^(1 − s/s0) matches its closed-form integral
/// A s0 e (1 − (1 + S/s0) e^(−S/s0)) to trapezoidal accuracy.
#[test]
fn energy_of_analytic_curve() {
    let a = 8e6; // Pa
    let s0 = 0.4e-3; // m
    let n = 4000;
    let end = 3e-3;
    let rows: Vec<CurveRow> = (1..=n)
        .map(|i| {
            // Denser near the start, where the curve bends most.
            let t = i as f64 / n as f64;
            let s = end * t * t;
            let sigma = a * (s / s0) * (1.0 - s / s0).exp();
            CurveRow::new(i, s, 0.0, s, sigma, 1)
        })
        .collect();
    let (peak, fed, _) = peak_bond_stress(&rows).unwrap();
    assert!(close(peak, a, 1e-5), "peak {peak}");
    assert!((fed - s0).abs() < 2e-6, "FED at peak {fed}");
    for limit in [0.25e-3, 1e-3, 2.2e-3] {
        let exact = a * s0 * std::f64::consts::E * (1.0 - (1.0 + limit / s0) * (-limit / s0).exp());
        let got = energy_to_fed(&rows, limit).unwrap();
        assert!(close(got, exact, 1e-5), "limit {limit}: {got} vs {exact}");
    }
}

/// The residual stress is a mean over FED, not over samples: a linear tail
/// sampled far more densely at one end still gives its mid-window value.
#[test]
fn residual_is_fed_weighted() {
    // Tail from 2 to 4 mm: σ = 6 − (s − 2) MPa, samples crowded near 2 mm.
    let mut pts = vec![(1.0, 8.0), (2.0, 6.0)];
    for k in 1..=50 {
        let s = 2.0 + 0.002 * k as f64;
        pts.push((s, 6.0 - (s - 2.0)));
    }
    pts.push((4.0, 4.0));
    let rows = rows_mm_mpa(&pts);
    // Window [2, 4] mm: mean of a linear function = value at 3 mm = 5 MPa.
    let r = residual_bond_stress(&rows, 0.5).unwrap();
    assert!(close(r, 5e6, 1e-12), "{r}");
}

/// A curve whose FED snaps back stays within σ_mb's range: the window is
/// the tail since the curve last entered it, from above as well as from
/// below. A brittle split that drops the FED to near zero in one step has
/// no window length left, and the last σ_mb is the residual (before, the
/// whole curve's area over a window of 3e-10 m: 6.8e11 Pa on such a run).
#[test]
fn residual_of_a_curve_whose_fed_snaps_back() {
    // Rises to 24 MPa at FED 0.058 mm, splits: FED 1.5e-6 mm, σ 0.27 kPa.
    let split = rows_mm_mpa(&[(0.02, 10.0), (0.058, 24.0), (1.5e-6, 2.7e-4)]);
    let r = residual_bond_stress(&split, 0.2).unwrap();
    assert!(close(r, 270.0, 1e-12), "{r}");
    // Past 4 mm the FED falls back to 3 and rises to 3.5 mm, σ 2 → 1 MPa
    // linearly on the way back and 1 MPa after: window [2.8, 3.5] mm, the
    // part of the way back from 3.5 to 3 mm and the rise to 3.5 mm.
    let back = rows_mm_mpa(&[(2.0, 4.0), (4.0, 2.0), (3.0, 1.0), (3.5, 1.0)]);
    let r = residual_bond_stress(&back, 0.2).unwrap();
    // From 3.5 down to 3 mm: σ from 1.5 to 1 MPa (mean 1.25) over 0.5 mm;
    // then 1 MPa over 0.5 mm.
    assert!(close(r, 1.125e6, 1e-12), "{r}");
    for rows in [&split, &back] {
        let lo = rows
            .iter()
            .map(|r| r.bond_stress)
            .fold(f64::INFINITY, f64::min);
        let hi = rows.iter().map(|r| r.bond_stress).fold(0.0, f64::max);
        let r = residual_bond_stress(rows, 0.5).unwrap();
        assert!((lo..=hi).contains(&r), "{r} outside [{lo}, {hi}]");
    }
}

/// An energy limit past the end of the curve is reported, not extrapolated;
/// invalid options are refused.
#[test]
fn summary_limits_and_bad_options() {
    let rows = rows_mm_mpa(&[(0.2, 3.0), (0.6, 2.0)]);
    let e = energy_to_fed(&rows, 1e-3).unwrap_err();
    assert!(matches!(e, PostError::FedLimitBeyondCurve { .. }), "{e}");
    let s = summarize(
        &rows,
        &SummaryOptions {
            energy_fed_limit: Some(1e-3),
            residual_fraction: 0.2,
        },
    )
    .unwrap();
    assert_eq!(s.energy, None);
    assert_eq!(s.energy_fed_limit, 1e-3);
    let whole = summarize(
        &rows,
        &SummaryOptions {
            energy_fed_limit: None,
            residual_fraction: 0.2,
        },
    )
    .unwrap();
    // 0.5·0.2·3 + 0.5·(3 + 2)·0.4 = 1.3 MPa·mm = 1300 J/m².
    assert!(close(whole.energy.unwrap(), 1300.0, 1e-12));

    assert!(residual_bond_stress(&rows, 0.0).is_err());
    assert!(residual_bond_stress(&rows, 1.5).is_err());
    assert!(energy_to_fed(&rows, -1e-3).is_err());
    assert!(summarize(&[], &SummaryOptions::default()).is_err());
    let stuck = rows_mm_mpa(&[(0.0, 1.0)]);
    assert!(residual_bond_stress(&stuck, 0.2).is_err());
    // A run cut short before slip still has a summary, without the
    // quantities it cannot define.
    let s = summarize(
        &stuck,
        &SummaryOptions {
            energy_fed_limit: None,
            residual_fraction: 0.2,
        },
    )
    .unwrap();
    assert_eq!(
        (s.peak_bond_stress, s.energy, s.residual_bond_stress),
        (1e6, None, None)
    );
    let bad = SummaryOptions {
        energy_fed_limit: Some(0.0),
        residual_fraction: 0.2,
    };
    assert!(summarize(&rows, &bad).is_err());
    let bad = SummaryOptions {
        energy_fed_limit: None,
        residual_fraction: 0.0,
    };
    assert!(summarize(&rows, &bad).is_err());
}

/// Table entries carry their unit in the name and are converted to it.
#[test]
fn table_entries_are_in_named_units() {
    let rows = rows_mm_mpa(&[(0.5, 5.0), (1.0, 10.0), (2.0, 4.0)]);
    let s = summarize(&rows, &SummaryOptions::default()).unwrap();
    let e = s.table_entries();
    let get = |k: &str| {
        e.iter()
            .find(|(n, _)| n == k)
            .unwrap_or_else(|| panic!("{k} in {e:?}"))
            .1
            .clone()
    };
    assert_eq!(get("peak_bond_stress_MPa"), pipeline::post::Cell::Num(10.0));
    assert_eq!(get("fed_at_peak_mm"), pipeline::post::Cell::Num(1.0));
    assert_eq!(
        get("energy_to_1mm_J_per_m2"),
        pipeline::post::Cell::Num(5000.0)
    );
}

/// Rows with the same value as abscissa for both axes: (x in m, σ in Pa).
fn rows_xy(points: &[(f64, f64)]) -> Vec<CurveRow> {
    points
        .iter()
        .enumerate()
        .map(|(i, &(x, s))| CurveRow::new(i + 1, x, 0.0, x, s, 1))
        .collect()
}

/// The relative L2 curve distance is exact for polylines whatever their
/// sampling: a curve scaled by 1.1 is 0.1 away, and a ramp against a ramp
/// that levels off at half-way is √(1/8) away (SPEC §7 "curve distance").
#[test]
fn curve_distance_closed_forms() {
    let reference = rows_xy(&[(0.13, 0.13e6), (0.5, 0.5e6), (0.71, 0.71e6), (1.0, 1.0e6)]);
    let scaled = rows_xy(&[(0.2, 0.22e6), (0.9, 0.99e6), (1.0, 1.1e6), (1.4, 1.54e6)]);
    let d = curve_distance(&scaled, &reference, CurveAxis::Fed, None).unwrap();
    assert!((d - 0.1).abs() < 1e-12, "{d}");

    let levelled = rows_xy(&[(0.25, 0.25e6), (0.5, 0.5e6), (0.8, 0.5e6), (1.0, 0.5e6)]);
    let d = curve_distance(&levelled, &reference, CurveAxis::ImposedDisplacement, None).unwrap();
    assert!((d - (1.0f64 / 8.0).sqrt()).abs() < 1e-12, "{d}");
    // Restricted to where the two agree: zero.
    let d = curve_distance(&levelled, &reference, CurveAxis::Fed, Some(0.5)).unwrap();
    assert!(d.abs() < 1e-12, "{d}");
}

/// Along FED the pre-slip branch (free end not yet moving) does not count;
/// along the imposed displacement it does.
#[test]
fn curve_distance_axes_differ_on_pre_slip() {
    let row = |i: usize, u: f64, fed: f64, s: f64| CurveRow::new(i, u, 0.0, fed, s, 1);
    let a = vec![
        row(1, 1.0, 0.0, 5e6),
        row(2, 2.0, 0.0, 8e6),
        row(3, 3.0, 1.0, 8e6),
        row(4, 4.0, 2.0, 6e6),
    ];
    let b = vec![
        row(1, 1.0, 0.0, 4e6),
        row(2, 2.0, 0.0, 8e6),
        row(3, 3.0, 1.0, 8e6),
        row(4, 4.0, 2.0, 6e6),
    ];
    assert!(curve_distance(&a, &b, CurveAxis::Fed, None).unwrap() < 1e-12);
    assert!(curve_distance(&a, &b, CurveAxis::ImposedDisplacement, None).unwrap() > 1e-3);
}

/// A step back of the abscissa within `FOLDED_RECESSION_SHARE` of the range
/// (the nanometres a free end comes back by in some steps) is folded into
/// a vertical jump of σ, so the distance
/// is continuous across it: the same, to the fold's share, as with the
/// step moved as far forward. A deeper step back is refused, and so are
/// small ones that add up past the share.
#[test]
fn curve_distance_folds_steps_back_of_a_few_nanometres() {
    use pipeline::post::FOLDED_RECESSION_SHARE;
    let reference = rows_xy(&[(0.3e-3, 1e6), (0.6e-3, 2e6), (1.0e-3, 2.5e6)]);
    let test = |back: f64| {
        rows_xy(&[
            (0.3e-3, 1.1e6),
            (0.3e-3 - back, 0.9e6),
            (0.6e-3, 2.2e6),
            (1.0e-3, 2.75e6),
        ])
    };
    let small = 0.5 * FOLDED_RECESSION_SHARE * 1.0e-3;
    let folded = curve_distance(&test(small), &reference, CurveAxis::Fed, None).unwrap();
    let forward = curve_distance(&test(-small), &reference, CurveAxis::Fed, None).unwrap();
    assert!(
        (folded / forward - 1.0).abs() < FOLDED_RECESSION_SHARE,
        "{folded} against {forward}"
    );
    let deep = 2.0 * FOLDED_RECESSION_SHARE * 1.0e-3;
    let e = curve_distance(&test(deep), &reference, CurveAxis::Fed, None).unwrap_err();
    assert!(
        e.to_string().contains("step 2") && e.to_string().contains("goes back"),
        "{e}"
    );
    let back = 0.8 * FOLDED_RECESSION_SHARE * 1.0e-3;
    let twice = rows_xy(&[
        (0.3e-3, 1.1e6),
        (0.3e-3 - back, 1.05e6),
        (0.6e-3, 2.2e6),
        (0.6e-3 - back, 2.1e6),
        (1.0e-3, 2.75e6),
    ]);
    let e = curve_distance(&twice, &reference, CurveAxis::Fed, None).unwrap_err();
    assert!(e.to_string().contains("step 4"), "{e}");
}

/// Curves the distance cannot be defined for are refused.
#[test]
fn curve_distance_refuses() {
    let good = rows_xy(&[(0.5, 1e6), (1.0, 2e6)]);
    let back = rows_xy(&[(0.5, 1e6), (0.3, 2e6), (1.0, 2e6)]);
    let e = curve_distance(&back, &good, CurveAxis::Fed, None).unwrap_err();
    assert!(e.to_string().contains("step 2"), "{e}");
    assert!(curve_distance(&[], &good, CurveAxis::Fed, None).is_err());
    let stuck = rows_xy(&[(0.0, 1e6)]);
    assert!(curve_distance(&good, &stuck, CurveAxis::Fed, None).is_err());
    assert!(curve_distance(&good, &good, CurveAxis::Fed, Some(-1.0)).is_err());
}

/// A frictional branch that rises above the adhesion peak (ribbed bars)
/// does not hide the first peak: it is the running maximum before the
/// first drop of more than 5 %.
#[test]
fn first_peak_is_the_adhesion_peak() {
    use pipeline::post::first_peak_bond_stress;
    let pts = [
        (1e-5, 4e6),
        (3e-5, 5.7e6),
        (1e-4, 4e6),
        (3e-4, 2.7e6),
        (1e-3, 5.9e6),
    ];
    let rows: Vec<CurveRow> = pts
        .iter()
        .enumerate()
        .map(|(i, &(fed, s))| CurveRow::new(i + 1, fed, 0.0, fed, s, 1))
        .collect();
    let (first, fed, step) = first_peak_bond_stress(&rows).unwrap();
    assert_eq!((first, fed, step), (5.7e6, 3e-5, 2));
    let s = summarize(&rows, &SummaryOptions::default()).unwrap();
    assert_eq!(s.peak_bond_stress, 5.9e6);
    assert_eq!(s.first_peak_bond_stress, 5.7e6);
    // Without a drop, the first peak is the overall peak.
    let rising: Vec<CurveRow> = rows.iter().take(2).copied().collect();
    assert_eq!(first_peak_bond_stress(&rising).unwrap().0, 5.7e6);
}
