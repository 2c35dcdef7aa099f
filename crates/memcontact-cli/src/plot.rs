//! PNG plots for reports: log-log convergence plots with reference slopes, and a colour map
//! of a nodal field over a triangle mesh.
//!
//! Rendering uses plotters' bitmap backend with the DejaVu Sans font shipped in
//! `assets/` (no system font is needed); images are rendered in memory, encoded as PNG and
//! written atomically, so a failure never leaves a half-written file.

use anyhow::{bail, Context, Result};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Image width in pixels.
pub const WIDTH: u32 = 900;
/// Image height in pixels.
pub const HEIGHT: u32 = 650;

/// The bundled font (DejaVu Sans, Bitstream Vera licence: `assets/LICENSE-DejaVu.txt`).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
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
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if !ok {
        bail!("the bundled font assets/DejaVuSans.ttf could not be loaded");
    }
    Ok(())
}

/// Encodes an RGB buffer as PNG and writes it atomically to `path`.
fn write_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<()> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, width, height, image::ColorType::Rgb8)
        .with_context(|| format!("encoding {}", path.display()))?;
    memcontact::io::write_atomic(path, |w| w.write_all(&png))?;
    Ok(())
}

/// Renders into a fresh white `WIDTH × HEIGHT` RGB buffer.
fn render(draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>) -> Result<()>) -> Result<Vec<u8>> {
    let mut rgb = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
    }
    Ok(rgb)
}

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

