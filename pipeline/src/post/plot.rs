//! Plots in the look of an experimental paper: white background, boxed
//! black axes, light grid, one colour and marker shape per series, axes in
//! MPa and mm.
//!
//! Text is drawn with a TrueType font read at run time (DejaVu Sans from
//! Debian's `fonts-dejavu-core`, or another `.ttf` under the system font
//! directories), so plotting needs no font-configuration libraries.

use super::curve::CurveRow;
use super::error::PostError;
use super::fsutil::{commit, create_parent, temp_sibling, write_atomic};
use plotters::coord::Shift;
/// Pixel coordinates of the drawing backend.
type BackendCoord = (i32, i32);
use plotters::coord::combinators::{LogCoord, WithKeyPoints};
use plotters::coord::types::RangedCoordf64;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Font family name the plots ask for; [`ensure_font`] registers it.
pub const FONT_FAMILY: &str = "sans-serif";

/// Size of single-panel plots, px (SVG user units).
pub(super) const SIZE: (u32, u32) = (900, 650);
/// Size of the two-panel interface plot.
const WIDE: (u32, u32) = (1400, 600);

pub(super) const AXIS_TITLE: u32 = 22;
pub(super) const TICK_LABEL: u32 = 17;
pub(super) const LEGEND: u32 = 17;

/// Series colours: black first, as single-curve figures are in papers.
pub(super) const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(200, 30, 30),
    RGBColor(30, 80, 200),
    RGBColor(20, 140, 60),
    RGBColor(230, 130, 0),
    RGBColor(130, 50, 160),
    RGBColor(0, 150, 170),
    RGBColor(120, 120, 120),
];
/// Marker shapes cycle more slowly than colours so that series stay
/// distinct in greyscale print too.
const MARKERS: usize = 5;
/// At most this many markers per series; the line carries the shape.
const MARKERS_PER_SERIES: usize = 14;

/// One sample of interface traction along the bar axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceSample {
    /// Position along the bar axis, m.
    pub z: f64,
    /// Normal traction t_n, Pa (positive in tension, negative in contact).
    pub normal: f64,
    /// Shear traction along the bar axis t_t, Pa.
    pub shear: f64,
}

/// Interface tractions along a line at one load step.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceProfile {
    /// Legend text, e.g. "FED = 0.25 mm".
    pub label: String,
    /// Samples in any order; they are drawn sorted by `z`.
    pub samples: Vec<InterfaceSample>,
}

/// Error of one quantity against wall time over a mesh (or settings) series.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorTimeSeries {
    /// Legend text (quantity name).
    pub label: String,
    /// (wall time in s, relative error, dimensionless). Points with a
    /// non-positive time or error cannot appear on log axes and are left out.
    pub points: Vec<(f64, f64)>,
}

impl ErrorTimeSeries {
    /// Relative error against the Richardson extrapolation versus wall time,
    /// for the grids of a convergence study that have a wall time.
    pub fn from_study(study: &super::convergence::ConvergenceStudy) -> Self {
        ErrorTimeSeries {
            label: study.quantity.clone(),
            points: study
                .rows()
                .iter()
                .filter_map(|r| Some((r.wall_time?, r.rel_error_vs_extrapolated?)))
                .collect(),
        }
    }

    /// The least-squares uncertainty U/|φ| (four grids or more) versus
    /// wall time: an error bar also for series whose triplets give no
    /// extrapolation.
    pub fn uncertainty_from_study(study: &super::convergence::ConvergenceStudy) -> Self {
        ErrorTimeSeries {
            label: format!("U: {}", study.quantity),
            points: study
                .rows()
                .iter()
                .filter_map(|r| Some((r.wall_time?, r.uncertainty?)))
                .collect(),
        }
    }
}

// ---------------------------------------------------------------- fonts --

static FONT: OnceLock<Result<PathBuf, String>> = OnceLock::new();

