//! The line chart.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::Path;

use super::{FONT, SERIES_COLORS, drawing, px, save_png, tick};

/// A named series of `(x, y)` points.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points, drawn joined in the given order, each with a small marker.
    pub points: Vec<(f64, f64)>,
}

/// A line chart.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LineChart {
    /// Title above the chart.
    pub title: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Logarithmic horizontal axis (points with `x <= 0` are left out).
    pub log_x: bool,
    /// Logarithmic vertical axis (points with `y <= 0` are left out).
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
}

fn padded_range(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let pad = ((b - a) * 0.05).max(0.05);
        (10f64.powf(a - pad), 10f64.powf(b + pad))
    } else {
        let pad = ((hi - lo) * 0.05).max(1e-12 * lo.abs().max(hi.abs()).max(1e-300));
        (lo - pad, hi + pad)
    }
}

/// A series as drawn: its name and `(x, y, error bar half-width)` points.
type Drawn<'a> = (&'a str, Vec<(f64, f64, f64)>);

/// Draws a line chart to a PNG of `size` pixels.
pub fn line_chart(path: &Path, chart: &LineChart, size: (u32, u32)) -> Result<()> {
    line_chart_with_errors(path, chart, &[], size)
}

/// [`line_chart`] with error bars: `errors[s][k]` is the half-width of the bar at point
/// `k` of series `s` (a series without an entry, or a zero, has none).
pub fn line_chart_with_errors(
    path: &Path,
    chart: &LineChart,
    errors: &[Vec<f64>],
    size: (u32, u32),
) -> Result<()> {
    save_png(path, size, |root, k| draw_chart(root, chart, errors, k))
}

/// Line charts stacked in one PNG of `size` pixels, each in an equal band, top first
/// (related cases, each with its own axes).
pub fn line_charts(path: &Path, charts: &[LineChart], size: (u32, u32)) -> Result<()> {
    save_png(path, size, |root, k| {
        let bands = root.split_evenly((charts.len().max(1), 1));
        for (band, chart) in bands.iter().zip(charts) {
            draw_chart(band, chart, &[], k)?;
        }
        Ok(())
    })
}

/// The points of `chart` as drawn, with their error bars: those a logarithmic axis
/// can show, every value finite.
fn drawn<'a>(chart: &'a LineChart, errors: &[Vec<f64>]) -> Vec<Drawn<'a>> {
    let keep = |&(x, y, _): &(f64, f64, f64)| {
        x.is_finite() && y.is_finite() && (!chart.log_x || x > 0.0) && (!chart.log_y || y > 0.0)
    };
    chart
        .series
        .iter()
        .enumerate()
        .map(|(n, s)| {
            let err = |k: usize| errors.get(n).and_then(|e| e.get(k)).copied();
            let points = s.points.iter().enumerate();
            let with_err =
                points.map(|(k, &(x, y))| (x, y, err(k).filter(|e| e.is_finite()).unwrap_or(0.0)));
            (s.name.as_str(), with_err.filter(keep).collect())
        })
        .collect()
}

/// One chart on `root`, its axes fitted to its points and error bars.
fn draw_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &LineChart,
    errors: &[Vec<f64>],
    k: f64,
) -> Result<()> {
    let series = drawn(chart, errors);
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, -f64::INFINITY, f64::INFINITY, -f64::INFINITY);
    for &(x, y, e) in all {
        let (lo, hi) = if chart.log_y && y - e <= 0.0 {
            (y, y + e)
        } else {
            (y - e, y + e)
        };
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(lo), y1.max(hi));
    }
    if x0 > x1 {
        return Err(anyhow!(
            "line chart {:?} has no drawable point",
            chart.title
        ));
    }
    let (x0, x1) = padded_range(x0, x1, chart.log_x);
    let (y0, y1) = padded_range(y0, y1, chart.log_y);
    match (chart.log_x, chart.log_y) {
        (false, false) => plot_lines(root, chart, &series, x0..x1, y0..y1, k),
        (true, false) => plot_lines(root, chart, &series, (x0..x1).log_scale(), y0..y1, k),
        (false, true) => plot_lines(root, chart, &series, x0..x1, (y0..y1).log_scale(), k),
        (true, true) => plot_lines(
            root,
            chart,
            &series,
            (x0..x1).log_scale(),
            (y0..y1).log_scale(),
            k,
        ),
    }
}

fn plot_lines<DB, X, Y>(
    root: &DrawingArea<DB, Shift>,
    chart: &LineChart,
    series: &[Drawn<'_>],
    x: X,
    y: Y,
    k: f64,
) -> Result<()>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let w = |v: f64| px(k, v).max(1) as u32;
    let mut ctx = ChartBuilder::on(root)
        .caption(&chart.title, (FONT, 22.0 * k))
        .margin(w(14.0))
        .x_label_area_size(w(48.0))
        .y_label_area_size(w(76.0))
        .build_cartesian_2d(x, y)
        .map_err(drawing)?;
    let format = |v: &f64| tick(*v);
    ctx.configure_mesh()
        .x_desc(&chart.x_label)
        .y_desc(&chart.y_label)
        .x_label_formatter(&format)
        .y_label_formatter(&format)
        .label_style((FONT, 14.0 * k))
        .axis_desc_style((FONT, 16.0 * k))
        .axis_style(BLACK.stroke_width(w(1.0)))
        .bold_line_style(RGBColor(215, 215, 215).stroke_width(w(1.0)))
        .light_line_style(RGBColor(240, 240, 240).stroke_width(w(1.0)))
        .set_all_tick_mark_size(w(5.0))
        .draw()
        .map_err(drawing)?;
    for (n, (name, points)) in series.iter().enumerate() {
        let color = SERIES_COLORS[n % SERIES_COLORS.len()];
        let line = color.stroke_width(w(2.0));
        let (len, marker) = (px(k, 22.0), px(k, 3.0));
        ctx.draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), line))
            .map_err(drawing)?
            .label(*name)
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (len, 0)], line)
                    + Circle::new((len / 2, 0), marker, color.filled())
            });
        ctx.draw_series(
            points
                .iter()
                .map(|&(x, y, _)| Circle::new((x, y), marker, color.filled())),
        )
        .map_err(drawing)?;
        let bars = points.iter().filter(|p| p.2 > 0.0).map(|&(x, y, e)| {
            let lo = if chart.log_y && y - e <= 0.0 {
                y
            } else {
                y - e
            };
            ErrorBar::new_vertical(
                x,
                lo,
                y,
                y + e,
                color.stroke_width(w(1.5)),
                px(k, 8.0) as u32,
            )
        });
        ctx.draw_series(bars).map_err(drawing)?;
    }
    if series.iter().any(|(name, _)| !name.is_empty()) {
        ctx.configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .margin(w(12.0))
            .legend_area_size(w(30.0))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(150, 150, 150).stroke_width(w(1.0)))
            .label_font((FONT, 14.0 * k))
            .draw()
            .map_err(drawing)?;
    }
    Ok(())
}