/// Writes a log-log plot as a `WIDTH × HEIGHT` PNG.
///
/// Each series is drawn as a line with markers and named in the legend. Points with a
/// non-positive or non-finite coordinate cannot be placed on log axes and are skipped; it is
/// an error when no point is left. Each `reference_slopes` entry `s` adds a dashed grey line
/// `y ∝ xˢ`, labelled "slope s" in the legend, drawn through a point half-way below the data
/// at its left end (its right end for `s < 0`), so that the data can be compared with the
/// expected convergence rates. Decades are labelled `10ᵏ`, with minor ticks between them.
/// The file is written atomically.
pub fn loglog_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    reference_slopes: &[f64],
) -> Result<()> {
    ensure_font()?;
    let ok = |&(x, y): &(f64, f64)| x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0;
    let clean: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(name, pts)| (name.as_str(), pts.iter().copied().filter(ok).collect()))
        .collect();
    let all: Vec<(f64, f64)> = clean.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    if all.is_empty() {
        bail!(
            "log-log plot {}: no point with positive finite coordinates",
            path.display()
        );
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
    write_png(path, &rgb, WIDTH, HEIGHT)
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

/// Linear tick label with at most four significant digits; values below `1e-9 × scale` in
/// magnitude (rounding noise of tick positions) are written `0`.
fn linear_tick_label(v: f64, scale: f64) -> String {
    if v.abs() <= 1e-9 * scale {
        return "0".into();
    }
    let l = v.abs().log10();
    if !(-3.0..5.0).contains(&l) {
        return format!("{v:.2e}");
    }
    let digits = (3 - l.floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Writes a colour map of the nodal field `values` over a triangle mesh as a
/// `WIDTH × HEIGHT` PNG, for a quick look at a solution (e.g. the deflection).
///
/// Each triangle is filled with the viridis colour of the mean of its three vertex values
/// (non-finite means are drawn grey), on axes of equal scale, with a colour bar. Every
/// triangle is drawn, so a mesh of millions of triangles takes seconds. Errors: `values`
/// not one per point, a triangle referring to a missing point, or no finite value.
pub fn field_plot(
    path: &Path,
    points: &[[f64; 2]],
    triangles: &[[u32; 3]],
    values: &[f64],
    title: &str,
) -> Result<()> {
    ensure_font()?;
    if values.len() != points.len() {
        bail!(
            "field plot {}: {} values for {} points",
            path.display(),
            values.len(),
            points.len()
        );
    }
    if let Some((t, tri)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= points.len()))
    {
        bail!(
            "field plot {}: triangle {t} {tri:?} refers to a missing point",
            path.display()
        );
    }
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (vmin, vmax) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if vmin > vmax {
        bail!("field plot {}: no finite value", path.display());
    }
    let (vmin, vmax) = if vmin < vmax {
        (vmin, vmax)
    } else {
        let d = if vmin == 0.0 { 1.0 } else { 0.5 * vmin.abs() };
        (vmin - d, vmax + d)
    };
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in triangles.iter().flatten().map(|&v| points[v as usize]) {
        (x0, x1, y0, y1) = (x0.min(p[0]), x1.max(p[0]), y0.min(p[1]), y1.max(p[1]));
    }
    if triangles.is_empty() || !(x1 > x0 && y1 > y0) {
        bail!(
            "field plot {}: the mesh has no area to draw",
            path.display()
        );
    }

    let rgb = render(|root| {
        let root = root.margin(12, 0, 0, 0).titled(title, (FAMILY, 26))?;
        let (map_area, bar_area) = root.split_horizontally(WIDTH as i32 - 150);
        // Equal scales: widen the data box to the shape of the plotting area.
        let (label_x, label_y, margin) = (45u32, 75u32, 15u32);
        let (w, h) = map_area.dim_in_pixel();
        let (pw, ph) = (
            (w - label_y - 2 * margin) as f64,
            (h - label_x - 2 * margin) as f64,
        );
        let (dx, dy) = (x1 - x0, y1 - y0);
        let scale = (dx / pw).max(dy / ph) * 1.02;
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let (hx, hy) = (0.5 * scale * pw, 0.5 * scale * ph);
        let mut chart = ChartBuilder::on(&map_area)
            .margin(margin)
            .x_label_area_size(label_x)
            .y_label_area_size(label_y)
            .build_cartesian_2d(cx - hx..cx + hx, cy - hy..cy + hy)?;
        let scale = hx.max(hy) + cx.abs().max(cy.abs());
        let fmt = |v: &f64| linear_tick_label(*v, scale);
        let vscale = vmax.abs().max(vmin.abs());
        let vfmt = |v: &f64| linear_tick_label(*v, vscale);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&fmt)
            .y_label_formatter(&fmt)
            .label_style((FAMILY, 16))
            .draw()?;
        chart.draw_series(triangles.iter().map(|t| {
            let mean = t.iter().map(|&v| values[v as usize]).sum::<f64>() / 3.0;
            let color = if mean.is_finite() {
                ViridisRGB::get_color_normalized(mean, vmin, vmax)
            } else {
                RGBColor(160, 160, 160)
            };
            let pts: Vec<(f64, f64)> = t
                .iter()
                .map(|&v| (points[v as usize][0], points[v as usize][1]))
                .collect();
            Polygon::new(pts, color.filled())
        }))?;

        // Colour bar.
        let mut bar = ChartBuilder::on(&bar_area)
            .margin_top(margin + 10)
            .margin_bottom(margin + label_x)
            .margin_left(10)
            .margin_right(10)
            .y_label_area_size(0)
            .right_y_label_area_size(85)
            .build_cartesian_2d(0.0..1.0, vmin..vmax)?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&vfmt)
            .label_style((FAMILY, 16))
            .draw()?;
        let steps = 256;
        bar.draw_series((0..steps).map(|k| {
            let a = vmin + (vmax - vmin) * k as f64 / steps as f64;
            let b = vmin + (vmax - vmin) * (k + 1) as f64 / steps as f64;
            let c = ViridisRGB::get_color_normalized(0.5 * (a + b), vmin, vmax);
            Rectangle::new([(0.0, a), (1.0, b)], c.filled())
        }))?;
        Ok(())
    })?;
    write_png(path, &rgb, WIDTH, HEIGHT)
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
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("convergence.png");
        loglog_plot(
            &path,
            "Convergence on the disc (made-up data)",
            "mesh size lₙ",
            "error",
            &convergence_data(),
            &[1.0, 2.0],
        )
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(png_size(&bytes), (WIDTH, HEIGHT));
        let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
        let non_white = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(non_white > 20_000, "{non_white} non-white pixels");
        // Every series colour is drawn (lines and markers), and so is the reference grey.
        for c in COLORS.iter().take(3).chain([&RGBColor(70, 70, 70)]) {
            let n = img.pixels().filter(|p| p.0 == [c.0, c.1, c.2]).count();
            assert!(n > 200, "colour {c:?}: {n} pixels");
        }
        // Only the PNG is left in the directory (the write is atomic).
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
            std::fs::copy(&path, Path::new(&keep).join("loglog.png")).unwrap();
        }
    }

    #[test]
    fn loglog_without_valid_points_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("empty.png");
        let series = vec![("bad".to_string(), vec![(0.0, 1.0), (-1.0, 2.0)])];
        let e = loglog_plot(&path, "t", "x", "y", &series, &[1.0]).unwrap_err();
        assert!(e.to_string().contains("no point"), "{e}");
        assert!(!path.exists());
    }

    #[test]
    fn tick_labels_and_reference_clipping() {
        assert_eq!(power_of_ten(-3), "10⁻³");
        assert_eq!(linear_tick_label(-2.22e-16, 1.0), "0");
        assert_eq!(linear_tick_label(0.25, 1.0), "0.25");
        assert_eq!(linear_tick_label(1.5e-7, 1e-6), "1.50e-7");
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

#[cfg(test)]
mod field_tests {
    use super::*;

    #[test]
    fn field_png_shows_the_colour_range() {
        // A structured mesh of the unit disc's bounding square, with a radial bump.
        let n = 30;
        let points: Vec<[f64; 2]> = (0..(n + 1) * (n + 1))
            .map(|k| {
                [
                    2.0 * (k % (n + 1)) as f64 / n as f64 - 1.0,
                    (k / (n + 1)) as f64 / n as f64 - 0.5,
                ]
            })
            .collect();
        let mut triangles = Vec::new();
        for j in 0..n as u32 {
            for i in 0..n as u32 {
                let a = j * (n as u32 + 1) + i;
                let d = a + n as u32 + 1;
                triangles.push([a, a + 1, d + 1]);
                triangles.push([a, d + 1, d]);
            }
        }
        let values: Vec<f64> = points
            .iter()
            .map(|p| 1.0 - p[0] * p[0] - p[1] * p[1])
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("field.png");
        field_plot(
            &path,
            &points,
            &triangles,
            &values,
            "deflection u (made-up)",
        )
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (WIDTH, HEIGHT));
        // Both ends of viridis appear: dark purple (low) and yellow (high).
        let near = |p: &image::Rgb<u8>, c: RGBColor| {
            (p.0[0] as i32 - c.0 as i32).abs()
                + (p.0[1] as i32 - c.1 as i32).abs()
                + (p.0[2] as i32 - c.2 as i32).abs()
                < 40
        };
        let low = ViridisRGB::get_color_normalized(0.0, 0.0, 1.0);
        let high = ViridisRGB::get_color_normalized(1.0, 0.0, 1.0);
        assert!(img.pixels().filter(|p| near(p, low)).count() > 100);
        assert!(img.pixels().filter(|p| near(p, high)).count() > 100);
        if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
            std::fs::copy(&path, Path::new(&keep).join("field.png")).unwrap();
        }
        let e = field_plot(&path, &points, &triangles, &values[1..], "t").unwrap_err();
        assert!(e.to_string().contains("values for"), "{e}");
    }
}
