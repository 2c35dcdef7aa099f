//! An RGB image buffer with the few drawing primitives the pictures need: filled
//! rectangles, anti-aliased thick lines and discs through coverage masks, and PNG encoding.
//!
//! Lines are drawn into a [`Coverage`] mask (the per-pixel maximum of the coverage of every
//! segment), then composited in one colour: overlapping segments of one polyline do not
//! darken their joints, and the result does not depend on the drawing order.

use crate::{Error, Result};
use rayon::prelude::*;

/// An RGB colour.
pub type Rgb = [u8; 3];

/// White.
pub const WHITE: Rgb = [255, 255, 255];
/// Black.
pub const BLACK: Rgb = [0, 0, 0];

/// A rectangle of pixels: columns `x0..x1`, rows `y0..y1` (half-open).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: i32,
    /// First row.
    pub y0: i32,
    /// One past the last column.
    pub x1: i32,
    /// One past the last row.
    pub y1: i32,
}

impl PixelRect {
    /// The rectangle of `w × h` pixels with its top-left corner at `(x, y)`.
    pub fn new(x: i32, y: i32, w: i32, h: i32) -> PixelRect {
        PixelRect {
            x0: x,
            y0: y,
            x1: x + w,
            y1: y + h,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> i32 {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> i32 {
        self.y1 - self.y0
    }

    /// True when the two rectangles share a pixel.
    pub fn overlaps(&self, o: &PixelRect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// True when `o` lies inside `self`.
    pub fn contains_rect(&self, o: &PixelRect) -> bool {
        o.x0 >= self.x0 && o.x1 <= self.x1 && o.y0 >= self.y0 && o.y1 <= self.y1
    }

    /// True when the pixel `(x, y)` lies inside.
    pub fn contains(&self, x: i32, y: i32) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }

    /// The rectangle grown by `d` pixels on every side.
    pub fn grow(&self, d: i32) -> PixelRect {
        PixelRect {
            x0: self.x0 - d,
            y0: self.y0 - d,
            x1: self.x1 + d,
            y1: self.y1 + d,
        }
    }
}

/// An RGB image, row by row from the top, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels, `3 × width × height` bytes.
    pub rgb: Vec<u8>,
}

impl Canvas {
    /// A white canvas.
    pub fn new(width: u32, height: u32) -> Canvas {
        Canvas {
            width,
            height,
            rgb: vec![255; 3 * width as usize * height as usize],
        }
    }

    /// The colour of pixel `(x, y)` (which must lie inside).
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Sets pixel `(x, y)` when it lies inside.
    #[inline]
    pub fn set(&mut self, x: i32, y: i32, c: Rgb) {
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Blends `c` with opacity `a` (0..1) over pixel `(x, y)` when it lies inside.
    #[inline]
    pub fn blend(&mut self, x: i32, y: i32, c: Rgb, a: f32) {
        if a <= 0.0 || x < 0 || y < 0 || x as u32 >= self.width || y as u32 >= self.height {
            return;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        blend_px(&mut self.rgb[i..i + 3], c, a);
    }

    /// Fills `r` (clipped to the canvas) with `c` at opacity `a`.
    pub fn fill_rect(&mut self, r: PixelRect, c: Rgb, a: f32) {
        let (x0, x1) = (r.x0.max(0), r.x1.min(self.width as i32));
        let (y0, y1) = (r.y0.max(0), r.y1.min(self.height as i32));
        for y in y0..y1 {
            for x in x0..x1 {
                self.blend(x, y, c, a);
            }
        }
    }

    /// Draws the one-pixel outline of `r` in `c`.
    pub fn stroke_rect(&mut self, r: PixelRect, c: Rgb) {
        for x in r.x0..r.x1 {
            self.set(x, r.y0, c);
            self.set(x, r.y1 - 1, c);
        }
        for y in r.y0..r.y1 {
            self.set(r.x0, y, c);
            self.set(r.x1 - 1, y, c);
        }
    }

    /// Composites a coverage mask in colour `c` at opacity `a`.
    pub fn composite(&mut self, mask: &Coverage, c: Rgb, a: f32) {
        let w = self.width as usize;
        if mask.width != self.width || mask.height != self.height {
            return;
        }
        self.rgb
            .par_chunks_mut(3 * w)
            .zip(mask.alpha.par_chunks(w))
            .for_each(|(row, m)| {
                for (px, &cov) in row.chunks_exact_mut(3).zip(m) {
                    if cov > 0.0 {
                        blend_px(px, c, cov * a);
                    }
                }
            });
    }

    /// Encodes the canvas as a PNG (fast deflate: pictures of flat colours and smooth
    /// gradients compress well enough, and encoding stays a few milliseconds).
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::with_capacity(self.rgb.len() / 4);
        let err = |e: png::EncodingError| Error::Data(format!("PNG encoding failed: {e}"));
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_compression(png::Compression::Fast);
            let mut w = enc.write_header().map_err(err)?;
            w.write_image_data(&self.rgb).map_err(err)?;
            w.finish().map_err(err)?;
        }
        Ok(out)
    }
}

#[inline]
fn blend_px(px: &mut [u8], c: Rgb, a: f32) {
    let a = a.clamp(0.0, 1.0);
    for k in 0..3 {
        let v = px[k] as f32 + (c[k] as f32 - px[k] as f32) * a;
        px[k] = v.round() as u8;
    }
}

/// A per-pixel coverage mask (0..1) for anti-aliased strokes.
#[derive(Debug, Clone)]
pub struct Coverage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Coverage per pixel, row by row.
    pub alpha: Vec<f32>,
    /// Pixels outside this rectangle are never covered.
    pub clip: PixelRect,
}

impl Coverage {
    /// An empty mask of the canvas size, clipped to `clip`.
    pub fn new(width: u32, height: u32, clip: PixelRect) -> Coverage {
        let full = PixelRect::new(0, 0, width as i32, height as i32);
        Coverage {
            width,
            height,
            alpha: vec![0.0; width as usize * height as usize],
            clip: PixelRect {
                x0: clip.x0.max(full.x0),
                y0: clip.y0.max(full.y0),
                x1: clip.x1.min(full.x1),
                y1: clip.y1.min(full.y1),
            },
        }
    }