/// Directories searched for a `.ttf`, after the preferred files.
const FONT_DIRS: [&str; 3] = [
    "/usr/share/fonts",
    "/usr/local/share/fonts",
    "/usr/share/fonts/truetype",
];
/// Preferred fonts, best first.
const PREFERRED_FONTS: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
];

fn collect_ttf(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() && depth > 0 {
            collect_ttf(&p, depth - 1, out);
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ttf")) {
            out.push(p);
        }
    }
}

fn load_font() -> Result<PathBuf, String> {
    let mut candidates: Vec<PathBuf> = PREFERRED_FONTS.iter().map(PathBuf::from).collect();
    let mut found = Vec::new();
    for dir in FONT_DIRS {
        collect_ttf(Path::new(dir), 4, &mut found);
    }
    // Upright regular faces read best; prefer them over bold/italic/mono.
    let plain = |p: &PathBuf| {
        let n = p
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_lowercase();
        ["bold", "italic", "oblique", "mono", "light", "math"]
            .iter()
            .all(|w| !n.contains(w))
    };
    let (first, rest): (Vec<_>, Vec<_>) = found.into_iter().partition(plain);
    candidates.extend(first);
    candidates.extend(rest);
    for path in candidates {
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        // The font table of plotters holds fonts for the whole process.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        if plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, bytes).is_ok() {
            return Ok(path);
        }
    }
    Err(format!(
        "{} and every .ttf under {}",
        PREFERRED_FONTS[0],
        FONT_DIRS[..2].join(", ")
    ))
}

/// Finds and registers the plot font once per process; returns its path.
/// Errors with [`PostError::FontNotFound`] (which says to install
/// `fonts-dejavu-core`) when no usable TrueType font exists.
pub fn ensure_font() -> Result<PathBuf, PostError> {
    FONT.get_or_init(load_font)
        .clone()
        .map_err(|searched| PostError::FontNotFound { searched })
}

// ------------------------------------------------------------ rendering --

pub(super) type DrawResult = Result<(), Box<dyn Error>>;

pub(super) fn render_png<F>(path: &Path, size: (u32, u32), draw: F) -> Result<(), PostError>
where
    F: FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> DrawResult,
{
    ensure_font()?;
    create_parent(path)?;
    let tmp = temp_sibling(path);
    let plot_err = |e: &dyn Error| PostError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let result = (|| -> DrawResult {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        draw(&root)?;
        root.present()?;
        Ok(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(plot_err(e.as_ref()));
    }
    commit(&tmp, path)
}

pub(super) fn render_svg<F>(path: &Path, size: (u32, u32), draw: F) -> Result<(), PostError>
where
    F: FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> DrawResult,
{
    ensure_font()?;
    let mut text = String::new();
    {
        let result = (|| -> DrawResult {
            let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
            draw(&root)?;
            root.present()?;
            Ok(())
        })();
        result.map_err(|e| PostError::Plot {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    }
    write_atomic(path, text.as_bytes())
}

/// Indices of at most [`MARKERS_PER_SERIES`] evenly spread points; dense
/// series start at a phase that depends on the series so that markers of
/// curves sharing a start (the origin) do not pile up.
fn marker_indices(n: usize, series: usize) -> impl Iterator<Item = usize> {
    let stride = n.div_ceil(MARKERS_PER_SERIES).max(1);
    let start = if stride > 1 {
        (1 + series * stride / 3) % stride
    } else {
        0
    };
    (start..n).step_by(stride)
}

/// Draws one series (line plus sparse markers) with its legend entry; the
/// marker shape cycles with `index`.
pub(super) fn draw_series<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    points: &[(f64, f64)],
    index: usize,
    label: Option<&str>,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let color = PALETTE[index % PALETTE.len()];
    chart.draw_series(LineSeries::new(
        points.iter().copied(),
        color.stroke_width(2),
    ))?;
    let r = 5;
    // One arm per shape: each shape is its own element type.
    macro_rules! with_shape {
        ($shape:expr) => {{
            let shape = $shape;
            draw_with(
                chart,
                points,
                index,
                label,
                move |c| EmptyElement::at(c) + shape((0, 0)),
                move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0i32, 0i32), (26, 0)], color.stroke_width(2))
                        + shape((13, 0))
                },
            )
        }};
    }
    match index % MARKERS {
        0 => with_shape!(move |c: BackendCoord| Circle::new(c, r, color.filled())),
        1 => with_shape!(move |(x, y): BackendCoord| {
            Rectangle::new([(x - r, y - r), (x + r, y + r)], color.filled())
        }),
        2 => with_shape!(move |c: BackendCoord| TriangleMarker::new(c, r + 1, color.filled())),
        3 => with_shape!(move |c: BackendCoord| Circle::new(c, r, color.stroke_width(2))),
        _ => with_shape!(move |(x, y): BackendCoord| {
            Rectangle::new([(x - r, y - r), (x + r, y + r)], color.stroke_width(2))
        }),
    }
}

