//! Linear axes around a rectangle of pixels: frame, ticks, tick labels that never overlap,
//! axis titles, grid lines, a colour bar and a legend.

use crate::canvas::{Canvas, Coverage, PixelRect, Rgb};
use crate::colormap::{Colormap, Norm};
use crate::text::{self, Anchor, Style};
use crate::ticks;

/// Tick label size, pixels.
pub const TICK_SIZE: f32 = 15.0;
/// Axis title size, pixels.
pub const LABEL_SIZE: f32 = 17.0;
/// Frame colour.
pub const FRAME: Rgb = [90, 90, 90];
/// Grid colour.
pub const GRID: Rgb = [228, 228, 228];

/// Axes mapping the data box `x × y` onto the pixel rectangle `rect` (y up).
#[derive(Debug, Clone, Copy)]
pub struct Axes {
    /// The plotting rectangle.
    pub rect: PixelRect,
    /// Data x at the left and right edges.
    pub x: (f64, f64),
    /// Data y at the bottom and top edges.
    pub y: (f64, f64),
}

impl Axes {
    /// Pixel x of data x.
    pub fn px(&self, x: f64) -> f64 {
        self.rect.x0 as f64 + (x - self.x.0) / (self.x.1 - self.x.0) * self.rect.width() as f64
    }

    /// Pixel y of data y.
    pub fn py(&self, y: f64) -> f64 {
        self.rect.y1 as f64 - (y - self.y.0) / (self.y.1 - self.y.0) * self.rect.height() as f64
    }

    /// Tick positions and labels along x that fit side by side.
    fn x_ticks(&self) -> Vec<(f64, String)> {
        let mut count = (self.rect.width() / 80).max(2) as usize;
        loop {
            let (t, step) = ticks::ticks(self.x.0, self.x.1, count);
            let labels: Vec<(f64, String)> =
                t.iter().map(|&v| (v, ticks::format(v, step))).collect();
            let boxes: Vec<PixelRect> = labels
                .iter()
                .map(|(v, s)| text::text_box(s, TICK_SIZE, self.px(*v), 0.0, Anchor::Top).grow(6))
                .collect();
            let fits = boxes.windows(2).all(|w| !w[0].overlaps(&w[1]));
            if fits || count <= 2 {
                return labels;
            }
            count -= 1;
        }
    }

    /// Tick positions and labels along y that fit one above the other.
    fn y_ticks(&self) -> Vec<(f64, String)> {
        let mut count = (self.rect.height() / 55).max(2) as usize;
        loop {
            let (t, step) = ticks::ticks(self.y.0, self.y.1, count);
            let labels: Vec<(f64, String)> =
                t.iter().map(|&v| (v, ticks::format(v, step))).collect();
            let boxes: Vec<PixelRect> = labels
                .iter()
                .map(|(v, s)| text::text_box(s, TICK_SIZE, 0.0, self.py(*v), Anchor::Right).grow(4))
                .collect();
            let fits = boxes.windows(2).all(|w| !w[0].overlaps(&w[1]));
            if fits || count <= 2 {
                return labels;
            }
            count -= 1;
        }
    }

    /// Light grid lines at the ticks (drawn under the data).
    pub fn grid(&self, canvas: &mut Canvas) {
        for (v, _) in self.x_ticks() {
            let x = self.px(v).floor() as i32;
            canvas.fill_rect(
                PixelRect::new(x, self.rect.y0, 1, self.rect.height()),
                GRID,
                1.0,
            );
        }
        for (v, _) in self.y_ticks() {
            let y = self.py(v).floor() as i32;
            canvas.fill_rect(
                PixelRect::new(self.rect.x0, y, self.rect.width(), 1),
                GRID,
                1.0,
            );
        }
    }

