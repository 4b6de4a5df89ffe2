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
