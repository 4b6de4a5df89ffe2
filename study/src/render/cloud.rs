//! A falling cloud's pictures, one row per moment: a thin slice through its axis (the
//! spheres' centres in `x-z`) and the number density averaged about the axis in
//! `(r, z)`, with arrows of the mean velocity in the cloud's frame (the circulation).

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

use super::{FONT, TAIL_COLOR, drawing, px, save_png, short, tick};
use crate::cloud::AxisMap;

/// One moment of a cloud, as drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudRow {
    /// Simulated time.
    pub time: f64,
    /// The slice's centres `(x, z)` relative to the cloud's centre.
    pub slice: Vec<(f64, f64)>,
    /// The slice's half width, for its title.
    pub half_width: f64,
    /// The averaged density and velocity about the axis.
    pub map: AxisMap,
    /// The slice panel's span: `x` within `±x_half`, `z` from `z_range.0` to `.1`.
    pub x_half: f64,
    /// See `x_half`.
    pub z_range: (f64, f64),
}

/// Colour of a density relative to the peak (`0` white, `1` dark blue).
fn shade(f: f64) -> RGBColor {
    let f = f.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
    // White to light blue to dark blue, in two linear pieces.
    let (a, b, t) = match f < 0.5 {
        true => ((255.0, 255.0, 255.0), (120.0, 170.0, 220.0), 2.0 * f),
        false => ((120.0, 170.0, 220.0), (8.0, 40.0, 110.0), 2.0 * f - 1.0),
    };
    RGBColor(lerp(a.0, b.0, t), lerp(a.1, b.1, t), lerp(a.2, b.2, t))
}

/// Draws `rows` (one per moment, top to bottom) to a PNG of width `width`, each row
/// `row_height` pixels high.
pub fn draw_cloud(
    path: &Path,
    title: &str,
    rows: &[CloudRow],
    width: u32,
    row_height: u32,
) -> Result<()> {
    if rows.is_empty() {
        return Err(anyhow!("a cloud picture needs at least one moment"));
    }
    let size = (width, 40 + row_height * rows.len() as u32);
    save_png(path, size, |root, k| {
        root.fill(&WHITE).map_err(drawing)?;
        let (head, body) = root.split_vertically(px(k, 40.0));
        head.draw(&Text::new(
            title.to_string(),
            (px(k, 12.0), px(k, 8.0)),
            (FONT, 22.0 * k).into_font().color(&BLACK),
        ))
        .map_err(drawing)?;
        for (row, area) in rows.iter().zip(body.split_evenly((rows.len(), 1))) {
            let (left, right) = area.split_horizontally(area.dim_in_pixel().0 as i32 / 2);
            draw_slice(&left, row, k)?;
            draw_map(&right, row, k)?;
        }
        Ok(())
    })
}

fn draw_slice<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    row: &CloudRow,
    k: f64,
) -> Result<()> {
    let w = |v: f64| px(k, v).max(1) as u32;
    let caption = format!(
        "t = {}: slice |y - y_c| < {} ({} spheres)",
        short(row.time),
        short(row.half_width),
        row.slice.len()
    );
    let mut ctx = ChartBuilder::on(area)
        .caption(caption, (FONT, 16.0 * k))
        .margin(w(8.0))
        .x_label_area_size(w(36.0))
        .y_label_area_size(w(52.0))
        .build_cartesian_2d(-row.x_half..row.x_half, row.z_range.0..row.z_range.1)
        .map_err(drawing)?;
    let format = |v: &f64| tick(*v);
    ctx.configure_mesh()
        .disable_mesh()
        .x_desc("x - x_c")
        .y_desc("z - z_c")
        .x_label_formatter(&format)
        .y_label_formatter(&format)
        .label_style((FONT, 12.0 * k))
        .axis_desc_style((FONT, 13.0 * k))
        .draw()
        .map_err(drawing)?;
    let inside = |&&(x, z): &&(f64, f64)| {
        x.abs() <= row.x_half && (row.z_range.0..=row.z_range.1).contains(&z)
    };
    ctx.draw_series(
        row.slice
            .iter()
            .filter(inside)
            .map(|&p| Circle::new(p, px(k, 1.6), TAIL_COLOR.filled())),
    )
    .map_err(drawing)?;
    Ok(())
}

fn draw_map<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    row: &CloudRow,
    k: f64,
) -> Result<()> {
    let w = |v: f64| px(k, v).max(1) as u32;
    let m = &row.map;
    let peak = m.peak();
    let caption = format!(
        "density about the axis (peak {:.2e}), cloud-frame velocity",
        peak
    );
    let mut ctx = ChartBuilder::on(area)
        .caption(caption, (FONT, 16.0 * k))
        .margin(w(8.0))
        .x_label_area_size(w(36.0))
        .y_label_area_size(w(52.0))
        .build_cartesian_2d(0.0..m.r_max, -m.z_half..m.z_half)
        .map_err(drawing)?;
    let format = |v: &f64| tick(*v);
    ctx.configure_mesh()
        .disable_mesh()
        .x_desc("r (distance from the axis)")
        .y_desc("z - z_c")
        .x_label_formatter(&format)
        .y_label_formatter(&format)
        .label_style((FONT, 12.0 * k))
        .axis_desc_style((FONT, 13.0 * k))
        .draw()
        .map_err(drawing)?;
    let (dr, dz) = (m.r_max / m.nr as f64, 2.0 * m.z_half / m.nz as f64);
    let cells = (0..m.nz).flat_map(|iz| (0..m.nr).map(move |ir| (ir, iz)));
    ctx.draw_series(cells.clone().map(|(ir, iz)| {
        let (r, z) = m.cell_centre(ir, iz);
        let f = match peak > 0.0 {
            true => m.density[iz * m.nr + ir] / peak,
            false => 0.0,
        };
        Rectangle::new(
            [(r - 0.5 * dr, z - 0.5 * dz), (r + 0.5 * dr, z + 0.5 * dz)],
            shade(f).filled(),
        )
    }))
    .map_err(drawing)?;
    // Arrows: the largest mean speed among cells with a few spheres spans one cell.
    let counted = |ir: usize, iz: usize| m.count[iz * m.nr + ir] >= 5;
    let fastest = cells
        .clone()
        .filter(|&(ir, iz)| counted(ir, iz))
        .map(|(ir, iz)| m.velocity[iz * m.nr + ir][0].hypot(m.velocity[iz * m.nr + ir][1]))
        .fold(0.0, f64::max);
    if fastest > 0.0 {
        let scale = 0.9 * dr.min(dz) / fastest;
        let pen = RGBColor(200, 30, 30).stroke_width(w(1.5));
        for (ir, iz) in cells.filter(|&(ir, iz)| counted(ir, iz)) {
            let (r, z) = m.cell_centre(ir, iz);
            let [ur, uz] = m.velocity[iz * m.nr + ir];
            let (tr, tz) = (r + scale * ur, z + scale * uz);
            // The head: two short strokes back from the tip at 25 degrees.
            let (len, ang) = ((ur * ur + uz * uz).sqrt() * scale, uz.atan2(ur));
            let h = 0.35 * len;
            let wing = |s: f64| {
                let a = ang + std::f64::consts::PI + s * 0.44;
                (tr + h * a.cos(), tz + h * a.sin())
            };
            ctx.draw_series([
                PathElement::new(vec![(r, z), (tr, tz)], pen),
                PathElement::new(vec![wing(1.0), (tr, tz), wing(-1.0)], pen),
            ])
            .map_err(drawing)?;
        }
    }
    Ok(())
}
