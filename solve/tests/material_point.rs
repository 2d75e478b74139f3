//! Material-point verification of the laws of SPEC §5, driven by the shipped
//! test files in `specs/material/` (the `material` subcommand's input).

use solve::laws::j2::von_mises;
use solve::problems::material_point::{
    run, run_file, MaterialPointError, MaterialTest, PointTable,
};
use std::path::PathBuf;

fn case_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../specs/material")
        .join(name)
}

fn case(name: &str) -> PointTable {
    run_file(&case_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn read_case(name: &str) -> MaterialTest {
    serde_yaml::from_str(&std::fs::read_to_string(case_path(name)).unwrap()).unwrap()
}

fn col(t: &PointTable, name: &str) -> Vec<f64> {
    t.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Trapezoidal ∫ y dx.
fn area(x: &[f64], y: &[f64]) -> f64 {
    x.windows(2)
        .zip(y.windows(2))
        .map(|(x, y)| 0.5 * (y[0] + y[1]) * (x[1] - x[0]))
        .sum()
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

/// The same test run with the Tvergaard law (the FCZM-only parameters dropped).
fn as_tvergaard(mut test: MaterialTest) -> MaterialTest {
    test.law = "tvergaard".into();
    test.parameters.mu = None;
    test.parameters.zeta = None;
    test.parameters.gamma = None;
    test
}

/// Asserts two tables agree on the named columns within `rel` of the largest magnitude.
fn assert_same(a: &PointTable, b: &PointTable, cols: &[&str], rel: f64) {
    for c in cols {
        let (x, y) = (col(a, c), col(b, c));
        assert_eq!(x.len(), y.len());
        let scale = x.iter().fold(1e-30f64, |m, v| m.max(v.abs()));
        let worst = x
            .iter()
            .zip(&y)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= rel * scale,
            "column {c}: max difference {worst:e} vs scale {scale:e}"
        );
    }
}

macro_rules! fczm_is_tvergaard {
    ($name:ident, $file:literal, $doc:literal) => {
        #[doc = $doc]
        #[test]
        fn $name() {
            let test = read_case($file);
            let f = run(&test).unwrap();
            let t = run(&as_tvergaard(test)).unwrap();
            assert_same(&f, &t, &["tn", "tt", "th", "D"], 1e-9);
        }
    };
}

fczm_is_tvergaard!(
    fczm_pure_tension_is_tvergaard,
    "fczm-tension.yaml",
    "In pure tension the FCZM reproduces Tvergaard's law exactly (paper §3.2, Fig. 9a; SPEC §5)."
);
fczm_is_tvergaard!(
    fczm_pure_compression_is_tvergaard,
    "fczm-compression.yaml",
    "In pure compression the FCZM reproduces Tvergaard's law exactly (paper §3.2, Fig. 9a; SPEC §5)."
);
fczm_is_tvergaard!(
    fczm_pure_shear_is_tvergaard,
    "fczm-shear.yaml",
    "In pure shear the FCZM reproduces Tvergaard's law exactly (paper §3.2, Fig. 9b; SPEC §5)."
);
fczm_is_tvergaard!(
    fczm_shear_with_initial_tension_is_tvergaard,
    "fczm-shear-tension.yaml",
    "In shear with initial tension the FCZM reproduces Tvergaard's law exactly (paper §3.2, Fig. 9b; SPEC §5)."
);

const COMPRESSIONS: [(f64, &str); 5] = [
    (0.5e6, "fczm-shear-compression-0.5MPa.yaml"),
    (3e6, "fczm-shear-compression-3MPa.yaml"),
    (5e6, "fczm-shear-compression-5MPa.yaml"),
    (10e6, "fczm-shear-compression-10MPa.yaml"),
    (20e6, "fczm-shear-compression-20MPa.yaml"),
];

/// Under initial compression the FCZM shear peak exceeds f_t and grows with |σ_N| (paper §3.2, Fig. 9b–c; SPEC §5).
#[test]
fn fczm_compression_raises_the_shear_peak() {
    let ft = 3e6;
    let mut last = ft;
    for (sn, file) in COMPRESSIONS {
        let peak = max(&col(&case(file), "tt"));
        assert!(
            peak > last,
            "sigma_N = -{sn} Pa: peak {peak} Pa not above {last} Pa"
        );
        last = peak;
    }
}

/// The residual shear stress under held compression equals μ|σ_N| within 0.5 % (paper §3.2; SPEC §5).
#[test]
fn fczm_residual_shear_is_friction() {
    for (sn, file) in COMPRESSIONS.iter().skip(1) {
        let tt = col(&case(file), "tt");
        let residual = *tt.last().unwrap();
        let expected = 0.4 * sn;
        assert!(
            (residual - expected).abs() <= 0.005 * expected,
            "sigma_N = -{sn}: residual {residual} vs mu |sigma_N| = {expected}"
        );
    }
}

/// At σ_N = −20 MPa the FCZM shear peak equals the residual μ|σ_N| (Coulomb-like), within 0.5 % (paper §3.2, Fig. 9c; SPEC §5).
#[test]
fn fczm_high_compression_peak_is_residual() {
    let tt = col(&case("fczm-shear-compression-20MPa.yaml"), "tt");
    let (peak, expected) = (max(&tt), 0.4 * 20e6);
    assert!(
        (peak - expected).abs() <= 0.005 * expected,
        "peak {peak} vs {expected}"
    );
}

/// In pure tension the area under σ_n(u_n) is f_t λ_0/2 + ζ G_f within 0.5 % (eqs. 22–25, A.6–A.10; SPEC §5).
#[test]
fn fczm_tension_energy() {
    let t = case("fczm-tension.yaml");
    let a = area(&col(&t, "un"), &col(&t, "tn"));
    let expected = 3e6 * 2e-5 / 2.0 + 1.0 * 300.0;
    assert!(
        (a - expected).abs() <= 0.005 * expected,
        "area {a} N/m vs {expected} N/m"
    );
}

/// With ζ = 8 the tension area grows to f_t λ_0/2 + ζ G_f (eq. 22; SPEC §5).
#[test]
fn fczm_tension_energy_scales_with_zeta() {
    let mut test = read_case("fczm-tension.yaml");
    test.parameters.zeta = Some(8.0.into());
    test.path[2].un = Some(6e-3.into());
    test.increments = 4000;
    let t = run(&test).unwrap();
    let a = area(&col(&t, "un"), &col(&t, "tn"));
    let expected = 3e6 * 2e-5 / 2.0 + 8.0 * 300.0;
    assert!(
        (a - expected).abs() <= 0.005 * expected,
        "area {a} N/m vs {expected} N/m"
    );
}

/// Tvergaard's normal response (App. A, Fig. A.1a) is linear K_n in compression, peaks at f_t and dissipates f_t λ_0/2 + G_f (A.5–A.10).
#[test]
fn tvergaard_appendix_a_normal() {
    let t = case("tvergaard-appA-normal.yaml");
    let (un, tn) = (col(&t, "un"), col(&t, "tn"));
    let kn = 3e6 / 1e-5;
    for (u, s) in un.iter().zip(&tn) {
        if *u < 0.0 {
            assert!((s - kn * u).abs() <= 1e-9 * kn * u.abs());
        }
    }
    assert!((max(&tn) - 3e6).abs() < 1e-6 * 3e6);
    let start = un
        .iter()
        .position(|&u| u == 0.0 && tn.iter().any(|_| true))
        .unwrap();
    let a = area(&un[start..], &tn[start..]);
    let expected = 3e6 * 1e-5 / 2.0 + 200.0;
    assert!(
        (a - expected).abs() <= 0.005 * expected,
        "area {a} vs {expected}"
    );
}

/// Tvergaard's shear peak drops as the imposed initial opening grows (App. A, Fig. A.1b).
#[test]
fn tvergaard_appendix_a_shear_peak_drops_with_opening() {
    let peaks: Vec<f64> = (0..5)
        .map(|i| max(&col(&case(&format!("tvergaard-appA-shear-{i}.yaml")), "tt")))
        .collect();
    assert!(
        (peaks[0] - 3e6).abs() < 1e-6 * 3e6,
        "pure shear peak {}",
        peaks[0]
    );
    assert!(peaks.windows(2).all(|w| w[1] < w[0]), "{peaks:?}");
}

/// The Coulomb interface is linear in compression and separates at f_t in tension (App. B, Fig. B.2a).
#[test]
fn coulomb_appendix_b_normal() {
    let t = case("coulomb-appB-normal.yaml");
    let (un, tn) = (col(&t, "un"), col(&t, "tn"));
    for (u, s) in un.iter().zip(&tn) {
        if *u <= 3e-5 {
            assert!((s - 1e11 * u).abs() <= 1e-6, "u = {u}: {s}");
        } else {
            assert_eq!(*s, 0.0, "u = {u}: separated interface carries {s}");
        }
    }
}

/// Coulomb shear: linear K_s up to C + |σ_n| tan φ, then constant; residual = peak (App. B, eqs. B.1–B.2, Fig. B.2b).
#[test]
fn coulomb_appendix_b_shear() {
    let t = case("coulomb-appB-shear.yaml");
    let tt = col(&t, "tt");
    let limit = 3e6 + 5e6 * (45f64).to_radians().tan();
    assert!((max(&tt) - limit).abs() <= 1e-6 * limit);
    assert!((tt.last().unwrap() - limit).abs() <= 1e-6 * limit);
    let ut = col(&t, "ut");
    for (u, s) in ut.iter().zip(&tt) {
        assert!((s - (1e11 * u).min(limit)).abs() <= 1e-6 * limit);
    }
}

/// Regularised Mazars dissipates G_f per unit area, l ∫σ dε = G_f within 1 %, for l = 1 and 5 mm (eqs. 9–10, Fig. 4b; SPEC §5).
#[test]
fn mazars_tension_energy_is_gf_for_any_size() {
    for (l, file) in [
        (1e-3, "mazars-tension-l1mm.yaml"),
        (5e-3, "mazars-tension-l5mm.yaml"),
    ] {
        let t = case(file);
        let w = l * area(&col(&t, "exx"), &col(&t, "sxx"));
        assert!((w - 80.0).abs() <= 0.01 * 80.0, "l = {l}: {w} N/m");
        // Uniaxial stress held, and the peak is f_t.
        assert!(col(&t, "syy").iter().all(|s| s.abs() < 1e-3 * 3e6));
        assert!((max(&col(&t, "sxx")) - 3e6).abs() < 0.01 * 3e6);
    }
}

/// Mazars compression curves with Table 1's A_c, B_c nearly coincide in stress–displacement: within 5 % of the l = 1 mm curve's peak past the elastic branches (whose slope E/l depends on l by nature, δ < 2 µm here) (Table 1, Fig. 5b; SPEC §5).
#[test]
fn mazars_compression_curves_coincide_in_displacement() {
    let curve = |l_mm: f64, file: &str| -> (Vec<f64>, Vec<f64>) {
        let t = case(file);
        let d = col(&t, "exx").iter().map(|e| -e * l_mm * 1e-3).collect();
        let s = col(&t, "sxx").iter().map(|s| -s).collect();
        (d, s)
    };
    let (d_ref, s_ref) = curve(1.0, "mazars-compression-l1mm.yaml");
    let peak = max(&s_ref);
    for (l, file) in [
        (0.2, "mazars-compression-l0.2mm.yaml"),
        (2.0, "mazars-compression-l2mm.yaml"),
        (3.0, "mazars-compression-l3mm.yaml"),
        (5.0, "mazars-compression-l5mm.yaml"),
    ] {
        let (d, s) = curve(l, file);
        let mut worst: f64 = 0.0;
        for (x, y) in d_ref.iter().zip(&s_ref).filter(|(x, _)| **x >= 1e-5) {
            let k = d.partition_point(|v| v < x).clamp(1, d.len() - 1);
            let yi = s[k - 1] + (s[k] - s[k - 1]) * (x - d[k - 1]) / (d[k] - d[k - 1]);
            worst = worst.max((yi - y).abs());
        }
        assert!(
            worst <= 0.05 * peak,
            "l = {l} mm: max deviation {worst} Pa vs peak {peak} Pa"
        );
    }
}

/// Mazars with eqs. (12)–(13) from l (SPEC §5 sign reading) stays within 5 % of Table 1's curves too.
#[test]
fn mazars_compression_fit_matches_table_1() {
    for (l, ac, bc) in [
        (1e-3, 0.0169, 29.6),
        (2e-3, 0.0343, 60.3),
        (3e-3, 0.0517, 90.0),
        (5e-3, 0.09, 152.0),
    ] {
        let (a, b) = solve::laws::mazars::compression_fit(l);
        assert!((a - ac).abs() <= 0.03 * ac, "A_c({l}) = {a} vs {ac}");
        assert!((b - bc).abs() <= 0.03 * bc, "B_c({l}) = {b} vs {bc}");
    }
}

/// J2 steel: the stress stays on the yield surface while yielding and unloads elastically (paper §2.3; SPEC §5).
#[test]
fn j2_uniaxial_cycle() {
    let t = case("j2-uniaxial-cycle.yaml");
    let sy = 365e6;
    let n = t.rows.len();
    let stress: Vec<nalgebra::Vector6<f64>> = (0..n)
        .map(|i| {
            nalgebra::Vector6::from_iterator(
                ["sxx", "syy", "szz", "sxy", "syz", "sxz"]
                    .iter()
                    .map(|c| col(&t, c)[i]),
            )
        })
        .collect();
    let ep = col(&t, "epxx");
    for i in 1..n {
        let vm = von_mises(&stress[i]);
        assert!(vm <= sy * (1.0 + 1e-9), "row {i}: von Mises {vm}");
        if ep[i] != ep[i - 1] {
            assert!(
                (vm - sy).abs() <= 1e-9 * sy,
                "row {i}: yielding off the surface, {vm}"
            );
        }
    }
    let sxx = col(&t, "sxx");
    assert!((max(&sxx) - sy).abs() < 1e-6 * sy);
    assert!((sxx.iter().copied().fold(f64::INFINITY, f64::min) + sy).abs() < 1e-6 * sy);
}

/// J2 in simple shear yields at τ = σ_y/√3 (von Mises; paper §2.3).
#[test]
fn j2_shear_yield() {
    let t = case("j2-shear.yaml");
    let sxy = col(&t, "sxy");
    assert!((sxy.last().unwrap() - 365e6 / 3f64.sqrt()).abs() < 1e-6 * 365e6);
}

/// Damage never decreases along any shipped material-point path (SPEC §5).
#[test]
fn damage_never_decreases_in_shipped_cases() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../specs/material");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "yaml") {
            let t = run_file(&path).unwrap_or_else(|e| panic!("{e}"));
            let d = col(&t, "D");
            assert!(d.windows(2).all(|w| w[1] >= w[0]), "{}", path.display());
            assert!(
                t.rows.iter().flatten().all(|v| v.is_finite()),
                "{}",
                path.display()
            );
            n += 1;
        }
    }
    assert!(n >= 20, "only {n} shipped cases");
}

