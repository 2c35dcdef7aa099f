//! The log-log convergence plot with reference slopes (used by `memcontact convergence`).
//!
//! Rendering uses plotters' bitmap backend with the bundled DejaVu Sans font (no system
//! font is needed); the image is rendered in memory, encoded as PNG and written
//! atomically, so a failure never leaves a half-written file.

use crate::canvas::Canvas;
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Image width in pixels.
pub const WIDTH: u32 = 900;
/// Image height in pixels.
pub const HEIGHT: u32 = 650;

/// The family name the bundled font is registered under.
const FAMILY: &str = "sans-serif";

/// Series colours (the "tab10" palette).
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Registers the bundled font with plotters (once per process).
fn ensure_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, crate::text::FONT_BYTES).is_ok()
    });
    if !ok {
        return Err(Error::Data(
            "the bundled font DejaVuSans.ttf could not be loaded".into(),
        ));
    }
    Ok(())
}

/// Renders into a fresh white `WIDTH × HEIGHT` RGB buffer.
fn render(draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>) -> DrawResult) -> Result<Vec<u8>> {
    let mut rgb = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        let drawn = (|| -> DrawResult {
            root.fill(&WHITE)?;
            draw(&root)?;
            root.present()?;
            Ok(())
        })();
        drawn.map_err(|e| Error::Data(format!("drawing the plot failed: {e}")))?;
    }
    Ok(rgb)
}

/// What plotters' drawing calls return.
type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// `10^k` written with superscript digits, e.g. `10⁻³`.
fn power_of_ten(k: i32) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if k < 0 {
        s.push('⁻');
    }
    for d in k.unsigned_abs().to_string().bytes() {
        s.push(SUP[(d - b'0') as usize]);
    }
    s
}

