//! Plots of sampled studies: each response against each parameter with
//! its least-squares trend, and the sensitivity indices as bars, one panel
//! per response. Same look as the other plots (`plot`).

use super::plot::{
    check_finite, draw_legend, frame, padded_range, render_png, render_svg, DrawResult, AXIS_TITLE,
    PALETTE, TICK_LABEL,
};
// The trend line is red (PALETTE[1]) over black points (PALETTE[0]).
use super::error::PostError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Size of one panel of a grid, px.
const PANEL: (u32, u32) = (520, 400);
/// Panels per row of a grid.
const COLUMNS: usize = 3;

/// A straight line y = intercept + slope x' fitted by least squares, x'
/// the abscissa or its base-10 logarithm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrendLine {
    pub intercept: f64,
    pub slope: f64,
    /// Coefficient of determination of the fit.
    pub r2: f64,
    pub log_x: bool,
}

impl TrendLine {
    pub fn at(&self, x: f64) -> f64 {
        let x = if self.log_x { x.log10() } else { x };
        self.intercept + self.slope * x
    }
}

/// The least-squares line through `points` (x, y), in log10 x when
/// `log_x`; none for fewer than 3 points or a constant x.
pub fn trend_line(points: &[(f64, f64)], log_x: bool) -> Option<TrendLine> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .map(|&(x, y)| (if log_x { x.log10() } else { x }, y))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my) * (p.1 - my)).sum();
    if sxx <= 1e-300 * n {
        return None;
    }
    let slope = sxy / sxx;
    Some(TrendLine {
        intercept: my - slope * mx,
        slope,
        r2: if syy > 0.0 {
            sxy * sxy / (sxx * syy)
        } else {
            1.0
        },
        log_x,
    })
}

/// One panel of a trend plot: a response against one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct TrendPanel {
    /// Axis title, unit included.
    pub x_label: String,
    /// (x, y) in the units of the axis titles.
    pub points: Vec<(f64, f64)>,
    pub trend: Option<TrendLine>,
}

fn grid<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    n: usize,
) -> Vec<DrawingArea<DB, Shift>> {
    let rows = n.div_ceil(COLUMNS).max(1);
    let cols = n.clamp(1, COLUMNS);
    root.split_evenly((rows, cols))
}

fn grid_size(n: usize) -> (u32, u32) {
    let rows = n.div_ceil(COLUMNS).max(1) as u32;
    let cols = n.clamp(1, COLUMNS) as u32;
    (PANEL.0 * cols, PANEL.1 * rows)
}

fn draw_trends<DB>(
    root: &DrawingArea<DB, Shift>,
    y_label: &str,
    panels: &[TrendPanel],
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    for (area, panel) in grid(root, panels.len()).iter().zip(panels) {
        let (x0, x1) = padded_range(panel.points.iter().map(|p| p.0), false);
        let (y0, y1) = padded_range(panel.points.iter().map(|p| p.1), false);
        let mut chart = ChartBuilder::on(area)
            .margin(14)
            .x_label_area_size(55)
            .y_label_area_size(75)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        // The trend's R² in the axis title, where no legend hides a point.
        let x_desc = match panel.trend {
            Some(t) => format!(
                "{}; trend{}: R² = {:.2}",
                panel.x_label,
                if t.log_x { " in log x" } else { "" },
                t.r2
            ),
            None => panel.x_label.clone(),
        };
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_label)
            .axis_desc_style((super::plot::FONT_FAMILY, AXIS_TITLE - 4))
            .label_style((super::plot::FONT_FAMILY, TICK_LABEL - 2))
            .x_labels(6)
            .y_labels(6)
            .light_line_style(RGBColor(244, 244, 244))
            .bold_line_style(RGBColor(218, 218, 218))
            .axis_style(BLACK.stroke_width(1))
            .draw()?;
        chart.draw_series(
            panel
                .points
                .iter()
                .map(|&p| Circle::new(p, 4, PALETTE[0].filled())),
        )?;
        if let Some(t) = panel.trend {
            let line: Vec<(f64, f64)> = (0..=60)
                .map(|i| x0 + (x1 - x0) * i as f64 / 60.0)
                .filter(|&x| !t.log_x || x > 0.0)
                .map(|x| (x, t.at(x)))
                .filter(|&(_, y)| y >= y0 && y <= y1)
                .collect();
            chart.draw_series(LineSeries::new(line, PALETTE[1].stroke_width(2)))?;
        }
        frame(&mut chart, (x0, x1), (y0, y1))?;
    }
    Ok(())
}

fn check_panels(panels: &[TrendPanel]) -> Result<(), PostError> {
    if panels.is_empty() || panels.iter().all(|p| p.points.is_empty()) {
        return Err(PostError::invalid("trend plot", "no panel has any point"));
    }
    for p in panels {
        check_finite(
            &format!("trend panel `{}`", p.x_label),
            p.points.iter().flat_map(|q| [q.0, q.1]),
        )?;
    }
    Ok(())
}

