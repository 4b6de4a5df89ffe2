//! Pictures: sphere configurations drawn to scale (side and top views, the paper's
//! Figure 1 layout) and two generic charts (line chart, categorical map), as PNG.
//!
//! Views: the side view looks along `+y` (the viewer stands at `y = -inf`), screen
//! right is `+x` and screen up is `+z`; the top view looks down from `z = +inf`, screen
//! right is `+x` and screen up is `+y`. Spheres are drawn as filled discs of their
//! true radius with a thin dark outline, farthest first, so nearer spheres cover
//! farther ones. Colours follow the paper: the head (particle 0) red, tails blue, the
//! last particle green.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::Path;

/// Head colour (particle 0).
pub const HEAD_COLOR: RGBColor = RGBColor(214, 39, 40);
/// Tail colour.
pub const TAIL_COLOR: RGBColor = RGBColor(52, 101, 164);
/// Colour of the last particle.
pub const LAST_COLOR: RGBColor = RGBColor(44, 160, 44);
/// Outline of every sphere.
pub const OUTLINE_COLOR: RGBColor = RGBColor(30, 30, 30);

/// Series colours of the line chart, in order.
pub const SERIES_COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

const FONT: &str = "sans-serif";

fn drawing<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e}")
}

/// Colours of an `n`-particle chain: head red, tails blue, last particle green.
pub fn chain_colors(n: usize) -> Vec<RGBColor> {
    (0..n)
        .map(|i| match i {
            0 => HEAD_COLOR,
            i if i + 1 == n => LAST_COLOR,
            _ => TAIL_COLOR,
        })
        .collect()
}

/// A projection of 3-D space onto a picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// Looking along `+y`: screen `(x, z)`.
    Side,
    /// Looking down `-z`: screen `(x, y)`.
    Top,
}

impl View {
    /// Screen coordinates `(right, up)` of a point and its nearness to the viewer
    /// (larger is nearer).
    pub fn project(self, p: [f64; 3]) -> (f64, f64, f64) {
        match self {
            View::Side => (p[0], p[2], -p[1]),
            View::Top => (p[0], p[1], p[2]),
        }
    }

    /// Short name for panel titles.
    pub fn name(self) -> &'static str {
        match self {
            View::Side => "side (x-z)",
            View::Top => "top (x-y)",
        }
    }
}

/// Sphere centres and radii at one moment.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Snapshot {
    /// Simulated time.
    pub time: f64,
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
}

/// Screen-space bounding box `(min_right, min_up, max_right, max_up)` of the spheres
/// in a view, radii included.
pub fn extent(snapshot: &Snapshot, view: View) -> (f64, f64, f64, f64) {
    let mut b = (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
    for (p, &r) in snapshot.positions.iter().zip(&snapshot.radii) {
        let (u, v, _) = view.project(*p);
        b = (
            b.0.min(u - r),
            b.1.min(v - r),
            b.2.max(u + r),
            b.3.max(v + r),
        );
    }
    if b.0 > b.2 { (0.0, 0.0, 0.0, 0.0) } else { b }
}

/// Height kept at the top of a sphere panel for its title (output pixels).
const PANEL_TITLE: f64 = 22.0;
/// Height kept at the bottom of a sphere panel for the scale bar (output pixels).
const PANEL_FOOT: f64 = 22.0;
/// Free margin around the spheres (output pixels).
const PANEL_PAD: f64 = 8.0;

/// Pictures are drawn this many times larger and averaged down to their final size,
/// which smooths the edges of discs, lines and text.
pub const SUPERSAMPLE: u32 = 2;

/// Rounds `v` output pixels, at `k` drawing pixels per output pixel, to drawing pixels.
fn px(k: f64, v: f64) -> i32 {
    (v * k).round() as i32
}

/// Pixels per length unit that fit each `(snapshot, view)` into a sphere panel of
/// `size` pixels (title, scale bar and margins left free).
pub fn fit_scale(items: &[(&Snapshot, View)], size: (u32, u32)) -> f64 {
    let w = (f64::from(size.0) - 2.0 * PANEL_PAD).max(1.0);
    let h = (f64::from(size.1) - PANEL_TITLE - PANEL_FOOT - 2.0 * PANEL_PAD).max(1.0);
    items
        .iter()
        .map(|(s, v)| {
            let b = extent(s, *v);
            let (dw, dh) = ((b.2 - b.0).max(1e-9), (b.3 - b.1).max(1e-9));
            (w / dw).min(h / dh)
        })
        .fold(f64::INFINITY, f64::min)
}

/// A "nice" length (1, 2 or 5 times a power of ten) at most `max`.
fn nice_length(max: f64) -> f64 {
    if max <= 0.0 || !max.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(max.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&l| l <= max)
        .unwrap_or(p)
}

/// Draws at [`SUPERSAMPLE`] times `size` into memory, averages the result down to
/// `size` and saves it as a PNG. `draw` gets the large drawing area and the factor.
fn save_png<F>(path: &Path, size: (u32, u32), draw: F) -> Result<()>
where
    F: FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>, f64) -> Result<()>,
{
    let k = SUPERSAMPLE;
    let (w, h) = size;
    let (bw, bh) = (w * k, h * k);
    let mut big = vec![255u8; bw as usize * bh as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        draw(&root, f64::from(k))?;
        root.present().map_err(drawing)?;
    }
    let (k, bw) = (k as usize, bw as usize);
    let mut small = vec![0u8; w as usize * h as usize * 3];
    for y in 0..h as usize {
        for x in 0..w as usize {
            for c in 0..3 {
                let mut sum = 0usize;
                for dy in 0..k {
                    let row = ((y * k + dy) * bw + x * k) * 3 + c;
                    for dx in 0..k {
                        sum += usize::from(big[row + dx * 3]);
                    }
                }
                small[(y * w as usize + x) * 3 + c] = ((sum + k * k / 2) / (k * k)) as u8;
            }
        }
    }
    let mut backend = BitMapBackend::new(path, size);
    backend.blit_bitmap((0, 0), size, &small).map_err(drawing)?;
    backend.present().map_err(drawing)?;
    Ok(())
}