/// FCZM unloading is secant toward the origin and reloading rejoins the monotonic envelope (A.6, SPEC §5 reading of λ).
#[test]
fn fczm_unload_reload_is_secant() {
    let t = case("fczm-unload-reload.yaml");
    let (tm, un, tn) = (col(&t, "t"), col(&t, "un"), col(&t, "tn"));
    let i_max = tm.iter().position(|&x| x == 1.0).unwrap();
    let secant = tn[i_max] / un[i_max];
    for i in 0..tm.len() {
        let reloading_below = tm[i] > 3.0 && un[i] > 0.0 && un[i] <= un[i_max];
        if (tm[i] > 1.0 && tm[i] <= 2.0) || reloading_below {
            assert!(
                (tn[i] - secant * un[i]).abs() <= 1e-9 * tn[i_max],
                "t = {}",
                tm[i]
            );
        }
        if tm[i] > 2.0 && tm[i] <= 3.0 {
            // Closed in compression: (1 − D)σ_un = K_n u_n (eq. 25) plus the damaged part D K_n u_n (eqs. 15–17).
            let d = col(&t, "D")[i];
            let expected = (1.0 + d) * 1.5e11 * un[i];
            assert!(
                (tn[i] - expected).abs() <= 1e-9 * expected.abs(),
                "compression t = {}",
                tm[i]
            );
        }
    }
    // Past the previous maximum the response is the monotonic one.
    let mono = case("fczm-tension.yaml");
    let (mu, mt) = (col(&mono, "un"), col(&mono, "tn"));
    let (u_end, t_end) = (*un.last().unwrap(), *tn.last().unwrap());
    let k = mu.partition_point(|v| *v < u_end).min(mu.len() - 1);
    let interp = mt[k - 1] + (mt[k] - mt[k - 1]) * (u_end - mu[k - 1]) / (mu[k] - mu[k - 1]);
    assert!((t_end - interp).abs() <= 1e-4 * 3e6, "{t_end} vs {interp}");
}