    /// The frame, ticks, tick labels and axis titles; every text box is added to `boxes`.
    pub fn frame(
        &self,
        canvas: &mut Canvas,
        x_label: &str,
        y_label: &str,
        boxes: &mut Vec<PixelRect>,
    ) {
        let r = self.rect;
        canvas.stroke_rect(r.grow(1), FRAME);
        let style = Style::new(TICK_SIZE);
        let mut bottom = r.y1 + 8;
        for (v, s) in self.x_ticks() {
            let x = self.px(v).floor() as i32;
            canvas.fill_rect(PixelRect::new(x, r.y1 + 1, 1, 6), FRAME, 1.0);
            let b = text::draw(
                canvas,
                &s,
                style,
                x as f64 + 0.5,
                (r.y1 + 9) as f64,
                Anchor::Top,
            );
            bottom = bottom.max(b.y1);
            boxes.push(b);
        }
        let mut left = r.x0 - 8;
        for (v, s) in self.y_ticks() {
            let y = self.py(v).floor() as i32;
            canvas.fill_rect(PixelRect::new(r.x0 - 7, y, 6, 1), FRAME, 1.0);
            let b = text::draw(
                canvas,
                &s,
                style,
                (r.x0 - 10) as f64,
                y as f64 + 0.5,
                Anchor::Right,
            );
            left = left.min(b.x0);
            boxes.push(b);
        }
        let ls = Style::new(LABEL_SIZE);
        if !x_label.is_empty() {
            let size = text::fit(x_label, LABEL_SIZE, 11.0, r.width());
            boxes.push(text::draw(
                canvas,
                x_label,
                Style { size, ..ls },
                (r.x0 + r.x1) as f64 / 2.0,
                (bottom + 6) as f64,
                Anchor::Top,
            ));
        }
        if !y_label.is_empty() {
            let size = text::fit(y_label, LABEL_SIZE, 11.0, r.height());
            let (_, h) = text::measure(y_label, size);
            boxes.push(text::draw_vertical(
                canvas,
                y_label,
                Style { size, ..ls },
                (left - 8 - h / 2) as f64,
                (r.y0 + r.y1) as f64 / 2.0,
            ));
        }
    }
}

/// Draws a title centred at `y` across `width`, shrunk (then cut at the front) to fit.
pub fn title(canvas: &mut Canvas, s: &str, y: f64, boxes: &mut Vec<PixelRect>) {
    let width = canvas.width as i32 - 40;
    let size = text::fit(s, 22.0, 14.0, width);
    let s = text::ellipsize_front(s, size, width);
    boxes.push(text::draw(
        canvas,
        &s,
        Style::new(size).color([10, 10, 10]),
        canvas.width as f64 / 2.0,
        y,
        Anchor::Center,
    ));
}

/// A vertical colour bar in `bar` for `[lo, hi]` (the data range) with nice ticks on its
/// right and `label` above it (fitted into `width` pixels from the bar's left edge).
#[allow(clippy::too_many_arguments)]
pub fn colorbar(
    canvas: &mut Canvas,
    bar: PixelRect,
    map: &Colormap,
    norm: &Norm,
    (lo, hi): (f64, f64),
    label: &str,
    width: i32,
    boxes: &mut Vec<PixelRect>,
) {
    let h = bar.height();
    for r in 0..h {
        let v = hi - (r as f64 + 0.5) / h as f64 * (hi - lo);
        let c = map.at(norm.t(v));
        canvas.fill_rect(PixelRect::new(bar.x0, bar.y0 + r, bar.width(), 1), c, 1.0);
    }
    canvas.stroke_rect(bar.grow(1), FRAME);
    let size = text::fit(label, LABEL_SIZE, 10.0, width);
    let label = text::ellipsize_front(label, size, width);
    let (_, th) = text::measure(&label, size);
    boxes.push(text::draw(
        canvas,
        &label,
        Style::new(size),
        bar.x0 as f64,
        (bar.y0 - 14 - th / 2) as f64,
        Anchor::Left,
    ));
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return;
    }
    let py = |v: f64| bar.y1 as f64 - (v - lo) / (hi - lo) * h as f64;
    let mut count = (h / 45).max(2) as usize;
    let labels = loop {
        let (t, step) = ticks::ticks(lo, hi, count);
        let l: Vec<(f64, String)> = t.iter().map(|&v| (v, ticks::format(v, step))).collect();
        let b: Vec<PixelRect> = l
            .iter()
            .map(|(v, s)| text::text_box(s, TICK_SIZE, 0.0, py(*v), Anchor::Left).grow(3))
            .collect();
        if b.windows(2).all(|w| !w[0].overlaps(&w[1])) || count <= 2 {
            break l;
        }
        count -= 1;
    };
    for (v, s) in labels {
        let y = py(v).floor().min((bar.y1 - 1) as f64) as i32;
        canvas.fill_rect(PixelRect::new(bar.x1 + 1, y, 6, 1), FRAME, 1.0);
        boxes.push(text::draw(
            canvas,
            &s,
            Style::new(TICK_SIZE),
            (bar.x1 + 10) as f64,
            y as f64 + 0.5,
            Anchor::Left,
        ));
    }
}

/// The symbol of a legend entry.
#[derive(Debug, Clone, Copy)]
pub enum Swatch {
    /// A line of a colour and width.
    Line(Rgb, f64),
    /// A dashed line.
    Dashed(Rgb, f64),
    /// A filled rectangle.
    Patch(Rgb),
    /// Hatching: `true` for `/` (the penetrating pattern), `false` for `\`.
    Hatch(bool),
    /// A disc: fill and ring colours.
    Disc(Rgb, Rgb),
    /// Diagonal stripes of two colours (see [`stripe_color`]).
    Stripes(Rgb, Rgb),
    /// Nothing (a line of text).
    None,
}