/// Draws one sphere panel: the spheres of `snapshot` in `view` at `scale` output
/// pixels per length unit, centred on their bounding box, under `title`, with a scale
/// bar (lengths in tail radii `a`) and, in side views, an arrow for gravity (`-z`).
/// `k` is the number of drawing pixels per output pixel of `area` (1 when drawing
/// straight to the final picture).
pub fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    snapshot: &Snapshot,
    colors: &[RGBColor],
    view: View,
    scale: f64,
    title: &str,
    k: f64,
) -> Result<()> {
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (f64::from(w) / k, f64::from(h) / k);
    let thin = |c: RGBColor| c.stroke_width(px(k, 1.0).max(1) as u32);
    let thick = BLACK.stroke_width(px(k, 2.0).max(1) as u32);
    let font = |size: f64| (FONT, size * k).into_font().color(&BLACK);
    area.draw(&Rectangle::new(
        [(0, 0), (px(k, w) - 1, px(k, h) - 1)],
        thin(RGBColor(190, 190, 190)),
    ))
    .map_err(drawing)?;
    area.draw(&Text::new(
        title.to_string(),
        (px(k, 6.0), px(k, 4.0)),
        font(15.0),
    ))
    .map_err(drawing)?;

    let b = extent(snapshot, view);
    let (uc, vc) = (0.5 * (b.0 + b.2), 0.5 * (b.1 + b.3));
    let (xc, yc) = (0.5 * w, PANEL_TITLE + 0.5 * (h - PANEL_TITLE - PANEL_FOOT));
    let mut order: Vec<usize> = (0..snapshot.positions.len()).collect();
    let nearness = |i: usize| view.project(snapshot.positions[i]).2;
    order.sort_by(|&i, &j| nearness(i).total_cmp(&nearness(j)).then(i.cmp(&j)));
    for i in order {
        let (u, v, _) = view.project(snapshot.positions[i]);
        let centre = (px(k, xc + (u - uc) * scale), px(k, yc - (v - vc) * scale));
        // A dark disc with the coloured disc one output pixel smaller on top: the
        // outline, with no gap between fill and outline.
        let r = (snapshot.radii[i] * scale).max(1.5) * k;
        let color = colors.get(i).copied().unwrap_or(TAIL_COLOR);
        area.draw(&Circle::new(centre, r, OUTLINE_COLOR.filled()))
            .map_err(drawing)?;
        area.draw(&Circle::new(centre, (r - k).max(0.5 * r), color.filled()))
            .map_err(drawing)?;
    }

    // Scale bar, bottom left.
    let bar = nice_length(0.3 * w / scale);
    let (x0, x1, y) = (8.0, 8.0 + bar * scale, h - 10.0);
    area.draw(&PathElement::new(
        vec![(px(k, x0), px(k, y)), (px(k, x1), px(k, y))],
        thick,
    ))
    .map_err(drawing)?;
    for x in [x0, x1] {
        area.draw(&PathElement::new(
            vec![(px(k, x), px(k, y - 4.0)), (px(k, x), px(k, y + 4.0))],
            thick,
        ))
        .map_err(drawing)?;
    }
    area.draw(&Text::new(
        format!("{} a", crate::output::format_f64(bar)),
        (px(k, x1 + 5.0), px(k, y - 8.0)),
        font(13.0),
    ))
    .map_err(drawing)?;

    if view == View::Side {
        let x = w - 16.0;
        let (y0, y1) = (PANEL_TITLE + 6.0, PANEL_TITLE + 34.0);
        area.draw(&PathElement::new(
            vec![(px(k, x), px(k, y0)), (px(k, x), px(k, y1 - 4.0))],
            thick,
        ))
        .map_err(drawing)?;
        area.draw(&Polygon::new(
            vec![
                (px(k, x - 5.0), px(k, y1 - 8.0)),
                (px(k, x + 5.0), px(k, y1 - 8.0)),
                (px(k, x), px(k, y1 + 1.0)),
            ],
            BLACK.filled(),
        ))
        .map_err(drawing)?;
        area.draw(&Text::new("g", (px(k, x - 14.0), px(k, y0)), font(14.0)))
            .map_err(drawing)?;
    }
    Ok(())
}