/// Markers of one series, carrying its legend entry (line and marker).
fn draw_with<'a, DB, X, Y, M, L>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    points: &[(f64, f64)],
    series: usize,
    label: Option<&str>,
    marker: impl Fn((f64, f64)) -> M,
    legend: impl Fn(BackendCoord) -> L + 'a,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
    M: Drawable<DB>,
    for<'b> &'b M: PointCollection<'b, (f64, f64)>,
    L: IntoDynElement<'a, DB, BackendCoord>,
{
    let markers =
        chart.draw_series(marker_indices(points.len(), series).map(|i| marker(points[i])))?;
    if let Some(label) = label {
        markers.label(label).legend(legend);
    }
    Ok(())
}

/// (min, max) of `values` padded for plotting; a degenerate span gets a unit width.
pub(super) fn padded_range(values: impl Iterator<Item = f64>, include_zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if include_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * span;
    (
        if lo == 0.0 { 0.0 } else { lo - pad },
        if hi == 0.0 { 0.0 } else { hi + pad },
    )
}

/// Tick label with no more digits than the tick spacing needs.
pub(super) fn tick(v: &f64) -> String {
    let s = format!("{:.3}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

pub(super) fn check_finite(what: &str, values: impl Iterator<Item = f64>) -> Result<(), PostError> {
    for v in values {
        if !v.is_finite() {
            return Err(PostError::invalid(
                what,
                "contains a value that is not finite",
            ));
        }
    }
    Ok(())
}

// ------------------------------------------------------------ bond–slip --

fn check_curves(curves: &[(&str, &[CurveRow])]) -> Result<(), PostError> {
    if curves.is_empty() || curves.iter().all(|(_, rows)| rows.is_empty()) {
        return Err(PostError::invalid(
            "bond–slip plot",
            "no curve has any point",
        ));
    }
    for (label, rows) in curves {
        check_finite(
            &format!("curve `{label}`"),
            rows.iter().flat_map(|r| [r.fed, r.bond_stress]),
        )?;
    }
    Ok(())
}

fn draw_bond_slip<DB>(
    root: &DrawingArea<DB, Shift>,
    curves: &[(&str, &[CurveRow])],
    references: &[ReferenceCurve],
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    // With the unloaded state included the axes start at the origin, as in
    // the experimental figures.
    let series: Vec<Vec<(f64, f64)>> = curves
        .iter()
        .map(|(_, rows)| {
            std::iter::once((0.0, 0.0))
                .chain(rows.iter().map(|r| (r.fed * 1e3, r.bond_stress * 1e-6)))
                .collect()
        })
        .collect();
    let lines: Vec<Vec<(f64, f64)>> = references
        .iter()
        .map(|r| r.points.iter().map(|&(s, t)| (s * 1e3, t * 1e-6)).collect())
        .collect();
    let (x0, x1) = padded_range(series.iter().flatten().map(|p| p.0), true);
    let (y0, y1) = padded_range(series.iter().chain(&lines).flatten().map(|p| p.1), true);
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .x_label_area_size(65)
        .y_label_area_size(85)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    style_mesh(
        &mut chart,
        "Free-end displacement FED (mm)",
        "Mean bond stress σ_mb (MPa)",
    )?;
    // A legend of more curves than this would cover the plot; a study's
    // table names its cases.
    const MAX_LEGEND: usize = 12;
    let legend = (curves.len() > 1 && curves.len() <= MAX_LEGEND) || !references.is_empty();
    for (i, ((label, _), pts)) in curves.iter().zip(&series).enumerate() {
        draw_series(&mut chart, pts, i, legend.then_some(*label))?;
    }
    for (i, (reference, pts)) in references.iter().zip(&lines).enumerate() {
        let color = PALETTE[(curves.len() + i) % PALETTE.len()];
        let style = color.stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(pts.iter().copied(), 10, 6, style))?
            .label(reference.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 26, y)], style));
    }
    frame(&mut chart, (x0, x1), (y0, y1))?;
    if legend {
        draw_legend(&mut chart)?;
    }
    Ok(())
}

