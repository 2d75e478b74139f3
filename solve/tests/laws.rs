//! Law-level verification (SPEC §5, STYLE 4): every tangent the solver can ask
//! for is checked against central finite differences in every regime, one
//! macro per property; damage monotonicity, the J2 return and finiteness are
//! checked on pseudo-random paths.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use solve::laws::coulomb::Coulomb;
use solve::laws::fczm::Fczm;
use solve::laws::j2::{von_mises, J2};
use solve::laws::mazars::{
    CompressionSoftening, Mazars, MazarsMaterial, MazarsSizeError, TensionSoftening,
};
use solve::laws::tvergaard::Tvergaard;
use solve::laws::{
    AnyInterfaceLaw, BulkLaw, BulkState, InterfaceLaw, InterfaceState, LawError, TangentKind,
};

/// Table 2 parameters (paper §3.2) with ζ = 1, γ = −1 MPa.
fn fczm() -> Fczm {
    Fczm {
        tensile_strength: 3e6,
        fracture_energy: 300.0,
        lambda0: 2e-5,
        delta_s: 1.0,
        friction: 0.4,
        zeta: 1.0,
        gamma: -1e6,
        min_damage: 0.0,
        contact_smoothing: 0.0,
    }
}

/// Table 3 R1-like parameters with δ_s ≠ 1 and ζ = 8, to exercise the ratios.
fn fczm_calibrated() -> Fczm {
    Fczm {
        tensile_strength: 2.16e6,
        fracture_energy: 97.0,
        lambda0: 5e-5,
        delta_s: 0.16,
        friction: 0.3,
        zeta: 8.0,
        ..fczm()
    }
}

/// R1's calibrated FCZM with the contact switch smoothed over |u_n| < 1 µm.
fn fczm_smoothed() -> Fczm {
    Fczm {
        contact_smoothing: 1e-6,
        ..fczm_calibrated()
    }
}

fn tvergaard() -> Tvergaard {
    Tvergaard {
        tensile_strength: 3e6,
        fracture_energy: 200.0,
        lambda0: 1e-5,
        delta_s: 0.5,
    }
}

/// Appendix B parameters.
fn coulomb() -> Coulomb {
    Coulomb {
        normal_stiffness: 1e11,
        shear_stiffness: 1e11,
        tensile_strength: 3e6,
        cohesion: 3e6,
        friction_angle: 45f64.to_radians(),
    }
}

/// Fig. 4b concrete (G_f = 80 N/m), Table 1 compression from eqs. (12)–(13),
/// regularised with each element's size.
fn fig4b_concrete() -> MazarsMaterial {
    MazarsMaterial {
        young_modulus: 30e9,
        poisson_ratio: 0.2,
        eps_d0: 1e-4,
        shear_exponent: 1.06,
        tension: TensionSoftening::Regularised {
            fracture_energy: 80.0,
        },
        compression: CompressionSoftening::SizeFit,
        regularisation_length: None,
        nonlocal_length: None,
    }
}

/// Fig. 4b concrete at l = 1 mm.
fn mazars() -> Mazars {
    fig4b_concrete().at_size(1e-3).unwrap()
}

fn j2() -> J2 {
    J2::default()
}

/// Commits the law along `history` from the virgin state.
fn interface_history(law: &dyn InterfaceLaw, history: &[[f64; 3]]) -> InterfaceState {
    history.iter().fold(InterfaceState::default(), |s, u| {
        law.step(&s, &Vector3::from(*u), TangentKind::Consistent)
            .unwrap()
            .state
    })
}

fn bulk_history(law: &dyn BulkLaw, history: &[[f64; 6]]) -> BulkState {
    history.iter().fold(BulkState::default(), |s, e| {
        law.step(&s, &Vector6::from(*e), TangentKind::Consistent)
            .unwrap()
            .state
    })
}

/// Central differences of the traction at fixed committed state.
fn fd_interface(
    law: &dyn InterfaceLaw,
    st: &InterfaceState,
    u: &Vector3<f64>,
    h: f64,
) -> Matrix3<f64> {
    let mut k = Matrix3::zeros();
    for j in 0..3 {
        let (mut p, mut m) = (*u, *u);
        p[j] += h;
        m[j] -= h;
        let tp = law.step(st, &p, TangentKind::Consistent).unwrap().traction;
        let tm = law.step(st, &m, TangentKind::Consistent).unwrap().traction;
        k.set_column(j, &((tp - tm) / (2.0 * h)));
    }
    k
}

fn fd_bulk(law: &dyn BulkLaw, st: &BulkState, e: &Vector6<f64>, h: f64) -> Matrix6<f64> {
    let mut k = Matrix6::zeros();
    for j in 0..6 {
        let (mut p, mut m) = (*e, *e);
        p[j] += h;
        m[j] -= h;
        let sp = law.step(st, &p, TangentKind::Consistent).unwrap().stress;
        let sm = law.step(st, &m, TangentKind::Consistent).unwrap().stress;
        k.set_column(j, &((sp - sm) / (2.0 * h)));
    }
    k
}

/// Consistent tangent of an interface law equals central differences of the traction
/// at `at` after `history`, and the step is in the regime `regime(before, after)` says.
macro_rules! interface_tangent {
    ($name:ident, $doc:literal, $law:expr, history: $hist:expr, at: $u:expr, regime: $regime:expr) => {
        #[doc = $doc]
        #[test]
        fn $name() {
            let law = $law;
            let st = interface_history(&law, &$hist);
            let u = Vector3::from($u);
            let r = law.step(&st, &u, TangentKind::Consistent).unwrap();
            let regime: fn(&InterfaceState, &InterfaceState) -> bool = $regime;
            assert!(
                regime(&st, &r.state),
                "not in the intended regime: {st:?} -> {:?}",
                r.state
            );
            let h = 1e-6 * u.amax();
            let fd = fd_interface(&law, &st, &u, h);
            let err = (fd - r.tangent).amax();
            assert!(
                err <= 1e-5 * r.tangent.amax(),
                "tangent\n{}vs finite differences\n{}",
                r.tangent,
                fd
            );
            // The secant reproduces the traction when it is a true secant (no slip history).
            assert!(law
                .step(&st, &u, TangentKind::Secant)
                .unwrap()
                .tangent
                .iter()
                .all(|v| v.is_finite()));
        }
    };
}

