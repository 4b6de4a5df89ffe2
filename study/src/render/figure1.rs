//! The paper's Figure 1 layout: cases side by side, initial and final state, side and
//! top views.

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use std::path::Path;

use super::{
    FONT, Snapshot, View, chain_colors, draw_panel, drawing, fit_scale, px, save_png, short,
};

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
    draw_figure1_scaled(path, cases, false)
}

/// [`draw_figure1`] with one common scale: every panel of every case at the largest
/// scale at which all of them fit, so that sizes compare across cases.
pub fn draw_figure1_common(path: &Path, cases: &[Figure1Case]) -> Result<()> {
    draw_figure1_scaled(path, cases, true)
}

/// The largest scale at which the four panels of `case` fit.
fn case_scale(case: &Figure1Case, side: (u32, u32), top: (u32, u32)) -> f64 {
    fit_scale(
        &[(&case.initial, View::Side), (&case.last, View::Side)],
        side,
    )
    .min(fit_scale(
        &[(&case.initial, View::Top), (&case.last, View::Top)],
        top,
    ))
}

fn draw_figure1_scaled(path: &Path, cases: &[Figure1Case], common: bool) -> Result<()> {
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
    let scales: Vec<f64> = cases
        .iter()
        .map(|c| case_scale(c, as_u32(side_size), as_u32(top_size)))
        .collect();
    let smallest = scales.iter().copied().fold(f64::INFINITY, f64::min);
    let heading = if common {
        "Settling helical chains at one common scale (every panel): side view (upper row) and \
         top view (lower row), initial (left) and final (right); head red, tails blue"
    } else {
        "Settling helical chains: side view (upper row) and top view (lower row), \
         initial (left) and final (right) state; head red, tails blue, last tail green"
    };
    save_png(path, (width as u32, height as u32), |root, k| {
        root.draw(&Text::new(
            heading,
            (px(k, FIG1_GAP), px(k, 14.0)),
            (FONT, 19.0 * k).into_font().color(&BLACK),
        ))
        .map_err(drawing)?;
        for (c, case) in cases.iter().enumerate() {
            let x0 = FIG1_GAP + c as f64 * (block_w + FIG1_GAP);
            root.draw(&Text::new(
                case.title.clone(),
                (px(k, x0), px(k, FIG1_HEADING + 4.0)),
                (FONT, 21.0 * k, FontStyle::Bold).into_font().color(&BLACK),
            ))
            .map_err(drawing)?;
            let scale = if common { smallest } else { scales[c] };
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

/// One row of a snapshot grid: a case's title and its configurations, by time (None
/// for a time the run did not reach).
#[derive(Debug, Clone, PartialEq)]
pub struct SnapshotRow {
    /// Row title, e.g. the case's.
    pub title: String,
    /// One configuration per column.
    pub snapshots: Vec<Option<Snapshot>>,
}

/// Width and height of a snapshot panel, pixels.
const SNAP_PANEL: (f64, f64) = (230.0, 420.0);

/// Draws a grid of side views to a PNG: rows (cases) by columns (the times asked,
/// `times`), every panel at one common scale; a panel is titled with the time of its
/// configuration (the first step at or after the time asked) and left empty for a time
/// the run did not reach.
pub fn draw_snapshots(path: &Path, rows: &[SnapshotRow], times: &[f64]) -> Result<()> {
    let columns = times.len();
    if rows.is_empty() || columns == 0 || rows.iter().any(|r| r.snapshots.len() != columns) {
        return Err(anyhow!(
            "a snapshot grid needs rows with one configuration per time ({columns} times)"
        ));
    }
    let (pw, ph) = SNAP_PANEL;
    let inset = 2.0;
    let panel = ((pw - 2.0 * inset) as u32, (ph - 2.0 * inset) as u32);
    let items: Vec<(&Snapshot, View)> = rows
        .iter()
        .flat_map(|r| r.snapshots.iter().flatten())
        .map(|s| (s, View::Side))
        .collect();
    let scale = if items.is_empty() {
        1.0
    } else {
        fit_scale(&items, panel)
    };
    let width = 2.0 * FIG1_GAP + columns as f64 * pw;
    let row_h = FIG1_CASE_TITLE + ph;
    let height = FIG1_HEADING + rows.len() as f64 * row_h + FIG1_GAP;
    save_png(path, (width as u32, height as u32), |root, k| {
        let font = |size: f64| (FONT, size * k).into_font().color(&BLACK);
        root.draw(&Text::new(
            "Side views at the times asked, one common scale; head red, tails blue",
            (px(k, FIG1_GAP), px(k, 14.0)),
            font(19.0),
        ))
        .map_err(drawing)?;
        for (r, row) in rows.iter().enumerate() {
            let top = FIG1_HEADING + r as f64 * row_h;
            root.draw(&Text::new(
                row.title.clone(),
                (px(k, FIG1_GAP), px(k, top + 4.0)),
                (FONT, 20.0 * k, FontStyle::Bold).into_font().color(&BLACK),
            ))
            .map_err(drawing)?;
            for (c, (snap, &asked)) in row.snapshots.iter().zip(times).enumerate() {
                let left = FIG1_GAP + c as f64 * pw;
                let area = root.clone().shrink(
                    (px(k, left + inset), px(k, top + FIG1_CASE_TITLE + inset)),
                    (
                        px(k, f64::from(panel.0)) as u32,
                        px(k, f64::from(panel.1)) as u32,
                    ),
                );
                match snap {
                    Some(s) => {
                        let colors = chain_colors(s.positions.len());
                        let title = format!("t = {}", short(s.time));
                        draw_panel(&area, s, &colors, View::Side, scale, &title, k)?;
                    }
                    None => {
                        let note = format!("t = {}: not reached", short(asked));
                        area.draw(&Text::new(note, (px(k, 6.0), px(k, 4.0)), font(15.0)))
                            .map_err(drawing)?;
                    }
                }
            }
        }
        Ok(())
    })
}