    #[inline]
    fn put(&mut self, x: i32, y: i32, a: f32) {
        if self.clip.contains(x, y) {
            let i = y as usize * self.width as usize + x as usize;
            if a > self.alpha[i] {
                self.alpha[i] = a;
            }
        }
    }

    /// A segment from `p` to `q` (pixel coordinates, pixel centres at `i + 0.5`) of width
    /// `width` pixels, with round caps.
    pub fn segment(&mut self, p: [f64; 2], q: [f64; 2], width: f64) {
        let hw = 0.5 * width;
        let r = hw + 1.0;
        let x0 = (p[0].min(q[0]) - r).floor() as i32;
        let x1 = (p[0].max(q[0]) + r).ceil() as i32;
        let y0 = (p[1].min(q[1]) - r).floor() as i32;
        let y1 = (p[1].max(q[1]) + r).ceil() as i32;
        let (x0, x1) = (x0.max(self.clip.x0), x1.min(self.clip.x1));
        let (y0, y1) = (y0.max(self.clip.y0), y1.min(self.clip.y1));
        let d = [q[0] - p[0], q[1] - p[1]];
        let dd = d[0] * d[0] + d[1] * d[1];
        for y in y0..y1 {
            for x in x0..x1 {
                let c = [x as f64 + 0.5 - p[0], y as f64 + 0.5 - p[1]];
                let t = if dd > 0.0 {
                    ((c[0] * d[0] + c[1] * d[1]) / dd).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let e = [c[0] - t * d[0], c[1] - t * d[1]];
                let dist = (e[0] * e[0] + e[1] * e[1]).sqrt();
                let a = (hw + 0.5 - dist).clamp(0.0, 1.0) as f32;
                if a > 0.0 {
                    self.put(x, y, a);
                }
            }
        }
    }

    /// A polyline through `pts`.
    pub fn polyline(&mut self, pts: &[[f64; 2]], width: f64) {
        for w in pts.windows(2) {
            self.segment(w[0], w[1], width);
        }
    }

    /// A dashed polyline: `dash` pixels drawn, `gap` pixels left out, measured along it.
    pub fn dashed(&mut self, pts: &[[f64; 2]], width: f64, dash: f64, gap: f64) {
        let period = dash + gap;
        let mut s = 0.0;
        for w in pts.windows(2) {
            let (p, q) = (w[0], w[1]);
            let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            if len == 0.0 {
                continue;
            }
            let mut a = 0.0;
            while a < len {
                let phase = (s + a) % period;
                let (on, left) = if phase < dash {
                    (true, dash - phase)
                } else {
                    (false, period - phase)
                };
                let b = (a + left).min(len);
                if on {
                    let at = |t: f64| {
                        [
                            p[0] + (q[0] - p[0]) * t / len,
                            p[1] + (q[1] - p[1]) * t / len,
                        ]
                    };
                    self.segment(at(a), at(b), width);
                }
                a = b;
            }
            s += len;
        }
    }

    /// A filled disc of radius `r` pixels centred at `c`.
    pub fn disc(&mut self, c: [f64; 2], r: f64) {
        let x0 = (c[0] - r - 1.0).floor() as i32;
        let x1 = (c[0] + r + 1.0).ceil() as i32;
        let y0 = (c[1] - r - 1.0).floor() as i32;
        let y1 = (c[1] + r + 1.0).ceil() as i32;
        for y in y0..y1 {
            for x in x0..x1 {
                let d = ((x as f64 + 0.5 - c[0]).powi(2) + (y as f64 + 0.5 - c[1]).powi(2)).sqrt();
                let a = (r + 0.5 - d).clamp(0.0, 1.0) as f32;
                if a > 0.0 {
                    self.put(x, y, a);
                }
            }
        }
    }

    /// Clears the mask inside `r` (e.g. under a label placed on a line).
    pub fn clear(&mut self, r: PixelRect) {
        let r = PixelRect {
            x0: r.x0.max(0),
            y0: r.y0.max(0),
            x1: r.x1.min(self.width as i32),
            y1: r.y1.min(self.height as i32),
        };
        for y in r.y0..r.y1 {
            let row = y as usize * self.width as usize;
            self.alpha[row + r.x0 as usize..row + r.x1 as usize].fill(0.0);
        }
    }
}

/// Decodes an 8-bit RGB PNG (as [`Canvas::encode_png`] writes) back into a canvas: for
/// checks of written pictures.
pub fn decode_png(bytes: &[u8]) -> Result<Canvas> {
    let err = |e: png::DecodingError| Error::Data(format!("PNG decoding failed: {e}"));
    let mut r = png::Decoder::new(bytes).read_info().map_err(err)?;
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).map_err(err)?;
    if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
        return Err(Error::Data(format!(
            "PNG is {:?} {:?}, expected 8-bit RGB",
            info.color_type, info.bit_depth
        )));
    }
    buf.truncate(info.buffer_size());
    Ok(Canvas {
        width: info.width,
        height: info.height,
        rgb: buf,
    })
}