macro_rules! bulk_tangent {
    ($name:ident, $doc:literal, $law:expr, history: $hist:expr, at: $e:expr, regime: $regime:expr) => {
        #[doc = $doc]
        #[test]
        fn $name() {
            let law = $law;
            let st = bulk_history(&law, &$hist);
            let e = Vector6::from($e);
            let r = law.step(&st, &e, TangentKind::Consistent).unwrap();
            let regime: fn(&BulkState, &BulkState) -> bool = $regime;
            assert!(
                regime(&st, &r.state),
                "not in the intended regime: {st:?} -> {:?}",
                r.state
            );
            let h = 1e-6 * e.amax();
            let fd = fd_bulk(&law, &st, &e, h);
            let err = (fd - r.tangent).amax();
            assert!(
                err <= 1e-5 * r.tangent.amax(),
                "tangent\n{}vs finite differences\n{}",
                r.tangent,
                fd
            );
        }
    };
}

/// Undamaged; in FCZM the (zero-weight) damaged part may still slide.
fn undamaged_i(_: &InterfaceState, b: &InterfaceState) -> bool {
    b.damage == 0.0
}
fn elastic_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    b.damage == 0.0 && a.slip == b.slip
}
fn loading_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    b.lambda_max > a.lambda_max
}
fn unloading_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    a.damage > 0.0 && b.lambda_max == a.lambda_max
}
fn sticking_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    a.damage > 0.0 && b.slip == a.slip
}
fn sliding_loading_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    b.slip != a.slip && b.lambda_max > a.lambda_max
}
fn sliding_unloading_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    b.slip != a.slip && b.lambda_max == a.lambda_max && a.damage > 0.0
}
fn sliding_i(a: &InterfaceState, b: &InterfaceState) -> bool {
    b.slip != a.slip
}

// FCZM (eqs. 15–26).
interface_tangent!(fczm_tangent_elastic, "FCZM consistent tangent matches finite differences below λ_0 (eq. A.5; SPEC §5).",
    fczm(), history: [], at: [5e-6, 3e-6, -2e-6], regime: undamaged_i);
interface_tangent!(fczm_tangent_tension_loading, "FCZM consistent tangent matches finite differences in opening-and-shear loading (eqs. 22–26).",
    fczm(), history: [], at: [4e-5, 1e-5, 5e-6], regime: loading_i);
interface_tangent!(fczm_tangent_tension_loading_calibrated, "FCZM consistent tangent matches finite differences in loading with δ_s ≠ 1 and ζ = 8 (Table 3).",
    fczm_calibrated(), history: [], at: [4e-5, 3e-5, -1e-5], regime: loading_i);
interface_tangent!(fczm_tangent_tension_unloading, "FCZM consistent (secant) tangent matches finite differences in tension unloading (SPEC §5 reading of λ).",
    fczm(), history: [[8e-5, 2e-5, 0.0]], at: [4e-5, 1e-5, 0.0], regime: unloading_i);
interface_tangent!(fczm_tangent_compression_sticking_loading, "FCZM consistent tangent matches finite differences under σ_N = −20 MPa while sticking and damaging (eqs. 19–26).",
    fczm(), history: [[-1.3333e-4, 0.0, 0.0]], at: [-1.3333e-4, 3e-5, 4e-6], regime: |a, b| b.slip == a.slip && b.lambda_max > a.lambda_max);
interface_tangent!(fczm_tangent_compression_sticking_unloading, "FCZM consistent tangent matches finite differences when sticking after a slip reversal under compression (eq. 21).",
    fczm(), history: [[-3.3333e-5, 6e-5, 0.0]], at: [-3.3333e-5, 5.9e-5, 0.0], regime: sticking_i);
interface_tangent!(fczm_tangent_compression_sliding_loading, "FCZM consistent tangent matches finite differences when sliding and damaging with σ_dn ≤ γ (eqs. 19–21, fourth case of 26).",
    fczm(), history: [[-3.3333e-5, 4e-5, 0.0]], at: [-3.3333e-5, 6e-5, 1e-5], regime: sliding_loading_i);
interface_tangent!(fczm_tangent_compression_band_sliding, "FCZM consistent tangent matches finite differences when sliding and damaging with γ < σ_dn < 0 (third case of 26, SPEC §5 reading).",
    fczm(), history: [[-3.3333e-6, 3e-5, 0.0]], at: [-3.3333e-6, 4e-5, 5e-6], regime: sliding_loading_i);
interface_tangent!(fczm_tangent_compression_sliding_unloading, "FCZM consistent tangent matches finite differences when sliding back without damage growth (eqs. 19–21).",
    fczm(), history: [[-3.3333e-5, 6e-5, 0.0]], at: [-3.3333e-5, 3e-5, 0.0], regime: sliding_unloading_i);
interface_tangent!(fczm_tangent_smoothed_band_open_loading, "Smoothed FCZM consistent tangent matches finite differences just open inside the contact band while damaging (docs/src/explanation/laws.md, contact smoothing).",
    fczm_smoothed(), history: [[4e-5, 2e-5, 0.0]], at: [3e-7, 6e-5, 1e-5], regime: loading_i);
interface_tangent!(fczm_tangent_smoothed_band_closed_sliding, "Smoothed FCZM consistent tangent matches finite differences just closed inside the contact band while sliding (docs/src/explanation/laws.md, contact smoothing).",
    fczm_smoothed(), history: [[4e-5, 6e-5, 0.0]], at: [-4e-7, 3e-5, -1e-5], regime: sliding_i);
interface_tangent!(fczm_tangent_smoothed_band_centre, "Smoothed FCZM consistent tangent matches finite differences at u_n = 0 of a damaged interface (docs/src/explanation/laws.md, contact smoothing).",
    fczm_smoothed(), history: [[4e-5, 2e-5, 0.0]], at: [0.0, 1e-5, 2e-6], regime: unloading_i);
interface_tangent!(fczm_tangent_pure_compression, "FCZM consistent tangent is K_n in undamaged compression (eqs. 17, 25).",
    fczm(), history: [], at: [-2e-5, 0.0, 0.0], regime: elastic_i);

// Tvergaard (App. A).
interface_tangent!(tvergaard_tangent_elastic, "Tvergaard consistent tangent matches finite differences below λ_0 (A.5).",
    tvergaard(), history: [], at: [4e-6, 2e-6, 1e-6], regime: elastic_i);
interface_tangent!(tvergaard_tangent_loading, "Tvergaard consistent tangent matches finite differences in mixed-mode loading (A.9–A.11).",
    tvergaard(), history: [], at: [3e-5, 1e-5, -5e-6], regime: loading_i);