/// Draws the side and top views of one configuration next to each other, at one
/// scale, into a PNG of `size` pixels.
pub fn draw_configuration(
    path: &Path,
    snapshot: &Snapshot,
    colors: &[RGBColor],
    title: &str,
    size: (u32, u32),
) -> Result<()> {
    let title_h = 36.0;
    let panel = (
        (f64::from(size.0) / 2.0 - 8.0).max(1.0),
        (f64::from(size.1) - title_h - 8.0).max(1.0),
    );
    let views = [View::Side, View::Top];
    let items: Vec<(&Snapshot, View)> = views.iter().map(|&v| (snapshot, v)).collect();
    let scale = fit_scale(&items, (panel.0 as u32, panel.1 as u32));
    save_png(path, size, |root, k| {
        root.draw(&Text::new(
            title.to_string(),
            (px(k, 8.0), px(k, 8.0)),
            (FONT, 20.0 * k).into_font().color(&BLACK),
        ))
        .map_err(drawing)?;
        for (col, view) in views.into_iter().enumerate() {
            let left = 4.0 + col as f64 * (panel.0 + 8.0);
            let area = root.clone().shrink(
                (px(k, left), px(k, title_h)),
                (px(k, panel.0) as u32, px(k, panel.1) as u32),
            );
            let t = format!("{}, t = {}", view.name(), short(snapshot.time));
            draw_panel(&area, snapshot, colors, view, scale, &t, k)?;
        }
        Ok(())
    })
}

/// A number for a label: at most four significant digits, no trailing zeros.
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A tick label: at most three significant digits, scientific notation (`1e-5`,
/// `2.5e6`) outside `[1e-3, 1e5)`.
fn tick(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !x.is_finite() || (1e-3..1e5).contains(&a) {
        short(x)
    } else {
        let s = format!("{x:.2e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = if mantissa.contains('.') {
            mantissa.trim_end_matches('0').trim_end_matches('.')
        } else {
            mantissa
        };
        format!("{mantissa}e{exponent}")
    }
}

/// One case of the Figure 1 layout.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure1Case {
    /// Case title, e.g. `(a) D=1.50, head 2^(1/3)`.
    pub title: String,
    /// Initial configuration.
    pub initial: Snapshot,
    /// Final (late) configuration.
    pub last: Snapshot,
}

/// Panel width of the Figure 1 layout, pixels.
const FIG1_PANEL_W: f64 = 270.0;
/// Side-view panel height of the Figure 1 layout, pixels.
const FIG1_SIDE_H: f64 = 620.0;
/// Top-view panel height of the Figure 1 layout, pixels.
const FIG1_TOP_H: f64 = 270.0;
/// Height of the figure's heading, pixels.
const FIG1_HEADING: f64 = 50.0;
/// Height of a case title, pixels.
const FIG1_CASE_TITLE: f64 = 34.0;
/// Gap between case blocks and around the figure, pixels.
const FIG1_GAP: f64 = 24.0;

