//! Colour maps (256-entry look-up tables built from published control colours) and the
//! normalisation of a value range onto them.

use crate::canvas::Rgb;
use std::sync::OnceLock;

/// A colour map: [`LUT_SIZE`] colours from low (0) to high (1).
#[derive(Debug, Clone)]
pub struct Colormap {
    lut: Vec<Rgb>,
}

/// Grey for values that cannot be mapped (NaN).
pub const NAN_COLOR: Rgb = [160, 160, 160];

/// Entries of a colour map's table (1000 intervals: the middle control colour of an even
/// number of intervals is hit exactly).
pub const LUT_SIZE: usize = 1001;

impl Colormap {
    /// Linear interpolation (in sRGB) between equally spaced control colours.
    fn from_knots(knots: &[Rgb]) -> Colormap {
        let n = knots.len() - 1;
        let lut = (0..LUT_SIZE)
            .map(|k| {
                let t = k as f64 / (LUT_SIZE - 1) as f64 * n as f64;
                let i = (t.floor() as usize).min(n - 1);
                let f = t - i as f64;
                let (a, b) = (knots[i], knots[i + 1]);
                [0, 1, 2].map(|c| (a[c] as f64 + (b[c] as f64 - a[c] as f64) * f).round() as u8)
            })
            .collect();
        Colormap { lut }
    }

    /// The colour at `t` in `[0, 1]` (clamped; NaN gives [`NAN_COLOR`]).
    #[inline]
    pub fn at(&self, t: f64) -> Rgb {
        if t.is_nan() {
            return NAN_COLOR;
        }
        self.lut[(t.clamp(0.0, 1.0) * (LUT_SIZE - 1) as f64).round() as usize]
    }
}

fn hex(s: &[&str]) -> Vec<Rgb> {
    s.iter()
        .map(|h| {
            let v = u32::from_str_radix(h.trim_start_matches('#'), 16).unwrap_or(0);
            [(v >> 16) as u8, (v >> 8) as u8, v as u8]
        })
        .collect()
}

/// Viridis (perceptually uniform, readable in grey and by colour-blind readers): for the
/// deflection.
pub fn viridis() -> &'static Colormap {
    static M: OnceLock<Colormap> = OnceLock::new();
    M.get_or_init(|| {
        Colormap::from_knots(&hex(&[
            "#440154", "#482475", "#414487", "#355f8d", "#2a788e", "#21918c", "#22a884", "#44bf70",
            "#7ad151", "#bddf26", "#fde725",
        ]))
    })
}

/// A sequential yellow-orange-red map (ColorBrewer YlOrRd): zero pressure pale, high
/// pressure dark red.
pub fn yellow_red() -> &'static Colormap {
    static M: OnceLock<Colormap> = OnceLock::new();
    M.get_or_init(|| {
        Colormap::from_knots(&hex(&[
            "#ffffcc", "#ffeda0", "#fed976", "#feb24c", "#fd8d3c", "#fc4e2a", "#e31a1c", "#bd0026",
            "#800026",
        ]))
    })
}

/// The map of pressure / allowable (with [`Norm::centered`] at 1): pale yellow to red up
/// to the allowable, then purple to nearly black above it, so that the exceeded area
/// stands out by hue, not only by shade.
pub fn ratio() -> &'static Colormap {
    static M: OnceLock<Colormap> = OnceLock::new();
    M.get_or_init(|| {
        let lower = Colormap::from_knots(&hex(&[
            "#ffffcc", "#ffeda0", "#fed976", "#feb24c", "#fd8d3c", "#fc4e2a", "#e31a1c",
        ]));
        let upper = Colormap::from_knots(&hex(&["#c51b8a", "#7a0177", "#49006a", "#20002e"]));
        let half = (LUT_SIZE - 1) / 2;
        let lut = (0..LUT_SIZE)
            .map(|k| {
                if k < half {
                    lower.lut[k * (LUT_SIZE - 1) / half]
                } else {
                    upper.lut[(k - half) * (LUT_SIZE - 1) / half]
                }
            })
            .collect();
        Colormap { lut }
    })
}

