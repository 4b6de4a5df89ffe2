//! State against time: one strip per run, a coloured band per state, on a time axis
//! from 0 to the run's duration, with a legend of every state name.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

use super::{FONT, drawing, nice_length, px, save_png, short};

/// Colours of the states, by their index in the list of names.
pub const STATE_COLORS: [RGBColor; 8] = [
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(227, 119, 194),
];
/// Colour of a state not in the list of names.
pub const UNKNOWN_STATE: RGBColor = RGBColor(150, 150, 150);

/// The colour of state `name` among `names`: by index, grey for an unknown name.
pub fn state_color(names: &[&str], name: &str) -> RGBColor {
    names
        .iter()
        .position(|&n| n == name)
        .map_or(UNKNOWN_STATE, |i| STATE_COLORS[i % STATE_COLORS.len()])
}

/// One strip: a label and its `(time, state)` rows, by time; each row's state holds
/// until the next row's time (the last row's only at its time).
#[derive(Debug, Clone, PartialEq)]
pub struct Strip<'a> {
    /// Label on the left (empty for none).
    pub label: String,
    /// `(time, state name)` by time.
    pub rows: Vec<(f64, &'a str)>,
}

/// Picture width, pixels.
const WIDTH: f64 = 960.0;
/// Heights: heading, band, gap between bands, time axis.
const HEADING: f64 = 36.0;
const BAND: f64 = 34.0;
const BAND_GAP: f64 = 10.0;
const AXIS: f64 = 44.0;
/// Height of one legend line.
const LEGEND_LINE: f64 = 26.0;

/// Draws one run's timeline to a PNG: state against time from 0 to `duration`.
pub fn draw_timeline(
    path: &Path,
    title: &str,
    rows: &[(f64, &str)],
    names: &[&str],
    duration: f64,
) -> Result<()> {
    let strip = Strip {
        label: String::new(),
        rows: rows.to_vec(),
    };
    draw_timelines(path, title, &[strip], names, duration)
}

/// Legend entries and their left edges, wrapped into lines of the picture's width:
/// `(line, x, name, colour)`.
fn legend_layout<'a>(names: &[&'a str], unknown: bool) -> Vec<(usize, f64, &'a str, RGBColor)> {
    let mut entries: Vec<(&str, RGBColor)> = names
        .iter()
        .enumerate()
        .map(|(i, &n)| (n, STATE_COLORS[i % STATE_COLORS.len()]))
        .collect();
    if unknown {
        entries.push(("unknown", UNKNOWN_STATE));
    }
    let (mut line, mut x) = (0, 20.0);
    let mut out = Vec::new();
    for (name, color) in entries {
        // About 8 pixels per character at 15 px, a swatch and a gap.
        let w = 30.0 + 8.0 * name.chars().count() as f64 + 24.0;
        if x + w > WIDTH - 10.0 && x > 20.0 {
            (line, x) = (line + 1, 20.0);
        }
        out.push((line, x, name, color));
        x += w;
    }
    out
}