pub(super) fn style_mesh<'a, DB>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    x_desc: &str,
    y_desc: &str,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT_FAMILY, AXIS_TITLE))
        .label_style((FONT_FAMILY, TICK_LABEL))
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_labels(10)
        .y_labels(10)
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(218, 218, 218))
        .axis_style(BLACK.stroke_width(1))
        .draw()?;
    Ok(())
}

/// A black box around the plotting area.
pub(super) fn frame<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart.draw_series(std::iter::once(Rectangle::new(
        [(x0, y0), (x1, y1)],
        BLACK.stroke_width(1),
    )))?;
    Ok(())
}

pub(super) fn draw_legend<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .margin(12)
        .legend_area_size(34)
        .label_font((FONT_FAMILY, LEGEND))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// A law drawn as a dashed line beside the curves (a design code's, a fit).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceCurve {
    /// Legend text.
    pub label: String,
    /// (slip m, τ Pa).
    pub points: Vec<(f64, f64)>,
}

/// Writes the σ_mb–FED plot (MPa against mm) as PNG.
pub fn bond_slip_png(curves: &[(&str, &[CurveRow])], png: &Path) -> Result<(), PostError> {
    bond_slip_with_laws_png(curves, &[], png)
}

/// Writes the σ_mb–FED plot (MPa against mm) as SVG.
pub fn bond_slip_svg(curves: &[(&str, &[CurveRow])], svg: &Path) -> Result<(), PostError> {
    bond_slip_with_laws_svg(curves, &[], svg)
}

fn check_references(references: &[ReferenceCurve]) -> Result<(), PostError> {
    for r in references {
        check_finite(
            &format!("law `{}`", r.label),
            r.points.iter().flat_map(|p| [p.0, p.1]),
        )?;
    }
    Ok(())
}

/// The σ_mb–FED plot with `references` (laws) drawn dashed, as PNG.
pub fn bond_slip_with_laws_png(
    curves: &[(&str, &[CurveRow])],
    references: &[ReferenceCurve],
    png: &Path,
) -> Result<(), PostError> {
    check_curves(curves)?;
    check_references(references)?;
    render_png(png, SIZE, |root| draw_bond_slip(root, curves, references))
}

/// The σ_mb–FED plot with `references` (laws) drawn dashed, as SVG.
pub fn bond_slip_with_laws_svg(
    curves: &[(&str, &[CurveRow])],
    references: &[ReferenceCurve],
    svg: &Path,
) -> Result<(), PostError> {
    check_curves(curves)?;
    check_references(references)?;
    render_svg(svg, SIZE, |root| draw_bond_slip(root, curves, references))
}

