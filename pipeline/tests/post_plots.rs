//! Plot files: σ_mb–FED curves, interface tractions along the bar (the
//! paper's Fig. 12) and error against run time (SPEC §7 "Outputs", issue 6
//! post and convergence study).

use pipeline::post::{
    bond_slip_plot, convergence_study, ensure_font, error_vs_time_plot, interface_line_plot,
    CurveRow, ErrorTimeSeries, GridResult, InterfaceProfile, InterfaceSample, PostError,
};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("post_plots")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A bond–slip curve shaped like the paper's smooth-bar response.
fn curve(peak_mpa: f64, s0_mm: f64, residual: f64, n: usize) -> Vec<CurveRow> {
    (1..=n)
        .map(|i| {
            let s = 2.0 * i as f64 / n as f64; // mm
            let x = s / s0_mm;
            let shape = x * (1.0 - x).exp();
            // Rises to the peak at s0, then softens towards a residual level.
            let sigma = if x <= 1.0 {
                peak_mpa * shape
            } else {
                peak_mpa * (residual + (1.0 - residual) * shape)
            };
            CurveRow::new(i, 0.0, 0.0, s * 1e-3, sigma * 1e6, 3)
        })
        .collect()
}

/// Checks a PNG's signature and the image size in its IHDR chunk.
fn assert_png(path: &Path, size: (u32, u32)) {
    let bytes = std::fs::read(path).unwrap();
    assert!(
        bytes.len() > 5_000,
        "{} is only {} bytes",
        path.display(),
        bytes.len()
    );
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!((w, h), size);
}

/// Checks an SVG's root element and that it contains each text in `texts`.
fn assert_svg(path: &Path, texts: &[&str]) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let start = text.trim_start();
    assert!(
        start.starts_with("<svg") || start.starts_with("<?xml"),
        "{}",
        &text[..80.min(text.len())]
    );
    assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));
    for t in texts {
        assert!(text.contains(t), "{} lacks `{t}`", path.display());
    }
    text
}