/// Draws the paper's Figure 1 layout to a PNG: the cases next to each other, each a
/// 2x2 block (upper row: side view, initial | final; lower row: top view, initial |
/// final), the four panels of a case at one scale, the largest that fits all four.
pub fn draw_figure1(path: &Path, cases: &[Figure1Case]) -> Result<()> {
    if cases.is_empty() {
        return Err(anyhow!("figure 1 needs at least one case"));
    }
    let n = cases.len() as f64;
    let block_w = 2.0 * FIG1_PANEL_W;
    let width = n * block_w + (n + 1.0) * FIG1_GAP;
    let height = FIG1_HEADING + FIG1_CASE_TITLE + FIG1_SIDE_H + FIG1_TOP_H + FIG1_GAP;
    let inset = 2.0;
    let side_size = (FIG1_PANEL_W - 2.0 * inset, FIG1_SIDE_H - 2.0 * inset);
    let top_size = (FIG1_PANEL_W - 2.0 * inset, FIG1_TOP_H - 2.0 * inset);
    let as_u32 = |s: (f64, f64)| (s.0 as u32, s.1 as u32);
    save_png(path, (width as u32, height as u32), |root, k| {
        root.draw(&Text::new(
            "Settling helical chains: side view (upper row) and top view (lower row), \
             initial (left) and final (right) state; head red, tails blue, last tail green",
            (px(k, FIG1_GAP), px(k, 14.0)),
            (FONT, 19.0 * k).into_font().color(&BLACK),
        ))
        .map_err(drawing)?;
        for (c, case) in cases.iter().enumerate() {
            let x0 = FIG1_GAP + c as f64 * (block_w + FIG1_GAP);
            root.draw(&Text::new(
                case.title.clone(),
                (px(k, x0), px(k, FIG1_HEADING + 4.0)),
                (FONT, 21.0 * k)
                    .into_font()
                    .style(FontStyle::Bold)
                    .color(&BLACK),
            ))
            .map_err(drawing)?;
            let scale = fit_scale(
                &[(&case.initial, View::Side), (&case.last, View::Side)],
                as_u32(side_size),
            )
            .min(fit_scale(
                &[(&case.initial, View::Top), (&case.last, View::Top)],
                as_u32(top_size),
            ));
            let colors = chain_colors(case.initial.positions.len());
            let states = [(&case.initial, "initial"), (&case.last, "final")];
            for (col, (snap, when)) in states.into_iter().enumerate() {
                for (row, view) in [View::Side, View::Top].into_iter().enumerate() {
                    let (top, size) = if row == 0 {
                        (FIG1_HEADING + FIG1_CASE_TITLE, side_size)
                    } else {
                        (FIG1_HEADING + FIG1_CASE_TITLE + FIG1_SIDE_H, top_size)
                    };
                    let left = x0 + col as f64 * FIG1_PANEL_W;
                    let area = root.clone().shrink(
                        (px(k, left + inset), px(k, top + inset)),
                        (px(k, size.0) as u32, px(k, size.1) as u32),
                    );
                    let name = if view == View::Side { "side" } else { "top" };
                    let title = format!("{name}, {when}, t = {}", short(snap.time));
                    draw_panel(&area, snap, &colors, view, scale, &title, k)?;
                }
            }
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------------------
// Charts
// ---------------------------------------------------------------------------------------

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

/// Draws a line chart to a PNG of `size` pixels.
pub fn line_chart(path: &Path, chart: &LineChart, size: (u32, u32)) -> Result<()> {
    let keep = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!chart.log_x || x > 0.0) && (!chart.log_y || y > 0.0)
    };
    let series: Vec<(&str, Vec<(f64, f64)>)> = chart
        .series
        .iter()
        .map(|s| {
            (
                s.name.as_str(),
                s.points.iter().copied().filter(keep).collect(),
            )
        })
        .collect();
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, -f64::INFINITY, f64::INFINITY, -f64::INFINITY);
    for &(x, y) in all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        return Err(anyhow!(
            "line chart {:?} has no drawable point",
            chart.title
        ));
    }
    let (x0, x1) = padded_range(x0, x1, chart.log_x);
    let (y0, y1) = padded_range(y0, y1, chart.log_y);
    save_png(path, size, |root, k| match (chart.log_x, chart.log_y) {
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
    })
}