/// Tick label of a log axis: decades as `10ᵏ`; other ticks are labelled only when the axis
/// holds fewer than two decades (`decades_only == false`), with at most three significant
/// digits.
fn log_tick_label(v: f64, decades_only: bool) -> String {
    let l = v.log10();
    if (l - l.round()).abs() < 1e-6 {
        let k = l.round() as i32;
        return if (-2..=3).contains(&k) && !decades_only {
            format!("{}", 10f64.powi(k))
        } else {
            power_of_ten(k)
        };
    }
    if decades_only {
        return String::new();
    }
    let digits = (2 - l.floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Number of powers of ten within `[a, b]`.
fn decades_in(a: f64, b: f64) -> i32 {
    (b.log10().floor() - a.log10().ceil()) as i32 + 1
}

/// Pads `[lo, hi]` (positive) by 6 % of its logarithmic span, at least 0.1 decade.
fn pad_log(lo: f64, hi: f64) -> (f64, f64) {
    let span = (hi.log10() - lo.log10()).max(0.0);
    let pad = (0.06 * span).max(0.1);
    (lo / 10f64.powf(pad), hi * 10f64.powf(pad))
}

/// The part of the line `log y = log ya + s (log x - log xa)` inside the box, if any.
fn clip_reference(
    anchor: (f64, f64),
    s: f64,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (lxa, lya) = (anchor.0.log10(), anchor.1.log10());
    let (mut lo, mut hi) = (x0.log10(), x1.log10());
    if s != 0.0 {
        let a = lxa + (y0.log10() - lya) / s;
        let b = lxa + (y1.log10() - lya) / s;
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    } else if !(y0..=y1).contains(&anchor.1) {
        return None;
    }
    if lo >= hi {
        return None;
    }
    let at = |lx: f64| (10f64.powf(lx), 10f64.powf(lya + s * (lx - lxa)));
    Some((at(lo), at(hi)))
}

/// Draws a log-log plot as a `WIDTH × HEIGHT` PNG.
///
/// Each series is drawn as a line with markers and named in the legend. Points with a
/// non-positive or non-finite coordinate cannot be placed on log axes and are skipped; it is
/// an error when no point is left. Each `reference_slopes` entry `s` adds a dashed grey line
/// `y ∝ xˢ`, labelled "slope s" in the legend, drawn through a point half-way below the data
/// at its left end (its right end for `s < 0`), so that the data can be compared with the
/// expected convergence rates. Decades are labelled `10ᵏ`, with minor ticks between them.
/// The file is written atomically.
pub fn loglog_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    reference_slopes: &[f64],
) -> Result<Canvas> {
    ensure_font()?;
    let ok = |&(x, y): &(f64, f64)| x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0;
    let clean: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(name, pts)| (name.as_str(), pts.iter().copied().filter(ok).collect()))
        .collect();
    let all: Vec<(f64, f64)> = clean.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    if all.is_empty() {
        return Err(Error::Data(format!(
            "log-log plot {}: no point with positive finite coordinates",
            title
        )));
    }
    let fold = |f: fn(f64, f64) -> f64, init: f64, c: fn(&(f64, f64)) -> f64| {
        all.iter().map(c).fold(init, f)
    };
    let (xmin, xmax) = (
        fold(f64::min, f64::INFINITY, |p| p.0),
        fold(f64::max, 0.0, |p| p.0),
    );
    let (mut ymin, ymax) = (
        fold(f64::min, f64::INFINITY, |p| p.1),
        fold(f64::max, 0.0, |p| p.1),
    );
    // Reference lines: from half-way below the lowest point at the left (right) end.
    let anchor_at = |x: f64| {
        let y = all
            .iter()
            .filter(|p| p.0 == x)
            .map(|p| p.1)
            .fold(f64::INFINITY, f64::min);
        (x, 0.5 * y)
    };
    let slopes: Vec<f64> = reference_slopes
        .iter()
        .copied()
        .filter(|s| s.is_finite())
        .collect();
    let anchors: Vec<(f64, f64)> = slopes
        .iter()
        .map(|&s| anchor_at(if s >= 0.0 { xmin } else { xmax }))
        .collect();
    for a in &anchors {
        ymin = ymin.min(a.1);
    }
    let (x0, x1) = pad_log(xmin, xmax);
    let (y0, y1) = pad_log(ymin, ymax);
    let x_decades_only = decades_in(x0, x1) >= 2;
    let y_decades_only = decades_in(y0, y1) >= 2;
    // Put the legend in the corner the data leave free.
    let rising = all
        .iter()
        .find(|p| p.0 == xmax)
        .map(|p| p.1)
        .unwrap_or(ymax)
        >= anchor_at(xmin).1 * 2.0;
    let legend_pos = if rising {
        SeriesLabelPosition::UpperLeft
    } else {
        SeriesLabelPosition::UpperRight
    };

    let rgb = render(|root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FAMILY, 26))
            .margin(20)
            .x_label_area_size(60)
            .y_label_area_size(85)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        let x_fmt = |v: &f64| log_tick_label(*v, x_decades_only);
        let y_fmt = |v: &f64| log_tick_label(*v, y_decades_only);
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .x_labels(40)
            .y_labels(40)
            .label_style((FAMILY, 17))
            .axis_desc_style((FAMILY, 19))
            .bold_line_style(RGBColor(232, 232, 232))
            .max_light_lines(0)
            .draw()?;
        // Stronger grid lines at the decades.
        let decade = RGBColor(195, 195, 195);
        for k in x0.log10().ceil() as i32..=x1.log10().floor() as i32 {
            let x = 10f64.powi(k);
            chart.draw_series(LineSeries::new([(x, y0), (x, y1)], decade))?;
        }
        for k in y0.log10().ceil() as i32..=y1.log10().floor() as i32 {
            let y = 10f64.powi(k);
            chart.draw_series(LineSeries::new([(x0, y), (x1, y)], decade))?;
        }
        for (k, (name, pts)) in clean.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let line = color.stroke_width(2);
            let marker = k % 3;
            chart.draw_series(LineSeries::new(pts.iter().copied(), line))?;
            let legend = move |(x, y): (i32, i32)| {
                EmptyElement::at((x + 12, y))
                    + PathElement::new(vec![(-12, 0), (12, 0)], line)
                    + marker_element(marker, color)
            };
            chart
                .draw_series(
                    pts.iter()
                        .map(|&p| EmptyElement::at(p) + marker_element(marker, color)),
                )?
                .label(*name)
                .legend(legend);
        }
        let grey = RGBColor(70, 70, 70).stroke_width(2);
        let label_font = (FAMILY, 16).into_font().color(&RGBColor(50, 50, 50));
        for (i, (&s, &a)) in slopes.iter().zip(&anchors).enumerate() {
            let Some((p, q)) = clip_reference(a, s, (x0, x1), (y0, y1)) else {
                continue;
            };
            // A different dash pattern for each reference line, the same in the legend.
            let (dash, gap) = [(12, 6), (5, 5), (2, 4)][i % 3];
            chart
                .draw_series(DashedLineSeries::new([p, q], dash, gap, grey))?
                .label(format!("slope {s}"))
                .legend(move |(x, y)| {
                    DashedPathElement::new([(x, y), (x + 24, y)], dash, gap, grey)
                });
            // The name beside the line, on its side away from the data (below it).
            let t = 0.8;
            let lx = (1.0 - t) * p.0.log10() + t * q.0.log10();
            let ly = (1.0 - t) * p.1.log10() + t * q.1.log10();
            let h = if s >= 0.0 { HPos::Left } else { HPos::Right };
            let style = label_font.clone().pos(Pos::new(h, VPos::Top));
            chart.draw_series(std::iter::once(
                EmptyElement::at((10f64.powf(lx), 10f64.powf(ly)))
                    + Text::new(
                        format!("slope {s}"),
                        (if s >= 0.0 { 6 } else { -6 }, 6),
                        style,
                    ),
            ))?;
        }
        chart
            .configure_series_labels()
            .position(legend_pos)
            .margin(12)
            .legend_area_size(34)
            .label_font((FAMILY, 17))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(150, 150, 150))
            .draw()?;
        Ok(())
    })?;
    Ok(Canvas {
        width: WIDTH,
        height: HEIGHT,
        rgb,
    })
}