/// A sequential blue map (ColorBrewer Blues, without its near-white end): for the gap of
/// the lift-off picture.
pub fn blues() -> &'static Colormap {
    static M: OnceLock<Colormap> = OnceLock::new();
    M.get_or_init(|| {
        Colormap::from_knots(&hex(&[
            "#deebf7", "#c6dbef", "#9ecae1", "#6baed6", "#4292c6", "#2171b5", "#08519c", "#08306b",
        ]))
    })
}

/// A sequential green map (ColorBrewer Greens, without its near-white end): for the gap
/// to the body below on the lift-off picture (the obstacle's gap is in [`blues`]).
pub fn greens() -> &'static Colormap {
    static M: OnceLock<Colormap> = OnceLock::new();
    M.get_or_init(|| {
        Colormap::from_knots(&hex(&[
            "#e5f5e0", "#c7e9c0", "#a1d99b", "#74c476", "#41ab5d", "#238b45", "#006d2c", "#00441b",
        ]))
    })
}

/// Maps values onto `[0, 1]`: linearly over `[lo, hi]`, or, with a `center` inside, each
/// side of the centre onto its half (`center ↦ 0.5`), so that a diverging map's middle
/// colour marks the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Norm {
    /// The value mapped to 0.
    pub lo: f64,
    /// The value mapped to 1.
    pub hi: f64,
    /// The value mapped to 0.5, if any.
    pub center: Option<f64>,
}

impl Norm {
    /// A linear normalisation of `[lo, hi]`; an empty range is widened so that it maps.
    pub fn linear(lo: f64, hi: f64) -> Norm {
        let (lo, hi) = widen(lo, hi);
        Norm {
            lo,
            hi,
            center: None,
        }
    }

    /// A two-sided normalisation of `[lo, hi]` around `center`.
    pub fn centered(lo: f64, hi: f64, center: f64) -> Norm {
        let (lo, hi) = widen(lo, hi);
        Norm {
            lo,
            hi,
            center: Some(center),
        }
    }

    /// The position of `v` in `[0, 1]` (not clamped).
    #[inline]
    pub fn t(&self, v: f64) -> f64 {
        match self.center {
            None => (v - self.lo) / (self.hi - self.lo),
            Some(c) => {
                if v < c {
                    if c > self.lo {
                        0.5 * (v - self.lo) / (c - self.lo)
                    } else {
                        0.0
                    }
                } else if self.hi > c {
                    0.5 + 0.5 * (v - c) / (self.hi - c)
                } else {
                    1.0
                }
            }
        }
    }
}

/// `[lo, hi]` widened when empty (a constant field), so that it has a length.
pub fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo {
        (lo, hi)
    } else {
        let d = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        (lo - d, hi + d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_run_from_their_first_to_their_last_colour() {
        assert_eq!(viridis().at(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis().at(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(viridis().at(-3.0), viridis().at(0.0));
        assert_eq!(viridis().at(f64::NAN), NAN_COLOR);
        assert_eq!(ratio().at(0.0), [0xff, 0xff, 0xcc]);
        assert_eq!(ratio().at(0.5), [0xc5, 0x1b, 0x8a]);
        let below = ratio().at(0.499);
        assert!(below[0] > 220 && below[2] < 40, "{below:?}");
        let n = Norm::centered(0.0, 3.0, 1.0);
        assert_eq!((n.t(0.0), n.t(1.0), n.t(3.0)), (0.0, 0.5, 1.0));
        assert_eq!(n.t(2.0), 0.75);
        let n = Norm::centered(0.2, 0.8, 1.0);
        assert_eq!(n.t(0.2), 0.0);
        assert!((n.t(0.8) - 0.375).abs() < 1e-12);
        let n = Norm::linear(2.0, 2.0);
        assert!(n.hi > n.lo && n.t(2.0) == 0.5);
    }
}