/// The single-case and study bond–slip plots are written as valid PNG and
/// SVG with labelled axes in MPa and mm, and a legend only for several curves.
#[test]
fn bond_slip_plots_written() {
    let dir = scratch("bond_slip");
    let a = curve(9.0, 0.15, 0.35, 120);
    let b = curve(6.5, 0.25, 0.2, 60);
    let c = curve(4.0, 0.4, 0.1, 25);

    let (png, svg) = (
        dir.join("one/plots/bond_slip.png"),
        dir.join("one/plots/bond_slip.svg"),
    );
    bond_slip_plot(&[("R1 coarse", &a)], &png, &svg).unwrap();
    assert_png(&png, (900, 650));
    let text = assert_svg(
        &svg,
        &[
            "Free-end displacement FED (mm)",
            "Mean bond stress σ_mb (MPa)",
        ],
    );
    assert!(
        !text.contains("R1 coarse"),
        "a single curve needs no legend"
    );

    let (png, svg) = (dir.join("study.png"), dir.join("study.svg"));
    bond_slip_plot(
        &[("δs = 0.02", &a), ("δs = 0.16", &b), ("δs = 1.0", &c)],
        &png,
        &svg,
    )
    .unwrap();
    assert_png(&png, (900, 650));
    assert_svg(&svg, &["δs = 0.02", "δs = 0.16", "δs = 1.0"]);
    // No temporary files are left beside the results.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Interface normal and shear traction along the bar at several steps, in
/// two panels as in Fig. 12 of Abbas, Bary & Jason (2023).
#[test]
fn interface_line_plot_written() {
    let dir = scratch("interface");
    let l = 5e-3 * 5.0; // bonded length, m
    let profiles: Vec<InterfaceProfile> = [(0.1, 1.0), (0.5, 0.6), (1.5, 0.3)]
        .iter()
        .map(|&(fed, k)| InterfaceProfile {
            label: format!("FED = {fed} mm"),
            samples: (0..=80)
                .rev()
                .map(|i| {
                    let z = l * i as f64 / 80.0;
                    let end = (-(z / 1.5e-3)).exp() + (-((l - z) / 1.5e-3)).exp();
                    InterfaceSample {
                        z,
                        normal: -1e6 * (0.8 + 3.0 * end / k),
                        shear: 4e6 * k * (1.0 - end),
                    }
                })
                .collect(),
        })
        .collect();
    let (png, svg) = (dir.join("interface.png"), dir.join("interface.svg"));
    interface_line_plot(&profiles, &png, &svg).unwrap();
    assert_png(&png, (1400, 600));
    assert_svg(
        &svg,
        &[
            "Normal traction t_n (MPa)",
            "Shear traction t_t (MPa)",
            "Position along the bar z (mm)",
            "FED = 0.5 mm",
        ],
    );
}

/// Error against wall time on log–log axes for several quantities, built
/// from convergence studies; non-positive errors are left out.
#[test]
fn error_vs_time_plot_written() {
    let dir = scratch("error_time");
    let h = [0.4e-3, 0.6e-3, 0.9e-3, 1.6e-3];
    let study = |name: &str, f0: f64, c: f64, p: f64| {
        let grids: Vec<GridResult> = h
            .iter()
            .map(|&h| GridResult {
                h,
                value: f0 + c * (h * 1e3).powf(p),
                dofs: Some((2e4 / (h * 1e3).powi(3)) as u64),
                wall_time: Some(3.0 / (h * 1e3).powi(3)),
            })
            .collect();
        convergence_study(name, &grids).unwrap()
    };
    let mut series = vec![
        ErrorTimeSeries::from_study(&study("peak σ_mb", 9.0, 0.8, 1.6)),
        ErrorTimeSeries::from_study(&study("FED at peak", 0.2, 0.05, 1.1)),
        ErrorTimeSeries::from_study(&study("energy", 5000.0, 300.0, 2.0)),
    ];
    assert_eq!(series[0].points.len(), 4);
    series[2].points.push((1.0, 0.0));
    let (png, svg) = (dir.join("err.png"), dir.join("err.svg"));
    error_vs_time_plot(&series, &png, &svg).unwrap();
    assert_png(&png, (900, 650));
    assert_svg(
        &svg,
        &["Wall time (s)", "Relative error", "peak σ_mb", "energy"],
    );
}

/// Plots refuse empty or non-finite input with a typed error instead of
/// drawing a misleading figure (SPEC §8).
#[test]
fn plots_refuse_bad_input() {
    let dir = scratch("bad");
    let (png, svg) = (dir.join("x.png"), dir.join("x.svg"));
    let e = bond_slip_plot(&[], &png, &svg).unwrap_err();
    assert!(matches!(e, PostError::InvalidInput { .. }), "{e}");
    let nan = vec![CurveRow::new(1, 0.0, 0.0, 1e-4, f64::NAN, 1)];
    let e = bond_slip_plot(&[("bad case", &nan)], &png, &svg).unwrap_err();
    assert!(e.to_string().contains("bad case"), "{e}");
    let zero = [ErrorTimeSeries {
        label: "q".into(),
        points: vec![(1.0, 0.0), (0.0, 0.1)],
    }];
    assert!(error_vs_time_plot(&zero, &png, &svg).is_err());
    assert!(interface_line_plot(&[], &png, &svg).is_err());
    assert!(!png.exists() && !svg.exists());
}

/// The font is found on a machine with fonts-dejavu-core, and the error for
/// a missing font tells how to install it.
#[test]
fn font_found_or_explained() {
    let path = ensure_font().unwrap();
    assert!(
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ttf")),
        "{}",
        path.display()
    );
    let msg = PostError::FontNotFound {
        searched: "/usr/share/fonts".into(),
    }
    .to_string();
    assert!(msg.contains("fonts-dejavu-core"), "{msg}");
}
