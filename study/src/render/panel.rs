//! Projections of 3-D space and the sphere panel: the spheres of one configuration in
//! one view, to scale, with a scale bar and the direction of gravity.

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

use super::{
    FONT, OUTLINE_COLOR, Snapshot, TAIL_COLOR, WALL_COLOR, WALL_FILL, drawing, nice_length, px,
    save_png, short,
};

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

/// Screen-space bounding box `(min_right, min_up, max_right, max_up)` of the spheres
/// in a view, radii included, and of the wall where the view shows it
/// ([`wall_in_view`]).
pub fn extent(snapshot: &Snapshot, view: View) -> (f64, f64, f64, f64) {
    let b = spheres_extent(snapshot, view);
    match wall_in_view(snapshot, view) {
        Some(h) => (b.0, b.1.min(h), b.2, b.3.max(h)),
        None => b,
    }
}

/// The height at which a side view draws the snapshot's wall: the wall's, when it lies
/// within the spheres' larger extent below their lowest point (so that a wall far
/// below does not shrink the spheres to dots; the panel then names it in words).
/// `None` for top views (the wall is the whole picture plane) and without a wall.
pub fn wall_in_view(snapshot: &Snapshot, view: View) -> Option<f64> {
    let h = snapshot.wall.filter(|h| h.is_finite())?;
    if view != View::Side {
        return None;
    }
    let b = spheres_extent(snapshot, view);
    let reach = (b.2 - b.0).max(b.3 - b.1);
    (b.1 - h <= reach).then_some(h)
}

/// [`extent`] of the spheres alone.
fn spheres_extent(snapshot: &Snapshot, view: View) -> (f64, f64, f64, f64) {
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

/// Refuses a panel whose spheres cannot be placed to a pixel at `scale`: coordinates
/// so far from the origin, for the spheres' spread, that their rounding (an epsilon of
/// the largest) is over half a pixel, or a scale that is not a positive number. Such a
/// picture would be wrong, and drawing it at the scale its rounding implies unbounded.
pub fn drawable(b: (f64, f64, f64, f64), scale: f64) -> Result<()> {
    let reach = [b.0, b.1, b.2, b.3]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let rounding = reach * f64::EPSILON * scale;
    if scale.is_finite() && scale > 0.0 && rounding <= 0.5 {
        return Ok(());
    }
    Err(Undrawable(format!(
        "the spheres cannot be drawn to scale: coordinates up to {reach:e} for a spread of {:e} \
         (their rounding is {rounding:e} pixels)",
        (b.2 - b.0).max(b.3 - b.1)
    ))
    .into())
}

/// Why a picture was not drawn ([`drawable`]): its caller may skip it.
#[derive(Debug)]
pub struct Undrawable(pub String);

impl std::fmt::Display for Undrawable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Undrawable {}

/// Spheres beyond this many are drawn without outlines (a big scene stays fast and
/// readable).
pub const OUTLINE_MAX: usize = 2000;

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
    drawable(b, scale)?;
    let (uc, vc) = (0.5 * (b.0 + b.2), 0.5 * (b.1 + b.3));
    let (xc, yc) = (0.5 * w, PANEL_TITLE + 0.5 * (h - PANEL_TITLE - PANEL_FOOT));
    if let Some(z) = wall_in_view(snapshot, view) {
        // The solid below the wall down to the foot, then the plane, under the spheres.
        let y = yc - (z - vc) * scale;
        let foot = (h - PANEL_FOOT).max(y + 4.0);
        area.draw(&Rectangle::new(
            [(px(k, 1.0), px(k, y)), (px(k, w - 1.0), px(k, foot))],
            WALL_FILL.filled(),
        ))
        .map_err(drawing)?;
        area.draw(&PathElement::new(
            vec![(px(k, 1.0), px(k, y)), (px(k, w - 1.0), px(k, y))],
            WALL_COLOR.stroke_width(px(k, 2.0).max(1) as u32),
        ))
        .map_err(drawing)?;
    }
    let outline = snapshot.positions.len() <= OUTLINE_MAX;
    let mut order: Vec<usize> = (0..snapshot.positions.len()).collect();
    let nearness = |i: usize| view.project(snapshot.positions[i]).2;
    order.sort_by(|&i, &j| nearness(i).total_cmp(&nearness(j)).then(i.cmp(&j)));
    for i in order {
        let (u, v, _) = view.project(snapshot.positions[i]);
        let centre = (px(k, xc + (u - uc) * scale), px(k, yc - (v - vc) * scale));
        // A dark disc with the coloured disc one output pixel smaller on top: the
        // outline, with no gap between fill and outline.
        // No disc larger than the panel's perimeter is needed to cover it: the work of
        // one disc stays bounded whatever the scale.
        let r = (snapshot.radii[i] * scale).clamp(1.5, 2.0 * (w + h)) * k;
        let color = colors.get(i).copied().unwrap_or(TAIL_COLOR);
        if outline {
            area.draw(&Circle::new(centre, r, OUTLINE_COLOR.filled()))
                .map_err(drawing)?;
            area.draw(&Circle::new(centre, (r - k).max(0.5 * r), color.filled()))
                .map_err(drawing)?;
        } else {
            area.draw(&Circle::new(centre, r, color.filled()))
                .map_err(drawing)?;
        }
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
        format!("{} a", hydrorattle_host::output::format_f64(bar)),
        (px(k, x1 + 5.0), px(k, y - 8.0)),
        font(13.0),
    ))
    .map_err(drawing)?;

    if let (View::Side, Some(z)) = (view, snapshot.wall) {
        let shown = wall_in_view(snapshot, view).is_some();
        let label = format!(
            "wall z = {}{}",
            short(z),
            if shown { "" } else { ", below" }
        );
        let x = w - 8.0 - 7.0 * label.chars().count() as f64;
        area.draw(&Text::new(label, (px(k, x), px(k, h - 18.0)), font(13.0)))
            .map_err(drawing)?;
    }

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

