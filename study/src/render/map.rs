//! The category map (e.g. the outcome phase diagram).

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

use super::{FONT, drawing, px, save_png, tick};

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
                (FONT, 17.0 * k, FontStyle::Bold).into_font().color(&BLACK),
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
    fn cell_edges_are_midpoints() {
        assert_eq!(edges(&[1.0, 2.0, 4.0]), vec![0.5, 1.5, 3.0, 5.0]);
    }
}