interface_tangent!(tvergaard_tangent_unloading, "Tvergaard consistent (secant) tangent matches finite differences in unloading (A.6, A.8).",
    tvergaard(), history: [[5e-5, 1e-5, 0.0]], at: [2e-5, 5e-6, 1e-6], regime: unloading_i);
interface_tangent!(tvergaard_tangent_compression_shear_loading, "Tvergaard consistent tangent matches finite differences in compression with shear loading (A.10–A.11).",
    tvergaard(), history: [], at: [-1e-5, 3e-5, 1e-5], regime: loading_i);

// Coulomb (App. B).
interface_tangent!(coulomb_tangent_sticking, "Coulomb consistent tangent is the elastic stiffness while sticking (A.5, App. B).",
    coulomb(), history: [], at: [-5e-5, 2e-5, 1e-5], regime: elastic_i);
interface_tangent!(coulomb_tangent_sliding_compression, "Coulomb consistent tangent matches finite differences when sliding under compression (B.1).",
    coulomb(), history: [], at: [-5e-5, 1e-4, 3e-5], regime: sliding_i);
interface_tangent!(coulomb_tangent_sliding_tension, "Coulomb consistent tangent matches finite differences when sliding under tension below f_t (B.1–B.2).",
    coulomb(), history: [], at: [1e-5, 1e-4, 0.0], regime: sliding_i);
interface_tangent!(coulomb_tangent_separated_sliding, "Coulomb consistent tangent matches finite differences when sliding in frictional contact after separation (App. B).",
    coulomb(), history: [[5e-5, 0.0, 0.0]], at: [-2e-5, 1e-4, 1e-5], regime: |a, b| a.damage == 1.0 && b.slip != a.slip);

fn elastic_b(a: &BulkState, b: &BulkState) -> bool {
    b.damage == a.damage && b.plastic_strain == a.plastic_strain
}
fn damaging_b(a: &BulkState, b: &BulkState) -> bool {
    b.damage > a.damage
}
fn unloading_b(a: &BulkState, b: &BulkState) -> bool {
    a.damage > 0.0 && b.damage == a.damage
}
fn yielding_b(a: &BulkState, b: &BulkState) -> bool {
    b.plastic_strain != a.plastic_strain
}

// Mazars (eqs. 1–9).
bulk_tangent!(mazars_tangent_elastic, "Mazars consistent tangent is C below ε_D0 (eq. 1).",
    mazars(), history: [], at: [5e-5, -1e-5, -1e-5, 2e-5, 0.0, 0.0], regime: elastic_b);
bulk_tangent!(mazars_tangent_tension_loading, "Mazars consistent tangent matches finite differences in tension loading, all effective principal stresses positive (eqs. 3, 9).",
    mazars(), history: [], at: [3e-4, -4e-5, -5e-5, 0.0, 0.0, 0.0], regime: damaging_b);
bulk_tangent!(mazars_tangent_mixed_loading, "Mazars consistent tangent matches finite differences in mixed tension–compression loading with 0 < α_t < 1 (eqs. 4–7).",
    mazars(), history: [], at: [3e-4, -8e-4, 0.0, 1e-4, 0.0, 0.0], regime: damaging_b);
bulk_tangent!(mazars_tangent_shear_loading, "Mazars consistent tangent matches finite differences in general shear-dominated loading (eqs. 3–7).",
    mazars(), history: [], at: [1e-4, -5e-5, 2e-5, 4e-4, -1e-4, 5e-5], regime: damaging_b);
bulk_tangent!(mazars_tangent_compression_loading, "Mazars consistent tangent matches finite differences in compression loading (eqs. 5, 12–13).",
    mazars(), history: [], at: [-2e-3, 3.5e-4, 3.5e-4, 1e-4, 0.0, 0.0], regime: damaging_b);
bulk_tangent!(mazars_tangent_unloading, "Mazars consistent tangent is the secant (1 − D)C in unloading (eq. 1, damage never decreases).",
    mazars(), history: [[5e-4, -1e-4, -1e-4, 0.0, 0.0, 0.0]], at: [2e-4, -4e-5, -4e-5, 0.0, 0.0, 0.0], regime: unloading_b);

// J2 (radial return).
bulk_tangent!(j2_tangent_elastic, "J2 consistent tangent is C inside the yield surface.",
    j2(), history: [], at: [5e-4, -1e-4, 0.0, 2e-4, 0.0, 0.0], regime: elastic_b);
bulk_tangent!(j2_tangent_yielding, "J2 consistent tangent matches finite differences while yielding (radial return, perfect plasticity).",
    j2(), history: [], at: [4e-3, -1e-3, -5e-4, 1e-3, 2e-4, -3e-4], regime: yielding_b);
bulk_tangent!(j2_tangent_reverse_yielding, "J2 consistent tangent matches finite differences while yielding in reverse after plastic flow.",
    j2(), history: [[4e-3, -1.2e-3, -1.2e-3, 0.0, 0.0, 0.0]], at: [-2e-3, 1e-4, 2e-4, 1e-3, 0.0, 0.0], regime: yielding_b);
bulk_tangent!(j2_tangent_unloading, "J2 consistent tangent is C in elastic unloading from a plastic state.",
    j2(), history: [[4e-3, -1.2e-3, -1.2e-3, 0.0, 0.0, 0.0]], at: [3.5e-3, -1.2e-3, -1.2e-3, 0.0, 0.0, 0.0], regime: elastic_b);

/// Deterministic pseudo-random numbers in [−1, 1) for path tests.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// The smoothed contact switch changes the FCZM only inside its band
/// |u_n| < δ, where the normal traction moves by at most K_n δ/4 (the
/// ramp's offset) times the closed/open stiffness difference and the
/// damaged part's weight, and the traction stays continuous
/// (docs/src/explanation/laws.md, contact smoothing).
#[test]
fn fczm_contact_smoothing_is_confined_to_its_band() {
    let sharp = fczm_calibrated();
    let smooth = fczm_smoothed();
    let delta = smooth.contact_smoothing;
    let kn = sharp.normal_stiffness();
    let st = interface_history(&sharp, &[[4e-5, 2e-5, 0.0]]);
    let t = |law: &Fczm, un: f64| {
        law.step(&st, &Vector3::new(un, 1e-5, 0.0), TangentKind::Consistent)
            .unwrap()
            .traction
    };
    for k in -40..=40 {
        let un = k as f64 * 0.05 * delta;
        let diff = (t(&smooth, un) - t(&sharp, un)).amax();
        if un.abs() >= delta {
            assert_eq!(diff, 0.0, "u_n = {un:e}");
        } else {
            assert!(diff <= 2.0 * kn * delta / 4.0, "u_n = {un:e}: {diff:e}");
        }
    }
    // Continuous across the band edges.
    for edge in [-delta, delta] {
        let jump = (t(&smooth, edge * (1.0 + 1e-9)) - t(&smooth, edge * (1.0 - 1e-9))).amax();
        assert!(jump < 1e-6 * kn * delta, "edge {edge:e}: {jump:e}");
    }
}

