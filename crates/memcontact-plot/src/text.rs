//! Text with the bundled DejaVu Sans font (no system font is needed): measuring and
//! drawing horizontal or vertical (bottom-to-top) strings on a [`Canvas`].

use crate::canvas::{Canvas, PixelRect, Rgb};
use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use std::sync::OnceLock;

/// The bundled font (DejaVu Sans, Bitstream Vera licence: `assets/LICENSE-DejaVu.txt`).
pub(crate) static FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    // The font is compiled in and known to parse (tested), so this cannot fail at run time.
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).expect("the bundled font parses"))
}

/// Where a text's anchor point lies on its box.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    /// Left end, vertically centred.
    Left,
    /// Centre.
    Center,
    /// Right end, vertically centred.
    Right,
    /// Top edge, horizontally centred.
    Top,
    /// Bottom edge, horizontally centred.
    Bottom,
    /// Top-left corner.
    TopLeft,
}

/// A text style: size in pixels and colour.
#[derive(Debug, Clone, Copy)]
pub struct Style {
    /// Font size (pixels per em).
    pub size: f32,
    /// Colour.
    pub color: Rgb,
}

impl Style {
    /// A style of `size` pixels in dark grey.
    pub fn new(size: f32) -> Style {
        Style {
            size,
            color: [30, 30, 30],
        }
    }

    /// The same size in another colour.
    pub fn color(self, color: Rgb) -> Style {
        Style { color, ..self }
    }
}

/// Glyph positions of a laid-out string: `(glyph, x offset)` and the total advance.
fn layout(text: &str, size: f32) -> (Vec<(ab_glyph::GlyphId, f32)>, f32) {
    let f = font().as_scaled(PxScale::from(size));
    let mut x = 0.0f32;
    let mut prev = None;
    let mut out = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            x += f.kern(p, id);
        }
        out.push((id, x));
        x += f.h_advance(id);
        prev = Some(id);
    }
    (out, x)
}

/// The size of `text`'s box: (advance width, line height) in pixels.
pub fn measure(text: &str, size: f32) -> (i32, i32) {
    let f = font().as_scaled(PxScale::from(size));
    let (_, w) = layout(text, size);
    (w.ceil() as i32, (f.ascent() - f.descent()).ceil() as i32)
}

/// Renders `text` into a coverage buffer of its box size (row-major, width × height).
fn rasterise(text: &str, size: f32) -> (i32, i32, Vec<f32>) {
    let scale = PxScale::from(size);
    let f = font().as_scaled(scale);
    let (glyphs, _) = layout(text, size);
    let (w, h) = measure(text, size);
    let (w, h) = (w.max(1) + 2, h.max(1));
    let mut cov = vec![0.0f32; (w * h) as usize];
    let ascent = f.ascent();
    for (id, x) in glyphs {
        let g = id.with_scale_and_position(scale, point(1.0 + x, ascent));
        if let Some(og) = font().outline_glyph(g) {
            let b = og.px_bounds();
            og.draw(|gx, gy, c| {
                let px = b.min.x as i32 + gx as i32;
                let py = b.min.y as i32 + gy as i32;
                if px >= 0 && py >= 0 && px < w && py < h {
                    let i = (py * w + px) as usize;
                    cov[i] = (cov[i] + c).min(1.0);
                }
            });
        }
    }
    (w, h, cov)
}

/// The box `text` occupies when drawn at `(x, y)` with `anchor` (horizontal text).
pub fn text_box(text: &str, size: f32, x: f64, y: f64, anchor: Anchor) -> PixelRect {
    let (w, h) = measure(text, size);
    let (w, h) = (w + 2, h);
    let (x, y) = (x.round() as i32, y.round() as i32);
    let (x0, y0) = match anchor {
        Anchor::Left => (x, y - h / 2),
        Anchor::Center => (x - w / 2, y - h / 2),
        Anchor::Right => (x - w, y - h / 2),
        Anchor::Top => (x - w / 2, y),
        Anchor::Bottom => (x - w / 2, y - h),
        Anchor::TopLeft => (x, y),
    };
    PixelRect::new(x0, y0, w, h)
}

/// Draws `text` horizontally at `(x, y)` with `anchor`; returns the box it occupies.
pub fn draw(
    canvas: &mut Canvas,
    text: &str,
    style: Style,
    x: f64,
    y: f64,
    anchor: Anchor,
) -> PixelRect {
    let r = text_box(text, style.size, x, y, anchor);
    let (w, h, cov) = rasterise(text, style.size);
    for j in 0..h {
        for i in 0..w {
            let a = cov[(j * w + i) as usize];
            if a > 0.0 {
                canvas.blend(r.x0 + i, r.y0 + j, style.color, a);
            }
        }
    }
    r
}

/// Draws `text` rotated a quarter turn counter-clockwise (reading upwards), centred on
/// `(x, y)`; returns the box it occupies.
pub fn draw_vertical(canvas: &mut Canvas, text: &str, style: Style, x: f64, y: f64) -> PixelRect {
    let (w, h, cov) = rasterise(text, style.size);
    // Rotated: width h, height w.
    let x0 = x.round() as i32 - h / 2;
    let y0 = y.round() as i32 - w / 2;
    for j in 0..h {
        for i in 0..w {
            let a = cov[(j * w + i) as usize];
            if a > 0.0 {
                // (i, j) → column j, row (w - 1 - i).
                canvas.blend(x0 + j, y0 + (w - 1 - i), style.color, a);
            }
        }
    }
    PixelRect::new(x0, y0, h, w)
}

/// The largest size ≤ `size` (down to `min`) at which `text` is at most `width` wide.
pub fn fit(text: &str, size: f32, min: f32, width: i32) -> f32 {
    let mut s = size;
    while s > min && measure(text, s).0 > width {
        s -= 1.0;
    }
    s
}

/// `text` cut (with an ellipsis at the front) so that it is at most `width` wide at `size`.
pub fn ellipsize_front(text: &str, size: f32, width: i32) -> String {
    if measure(text, size).0 <= width {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    for k in 1..chars.len() {
        let s: String = std::iter::once('…')
            .chain(chars[k..].iter().copied())
            .collect();
        if measure(&s, size).0 <= width {
            return s;
        }
    }
    "…".into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_font_parses_and_text_has_ink() {
        let (w, h) = measure("u [m]", 16.0);
        assert!(w > 20 && w < 80 && h > 12 && h < 30, "{w} × {h}");
        assert!(measure("long text here", 16.0).0 > measure("short", 16.0).0);
        let mut c = Canvas::new(100, 40);
        let r = draw(
            &mut c,
            "φ ≤ u²",
            Style::new(18.0),
            50.0,
            20.0,
            Anchor::Center,
        );
        assert!(r.width() > 20);
        let ink = c.rgb.chunks(3).filter(|p| p[0] < 128).count();
        assert!(ink > 30, "{ink} dark pixels");
        let mut v = Canvas::new(40, 100);
        let r = draw_vertical(&mut v, "y [m]", Style::new(16.0), 20.0, 50.0);
        assert!(r.height() > r.width());
        assert!(v.rgb.chunks(3).filter(|p| p[0] < 128).count() > 20);
        assert!(ellipsize_front("a/very/long/path/case.toml", 14.0, 80).starts_with('…'));
        assert!(fit("some title", 30.0, 10.0, 50) < 30.0);
    }
}