/// The marker of kind `k` (circle, triangle, square), centred on its anchor.
fn marker_element<DB: DrawingBackend>(
    k: usize,
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    let style = color.filled();
    match k {
        0 => Circle::new((0, 0), 5, style).into_dyn(),
        1 => TriangleMarker::new((0, 0), 7, style).into_dyn(),
        _ => Rectangle::new([(-5, -5), (5, 5)], style).into_dyn(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Width and height from the IHDR chunk, after checking the PNG signature.
    fn png_size(bytes: &[u8]) -> (u32, u32) {
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR");
        let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
        (be(16), be(20))
    }

    fn convergence_data() -> Vec<(String, Vec<(f64, f64)>)> {
        let hs: Vec<f64> = (0..6).map(|k| 0.2 / 2f64.powi(k)).collect();
        vec![
            (
                "H¹ error".to_string(),
                hs.iter().map(|&h| (h, 0.8 * h * (1.0 + 0.3 * h))).collect(),
            ),
            (
                "L² error".to_string(),
                hs.iter().map(|&h| (h, 0.3 * h * h)).collect(),
            ),
            (
                "energy".to_string(),
                // a zero and a NaN are skipped, not fatal
                hs.iter()
                    .map(|&h| (h, 2.0 * h.powf(1.5)))
                    .chain([(0.0, 1.0), (0.1, f64::NAN)])
                    .collect(),
            ),
        ]
    }

    #[test]
    fn loglog_png_has_the_size_and_the_lines() {
        let bytes = loglog_plot(
            "Convergence on the disc (made-up data)",
            "mesh size lₙ",
            "error",
            &convergence_data(),
            &[1.0, 2.0],
        )
        .unwrap()
        .encode_png()
        .unwrap();
        assert_eq!(png_size(&bytes), (WIDTH, HEIGHT));
        let img = crate::canvas::decode_png(&bytes).unwrap();
        let px = || img.rgb.chunks_exact(3);
        let non_white = px().filter(|p| p != &[255, 255, 255]).count();
        assert!(non_white > 20_000, "{non_white} non-white pixels");
        // Every series colour is drawn (lines and markers), and so is the reference grey.
        for c in COLORS.iter().take(3).chain([&RGBColor(70, 70, 70)]) {
            let n = px().filter(|p| p == &[c.0, c.1, c.2]).count();
            assert!(n > 200, "colour {c:?}: {n} pixels");
        }
        if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
            std::fs::write(std::path::Path::new(&keep).join("loglog.png"), &bytes).unwrap();
        }
    }

    #[test]
    fn loglog_without_valid_points_is_an_error() {
        let series = vec![("bad".to_string(), vec![(0.0, 1.0), (-1.0, 2.0)])];
        let e = loglog_plot("t", "x", "y", &series, &[1.0]).unwrap_err();
        assert!(e.to_string().contains("no point"), "{e}");
    }

    #[test]
    fn tick_labels_and_reference_clipping() {
        assert_eq!(power_of_ten(-3), "10⁻³");
        assert_eq!(power_of_ten(12), "10¹²");
        assert_eq!(log_tick_label(1e-3, true), "10⁻³");
        assert_eq!(log_tick_label(2e-3, true), "");
        assert_eq!(log_tick_label(0.2, false), "0.2");
        assert_eq!(log_tick_label(0.00253, false), "0.00253");
        assert_eq!(log_tick_label(10.0, false), "10");
        // slope 2 through (1, 1) in the box [0.1, 10] × [0.1, 10]: from x = 10^-0.5 to 10^0.5
        let (p, q) = clip_reference((1.0, 1.0), 2.0, (0.1, 10.0), (0.1, 10.0)).unwrap();
        assert!((p.0 - 10f64.powf(-0.5)).abs() < 1e-12 && (p.1 - 0.1).abs() < 1e-12);
        assert!((q.0 - 10f64.powf(0.5)).abs() < 1e-12 && (q.1 - 10.0).abs() < 1e-12);
        assert!(clip_reference((100.0, 100.0), 0.0, (0.1, 10.0), (0.1, 10.0)).is_none());
    }
}