/// Damage (and λ̃, κ) never decreases along random interface paths (SPEC §5).
#[test]
fn interface_damage_never_decreases() {
    let laws = [
        AnyInterfaceLaw::Fczm(fczm()),
        AnyInterfaceLaw::Fczm(fczm_calibrated()),
        AnyInterfaceLaw::Fczm(fczm_smoothed()),
        AnyInterfaceLaw::Tvergaard(tvergaard()),
        AnyInterfaceLaw::Coulomb(coulomb()),
    ];
    let mut rng = Lcg(7);
    for law in laws {
        let mut st = InterfaceState::default();
        let mut u = Vector3::zeros();
        for _ in 0..400 {
            u += Vector3::new(rng.next(), rng.next(), rng.next()) * 1e-5;
            let r = law.step(&st, &u, TangentKind::Consistent).unwrap();
            assert!(
                r.state.damage >= st.damage && r.state.lambda_max >= st.lambda_max,
                "{law:?}"
            );
            assert!((0.0..=1.0).contains(&r.state.damage));
            st = r.state;
        }
    }
}

/// Mazars damage never decreases along random strain paths (SPEC §5).
#[test]
fn mazars_damage_never_decreases() {
    let law = mazars();
    let mut rng = Lcg(11);
    let mut st = BulkState::default();
    let mut e = Vector6::zeros();
    for _ in 0..400 {
        e += Vector6::from_fn(|_, _| rng.next()) * 1e-4;
        let r = law.step(&st, &e, TangentKind::Consistent).unwrap();
        assert!(r.state.damage >= st.damage && r.state.kappa >= st.kappa);
        assert!((0.0..=1.0).contains(&r.state.damage));
        st = r.state;
    }
    assert!(
        st.damage > 0.5,
        "the path should have damaged the point, D = {}",
        st.damage
    );
}

/// J2 radial return lands on the yield surface whenever it flows, and stays inside otherwise (SPEC §5).
#[test]
fn j2_returns_onto_the_yield_surface() {
    let law = j2();
    let mut rng = Lcg(3);
    let mut st = BulkState::default();
    let mut e = Vector6::zeros();
    let mut flowed = 0;
    for _ in 0..400 {
        e += Vector6::from_fn(|_, _| rng.next()) * 1e-3;
        let r = law.step(&st, &e, TangentKind::Consistent).unwrap();
        let vm = von_mises(&r.stress);
        if r.state.plastic_strain != st.plastic_strain {
            flowed += 1;
            assert!((vm - 365e6).abs() <= 1e-9 * 365e6, "von Mises {vm}");
            // Plastic flow is isochoric.
            let p = &r.state.plastic_strain;
            assert!((p[0] + p[1] + p[2]).abs() <= 1e-12);
        } else {
            assert!(vm <= 365e6 * (1.0 + 1e-12));
        }
        st = r.state;
    }
    assert!(flowed > 50);
}