/// A response (`y_label`, unit included) against each parameter, one
/// panel each with its points and trend line, as PNG and SVG.
pub fn trend_plot(
    y_label: &str,
    panels: &[TrendPanel],
    png: &Path,
    svg: &Path,
) -> Result<(), PostError> {
    check_panels(panels)?;
    let size = grid_size(panels.len());
    render_png(png, size, |root| draw_trends(root, y_label, panels))?;
    render_svg(svg, size, |root| draw_trends(root, y_label, panels))
}

/// One measure of a response's indices (S1, ST, μ*, σ): per parameter its
/// value and, where it has one, its confidence half-width.
#[derive(Debug, Clone, PartialEq)]
pub struct Measure {
    pub name: String,
    pub bars: Vec<(f64, Option<f64>)>,
}

/// The indices of one response: one group of bars per parameter, one bar
/// per measure (S1 and ST, or μ* and σ).
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityBars {
    pub response: String,
    pub parameters: Vec<String>,
    pub measures: Vec<Measure>,
}

fn draw_bars<DB>(
    root: &DrawingArea<DB, Shift>,
    y_label: &str,
    panels: &[SensitivityBars],
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    for (area, panel) in grid(root, panels.len()).iter().zip(panels) {
        let p = panel.parameters.len();
        let tops = panel
            .measures
            .iter()
            .flat_map(|m| m.bars.iter().map(|(x, c)| x + c.unwrap_or(0.0)));
        let lows = panel
            .measures
            .iter()
            .flat_map(|m| m.bars.iter().map(|(x, c)| x - c.unwrap_or(0.0)));
        let (y0, y1) = padded_range(tops.chain(lows), true);
        let names = panel.parameters.clone();
        let mut chart = ChartBuilder::on(area)
            .margin(14)
            .caption(&panel.response, (super::plot::FONT_FAMILY, AXIS_TITLE - 4))
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..p as f64 - 0.5, y0..y1)?;
        chart
            .configure_mesh()
            .y_desc(y_label)
            .axis_desc_style((super::plot::FONT_FAMILY, AXIS_TITLE - 4))
            .label_style((super::plot::FONT_FAMILY, TICK_LABEL - 3))
            // Ticks at unit steps fall on the parameters; any other tick
            // is left blank.
            .x_labels(p + 1)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-9 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_labels(6)
            .light_line_style(RGBColor(244, 244, 244))
            .bold_line_style(RGBColor(218, 218, 218))
            .axis_style(BLACK.stroke_width(1))
            .draw()?;
        let groups = panel.measures.len().max(1) as f64;
        let width = 0.8 / groups;
        for (m, Measure { name, bars: values }) in panel.measures.iter().enumerate() {
            let color = PALETTE[(m + 1) % PALETTE.len()];
            let left = |i: usize| i as f64 - 0.4 + width * m as f64;
            chart
                .draw_series(values.iter().enumerate().map(|(i, (v, _))| {
                    Rectangle::new(
                        [(left(i), 0.0), (left(i) + width * 0.9, *v)],
                        color.filled(),
                    )
                }))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 18, y + 6)], color.filled())
                });
            for (i, (v, conf)) in values.iter().enumerate() {
                let Some(c) = conf else { continue };
                let mid = left(i) + width * 0.45;
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(mid, v - c), (mid, v + c)],
                    BLACK.stroke_width(1),
                )))?;
            }
        }
        frame(&mut chart, (-0.5, p as f64 - 0.5), (y0, y1))?;
        draw_legend(&mut chart)?;
    }
    Ok(())
}

/// The sensitivity indices of each response as grouped bars, one panel per
/// response, as PNG and SVG.
pub fn sensitivity_plot(
    y_label: &str,
    panels: &[SensitivityBars],
    png: &Path,
    svg: &Path,
) -> Result<(), PostError> {
    if panels.is_empty() {
        return Err(PostError::invalid(
            "sensitivity plot",
            "no response has indices",
        ));
    }
    for p in panels {
        check_finite(
            &format!("indices of `{}`", p.response),
            p.measures
                .iter()
                .flat_map(|m| m.bars.iter().flat_map(|(x, c)| [*x, c.unwrap_or(0.0)])),
        )?;
    }
    let size = grid_size(panels.len());
    render_png(png, size, |root| draw_bars(root, y_label, panels))?;
    render_svg(svg, size, |root| draw_bars(root, y_label, panels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trend of points on a line is that line with R² = 1, in x or in
    /// log10 x; too few points or a constant x give none.
    #[test]
    fn trends_fit_lines() {
        let pts: Vec<(f64, f64)> = (1..=5).map(|i| (i as f64, 3.0 + 2.0 * i as f64)).collect();
        let t = trend_line(&pts, false).unwrap();
        assert!((t.slope - 2.0).abs() < 1e-12 && (t.r2 - 1.0).abs() < 1e-12);
        let logs: Vec<(f64, f64)> = [1.0, 10.0, 100.0]
            .iter()
            .map(|&x: &f64| (x, x.log10()))
            .collect();
        let t = trend_line(&logs, true).unwrap();
        assert!((t.at(1000.0) - 3.0).abs() < 1e-12);
        assert!(trend_line(&pts[..2], false).is_none());
        assert!(trend_line(&[(1.0, 1.0), (1.0, 2.0), (1.0, 3.0)], false).is_none());
    }
}
