//! Pictures: sphere configurations drawn to scale (side and top views, the paper's
//! Figure 1 layout, snapshots, animations), state timelines and two generic charts (line
//! chart, categorical map), as PNG and GIF.
//!
//! Views: the side view looks along `+y` (the viewer stands at `y = -inf`), screen
//! right is `+x` and screen up is `+z`; the top view looks down from `z = +inf`, screen
//! right is `+x` and screen up is `+y`. Spheres are drawn as filled discs of their
//! true radius with a thin dark outline, farthest first, so nearer spheres cover
//! farther ones. Colours follow the paper: the head (particle 0) red, tails blue, the
//! last particle green. A scene's wall is a dark line on a grey band in side views.
//!
//! * [`panel`]: projections and one sphere panel, a configuration's picture;
//! * [`cloud`]: a falling cloud's slice through its axis and its density about it;
//! * [`figure1`]: the Figure 1 layout (own or common scale) and snapshot grids;
//! * [`charts`]: the line chart; [`map`]: the category map;
//! * [`timeline`]: state against time; [`animation`]: GIF animations.

pub mod animation;
pub mod charts;
pub mod cloud;
pub mod figure1;
pub mod map;
pub mod panel;
pub mod timeline;

pub use animation::*;
pub use charts::*;
pub use cloud::*;
pub use figure1::*;
pub use map::*;
pub use panel::*;
pub use timeline::*;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
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
/// The wall's plane (side views).
pub const WALL_COLOR: RGBColor = RGBColor(90, 90, 90);
/// The solid below the wall.
pub const WALL_FILL: RGBColor = RGBColor(215, 215, 215);

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

const FONT: &str = crate::fonts::FAMILY;

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

/// Sphere centres and radii at one moment: the run's record of a frame (the host
/// library's), drawn here.
pub use hydrorattle_host::sim::Snapshot;

/// Pictures are drawn this many times larger and averaged down to their final size,
/// which smooths the edges of discs, lines and text.
pub const SUPERSAMPLE: u32 = 2;

/// Rounds `v` output pixels, at `k` drawing pixels per output pixel, to drawing pixels.
fn px(k: f64, v: f64) -> i32 {
    (v * k).round() as i32
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
    crate::fonts::register();
    let k = SUPERSAMPLE;
    let (w, h) = size;
    let (bw, bh) = (w * k, h * k);
    let mut big = vec![255u8; bw as usize * bh as usize * 3];
    {
        // The buffer starts white.
        let root = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
        draw(&root, f64::from(k))?;
        root.present().map_err(drawing)?;
    }
    let (k, bw, w) = (k as usize, bw as usize, w as usize);
    let mut small = vec![0u8; w * h as usize * 3];
    let mut sums = vec![0u32; w * 3];
    for (y, out) in small.chunks_exact_mut(w * 3).enumerate() {
        sums.fill(0);
        for row in big[y * k * bw * 3..(y + 1) * k * bw * 3].chunks_exact(bw * 3) {
            for (x, px) in row.chunks_exact(3 * k).enumerate() {
                for (c, v) in px.iter().enumerate() {
                    sums[3 * x + c % 3] += u32::from(*v);
                }
            }
        }
        let n = (k * k) as u32;
        for (o, s) in out.iter_mut().zip(&sums) {
            *o = ((s + n / 2) / n) as u8;
        }
    }
    let mut backend = BitMapBackend::new(path, size);
    backend.blit_bitmap((0, 0), size, &small).map_err(drawing)?;
    backend.present().map_err(drawing)?;
    Ok(())
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
}
