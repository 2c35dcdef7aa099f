//! A fit's picture (`fit.png` of a result set): the measurements against the deflections
//! computed at the fitted parameters (left, with the line of perfect agreement), and a map
//! of the residuals at the sensors over the mesh's outline (right, blue below the
//! measurement, red above, white where they agree).

use crate::axes::{self, Axes, Swatch};
use crate::canvas::{Canvas, Coverage, PixelRect, Rgb, WHITE};
use crate::text::{self, Anchor, Style};
use crate::Units;
use crate::{Error, Result};

/// Width, pixels.
pub const FIT_WIDTH: u32 = 1500;
/// Height, pixels.
pub const FIT_HEIGHT: u32 = 720;

/// The residual map's colours: blue, white, red.
const BLUE: Rgb = [33, 102, 172];
const RED: Rgb = [178, 24, 43];
const MARKER: Rgb = [31, 119, 180];

/// One sensor of a fit: where it is, what was measured there and what the model computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSensor {
    /// Its position.
    pub at: [f64; 2],
    /// The measured deflection.
    pub measured: f64,
    /// The deflection computed at the fitted parameters.
    pub computed: f64,
}

/// What a fit's picture shows, borrowed.
#[derive(Debug, Clone, Copy)]
pub struct FitPlot<'a> {
    /// The title.
    pub title: &'a str,
    /// The last line of the legend (e.g. the fit's rms and iterations).
    pub note: &'a str,
    /// The mesh's vertices (its outline is drawn under the residuals).
    pub points: &'a [[f64; 2]],
    /// The mesh's triangles.
    pub triangles: &'a [[u32; 3]],
    /// The sensors.
    pub sensors: &'a [FitSensor],
    /// Units for the labels.
    pub units: &'a Units,
}

/// The diverging colour of `t` in `[-1, 1]`.
fn diverging(t: f64) -> Rgb {
    let t = t.clamp(-1.0, 1.0);
    let (end, s) = if t < 0.0 { (BLUE, -t) } else { (RED, t) };
    [0, 1, 2].map(|k| (WHITE[k] as f64 + s * (end[k] as f64 - WHITE[k] as f64)).round() as u8)
}