/// A law never returns NaN or infinity for finite input: it returns a `LawError` (SPEC §5, issue 4).
#[test]
fn laws_return_errors_not_nan() {
    let interfaces = [
        AnyInterfaceLaw::Fczm(fczm()),
        AnyInterfaceLaw::Tvergaard(tvergaard()),
        AnyInterfaceLaw::Coulomb(coulomb()),
        AnyInterfaceLaw::contact(1e11),
    ];
    let extremes = [1e300, -1e300, 1e-300, 0.0, 1e150, -1e150];
    for law in interfaces {
        for &a in &extremes {
            for &b in &extremes {
                for kind in [
                    TangentKind::Elastic,
                    TangentKind::Secant,
                    TangentKind::Consistent,
                ] {
                    match law.step(&InterfaceState::default(), &Vector3::new(a, b, -b), kind) {
                        Ok(r) => assert!(r
                            .traction
                            .iter()
                            .chain(r.tangent.iter())
                            .all(|v| v.is_finite())),
                        Err(e) => assert!(matches!(e, LawError::NonFiniteResult { .. })),
                    }
                }
            }
        }
        let err = law.step(
            &InterfaceState::default(),
            &Vector3::new(f64::NAN, 0.0, 0.0),
            TangentKind::Consistent,
        );
        assert!(matches!(err, Err(LawError::NonFiniteInput { .. })));
    }
    let bulks: [&dyn BulkLaw; 2] = [&mazars(), &j2()];
    for law in bulks {
        for &a in &extremes {
            for &b in &extremes {
                let e = Vector6::new(a, b, -a, b, 0.0, a);
                match law.step(&BulkState::default(), &e, TangentKind::Consistent) {
                    Ok(r) => assert!(r
                        .stress
                        .iter()
                        .chain(r.tangent.iter())
                        .all(|v| v.is_finite())),
                    Err(e) => assert!(matches!(e, LawError::NonFiniteResult { .. })),
                }
            }
        }
        let e = Vector6::new(f64::INFINITY, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(matches!(
            law.step(&BulkState::default(), &e, TangentKind::Consistent),
            Err(LawError::NonFiniteInput { .. })
        ));
    }
}

/// The non-adhesive contact option carries no tension and no shear, and K_n u_n in compression (SPEC §2).
#[test]
fn contact_is_no_tension_frictionless() {
    let law = AnyInterfaceLaw::contact(4e10);
    let st = InterfaceState::default();
    let open = law
        .step(
            &st,
            &Vector3::new(1e-4, 2e-4, -1e-4),
            TangentKind::Consistent,
        )
        .unwrap();
    assert_eq!(open.traction, Vector3::zeros());
    let closed = law
        .step(
            &st,
            &Vector3::new(-1e-5, 2e-4, 3e-4),
            TangentKind::Consistent,
        )
        .unwrap();
    assert!((closed.traction[0] + 4e10 * 1e-5).abs() < 1e-6);
    assert_eq!(closed.traction[1], 0.0);
    assert_eq!(closed.traction[2], 0.0);
    assert_eq!(closed.state.damage, 1.0);
}

/// Hillerborg's B_t follows the energy balance G_f = l (E ε_D0²/2 + E ε_D0/B_t), and too large an element is an error naming the limit (eq. 10 as read in SPEC §5).
#[test]
fn mazars_size_regularisation() {
    let m = fig4b_concrete();
    for l in [0.2e-3, 1e-3, 5e-3] {
        let law = m.at_size(l).unwrap();
        let solve::laws::mazars::TensionBranch::Exponential { b_t } = law.tension else {
            panic!()
        };
        let gf = l * (30e9 * 1e-8 / 2.0 + 30e9 * 1e-4 / b_t);
        assert!((gf - 80.0).abs() < 1e-9 * 80.0);
    }
    // l_max = 2 G_f / (E ε_D0²) = 0.5333 m.
    let err = m.at_size(0.6).unwrap_err();
    assert!(matches!(err, MazarsSizeError::TooLarge { .. }));
    assert!(
        err.to_string().contains("too large") && err.to_string().contains("0.5333"),
        "{err}"
    );
    assert!(matches!(
        m.at_size(1e-6),
        Err(MazarsSizeError::OutsideFit { .. })
    ));
    assert!(matches!(
        m.at_size(-1.0),
        Err(MazarsSizeError::BadSize { .. })
    ));
}

/// With the averaged strain equal to the point's own, the averaged history
/// is the local law's (in tension, shear and compression, loading and
/// unloading); a smaller average leaves κ where it was committed.
#[test]
fn mazars_averaged_history_with_the_local_strain_is_the_local_law() {
    let law = mazars();
    let strains = [
        Vector6::new(4e-4, -0.8e-4, -0.8e-4, 0.0, 0.0, 0.0),
        Vector6::new(1e-4, 0.5e-4, 0.0, 3e-4, 0.0, 1e-4),
        Vector6::new(-3e-3, 6e-4, 6e-4, 0.0, 0.0, 0.0),
    ];
    for strain in strains {
        let mut committed = BulkState::default();
        for scale in [0.5, 1.0, 2.0, 1.5, 3.0] {
            let e = strain * scale;
            let local = law.step(&committed, &e, TangentKind::Secant).unwrap().state;
            let (eps_eq, alpha_t) = law.local_measures(&e);
            let averaged = law.averaged_state(&committed, &local, eps_eq, alpha_t);
            assert!((averaged.damage - local.damage).abs() < 1e-14, "{e:?}");
            assert!((averaged.kappa - local.kappa).abs() < 1e-18, "{e:?}");
            assert_eq!(averaged.kappa_increment, local.kappa_increment, "{e:?}");
            let below = law.averaged_state(&committed, &local, 0.0, alpha_t);
            assert_eq!(below.kappa, committed.kappa.max(law.eps_d0));
            assert_eq!(below.kappa_increment, 0.0);
            assert!(below.damage >= committed.damage);
            committed = local;
        }
        assert!(committed.damage > 0.0);
    }
}

/// With a fixed `regularisation_length` every element size gets the law of
/// that length (the same B_t and compression fit), so a damage zone spread
/// over many elements dissipates G_f / l per volume on any mesh; without it
/// the law follows the element (eq. 11). A length the regularised tension
/// does not admit is an error naming the limit.
#[test]
fn mazars_fixed_regularisation_length() {
    let paper = fig4b_concrete();
    let fixed = MazarsMaterial {
        regularisation_length: Some(1e-3),
        ..paper
    };
    let at_1mm = paper.at_size(1e-3).unwrap();
    for l in [0.2e-3, 0.66e-3, 3e-3] {
        assert_eq!(fixed.at_size(l).unwrap(), at_1mm, "l = {l}");
        assert_ne!(paper.at_size(l).unwrap(), at_1mm, "l = {l}");
    }
    // The element size is still checked.
    assert!(matches!(
        fixed.at_size(-1.0),
        Err(MazarsSizeError::BadSize { .. })
    ));
    let too_long = MazarsMaterial {
        regularisation_length: Some(0.6),
        ..paper
    };
    assert!(matches!(
        too_long.at_size(1e-3),
        Err(MazarsSizeError::TooLarge { .. })
    ));
}

/// Secant tangents are what the docs say: (1 − D)C for Mazars, σ = K_sec u for Tvergaard (docs/src/explanation/laws.md).
#[test]
fn secant_tangents() {
    let law = mazars();
    let e = Vector6::new(5e-4, -1e-4, -1e-4, 0.0, 0.0, 0.0);
    let r = law
        .step(&BulkState::default(), &e, TangentKind::Secant)
        .unwrap();
    assert!((r.tangent - law.stiffness() * (1.0 - r.state.damage)).amax() < 1e-6);
    assert!((r.tangent * e - r.stress).amax() < 1e-6);
    let t = tvergaard();
    let u = Vector3::new(3e-5, -2e-5, 1e-5);
    let r = t
        .step(&InterfaceState::default(), &u, TangentKind::Secant)
        .unwrap();
    assert!((r.tangent * u - r.traction).amax() < 1e-6);
}

/// Virgin points whose strain norm stays below ε_D0 take the elastic fast
/// path (no eigen-decomposition); it must give exactly what the general path
/// gives, and must not hide the onset of damage just beyond the bound.
#[test]
fn mazars_virgin_points_below_the_strain_bound_are_elastic() {
    let law = mazars();
    let c = law.stiffness();
    let virgin = BulkState::default();
    let e0 = law.eps_d0;
    // Below the bound (fast path), and compressive beyond it (general path,
    // ε_eq = 0): elastic either way.
    let below = [
        Vector6::new(0.99 * e0, 0.0, 0.0, 0.0, 0.0, 0.0),
        Vector6::new(0.5 * e0, -0.5 * e0, 0.3 * e0, 0.4 * e0, -0.2 * e0, 0.1 * e0),
        Vector6::new(-3.0 * e0, -3.0 * e0, -3.0 * e0, 0.0, 0.0, 0.0),
    ];
    for e in below {
        for kind in [
            TangentKind::Consistent,
            TangentKind::Secant,
            TangentKind::Elastic,
        ] {
            let r = law.step(&virgin, &e, kind).unwrap();
            assert_eq!(r.state.damage, 0.0, "{e:?}");
            assert_eq!(r.state.kappa, e0, "{e:?}");
            assert!((r.stress - c * e).norm() <= 1e-12 * (c * e).norm(), "{e:?}");
            assert_eq!(r.tangent, c, "{e:?}");
        }
    }
    // Just beyond the bound in uniaxial tension: ε_eq > ε_D0, damage starts.
    let e = Vector6::new(1.01 * e0, -0.2 * 1.01 * e0, -0.2 * 1.01 * e0, 0.0, 0.0, 0.0);
    let r = law.step(&virgin, &e, TangentKind::Consistent).unwrap();
    assert!(r.state.damage > 0.0 && r.state.kappa > e0);
}

/// IMPL-EX (`solver.concrete_integration: impl_ex`): with a stress damage
/// D̃ in the committed state, the stress is (1 − D̃) C ε and every tangent
/// the solver asks for is exactly its derivative (the stress is linear in
/// ε), while κ and D follow the implicit law, so the next extrapolation
/// starts from the same history; the increment of D is recorded.
#[test]
fn mazars_impl_ex_stress_uses_the_extrapolated_damage() {
    let law = mazars();
    let c = law.stiffness();
    let e0 = law.eps_d0;
    let history = [[1.5 * e0, -0.3 * e0, -0.3 * e0, 0.2 * e0, 0.0, 0.0]];
    let committed = bulk_history(&law, &history);
    assert!(committed.damage > 0.0);
    let strains = [
        // loading further, unloading, compression
        Vector6::new(3.0 * e0, -0.6 * e0, -0.6 * e0, 0.5 * e0, 0.1 * e0, 0.0),
        Vector6::new(0.5 * e0, -0.1 * e0, -0.1 * e0, 0.0, 0.0, 0.0),
        Vector6::new(-2.0 * e0, 0.4 * e0, 0.4 * e0, 0.0, 0.0, 0.3 * e0),
    ];
    for d_explicit in [committed.damage, 0.5 * (1.0 + committed.damage)] {
        let start = BulkState {
            explicit_damage: Some(d_explicit),
            ..committed
        };
        for e in strains {
            let implicit = law.step(&committed, &e, TangentKind::Consistent).unwrap();
            for kind in [TangentKind::Consistent, TangentKind::Secant] {
                let r = law.step(&start, &e, kind).unwrap();
                let expected = c * e * (1.0 - d_explicit);
                assert!(
                    (r.stress - expected).norm() <= 1e-12 * expected.norm(),
                    "{e:?}"
                );
                assert!((r.tangent - c * (1.0 - d_explicit)).norm() <= 1e-12 * c.norm());
                let fd = fd_bulk(&law, &start, &e, 1e-9 * e0);
                assert!((fd - r.tangent).norm() <= 1e-6 * c.norm(), "{e:?}");
                assert_eq!(r.state.kappa, implicit.state.kappa);
                assert_eq!(r.state.damage, implicit.state.damage);
                assert_eq!(
                    r.state.kappa_increment,
                    implicit.state.kappa - committed.kappa
                );
                assert!((0.0..=1.0).contains(&r.state.alpha_t));
                assert_eq!(r.state.explicit_damage, Some(d_explicit));
            }
        }
    }
}

/// `BulkLaw::stress` (no history update) gives the bits of `step`'s secant
/// stress for every law and state: virgin, damaged, IMPL-EX with the
/// committed or a larger extrapolated damage, plastic steel; and the same
/// error for a non-finite strain. `step_without_history` gives `step`'s
/// stress, tangent and fixed scale for every tangent kind, and leaves the
/// history where it is deferrable (IMPL-EX) only.
#[test]
fn stress_without_history_is_the_step_stress() {
    let law = mazars();
    let e0 = law.eps_d0;
    let damaged = bulk_history(
        &law,
        &[[1.5 * e0, -0.3 * e0, -0.3 * e0, 0.2 * e0, 0.0, 0.0]],
    );
    assert!(damaged.damage > 0.0);
    let strains = [
        Vector6::new(0.2 * e0, -0.05 * e0, 0.0, 0.1 * e0, 0.0, 0.0),
        Vector6::new(3.0 * e0, -0.6 * e0, -0.6 * e0, 0.5 * e0, 0.1 * e0, 0.0),
        Vector6::new(0.5 * e0, -0.1 * e0, -0.1 * e0, 0.0, 0.0, 0.0),
        Vector6::new(-2.0 * e0, 0.4 * e0, 0.4 * e0, 0.0, 0.0, 0.3 * e0),
    ];
    let mut states = vec![BulkState::default(), damaged];
    for base in [BulkState::default(), damaged] {
        for d in [base.damage, 0.5 * (1.0 + base.damage)] {
            states.push(BulkState {
                explicit_damage: Some(d),
                ..base
            });
        }
    }
    for state in &states {
        for e in &strains {
            let step = law.step(state, e, TangentKind::Secant).unwrap().stress;
            assert_eq!(law.stress(state, e).unwrap(), step, "{state:?} {e:?}");
            // Newton's iterates: everything but the history, for each kind.
            assert_eq!(
                law.history_deferrable(state),
                state.explicit_damage.is_some()
            );
            for kind in [
                TangentKind::Elastic,
                TangentKind::Secant,
                TangentKind::Consistent,
            ] {
                let step = law.step(state, e, kind).unwrap();
                let lean = law.step_without_history(state, e, kind).unwrap();
                assert_eq!(lean.stress, step.stress, "{state:?} {e:?} {kind:?}");
                assert_eq!(lean.tangent, step.tangent, "{state:?} {e:?} {kind:?}");
                assert_eq!(lean.fixed_scale, step.fixed_scale, "{state:?} {e:?}");
                let expected = if law.history_deferrable(state) {
                    *state
                } else {
                    step.state
                };
                assert_eq!(lean.state, expected);
            }
        }
    }
    let nan = Vector6::new(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
    for state in &states {
        assert_eq!(
            law.stress(state, &nan).unwrap_err(),
            law.step(state, &nan, TangentKind::Secant).unwrap_err()
        );
    }
    let steel = j2();
    let yielded = bulk_history(&steel, &[[0.01, -0.005, -0.005, 0.0, 0.0, 0.0]]);
    for e in &strains {
        let e = e * 1e3;
        let step = steel
            .step(&yielded, &e, TangentKind::Secant)
            .unwrap()
            .stress;
        assert_eq!(steel.stress(&yielded, &e).unwrap(), step);
    }
}

/// IMPL-EX extrapolation: κ̃ = κ + ratio·Δκ through the law's own D(κ, α_t):
/// ratio 0 gives the committed damage, the extrapolated damage grows with
/// the ratio, stays in [D, 1] and, for a step like the last one, matches
/// the implicit damage of continuing the same uniaxial path; laws without
/// damage are untouched.
#[test]
fn mazars_extrapolation_follows_the_softening_law() {
    let law = mazars();
    let e0 = law.eps_d0;
    let uniaxial = |x: f64| Vector6::new(x * e0, -0.2 * x * e0, -0.2 * x * e0, 0.0, 0.0, 0.0);
    let first = law
        .step(
            &BulkState::default(),
            &uniaxial(1.2),
            TangentKind::Consistent,
        )
        .unwrap()
        .state;
    let second = law
        .step(&first, &uniaxial(1.6), TangentKind::Consistent)
        .unwrap()
        .state;
    let third = law
        .step(&second, &uniaxial(2.0), TangentKind::Consistent)
        .unwrap()
        .state;
    let at = |ratio: f64| law.extrapolate(&second, ratio).explicit_damage.unwrap();
    assert!(
        (at(0.0) - second.damage).abs() <= 1e-12,
        "{} vs {}",
        at(0.0),
        second.damage
    );
    let mut last = at(0.0);
    for ratio in [0.5, 1.0, 2.0, 10.0, 1e3] {
        let d = at(ratio);
        assert!(d >= last && d <= 1.0, "ratio {ratio}: {d}");
        last = d;
    }
    // The same strain increment again: κ grows by the same amount on a
    // proportional path, so the extrapolation is the implicit answer.
    assert!(
        (at(1.0) - third.damage).abs() <= 1e-9,
        "{} vs {}",
        at(1.0),
        third.damage
    );
    let steel = j2();
    let s = BulkState {
        kappa_increment: 1.0,
        ..BulkState::default()
    };
    assert_eq!(steel.extrapolate(&s, 3.0), s);
}

/// `fixed_scale` (the assembly keeps such element matrices through a
/// step): when a law reports a scale s, its tangent is exactly s times its
/// elastic stiffness, and every strain of the step that reports one reports
/// the same s (it is fixed by the committed state); a tangent that moves
/// with the strain (growing implicit damage, a consistent plastic tangent)
/// reports none.
#[test]
fn a_fixed_scale_is_the_tangent_over_the_elastic_stiffness_for_every_strain() {
    let law = mazars();
    let e0 = law.eps_d0;
    let uniaxial =
        |x: f64| Vector6::new(x * e0, -0.2 * x * e0, -0.2 * x * e0, 0.1 * x * e0, 0.0, 0.0);
    let damaged = bulk_history(
        &law,
        &[[2.0 * e0, -0.4 * e0, -0.4 * e0, 0.2 * e0, 0.0, 0.0]],
    );
    assert!(damaged.damage > 0.0);
    let impl_ex = BulkState {
        explicit_damage: Some(0.5 * (1.0 + damaged.damage)),
        ..damaged
    };
    let steel = j2();
    let yield_strain = steel.yield_stress / steel.young_modulus;
    let bar = |x: f64| {
        Vector6::new(
            x * yield_strain,
            -0.3 * x * yield_strain,
            -0.3 * x * yield_strain,
            0.0,
            0.0,
            0.0,
        )
    };
    let elastic_law = solve::laws::elastic::LinearElastic {
        young_modulus: 30e9,
        poisson_ratio: 0.2,
    };
    // (law, committed state, strains of one step, whether each has a scale)
    type Strains = Vec<(Vector6<f64>, [bool; 3])>;
    let cases: Vec<(&dyn BulkLaw, BulkState, Strains)> = vec![
        (
            &law,
            BulkState::default(),
            vec![
                (uniaxial(0.5), [true; 3]),
                // loading past ε_D0: Consistent and Secant follow the strain
                (uniaxial(1.5), [false, false, true]),
                (uniaxial(-3.0), [true; 3]),
            ],
        ),
        (
            &law,
            damaged,
            vec![
                (uniaxial(0.5), [true; 3]),
                (uniaxial(1.0), [true; 3]),
                (uniaxial(4.0), [false, false, true]),
            ],
        ),
        (
            &law,
            impl_ex,
            vec![
                (uniaxial(0.5), [true; 3]),
                (uniaxial(4.0), [true; 3]),
                (uniaxial(-2.0), [true; 3]),
            ],
        ),
        (
            &steel,
            BulkState::default(),
            vec![
                (bar(0.5), [true; 3]),
                // yielding: only the consistent tangent is the elastoplastic one
                (bar(2.0), [false, true, true]),
            ],
        ),
        (
            &elastic_law,
            BulkState::default(),
            vec![(uniaxial(3.0), [true; 3])],
        ),
    ];
    let kinds = [
        TangentKind::Consistent,
        TangentKind::Secant,
        TangentKind::Elastic,
    ];
    for (case, (law, committed, strains)) in cases.iter().enumerate() {
        let c = law.elastic_stiffness();
        for (k, kind) in kinds.into_iter().enumerate() {
            let mut scale_of_step = None;
            for (e, expected) in strains {
                let r = law.step(committed, e, kind).unwrap();
                assert_eq!(
                    r.fixed_scale.is_some(),
                    expected[k],
                    "case {case}, {kind:?}, {e:?}"
                );
                if let Some(s) = r.fixed_scale {
                    assert_eq!(r.tangent, c * s, "case {case}, {kind:?}, {e:?}");
                    assert_eq!(*scale_of_step.get_or_insert(s), s, "case {case}, {kind:?}");
                }
            }
        }
    }
}

/// A held interface point (the solver's retry of a step in which the point
/// kept switching regime) keeps its history whatever the jump, its
/// consistent tangent is the derivative of its traction, and held at the
/// history the law reaches at a jump it gives the law's own traction
/// there: what lets the solver settle a hold by re-holding the point at its
/// implicit history until the equilibrium no longer moves. For every
/// interface law, along random paths through loading, unloading, sticking
/// and sliding.
#[test]
fn held_points_keep_their_history_and_give_the_laws_traction_once_settled() {
    let laws: Vec<(&str, Box<dyn InterfaceLaw>)> = vec![
        ("fczm", Box::new(fczm())),
        ("fczm calibrated", Box::new(fczm_calibrated())),
        ("tvergaard", Box::new(tvergaard())),
        ("coulomb", Box::new(coulomb())),
    ];
    let mut rng = Lcg(11);
    for (name, law) in &laws {
        let mut committed = InterfaceState::default();
        let mut held_elsewhere = 0;
        for step in 0..60 {
            let mut u = Vector3::new(rng.next() * 6e-5, rng.next() * 1.2e-4, rng.next() * 4e-5);
            if u[0].abs() < 1e-6 {
                u[0] = 1e-6;
            }
            let implicit = law.step(&committed, &u, TangentKind::Consistent).unwrap();
            // Held at the implicit history: the law's traction.
            let settled = law
                .held_step(&implicit.state, &u, TangentKind::Consistent)
                .unwrap();
            // Rounding: the return map subtracts slip from jumps of the
            // elastic traction's size.
            let scale = law.elastic_stiffness().amax() * u.amax();
            assert!(
                (settled.traction - implicit.traction).amax() <= 1e-9 * scale,
                "{name}, step {step}: held {:?} vs law {:?}",
                settled.traction,
                implicit.traction
            );
            // Held at the committed history, at a jump twice as far: no
            // damage growth, no slip, and the exact tangent.
            let far = u * 2.0;
            let held = law
                .held_step(&committed, &far, TangentKind::Consistent)
                .unwrap();
            assert_eq!(held.state, committed, "{name}, step {step}");
            let h = 1e-6 * far.amax();
            let mut fd = Matrix3::zeros();
            for j in 0..3 {
                let (mut p, mut m) = (far, far);
                p[j] += h;
                m[j] -= h;
                let tp = law
                    .held_step(&committed, &p, TangentKind::Consistent)
                    .unwrap();
                let tm = law
                    .held_step(&committed, &m, TangentKind::Consistent)
                    .unwrap();
                fd.set_column(j, &((tp.traction - tm.traction) / (2.0 * h)));
            }
            assert!(
                (fd - held.tangent).amax() <= 1e-5 * held.tangent.amax(),
                "{name}, step {step}: held tangent\n{}vs finite differences\n{}",
                held.tangent,
                fd
            );
            let law_far = law.step(&committed, &far, TangentKind::Consistent).unwrap();
            if law_far.state != committed {
                held_elsewhere += 1;
            }
            committed = implicit.state;
        }
        // The paths did reach jumps where the law's history would move.
        assert!(held_elsewhere >= 10, "{name}: {held_elsewhere}");
    }
}

/// Interface IMPL-EX (`interface_integration: impl_ex`), FCZM and
/// Tvergaard: with λ̃ extrapolated to `explicit_lambda` the traction is
/// the law's at that fixed history (the same as from a committed state
/// with λ̃ there, where the jump does not load further), its consistent
/// tangent is the finite-difference derivative at that fixed history
/// (no softening term), and the state returned is the implicit one with
/// the increment of λ̃ the next extrapolation uses.
#[test]
fn interface_impl_ex_traction_uses_the_extrapolated_history() {
    let laws: [(&str, AnyInterfaceLaw, f64); 3] = [
        ("fczm", AnyInterfaceLaw::Fczm(fczm()), 2e-5),
        (
            "fczm calibrated",
            AnyInterfaceLaw::Fczm(fczm_calibrated()),
            5e-5,
        ),
        ("tvergaard", AnyInterfaceLaw::Tvergaard(tvergaard()), 1e-5),
    ];
    for (name, law, l0) in laws {
        let committed = interface_history(&law, &[[0.3 * l0, 1.0 * l0, 0.2 * l0]]);
        assert!(committed.lambda_max > 0.0, "{name}");
        let le = committed.lambda_max + 2.0 * l0;
        let start = InterfaceState {
            explicit_lambda: Some(le),
            ..committed
        };
        // At the extrapolated history, as a committed state (slip kept).
        let at_history = InterfaceState {
            lambda_max: le,
            ..committed
        };
        let jumps = [
            // Opening and sliding beyond both histories (implicit damage
            // grows), in between, and closed in compression.
            Vector3::new(1.0 * l0, 3.0 * l0, 0.5 * l0),
            Vector3::new(0.2 * l0, 1.4 * l0, 0.3 * l0),
            Vector3::new(-0.2 * l0, 1.2 * l0, -0.4 * l0),
        ];
        let mut checked = 0;
        for u in jumps {
            let implicit = law.step(&committed, &u, TangentKind::Consistent).unwrap();
            let r = law.step(&start, &u, TangentKind::Consistent).unwrap();
            let k = law.elastic_stiffness().norm();
            let fixed = law.step(&at_history, &u, TangentKind::Consistent).unwrap();
            // Where the jump does not pass the extrapolated history.
            if fixed.state.lambda_max == le {
                checked += 1;
                assert!(
                    (r.traction - fixed.traction).norm() <= 1e-12 * k * l0,
                    "{name} {u:?}: {} vs {}",
                    r.traction,
                    fixed.traction
                );
            }
            let fd = fd_interface(&law, &start, &u, 1e-6 * l0);
            assert!(
                (fd - r.tangent).norm() <= 1e-6 * k,
                "{name} {u:?}: fd {fd} vs {}",
                r.tangent
            );
            assert_eq!(r.state.lambda_max, implicit.state.lambda_max, "{name}");
            assert_eq!(r.state.damage, implicit.state.damage, "{name}");
            assert_eq!(r.state.slip, implicit.state.slip, "{name}");
            assert_eq!(
                r.state.lambda_increment,
                implicit.state.lambda_max - committed.lambda_max,
                "{name}"
            );
            assert_eq!(r.state.explicit_lambda, Some(le), "{name}");
        }
        assert!(checked >= 2, "{name}: {checked}");
        // The extrapolation: the committed λ̃ at ratio 0, growing with the
        // ratio by the last increment; laws without λ̃ untouched.
        let next = law
            .step(
                &committed,
                &Vector3::new(0.5 * l0, 1.6 * l0, 0.3 * l0),
                TangentKind::Consistent,
            )
            .unwrap()
            .state;
        assert!(next.lambda_increment > 0.0, "{name}");
        let at = |ratio: f64| law.extrapolate(&next, ratio).explicit_lambda.unwrap();
        assert_eq!(at(0.0), next.lambda_max, "{name}");
        assert!(
            (at(2.0) - (next.lambda_max + 2.0 * next.lambda_increment)).abs() <= 1e-15,
            "{name}"
        );
    }
    let c = AnyInterfaceLaw::Coulomb(coulomb());
    let s = InterfaceState {
        lambda_increment: 1.0,
        ..InterfaceState::default()
    };
    assert_eq!(c.extrapolate(&s, 3.0), s);
}
