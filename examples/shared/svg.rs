//! A log-log scatter chart as SVG text for the examples (shared by `#[path]`): panels
//! side by side, decade ticks, one colour a series, each point labelled. Plain SVG
//! elements only, so the file is diffable and needs no plotting library or font.

use std::fmt::Write;

/// Colours of the series, in order.
const COLORS: [&str; 6] = [
    "#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#a6761d",
];
const W: f64 = 460.0;
const H: f64 = 400.0;
const MARGIN: (f64, f64, f64, f64) = (70.0, 20.0, 40.0, 60.0); // left, right, top, bottom

/// A point: its coordinates, its series (colour) and a short label drawn beside it.
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub series: usize,
    pub label: String,
}

/// One panel: a title, axis labels, points, and notes printed under the axes (what
/// has no point: a refused model, an error at zero).
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub points: Vec<Point>,
    pub notes: Vec<String>,
}

/// Escapes text for SVG.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Decades `[lo, hi]` covering the values (at least one decade).
fn decades(v: impl Iterator<Item = f64>) -> (i32, i32) {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let (lo, hi) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (lo, hi.max(lo + 1))
}

/// The chart: `panels` side by side under `title`, the legend naming each series.
pub fn chart(title: &str, legend: &[&str], panels: &[Panel]) -> String {
    let notes = panels.iter().map(|p| p.notes.len()).max().unwrap_or(0) as f64;
    let (width, height) = (W * panels.len() as f64, H + 40.0 + 16.0 * notes);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="18" text-anchor="middle" font-size="14">{}</text>"#,
        width / 2.0,
        esc(title)
    );
    let mut lx = 10.0;
    for (k, name) in legend.iter().enumerate() {
        let c = COLORS[k % COLORS.len()];
        let _ = writeln!(
            s,
            r#"<circle cx="{lx}" cy="{}" r="4" fill="{c}"/><text x="{}" y="{}">{}</text>"#,
            H + 22.0,
            lx + 8.0,
            H + 26.0,
            esc(name)
        );
        lx += 16.0 + 7.0 * name.len() as f64;
    }
    for (k, p) in panels.iter().enumerate() {
        panel(&mut s, W * k as f64, p);
    }
    s.push_str("</svg>\n");
    s
}

/// Draws one panel with its left edge at `x0`.
fn panel(s: &mut String, x0: f64, p: &Panel) {
    let (ml, mr, mt, mb) = MARGIN;
    let (px0, px1, py0, py1) = (x0 + ml, x0 + W - mr, mt, H - mb);
    let (xa, xb) = decades(p.points.iter().map(|q| q.x));
    let (ya, yb) = decades(p.points.iter().map(|q| q.y));
    let sx = |x: f64| px0 + (x.log10() - xa as f64) / (xb - xa) as f64 * (px1 - px0);
    let sy = |y: f64| py1 - (y.log10() - ya as f64) / (yb - ya) as f64 * (py1 - py0);
    let _ = writeln!(
        s,
        r#"<rect x="{px0}" y="{py0}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        px1 - px0,
        py1 - py0
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>"#,
        (px0 + px1) / 2.0,
        py0 - 6.0,
        esc(&p.title)
    );
    for d in xa..=xb {
        let x = sx(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{x}" y1="{py0}" x2="{x}" y2="{py1}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"##,
            py1 + 14.0
        );
    }
    for d in ya..=yb {
        let y = sy(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{px0}" y1="{y}" x2="{px1}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{d}</text>"##,
            px0 - 4.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        (px0 + px1) / 2.0,
        py1 + 30.0,
        esc(&p.x_label)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate({},{}) rotate(-90)" text-anchor="middle">{}</text>"#,
        x0 + 16.0,
        (py0 + py1) / 2.0,
        esc(&p.y_label)
    );
    for q in &p.points {
        // Rungs of equal cost and error would hide each other: each series' markers
        // and labels are set off by a few pixels.
        let off = q.series as f64 - 2.0;
        let (x, y, c) = (
            sx(q.x) + 5.0 * off,
            sy(q.y),
            COLORS[q.series % COLORS.len()],
        );
        let y_label = y + 10.0 * off;
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="{c}"/><text x="{:.1}" y="{:.1}" fill="{c}">{}</text>"#,
            x + 6.0,
            y_label + 4.0,
            esc(&q.label)
        );
    }
    for (k, note) in p.notes.iter().enumerate() {
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}">{}</text>"#,
            x0 + 10.0,
            H + 44.0 + 16.0 * k as f64,
            esc(note)
        );
    }
}