/// Draws several runs' timelines stacked on one time axis from 0 to `duration`, to a
/// PNG; states coloured by their index in `names` (unknown ones grey).
pub fn draw_timelines(
    path: &Path,
    title: &str,
    strips: &[Strip<'_>],
    names: &[&str],
    duration: f64,
) -> Result<()> {
    if strips.is_empty() || !(duration.is_finite() && duration > 0.0) {
        return Err(anyhow!(
            "a timeline needs a strip and a positive duration (got {} strips, duration {duration})",
            strips.len()
        ));
    }
    let unknown = strips
        .iter()
        .flat_map(|s| &s.rows)
        .any(|(_, n)| !names.contains(n));
    let legend = legend_layout(names, unknown);
    let lines = legend.last().map_or(0, |l| l.0 + 1) as f64;
    let n = strips.len() as f64;
    let height = HEADING + n * (BAND + BAND_GAP) + AXIS + lines * LEGEND_LINE + 8.0;
    let size = (WIDTH as u32, height as u32);
    save_png(path, size, |root, k| {
        draw_strips(root, title, strips, names, duration, &legend, k)
    })
}

fn draw_strips<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    strips: &[Strip<'_>],
    names: &[&str],
    duration: f64,
    legend: &[(usize, f64, &str, RGBColor)],
    k: f64,
) -> Result<()> {
    let font = |size: f64| (FONT, size * k).into_font().color(&BLACK);
    let labelled = strips.iter().any(|s| !s.label.is_empty());
    let (x0, x1) = (if labelled { 70.0 } else { 20.0 }, WIDTH - 24.0);
    let x_of = |t: f64| x0 + (x1 - x0) * (t / duration).clamp(0.0, 1.0);
    let line = |c: RGBColor| c.stroke_width(px(k, 1.0).max(1) as u32);
    root.draw(&Text::new(
        title.to_string(),
        (px(k, 20.0), px(k, 9.0)),
        font(18.0),
    ))
    .map_err(drawing)?;
    for (j, strip) in strips.iter().enumerate() {
        let top = HEADING + j as f64 * (BAND + BAND_GAP);
        let y = |v: f64| px(k, top + v);
        // Runs of one state become one rectangle.
        let mut start = 0;
        while start < strip.rows.len() {
            let (t0, state) = strip.rows[start];
            let mut end = start + 1;
            while end < strip.rows.len() && strip.rows[end].1 == state {
                end += 1;
            }
            let t1 = strip.rows.get(end).map_or(strip.rows[end - 1].0, |r| r.0);
            let (a, b) = (px(k, x_of(t0)), px(k, x_of(t1)).max(px(k, x_of(t0)) + 1));
            let color = state_color(names, state);
            root.draw(&Rectangle::new([(a, y(0.0)), (b, y(BAND))], color.filled()))
                .map_err(drawing)?;
            start = end;
        }
        root.draw(&Rectangle::new(
            [(px(k, x0), y(0.0)), (px(k, x1), y(BAND))],
            line(RGBColor(120, 120, 120)),
        ))
        .map_err(drawing)?;
        if !strip.label.is_empty() {
            root.draw(&Text::new(
                strip.label.clone(),
                (px(k, 16.0), y(0.5 * BAND - 9.0)),
                (FONT, 16.0 * k, FontStyle::Bold).into_font().color(&BLACK),
            ))
            .map_err(drawing)?;
        }
    }

    // Time axis.
    let axis_y = HEADING + strips.len() as f64 * (BAND + BAND_GAP);
    let ay = px(k, axis_y);
    root.draw(&PathElement::new(
        vec![(px(k, x0), ay), (px(k, x1), ay)],
        line(BLACK),
    ))
    .map_err(drawing)?;
    let step = nice_length(duration / 5.0);
    let mut t = 0.0;
    while t <= duration * (1.0 + 1e-9) {
        let x = px(k, x_of(t));
        root.draw(&PathElement::new(
            vec![(x, ay), (x, ay + px(k, 5.0))],
            line(BLACK),
        ))
        .map_err(drawing)?;
        let label = short(t);
        let half = 4.0 * label.len() as f64;
        root.draw(&Text::new(
            label,
            (x - px(k, half), ay + px(k, 8.0)),
            font(13.0),
        ))
        .map_err(drawing)?;
        t += step;
    }
    root.draw(&Text::new(
        "time (a / U0)",
        (px(k, x1 - 90.0), ay + px(k, 24.0)),
        font(13.0),
    ))
    .map_err(drawing)?;

    for &(l, x, name, color) in legend {
        let y = axis_y + AXIS + l as f64 * LEGEND_LINE;
        let swatch = [(px(k, x), px(k, y)), (px(k, x + 22.0), px(k, y + 16.0))];
        root.draw(&Rectangle::new(swatch, color.filled()))
            .map_err(drawing)?;
        root.draw(&Rectangle::new(swatch, line(BLACK)))
            .map_err(drawing)?;
        root.draw(&Text::new(
            name.to_string(),
            (px(k, x + 28.0), px(k, y)),
            font(15.0),
        ))
        .map_err(drawing)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_are_coloured_by_index_and_unknown_grey() {
        let names = ["stretched", "other"];
        assert_eq!(state_color(&names, "stretched"), STATE_COLORS[0]);
        assert_eq!(state_color(&names, "other"), STATE_COLORS[1]);
        assert_eq!(state_color(&names, "flying"), UNKNOWN_STATE);
    }

    #[test]
    fn the_legend_wraps() {
        let names = ["a long state name"; 12];
        let l = legend_layout(&names, true);
        assert_eq!(l.len(), 13);
        assert!(l.last().unwrap().0 >= 2);
        assert!(l.iter().all(|e| e.1 < WIDTH));
    }
}
