//! The font of every picture and chart: DejaVu Sans, regular and bold, embedded in the
//! binary (`fonts/`, licence in `fonts/LICENSE`) and registered with plotters' ab_glyph
//! text backend. Drawing text needs no system library (no fontconfig, no freetype) and
//! no installed font.

use plotters::style::{FontStyle, register_font};
use std::sync::Once;

/// The family every text style of [`crate::render`] names.
pub const FAMILY: &str = "sans-serif";

const REGULAR: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");
const BOLD: &[u8] = include_bytes!("../fonts/DejaVuSans-Bold.ttf");

/// Registers the embedded fonts under [`FAMILY`], once per process (later calls return
/// at once). The drawing entry points call it before they build a text style; a style
/// other than normal and bold (italic, oblique) falls back to normal.
pub fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for (style, bytes) in [(FontStyle::Normal, REGULAR), (FontStyle::Bold, BOLD)] {
            let registered = register_font(FAMILY, style, bytes).is_ok();
            assert!(
                registered,
                "the embedded {} font does not parse",
                style.as_str()
            );
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::style::IntoFont;

    /// Every style resolves to an embedded font that lays text out, and bold to the bold
    /// face (a style is chosen when the font is made: `(family, size, style)`; plotters'
    /// `FontDesc::style` keeps the face already loaded).
    #[test]
    fn styles_resolve_and_measure() {
        register();
        register();
        let width = |style: FontStyle| {
            let (w, h) = (FAMILY, 20.0, style)
                .into_font()
                .box_size("Wide 0.5")
                .expect("a registered font");
            assert!(w > 40 && h > 5, "{}: {w} x {h}", style.as_str());
            w
        };
        let regular = width(FontStyle::Normal);
        assert!(width(FontStyle::Bold) > regular, "bold is the bold face");
        assert_eq!(
            width(FontStyle::Italic),
            regular,
            "italic falls back to regular"
        );
    }
}