/// Draws a fit's picture in memory: the measurements against the computed values, and
/// their residuals on the outline of the mesh.
pub fn render_fit_plot(plot: &FitPlot) -> Result<Canvas> {
    let FitPlot {
        title,
        note,
        points,
        triangles,
        sensors: ms,
        units,
    } = *plot;
    if let Some((k, t)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= points.len()))
    {
        return Err(Error::Data(format!(
            "fit picture: triangle {k} {t:?} refers to a vertex beyond the {} vertices",
            points.len()
        )));
    }
    if ms.is_empty() || triangles.is_empty() {
        return Err(Error::Data("fit picture: no measurement or no mesh".into()));
    }
    let mut canvas = Canvas::new(FIT_WIDTH, FIT_HEIGHT);
    let mut boxes = Vec::new();
    axes::title(&mut canvas, title, 26.0, &mut boxes);
    let len = units.length_suffix();
    // Left: measured against computed.
    let vals: Vec<f64> = ms
        .iter()
        .flat_map(|m| [m.measured, m.computed])
        .filter(|v| v.is_finite())
        .collect();
    let (lo, hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| {
            (a.0.min(v), a.1.max(v))
        });
    let (lo, hi) = crate::colormap::widen(lo, hi);
    let pad = 0.06 * (hi - lo);
    let ax = Axes {
        rect: PixelRect {
            x0: 110,
            y0: 70,
            x1: 650,
            y1: FIT_HEIGHT as i32 - 95,
        },
        x: (lo - pad, hi + pad),
        y: (lo - pad, hi + pad),
    };
    ax.grid(&mut canvas);
    let mut diag = Coverage::new(canvas.width, canvas.height, ax.rect);
    diag.dashed(
        &[
            [ax.px(lo - pad), ax.py(lo - pad)],
            [ax.px(hi + pad), ax.py(hi + pad)],
        ],
        1.5,
        8.0,
        5.0,
    );
    canvas.composite(&diag, [120, 120, 120], 1.0);
    let mut marks = Coverage::new(canvas.width, canvas.height, ax.rect.grow(6));
    for m in ms
        .iter()
        .filter(|m| m.measured.is_finite() && m.computed.is_finite())
    {
        marks.disc([ax.px(m.measured), ax.py(m.computed)], 5.0);
    }
    canvas.composite(&marks, MARKER, 1.0);
    ax.frame(
        &mut canvas,
        &format!("measured u{len}"),
        &format!("computed u{len}"),
        &mut boxes,
    );
    let legend = [
        (Swatch::Disc(MARKER, MARKER), "sensor".to_string()),
        (
            Swatch::Dashed([120, 120, 120], 1.5),
            "computed = measured".to_string(),
        ),
        (Swatch::None, note.to_string()),
    ];
    let lw = 300;
    let box_ = PixelRect::new(ax.rect.x0 + 10, ax.rect.y0 + 10, lw, 24 * 3 + 12);
    canvas.fill_rect(box_, WHITE, 0.9);
    canvas.stroke_rect(box_, [170, 170, 170]);
    axes::legend(
        &mut canvas,
        box_.x0 + 8,
        box_.y0 + 6,
        lw - 14,
        &legend,
        &mut boxes,
    );
    // Right: the residuals over the outline of the mesh, equal scales.
    let map = PixelRect {
        x0: 760,
        y0: 70,
        x1: FIT_WIDTH as i32 - 150,
        y1: FIT_HEIGHT as i32 - 95,
    };
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        (x0, x1) = (x0.min(p[0]), x1.max(p[0]));
        (y0, y1) = (y0.min(p[1]), y1.max(p[1]));
    }
    let (w, h) = ((x1 - x0).max(1e-300), (y1 - y0).max(1e-300));
    let scale = (map.width() as f64 / w).min(map.height() as f64 / h);
    let ox = map.x0 as f64 + 0.5 * (map.width() as f64 - scale * w);
    let oy = map.y1 as f64 - 0.5 * (map.height() as f64 - scale * h);
    let to_px = |p: [f64; 2]| [ox + (p[0] - x0) * scale, oy - (p[1] - y0) * scale];
    let map_ax = Axes {
        rect: PixelRect {
            x0: ox.floor() as i32,
            y0: (oy - scale * h).floor() as i32,
            x1: (ox + scale * w).ceil() as i32,
            y1: oy.ceil() as i32,
        },
        x: (x0, x1),
        y: (y0, y1),
    };
    // The outline: edges of one triangle only.
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|[a, b]| if a < b { [a, b] } else { [b, a] })
        .collect();
    edges.sort_unstable();
    let mut outline = Coverage::new(canvas.width, canvas.height, map_ax.rect.grow(3));
    let mut k = 0;
    while k < edges.len() {
        let mut j = k + 1;
        while j < edges.len() && edges[j] == edges[k] {
            j += 1;
        }
        if j - k == 1 {
            let [a, b] = edges[k];
            outline.segment(to_px(points[a as usize]), to_px(points[b as usize]), 1.5);
        }
        k = j;
    }
    canvas.composite(&outline, [80, 80, 80], 1.0);
    let residual = |m: &FitSensor| m.computed - m.measured;
    let largest = ms
        .iter()
        .map(|m| residual(m).abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for m in ms {
        let c = to_px(m.at);
        let mut ring = Coverage::new(canvas.width, canvas.height, map.grow(12));
        ring.disc(c, 8.0);
        canvas.composite(&ring, [40, 40, 40], 1.0);
        let mut dot = Coverage::new(canvas.width, canvas.height, map.grow(12));
        dot.disc(c, 6.5);
        canvas.composite(&dot, diverging(residual(m) / largest), 1.0);
    }
    map_ax.frame(
        &mut canvas,
        &format!("x{len}"),
        &format!("y{len}"),
        &mut boxes,
    );
    // Colour bar of the residuals.
    let bar = PixelRect::new(FIT_WIDTH as i32 - 115, 110, 22, map.height() - 80);
    for r in 0..bar.height() {
        let t = 1.0 - 2.0 * (r as f64 + 0.5) / bar.height() as f64;
        canvas.fill_rect(
            PixelRect::new(bar.x0, bar.y0 + r, bar.width(), 1),
            diverging(t),
            1.0,
        );
    }
    canvas.stroke_rect(bar.grow(1), axes::FRAME);
    for (t, v) in [(1.0, largest), (0.0, 0.0), (-1.0, -largest)] {
        let y = bar.y0 as f64 + (1.0 - t) / 2.0 * bar.height() as f64;
        boxes.push(text::draw(
            &mut canvas,
            &format!("{v:.2e}"),
            Style::new(13.0),
            (bar.x1 + 6) as f64,
            y,
            Anchor::Left,
        ));
    }
    boxes.push(text::draw(
        &mut canvas,
        &format!("residual{len}"),
        Style::new(15.0),
        bar.x0 as f64 - 20.0,
        (bar.y0 - 22) as f64,
        Anchor::Left,
    ));
    boxes.push(text::draw(
        &mut canvas,
        "computed − measured",
        Style::new(13.0),
        bar.x0 as f64 - 40.0,
        (bar.y1 + 22) as f64,
        Anchor::Left,
    ));
    Ok(canvas)
}