/// Mean bond stress against free-end displacement for one or several
/// labelled curves (a legend is drawn when there are several), as PNG and SVG.
/// Parent directories are created; files are replaced atomically.
pub fn bond_slip_plot(
    curves: &[(&str, &[CurveRow])],
    png: &Path,
    svg: &Path,
) -> Result<(), PostError> {
    bond_slip_png(curves, png)?;
    bond_slip_svg(curves, svg)
}

// ------------------------------------------------------ interface lines --

fn check_profiles(profiles: &[InterfaceProfile]) -> Result<(), PostError> {
    if profiles.is_empty() || profiles.iter().all(|p| p.samples.is_empty()) {
        return Err(PostError::invalid(
            "interface line plot",
            "no profile has any sample",
        ));
    }
    for p in profiles {
        check_finite(
            &format!("interface profile `{}`", p.label),
            p.samples.iter().flat_map(|s| [s.z, s.normal, s.shear]),
        )?;
    }
    Ok(())
}

fn draw_interface<DB>(root: &DrawingArea<DB, Shift>, profiles: &[InterfaceProfile]) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let sorted: Vec<Vec<InterfaceSample>> = profiles
        .iter()
        .map(|p| {
            let mut s = p.samples.clone();
            s.sort_by(|a, b| a.z.total_cmp(&b.z));
            s
        })
        .collect();
    let (x0, x1) = padded_range(sorted.iter().flatten().map(|s| s.z * 1e3), false);
    let (left, right) = root.split_horizontally(root.dim_in_pixel().0 / 2);
    type Pick = fn(&InterfaceSample) -> f64;
    let panels: [(&DrawingArea<DB, Shift>, &str, Pick); 2] = [
        (&left, "Normal traction t_n (MPa)", |s| s.normal),
        (&right, "Shear traction t_t (MPa)", |s| s.shear),
    ];
    for (area, y_desc, value) in panels {
        let series: Vec<Vec<(f64, f64)>> = sorted
            .iter()
            .map(|s| s.iter().map(|s| (s.z * 1e3, value(s) * 1e-6)).collect())
            .collect();
        let (y0, y1) = padded_range(series.iter().flatten().map(|p| p.1), true);
        let mut chart = ChartBuilder::on(area)
            .margin(20)
            .x_label_area_size(65)
            .y_label_area_size(85)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        style_mesh(&mut chart, "Position along the bar z (mm)", y_desc)?;
        for (i, (p, pts)) in profiles.iter().zip(&series).enumerate() {
            draw_series(&mut chart, pts, i, Some(&p.label))?;
        }
        frame(&mut chart, (x0, x1), (y0, y1))?;
        draw_legend(&mut chart)?;
    }
    Ok(())
}

/// Writes the interface traction plot as PNG (see [`interface_line_plot`]).
pub fn interface_line_png(profiles: &[InterfaceProfile], png: &Path) -> Result<(), PostError> {
    check_profiles(profiles)?;
    render_png(png, WIDE, |root| draw_interface(root, profiles))
}

/// Writes the interface traction plot as SVG (see [`interface_line_plot`]).
pub fn interface_line_svg(profiles: &[InterfaceProfile], svg: &Path) -> Result<(), PostError> {
    check_profiles(profiles)?;
    render_svg(svg, WIDE, |root| draw_interface(root, profiles))
}

/// Normal (left panel) and shear (right panel) interface traction, MPa,
/// along the bar axis z, mm, one line per profile (load step), as in Fig. 12
/// of Abbas, Bary & Jason (2023). PNG and SVG.
pub fn interface_line_plot(
    profiles: &[InterfaceProfile],
    png: &Path,
    svg: &Path,
) -> Result<(), PostError> {
    interface_line_png(profiles, png)?;
    interface_line_svg(profiles, svg)
}

// ---------------------------------------------------- error against time --

