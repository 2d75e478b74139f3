//! Rib-design sweep (issue 2): rib angle 35°–90°, height 0.03 d–0.1 d,
//! spacing 0.4 d–1.2 d on d = 8 and 16 mm. The full grid goes through
//! validation and the analytic/parry3d checks. The builds in real gmsh with
//! the three-way checks are the envelope test's (`mesh/tests/envelope.rs`:
//! 30 designs over the standards' whole ranges, corners included, built and
//! meshed).

use geom::build::offline_metrics;
use geom::spec::{resolve, Bar, RawBar, RawSpecimen, Specimen};

const ANGLES: [f64; 5] = [35.0, 45.0, 55.0, 70.0, 90.0];
const HEIGHTS: [f64; 5] = [0.03, 0.05, 0.065, 0.08, 0.1];
const SPACINGS: [f64; 5] = [0.4, 0.6, 0.8, 1.0, 1.2];

fn design(
    d_mm: f64,
    angle: f64,
    h: f64,
    s: f64,
    cube_sides: f64,
) -> Result<(Bar, Specimen), geom::spec::SpecError> {
    let bar: RawBar = serde_yaml::from_str(&format!(
        "{{kind: ribbed, diameter: {d_mm} mm, ribs: {{angle: {angle} deg, height: {} mm, spacing: {} mm}}}}",
        h * d_mm,
        s * d_mm
    ))
    .unwrap();
    let sp: RawSpecimen =
        serde_yaml::from_str(&format!("{{cube_side: {} mm}}", cube_sides * d_mm)).unwrap();
    resolve(&bar, &sp)
}

/// Overlap bound of SPEC §3 with the default widths b_top = 0.1 d, b_base = b_top + 2a.
fn overlaps(angle: f64, h: f64, s: f64) -> bool {
    0.1 + 2.0 * h >= 0.98 * s * angle.to_radians().sin()
}

/// Every valid design of the grid resolves and its parry3d tessellation agrees with the analytic metrics within 1 %; every overlapping one is rejected naming bar.ribs.base_width (SPEC §3).
#[test]
fn full_grid_validates_and_cross_checks() {
    // One thread per diameter: the tessellations take seconds each.
    let counts: Vec<(usize, usize)> = std::thread::scope(|scope| {
        let workers: Vec<_> = [8.0, 16.0]
            .map(|d| scope.spawn(move || grid_on_diameter(d)))
            .into_iter()
            .collect();
        workers.into_iter().map(|w| w.join().unwrap()).collect()
    });
    let (valid, rejected) = counts.iter().fold((0, 0), |(v, r), (a, b)| (v + a, r + b));
    assert!(
        valid > 200 && rejected >= 8,
        "{valid} valid, {rejected} rejected"
    );
}

/// The grid's designs on one bar diameter (mm): (valid, rejected).
fn grid_on_diameter(d: f64) -> (usize, usize) {
    let (mut valid, mut rejected) = (0, 0);
    for angle in ANGLES {
        for h in HEIGHTS {
            for s in SPACINGS {
                match design(d, angle, h, s, 10.0) {
                    Ok((bar, sp)) => {
                        assert!(
                            !overlaps(angle, h, s),
                            "accepted overlapping ribs {d} {angle} {h} {s}"
                        );
                        let (m, t) = offline_metrics(&bar, &sp);
                        let core = std::f64::consts::PI
                            * (d * 5e-4f64).powi(2)
                            * (sp.bar_z_max() - sp.bar_z_min());
                        if let Err(e) = geom::metrics::check_offline(&m, &t, core, 0.01) {
                            panic!("{d} {angle} {h} {s}: {e}");
                        }
                        assert!(m.f_r > 0.0 && m.rib_volume_m3 > 0.0);
                        valid += 1;
                    }
                    Err(e) => {
                        assert!(
                            overlaps(angle, h, s),
                            "rejected a valid design {d} {angle} {h} {s}: {e}"
                        );
                        assert!(e.to_string().contains("bar.ribs.base_width"), "{e}");
                        rejected += 1;
                    }
                }
            }
        }
    }
    (valid, rejected)
}
