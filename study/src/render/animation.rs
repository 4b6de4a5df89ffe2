//! GIF animations of a run: one side-view sphere panel per frame, centred on the
//! spheres, at one scale for the whole animation, with the time over the spheres.
//!
//! Fast by construction: frames are drawn with plotters into RGB buffers in parallel,
//! mapped to a fixed 256-colour palette (the scene's few colours, their blends, greys
//! and a coarse colour cube) through a lookup table instead of per-frame quantisation,
//! reduced to the rectangle of pixels that changed since the previous frame (the
//! unchanged ones in it transparent), and LZW-encoded in parallel with the `gif` crate.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Result, anyhow};
use gif::{DisposalMethod, Encoder, Frame, Repeat};
use plotters::prelude::*;
use rayon::prelude::*;

use super::{
    FONT, HEAD_COLOR, LAST_COLOR, OUTLINE_COLOR, Snapshot, TAIL_COLOR, View, draw_panel, drawing,
    fit_scale,
};

/// Palette index of "unchanged since the previous frame".
pub const CLEAR_INDEX: u8 = 255;

/// An animation to write.
#[derive(Debug, Clone, Copy)]
pub struct Animation<'a> {
    /// Title of every frame (the time is added).
    pub title: &'a str,
    /// The configurations, by time.
    pub frames: &'a [Snapshot],
    /// Sphere colours.
    pub colors: &'a [RGBColor],
    /// Frame size, pixels (at most 65535 each way).
    pub size: (u32, u32),
    /// Delay between frames, hundredths of a second (the last frame holds 2.5 s).
    pub delay: u16,
}

/// What was written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GifInfo {
    /// Frames.
    pub frames: usize,
    /// File size, bytes.
    pub bytes: usize,
}

/// The palette (256 RGB triples) and the lookup table from 5-bit-per-channel colours
/// to the nearest palette index (never [`CLEAR_INDEX`]).
fn palette() -> &'static (Vec<u8>, Vec<u8>) {
    static PALETTE: OnceLock<(Vec<u8>, Vec<u8>)> = OnceLock::new();
    PALETTE.get_or_init(|| {
        let rgb = |c: RGBColor| [c.0, c.1, c.2];
        let base = [
            [255, 255, 255],
            [0, 0, 0],
            rgb(OUTLINE_COLOR),
            rgb(HEAD_COLOR),
            rgb(TAIL_COLOR),
            rgb(LAST_COLOR),
            [190, 190, 190],
        ];
        let mix = |a: [u8; 3], b: [u8; 3], t: f64| -> [u8; 3] {
            std::array::from_fn(|c| {
                (f64::from(a[c]) * (1.0 - t) + f64::from(b[c]) * t).round() as u8
            })
        };
        let mut colors: Vec<[u8; 3]> = base.to_vec();
        for i in 0..base.len() {
            for j in i + 1..base.len() {
                colors.extend([0.25, 0.5, 0.75].map(|t| mix(base[i], base[j], t)));
            }
        }
        colors.extend((0..16u8).map(|g| [g * 17; 3]));
        let level = [0, 85, 170, 255];
        for r in level {
            for g in level {
                colors.extend(level.map(|b| [r, g, b]));
            }
        }
        for fg in [HEAD_COLOR, TAIL_COLOR, LAST_COLOR] {
            for bg in [[255, 255, 255], rgb(OUTLINE_COLOR)] {
                colors.extend([0.125, 0.375, 0.625, 0.875].map(|t| mix(rgb(fg), bg, t)));
            }
        }
        colors.truncate(usize::from(CLEAR_INDEX));
        colors.resize(256, [255, 255, 255]);
        let search = &colors[..usize::from(CLEAR_INDEX)];
        let lut: Vec<u8> = (0..32 * 32 * 32u32)
            .into_par_iter()
            .map(|key| {
                let c = [key >> 10, (key >> 5) & 31, key & 31].map(|v| (v * 8 + 4) as i32);
                let (mut best, mut best_d) = (0, i32::MAX);
                for (i, p) in search.iter().enumerate() {
                    let d = (i32::from(p[0]) - c[0]).pow(2)
                        + (i32::from(p[1]) - c[1]).pow(2)
                        + (i32::from(p[2]) - c[2]).pow(2);
                    if d < best_d {
                        (best, best_d) = (i, d);
                    }
                }
                best as u8
            })
            .collect();
        (colors.concat(), lut)
    })
}

/// Palette indices of an RGB buffer.
fn quantise(rgb: &[u8]) -> Vec<u8> {
    let lut = &palette().1;
    rgb.chunks_exact(3)
        .map(|p| {
            let key = (usize::from(p[0] >> 3) << 10)
                | (usize::from(p[1] >> 3) << 5)
                | usize::from(p[2] >> 3);
            lut[key]
        })
        .collect()
}

/// Draws one frame (side view, `scale` pixels per length unit) as palette indices.
fn frame_indices(a: &Animation<'_>, snapshot: &Snapshot, scale: f64) -> Result<Vec<u8>> {
    crate::fonts::register();
    let (w, h) = a.size;
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw_panel(&root, snapshot, a.colors, View::Side, scale, "", 1.0)?;
        // The time, centred over the spheres: the pixels that change from frame to
        // frame stay in one narrow column (small frames, fast encoding).
        let stamp = format!("{}  t = {:.1}", a.title, snapshot.time);
        let style = (FONT, 15.0).into_font().color(&BLACK);
        let half = (stamp.chars().count() * 4) as i32;
        root.draw(&Text::new(stamp, (w as i32 / 2 - half, 5), style))
            .map_err(drawing)?;
        root.present().map_err(drawing)?;
    }
    Ok(quantise(&rgb))
}