#[cfg(test)]
mod tests {
    use super::*;

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
            wall: None,
        };
        assert_eq!(extent(&s, View::Side), (-1.0, -1.0, 6.0, 3.0));
        let scale = fit_scale(&[(&s, View::Side)], (116, 200));
        assert!((scale - 100.0 / 7.0).abs() < 1e-12);
    }

    #[test]
    fn side_views_hold_a_wall_near_the_spheres() {
        // Spheres spanning x -1..6, z -1..3 (larger extent 7).
        let at = |wall| Snapshot {
            time: 0.0,
            positions: vec![[0.0, 0.0, 0.0], [4.0, 0.0, 1.0]],
            radii: vec![1.0, 2.0],
            wall: Some(wall),
        };
        // Touching, and a little below: drawn, and the extent reaches down to it.
        assert_eq!(wall_in_view(&at(-1.0), View::Side), Some(-1.0));
        assert_eq!(extent(&at(-1.0), View::Side), (-1.0, -1.0, 6.0, 3.0));
        assert_eq!(wall_in_view(&at(-8.0), View::Side), Some(-8.0));
        assert_eq!(extent(&at(-8.0), View::Side), (-1.0, -8.0, 6.0, 3.0));
        // Far below: named, not drawn; never in top views.
        assert_eq!(wall_in_view(&at(-8.5), View::Side), None);
        assert_eq!(extent(&at(-8.5), View::Side), (-1.0, -1.0, 6.0, 3.0));
        assert_eq!(wall_in_view(&at(-1.0), View::Top), None);
        assert_eq!(extent(&at(-5.0), View::Top), (-1.0, -2.0, 6.0, 2.0));
        assert_eq!(wall_in_view(&at(f64::NAN), View::Side), None);
    }
}