fn plot_lines<DB, X, Y>(
    root: &DrawingArea<DB, Shift>,
    chart: &LineChart,
    series: &[(&str, Vec<(f64, f64)>)],
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
        ctx.draw_series(LineSeries::new(points.iter().copied(), line))
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
                .map(|&p| Circle::new(p, marker, color.filled())),
        )
        .map_err(drawing)?;
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

/// A marked point on a [`CategoryMap`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mark {
    /// Horizontal position, in axis units.
    pub x: f64,
    /// Vertical position, in axis units.
    pub y: f64,
    /// Label written next to the marker.
    pub label: String,
}

/// A map of categories over a grid of `(x, y)` cells, e.g. the outcome phase diagram.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CategoryMap {
    /// Title above the map.
    pub title: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Cell centres along `x`, increasing.
    pub x: Vec<f64>,
    /// Cell centres along `y`, increasing.
    pub y: Vec<f64>,
    /// Category index of each cell, row by row: `cells[iy * x.len() + ix]`; `None`
    /// for a cell without a result (drawn grey and crossed).
    pub cells: Vec<Option<usize>>,
    /// Category names and colours.
    pub categories: Vec<(String, RGBColor)>,
    /// Points to mark.
    pub marks: Vec<Mark>,
}

/// Cell edges around increasing centres: midpoints inside, half a spacing outside.
fn edges(centres: &[f64]) -> Vec<f64> {
    let n = centres.len();
    if n == 1 {
        return vec![centres[0] - 0.5, centres[0] + 0.5];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(centres[0] - 0.5 * (centres[1] - centres[0]));
    for k in 0..n - 1 {
        e.push(0.5 * (centres[k] + centres[k + 1]));
    }
    e.push(centres[n - 1] + 0.5 * (centres[n - 1] - centres[n - 2]));
    e
}

/// Draws a category map to a PNG of `size` pixels, with a legend on the right.
pub fn category_map(path: &Path, map: &CategoryMap, size: (u32, u32)) -> Result<()> {
    let (nx, ny) = (map.x.len(), map.y.len());
    if nx == 0 || ny == 0 || map.cells.len() != nx * ny {
        return Err(anyhow!(
            "category map needs {nx} x {ny} = {} cells, got {}",
            nx * ny,
            map.cells.len()
        ));
    }
    let increasing = |v: &[f64]| v.windows(2).all(|w| w[0] < w[1]);
    if !increasing(&map.x) || !increasing(&map.y) {
        return Err(anyhow!("category map cell centres must increase"));
    }
    if let Some(bad) = map
        .cells
        .iter()
        .flatten()
        .find(|&&c| c >= map.categories.len())
    {
        return Err(anyhow!("category {bad} has no name and colour"));
    }
    let (ex, ey) = (edges(&map.x), edges(&map.y));
    save_png(path, size, |root, k| {
        draw_category_map(root, map, &ex, &ey, k)
    })
}

fn draw_category_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &CategoryMap,
    ex: &[f64],
    ey: &[f64],
    k: f64,
) -> Result<()> {
    let (nx, ny) = (map.x.len(), map.y.len());
    let w = |v: f64| px(k, v).max(1) as u32;
    let font = |size: f64| (FONT, size * k).into_font().color(&BLACK);
    let legend_w = px(k, 190.0).min(root.dim_in_pixel().0 as i32 / 3);
    let (plot, legend) = root.split_horizontally(root.dim_in_pixel().0 as i32 - legend_w);
    let mut ctx = ChartBuilder::on(&plot)
        .caption(&map.title, (FONT, 22.0 * k))
        .margin(w(14.0))
        .x_label_area_size(w(48.0))
        .y_label_area_size(w(64.0))
        .build_cartesian_2d(ex[0]..ex[nx], ey[0]..ey[ny])
        .map_err(drawing)?;
    let format = |v: &f64| tick(*v);
    ctx.configure_mesh()
        .disable_mesh()
        .x_desc(&map.x_label)
        .y_desc(&map.y_label)
        .x_label_formatter(&format)
        .y_label_formatter(&format)
        .label_style((FONT, 14.0 * k))
        .axis_desc_style((FONT, 16.0 * k))
        .axis_style(BLACK.stroke_width(w(1.0)))
        .set_all_tick_mark_size(w(5.0))
        .draw()
        .map_err(drawing)?;
    let missing = RGBColor(200, 200, 200);
    let grey = RGBColor(120, 120, 120).stroke_width(w(1.0));
    for iy in 0..ny {
        for ix in 0..nx {
            let corners = [(ex[ix], ey[iy]), (ex[ix + 1], ey[iy + 1])];
            let (color, cross) = match map.cells[iy * nx + ix] {
                Some(c) => (map.categories[c].1, false),
                None => (missing, true),
            };
            ctx.draw_series([
                Rectangle::new(corners, color.filled()),
                Rectangle::new(corners, WHITE.stroke_width(w(1.0))),
            ])
            .map_err(drawing)?;
            if cross {
                let [(a, b), (c, d)] = corners;
                ctx.draw_series([
                    PathElement::new(vec![(a, b), (c, d)], grey),
                    PathElement::new(vec![(a, d), (c, b)], grey),
                ])
                .map_err(drawing)?;
            }
        }
    }
    for m in &map.marks {
        let p = (m.x, m.y);
        ctx.draw_series([
            Circle::new(p, px(k, 7.0), WHITE.filled()),
            Circle::new(p, px(k, 7.0), BLACK.stroke_width(w(2.0))),
            Circle::new(p, px(k, 2.0), BLACK.filled()),
        ])
        .map_err(drawing)?;
        ctx.draw_series([EmptyElement::at(p)
            + Text::new(
                m.label.clone(),
                (px(k, 10.0), px(k, -20.0)),
                (FONT, 17.0 * k)
                    .into_font()
                    .style(FontStyle::Bold)
                    .color(&BLACK),
            )])
        .map_err(drawing)?;
    }

    // Legend: one swatch per category, then the "no result" swatch if needed.
    let mut entries: Vec<(&str, RGBColor)> = map
        .categories
        .iter()
        .map(|(name, color)| (name.as_str(), *color))
        .collect();
    if map.cells.iter().any(Option::is_none) {
        entries.push(("no result", missing));
    }
    for (n, (name, color)) in entries.into_iter().enumerate() {
        let y = 60.0 + 30.0 * n as f64;
        let swatch = [(px(k, 10.0), px(k, y)), (px(k, 30.0), px(k, y + 20.0))];
        legend
            .draw(&Rectangle::new(swatch, color.filled()))
            .map_err(drawing)?;
        legend
            .draw(&Rectangle::new(swatch, BLACK.stroke_width(w(1.0))))
            .map_err(drawing)?;
        legend
            .draw(&Text::new(
                name.to_string(),
                (px(k, 38.0), px(k, y + 2.0)),
                font(16.0),
            ))
            .map_err(drawing)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_colours_mark_head_and_last() {
        let c = chain_colors(4);
        assert_eq!(c, vec![HEAD_COLOR, TAIL_COLOR, TAIL_COLOR, LAST_COLOR]);
        assert_eq!(chain_colors(1), vec![HEAD_COLOR]);
    }

    #[test]
    fn views_project_and_order_by_nearness() {
        let p = [1.0, 2.0, 3.0];
        assert_eq!(View::Side.project(p), (1.0, 3.0, -2.0));
        assert_eq!(View::Top.project(p), (1.0, 2.0, 3.0));
    }

    #[test]
    fn extent_includes_radii() {
        let s = Snapshot {
            time: 0.0,
            positions: vec![[0.0, 0.0, 0.0], [4.0, 0.0, 1.0]],
            radii: vec![1.0, 2.0],
        };
        assert_eq!(extent(&s, View::Side), (-1.0, -1.0, 6.0, 3.0));
        let scale = fit_scale(&[(&s, View::Side)], (116, 200));
        assert!((scale - 100.0 / 7.0).abs() < 1e-12);
    }

    #[test]
    fn nice_lengths() {
        assert_eq!(nice_length(7.3), 5.0);
        assert_eq!(nice_length(23.0), 20.0);
        assert_eq!(nice_length(0.15), 0.1);
        assert_eq!(short(400.0), "400");
        assert_eq!(short(0.012345), "0.01235");
        assert_eq!(tick(9.999999999e-5), "1e-4");
        assert_eq!(tick(2.5e6), "2.5e6");
        assert_eq!(tick(0.30000000000000004), "0.3");
    }

    #[test]
    fn cell_edges_are_midpoints() {
        assert_eq!(edges(&[1.0, 2.0, 4.0]), vec![0.5, 1.5, 3.0, 5.0]);
    }
}