/// The pixels of `now` that differ from `before` (the others [`CLEAR_INDEX`]), cropped
/// to the rectangle that holds them: `(left, top, width, height, indices)`.
fn changes(now: &[u8], before: &[u8], w: usize) -> (u16, u16, u16, u16, Vec<u8>) {
    let h = now.len() / w;
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (y, (a, b)) in now.chunks_exact(w).zip(before.chunks_exact(w)).enumerate() {
        if let Some(first) = a.iter().zip(b).position(|(p, q)| p != q) {
            let last = w - a
                .iter()
                .rev()
                .zip(b.iter().rev())
                .position(|(p, q)| p != q)
                .unwrap_or(0);
            (x0, y0, x1, y1) = (x0.min(first), y0.min(y), x1.max(last), y1.max(y + 1));
        }
    }
    if x0 >= x1 {
        return (0, 0, 1, 1, vec![CLEAR_INDEX]);
    }
    let mut out = Vec::with_capacity((x1 - x0) * (y1 - y0));
    for y in y0..y1 {
        let row = y * w;
        out.extend(
            now[row + x0..row + x1]
                .iter()
                .zip(&before[row + x0..row + x1])
                .map(|(&a, &b)| if a == b { CLEAR_INDEX } else { a }),
        );
    }
    let c = |v: usize| v as u16;
    (c(x0), c(y0), c(x1 - x0), c(y1 - y0), out)
}

/// Writes `a` as a looping GIF to `path` (atomically): every frame at one scale, the
/// largest at which each frame fits around its own centre.
pub fn write_gif(path: &Path, a: &Animation<'_>) -> Result<GifInfo> {
    let (w, h) = a.size;
    if a.frames.is_empty() || w == 0 || h == 0 || w > 65535 || h > 65535 {
        return Err(anyhow!(
            "an animation needs a frame and a size of 1 to 65535 pixels each way ({} frames, {w} x {h})",
            a.frames.len()
        ));
    }
    let items: Vec<(&Snapshot, View)> = a.frames.iter().map(|s| (s, View::Side)).collect();
    let scale = fit_scale(&items, a.size);
    let indices: Vec<Vec<u8>> = a
        .frames
        .par_iter()
        .map(|s| frame_indices(a, s, scale))
        .collect::<Result<_>>()?;
    let last = indices.len() - 1;
    let frames: Vec<Frame<'static>> = (0..indices.len())
        .into_par_iter()
        .map(|i| {
            let mut f = if i == 0 {
                Frame::from_indexed_pixels(w as u16, h as u16, &indices[0], None)
            } else {
                let (left, top, fw, fh, px) = changes(&indices[i], &indices[i - 1], w as usize);
                let mut f = Frame::from_indexed_pixels(fw, fh, &px, Some(CLEAR_INDEX));
                (f.left, f.top) = (left, top);
                f
            };
            f.delay = if i == last { 250 } else { a.delay };
            f.dispose = DisposalMethod::Keep;
            f.make_lzw_pre_encoded();
            f
        })
        .collect();
    let mut bytes = Vec::new();
    {
        let gif_error =
            |e: gif::EncodingError| anyhow!("{}: GIF encoding failed: {e}", path.display());
        let mut enc =
            Encoder::new(&mut bytes, w as u16, h as u16, &palette().0).map_err(gif_error)?;
        enc.set_repeat(Repeat::Infinite).map_err(gif_error)?;
        for f in &frames {
            enc.write_lzw_pre_encoded_frame(f).map_err(gif_error)?;
        }
    }
    hydrorattle_host::output::write_atomic(path, &bytes)?;
    Ok(GifInfo {
        frames: frames.len(),
        bytes: bytes.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_colours_are_in_the_palette() {
        let rgb: Vec<u8> = [
            HEAD_COLOR,
            TAIL_COLOR,
            LAST_COLOR,
            OUTLINE_COLOR,
            WHITE,
            BLACK,
        ]
        .iter()
        .flat_map(|c| [c.0, c.1, c.2])
        .collect();
        let (pal, _) = palette();
        for (k, i) in quantise(&rgb).into_iter().enumerate() {
            assert_ne!(i, CLEAR_INDEX);
            let got = &pal[3 * usize::from(i)..3 * usize::from(i) + 3];
            let want = &rgb[3 * k..3 * k + 3];
            let close = got.iter().zip(want).all(|(a, b)| a.abs_diff(*b) <= 4);
            assert!(close, "{got:?} {want:?}");
        }
    }

    #[test]
    fn only_changed_pixels_are_kept() {
        let before = vec![1u8; 12];
        let mut now = before.clone();
        now[5] = 2;
        now[6] = 3;
        // 4 wide, 3 high: pixels (1, 1) and (2, 1).
        assert_eq!(changes(&now, &before, 4), (1, 1, 2, 1, vec![2, 3]));
        assert_eq!(
            changes(&before, &before, 4),
            (0, 0, 1, 1, vec![CLEAR_INDEX])
        );
    }
}