/// Draws legend entries one below the other from `(x, y)`, text fitted into `width`;
/// returns the y below the last entry.
pub fn legend(
    canvas: &mut Canvas,
    x: i32,
    mut y: i32,
    width: i32,
    entries: &[(Swatch, String)],
    boxes: &mut Vec<PixelRect>,
) -> i32 {
    let size = 14.0;
    let line_h = 24;
    for (sw, label) in entries {
        let cy = y + line_h / 2;
        let sx = x;
        let sr = PixelRect::new(sx, cy - 7, 26, 14);
        match *sw {
            Swatch::Line(c, w) | Swatch::Dashed(c, w) => {
                let mut m = Coverage::new(canvas.width, canvas.height, sr.grow(2));
                let pts = [
                    [sx as f64, cy as f64 + 0.5],
                    [(sx + 26) as f64, cy as f64 + 0.5],
                ];
                if matches!(sw, Swatch::Dashed(..)) {
                    m.dashed(&pts, w, 6.0, 4.0);
                } else {
                    m.segment(pts[0], pts[1], w);
                }
                canvas.composite(&m, c, 1.0);
            }
            Swatch::Patch(c) => {
                canvas.fill_rect(sr, c, 1.0);
                canvas.stroke_rect(sr, FRAME);
            }
            Swatch::Hatch(slash) => {
                canvas.fill_rect(sr, [150, 150, 150], 1.0);
                for py in sr.y0..sr.y1 {
                    for px in sr.x0..sr.x1 {
                        if let Some(c) = hatch_color(px, py, slash) {
                            canvas.set(px, py, c);
                        }
                    }
                }
                canvas.stroke_rect(sr, FRAME);
            }
            Swatch::Stripes(a, b) => {
                for py in sr.y0..sr.y1 {
                    for px in sr.x0..sr.x1 {
                        canvas.set(px, py, stripe_color(px, py, a, b));
                    }
                }
                canvas.stroke_rect(sr, FRAME);
            }
            Swatch::Disc(fill, ring) => {
                let c = [(sx + 13) as f64, cy as f64 + 0.5];
                let mut m = Coverage::new(canvas.width, canvas.height, sr.grow(3));
                m.disc(c, 4.6);
                canvas.composite(&m, ring, 1.0);
                let mut m = Coverage::new(canvas.width, canvas.height, sr.grow(3));
                m.disc(c, 3.0);
                canvas.composite(&m, fill, 1.0);
            }
            Swatch::None => {}
        }
        let tx = if matches!(sw, Swatch::None) {
            x
        } else {
            x + 34
        };
        let avail = width - (tx - x);
        let s = text::fit(label, size, 10.0, avail);
        let label = text::ellipsize_front(label, s, avail);
        boxes.push(text::draw(
            canvas,
            &label,
            Style::new(s),
            tx as f64,
            cy as f64,
            Anchor::Left,
        ));
        y += line_h;
    }
    y
}

/// Spacing of the hatch lines of the contact zone, pixels (along x).
pub const HATCH_SPACING: i32 = 11;
/// The light line of the hatching.
pub const HATCH_LIGHT: Rgb = [255, 255, 255];
/// The dark line of the hatching.
pub const HATCH_DARK: Rgb = [0, 0, 0];

/// The hatch colour of pixel `(x, y)`, if it lies on a hatch line: `/` lines where
/// `x + y ≡ 0, 1 (mod HATCH_SPACING)` (penetrating), `\` lines where `x − y ≡ 0, 1`
/// (touching); the first pixel of a line is light, the second dark, so that the hatching
/// shows on any background colour.
#[inline]
pub fn hatch_color(x: i32, y: i32, slash: bool) -> Option<Rgb> {
    let k = if slash { x + y } else { x - y }.rem_euclid(HATCH_SPACING);
    match k {
        0 => Some(HATCH_LIGHT),
        1 => Some(HATCH_DARK),
        _ => None,
    }
}

/// Width of the stripes where the membrane is squeezed between two bodies, pixels
/// (along x).
pub const STRIPE_WIDTH: i32 = 6;

/// The colour of pixel `(x, y)` in diagonal stripes of `a` and `b`, each
/// [`STRIPE_WIDTH`] pixels wide along x (`a` where `⌊(x + y) / STRIPE_WIDTH⌋` is even).
#[inline]
pub fn stripe_color(x: i32, y: i32, a: Rgb, b: Rgb) -> Rgb {
    if (x + y).div_euclid(STRIPE_WIDTH) % 2 == 0 {
        a
    } else {
        b
    }
}