fn positive_series(series: &[ErrorTimeSeries]) -> Result<Vec<Vec<(f64, f64)>>, PostError> {
    let kept: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            let mut pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(t, e)| t.is_finite() && e.is_finite() && t > 0.0 && e > 0.0)
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts
        })
        .collect();
    if kept.iter().all(Vec::is_empty) {
        return Err(PostError::invalid(
            "error against time plot",
            "no point has a positive wall time and a positive error",
        ));
    }
    Ok(kept)
}

/// Log-axis range: the data's decade span, widened by a factor 1.5 each side.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if hi / lo < 1.5 {
        (lo / 2.0, hi * 2.0)
    } else {
        (lo / 1.5, hi * 1.5)
    }
}

/// A log axis ticked at 1-2-5 steps (1 per decade when the span is wide),
/// with light grid lines at the integer multiples of each decade. The
/// default key points of plotters repeat labels near decade boundaries.
fn log_axis(lo: f64, hi: f64) -> WithKeyPoints<LogCoord<f64>> {
    let decade = |m: u32, d: i32| format!("{m}e{d}").parse::<f64>().unwrap_or(f64::NAN);
    let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mults: &[u32] = if d1 - d0 > 3 { &[1] } else { &[1, 2, 5] };
    let inside = |v: &f64| *v >= lo && *v <= hi;
    let bold: Vec<f64> = (d0..=d1)
        .flat_map(|d| mults.iter().map(move |&m| decade(m, d)))
        .filter(inside)
        .collect();
    let light: Vec<f64> = (d0..=d1)
        .flat_map(|d| (1..10).map(move |m| decade(m, d)))
        .filter(inside)
        .collect();
    (lo..hi)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

fn log_tick(v: &f64) -> String {
    if (1e-3..1e4).contains(&v.abs()) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

fn draw_error_time<DB>(
    root: &DrawingArea<DB, Shift>,
    series: &[ErrorTimeSeries],
    pts: &[Vec<(f64, f64)>],
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (x0, x1) = log_range(pts.iter().flatten().map(|p| p.0));
    let (y0, y1) = log_range(pts.iter().flatten().map(|p| p.1));
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .x_label_area_size(65)
        .y_label_area_size(85)
        .build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))?;
    chart
        .configure_mesh()
        .x_desc("Wall time (s)")
        .y_desc("Relative error, uncertainty U (–)")
        .axis_desc_style((FONT_FAMILY, AXIS_TITLE))
        .label_style((FONT_FAMILY, TICK_LABEL))
        .x_label_formatter(&log_tick)
        .y_label_formatter(&log_tick)
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(218, 218, 218))
        .axis_style(BLACK.stroke_width(1))
        .draw()?;
    for (i, (s, p)) in series.iter().zip(pts).enumerate() {
        if !p.is_empty() {
            draw_series(&mut chart, p, i, Some(&s.label))?;
        }
    }
    frame(&mut chart, (x0, x1), (y0, y1))?;
    draw_legend(&mut chart)?;
    Ok(())
}

/// Writes the error-against-time plot as PNG (see [`error_vs_time_plot`]).
pub fn error_vs_time_png(series: &[ErrorTimeSeries], png: &Path) -> Result<(), PostError> {
    let pts = positive_series(series)?;
    render_png(png, SIZE, |root| draw_error_time(root, series, &pts))
}

/// Writes the error-against-time plot as SVG (see [`error_vs_time_plot`]).
pub fn error_vs_time_svg(series: &[ErrorTimeSeries], svg: &Path) -> Result<(), PostError> {
    let pts = positive_series(series)?;
    render_svg(svg, SIZE, |root| draw_error_time(root, series, &pts))
}

/// Relative error against wall time on log–log axes, one series per
/// quantity, as PNG and SVG.
pub fn error_vs_time_plot(
    series: &[ErrorTimeSeries],
    png: &Path,
    svg: &Path,
) -> Result<(), PostError> {
    error_vs_time_png(series, png)?;
    error_vs_time_svg(series, svg)
}