/// Mazars unloading is secant ((1 − D)C), compression after tension is undamaged-stiff only through D, and reloading rejoins the envelope (eq. 1, SPEC §5).
#[test]
fn mazars_unload_reload() {
    let t = case("mazars-tension-unload-reload.yaml");
    let (tm, e, s, d) = (col(&t, "t"), col(&t, "exx"), col(&t, "sxx"), col(&t, "D"));
    let i_max = tm.iter().position(|&x| x == 1.0).unwrap();
    let secant = s[i_max] / e[i_max];
    for i in 0..tm.len() {
        let unloading = tm[i] > 1.0 && tm[i] <= 3.0;
        let reloading_below = tm[i] > 3.0 && e[i] <= e[i_max];
        if unloading || reloading_below {
            assert!(
                (s[i] - secant * e[i]).abs() <= 1e-6 * s[i_max],
                "t = {}",
                tm[i]
            );
            assert_eq!(d[i], d[i_max]);
        }
    }
    assert!(*d.last().unwrap() > d[i_max]);
}

/// Errors in a test file name the file, the key and the problem (SPEC §8).
#[test]
fn bad_test_files_name_file_and_key() {
    let dir = std::env::temp_dir().join(format!("ribbar-mp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        ("law: fczm\nparameters: {ft: 3e6, Gf: 300, delta_s: 1, mu: -1}\npath: [{t: 0}, {t: 1, un: 1e-5}]\n", "parameters.mu"),
        ("law: fczm\nparameters: {ft: 3e6, Gf: 300, sigma_y: 1}\npath: [{t: 0}, {t: 1}]\n", "parameters.sigma_y"),
        ("law: fczm\nparameters: {ft: \"3 mm\", Gf: 300}\npath: [{t: 0}, {t: 1}]\n", "parameters.ft"),
        ("law: fczm\nparameters: {ft: 3e6, Gf: 300, delta_s: 1}\npath: [{t: 0}, {t: 0, un: 1e-5}]\n", "path[1].t"),
        ("law: fczm\nparameters: {ft: 3e6, Gf: 300, delta_s: 1}\npath: [{t: 0}, {t: 1, exx: 1e-5}]\n", "path[1].exx"),
        ("law: j2\npath: [{t: 0}, {t: 1, exx: 1e-3}]\nstress: {tn: 0}\n", "stress.tn"),
        ("law: j2\npath: [{t: 0}, {t: 1, eyy: 1e-3}]\nstress: {syy: 0}\n", "path[1].eyy"),
        ("law: mazars\nparameters: {Gf: 80}\npath: [{t: 0}, {t: 1, exx: 1e-3}]\n", "parameters.l"),
        ("law: mazars\nparameters: {Gf: 80, l: \"30 m\"}\npath: [{t: 0}, {t: 1, exx: 1e-3}]\n", "too large"),
        ("law: fczm\nparameters: {ft: 3e6, Gf: 300, delta_s: 1}\npath: [{t: 0}, {t: 1, un: 1e-5, ux: 2}]\n", "unknown field `ux`"),
        ("law: plasticine\npath: [{t: 0}, {t: 1}]\n", "plasticine"),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let p = dir.join(format!("case{i}.yaml"));
        std::fs::write(&p, text).unwrap();
        let err: MaterialPointError = run_file(&p).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains(&format!("case{i}.yaml")) && msg.contains(needle),
            "{msg}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The CSV has exactly the leading columns, law internals after them.
#[test]
fn csv_columns() {
    let mut out = Vec::new();
    case("fczm-shear.yaml").write_csv(&mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.starts_with("t,un,ut,uh,tn,tt,th,D,"));
    let mut out = Vec::new();
    case("j2-shear.yaml").write_csv(&mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.starts_with("t,exx,eyy,ezz,exy,eyz,exz,sxx,syy,szz,sxy,syz,sxz,D"));
    assert_eq!(text.lines().count(), 1 + 101);
}

/// Held tractions are met at every point (mixed control, issue 4); with the
/// total σ_n held the FCZM's closed normal stiffness (1 + D) K_n shows as a
/// shrinking u_n (docs/src/explanation/laws.md).
#[test]
fn held_normal_traction_under_shear() {
    let mut test = read_case("fczm-shear-compression-5MPa.yaml");
    for row in &mut test.path {
        row.un = None;
    }
    test.stress
        .insert("tn".into(), geom::units::RawQuantity::Text("-5 MPa".into()));
    let t = run(&test).unwrap();
    assert!(col(&t, "tn").iter().all(|s| (s + 5e6).abs() <= 1e-6 * 5e6));
    let (un, d) = (col(&t, "un"), col(&t, "D"));
    let last = un.len() - 1;
    assert!((un[last] * 1.5e11 * (1.0 + d[last]) + 5e6).abs() <= 1e-6 * 5e6);
}

/// A test of 10^12 increments is refused before any row is computed,
/// naming `increments`, the row count and `max_rows`; `max_rows` raises
/// the limit.
#[test]
fn a_test_of_too_many_rows_is_refused_before_it_runs() {
    let mut test = read_case("fczm-shear.yaml");
    test.increments = 1_000_000_000_000;
    let err = run(&test).unwrap_err().to_string();
    let segments = test.path.len() - 1;
    assert!(
        err.contains("increments")
            && err.contains(&format!("{} rows", 1_000_000_000_000 * segments + 1))
            && err.contains("max_rows = 1000000"),
        "{err}"
    );
    test.increments = 10;
    test.max_rows = Some(5);
    assert!(run(&test).unwrap_err().to_string().contains("max_rows = 5"));
    test.max_rows = None;
    assert!(run(&test).is_ok());
}
