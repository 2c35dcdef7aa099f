//! An x-y line plot with markers (e.g. the force-deflection curve of a load sweep):
//! several named series on linear axes, a legend in the emptiest corner.

use crate::axes::{self, Axes, Swatch};
use crate::canvas::{Canvas, Coverage, PixelRect, Rgb, WHITE};
use crate::{Error, Result};

/// Width of a line plot, pixels.
pub const LINE_WIDTH: u32 = 1000;
/// Height of a line plot, pixels.
pub const LINE_HEIGHT: u32 = 700;

/// Series colours (the "tab10" palette).
pub const COLORS: [Rgb; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// One named curve; a non-finite coordinate breaks the line there.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// The name in the legend.
    pub name: String,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// An x-y line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// The title.
    pub title: String,
    /// The x-axis title, units included (e.g. `load factor`).
    pub x_label: String,
    /// The y-axis title, units included (e.g. `max deflection [m]`).
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

/// Marker shapes, one per series in turn.
#[derive(Debug, Clone, Copy)]
enum Marker {
    Circle,
    Square,
    Diamond,
}

fn marker(m: &mut Coverage, kind: Marker, c: [f64; 2], r: f64) {
    match kind {
        Marker::Circle => m.disc(c, r),
        Marker::Square => {
            let r = r * 0.85;
            let x0 = (c[0] - r).round() as i32;
            let y0 = (c[1] - r).round() as i32;
            let s = (2.0 * r).round() as i32;
            for y in y0..y0 + s {
                m.segment(
                    [x0 as f64, y as f64 + 0.5],
                    [(x0 + s) as f64, y as f64 + 0.5],
                    1.0,
                );
            }
        }
        Marker::Diamond => {
            let r = r * 1.25;
            let mut k = -r;
            while k <= r {
                let half = r - k.abs();
                m.segment([c[0] - half, c[1] + k], [c[0] + half, c[1] + k], 1.0);
                k += 0.5;
            }
        }
    }
}

const MARKERS: [Marker; 3] = [Marker::Circle, Marker::Square, Marker::Diamond];

/// Draws the plot in memory.
pub fn render_line_plot(plot: &LinePlot) -> Result<Canvas> {
    let pts: Vec<(f64, f64)> = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(Error::Data(format!(
            "line plot \"{}\": no point with finite coordinates",
            plot.title
        )));
    }
    let fold = |f: fn(&(f64, f64)) -> f64| {
        pts.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |a, v| {
                (a.0.min(v), a.1.max(v))
            })
    };
    let pad = |(lo, hi): (f64, f64)| {
        let (lo, hi) = crate::colormap::widen(lo, hi);
        let d = 0.05 * (hi - lo);
        (lo - d, hi + d)
    };
    let mut canvas = Canvas::new(LINE_WIDTH, LINE_HEIGHT);
    let mut boxes = Vec::new();
    let ax = Axes {
        rect: PixelRect {
            x0: 110,
            y0: 60,
            x1: LINE_WIDTH as i32 - 30,
            y1: LINE_HEIGHT as i32 - 85,
        },
        x: pad(fold(|p| p.0)),
        y: pad(fold(|p| p.1)),
    };
    axes::title(&mut canvas, &plot.title, 28.0, &mut boxes);
    ax.grid(&mut canvas);
    let mut legend = Vec::new();
    for (k, s) in plot.series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let mut line = Coverage::new(canvas.width, canvas.height, ax.rect);
        let mut marks = Coverage::new(canvas.width, canvas.height, ax.rect.grow(6));
        let px: Vec<Option<[f64; 2]>> = s
            .points
            .iter()
            .map(|&(x, y)| (x.is_finite() && y.is_finite()).then(|| [ax.px(x), ax.py(y)]))
            .collect();
        for w in px.windows(2) {
            if let (Some(a), Some(b)) = (w[0], w[1]) {
                line.segment(a, b, 2.2);
            }
        }
        for p in px.iter().flatten() {
            marker(&mut marks, MARKERS[k % MARKERS.len()], *p, 4.5);
        }
        canvas.composite(&line, color, 1.0);
        canvas.composite(&marks, color, 1.0);
        legend.push((Swatch::Line(color, 2.2), s.name.clone()));
    }
    ax.frame(&mut canvas, &plot.x_label, &plot.y_label, &mut boxes);
    // Legend: in the corner with the fewest data points under it.
    let h = 24 * legend.len() as i32 + 12;
    let w = legend
        .iter()
        .map(|(_, n)| crate::text::measure(n, 14.0).0 + 50)
        .max()
        .unwrap_or(100)
        .min(ax.rect.width() / 2);
    let corners = [
        PixelRect::new(ax.rect.x1 - w - 12, ax.rect.y0 + 12, w, h),
        PixelRect::new(ax.rect.x0 + 12, ax.rect.y0 + 12, w, h),
        PixelRect::new(ax.rect.x1 - w - 12, ax.rect.y1 - h - 12, w, h),
        PixelRect::new(ax.rect.x0 + 12, ax.rect.y1 - h - 12, w, h),
    ];
    let crowd = |r: &PixelRect| {
        pts.iter()
            .filter(|p| r.grow(10).contains(ax.px(p.0) as i32, ax.py(p.1) as i32))
            .count()
    };
    let best = corners
        .iter()
        .min_by_key(|r| crowd(r))
        .copied()
        .unwrap_or(corners[0]);
    if !legend.is_empty() {
        canvas.fill_rect(best, WHITE, 0.9);
        canvas.stroke_rect(best, [170, 170, 170]);
        axes::legend(
            &mut canvas,
            best.x0 + 8,
            best.y0 + 6,
            w - 14,
            &legend,
            &mut boxes,
        );
    }
    Ok(canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_deflection_curves_are_drawn_with_legend_and_gaps() {
        let load: Vec<f64> = (0..10).map(|k| 0.2 * (k + 1) as f64).collect();
        let plot = LinePlot {
            title: "Force-deflection: examples/roof.toml".into(),
            x_label: "load factor".into(),
            y_label: "max deflection [m]".into(),
            series: vec![
                Series {
                    name: "warm start".into(),
                    points: load.iter().map(|&l| (l, 0.3 * l.powf(0.8))).collect(),
                },
                Series {
                    name: "cold start".into(),
                    // a failed step leaves a gap
                    points: load
                        .iter()
                        .map(|&l| (l, if l == 1.0 { f64::NAN } else { 0.25 * l }))
                        .collect(),
                },
            ],
        };
        let c = render_line_plot(&plot).unwrap();
        assert_eq!((c.width, c.height), (LINE_WIDTH, LINE_HEIGHT));
        for col in &COLORS[..2] {
            let n = c.rgb.chunks_exact(3).filter(|p| p == col).count();
            assert!(n > 300, "series colour {col:?}: {n} pixels");
        }
        let png = c.encode_png().unwrap();
        let back = crate::canvas::decode_png(&png).unwrap();
        assert_eq!(back, c);
        if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
            std::fs::write(
                std::path::Path::new(&keep).join("force-deflection.png"),
                &png,
            )
            .unwrap();
        }
        let empty = LinePlot {
            series: vec![Series {
                name: "none".into(),
                points: vec![(f64::NAN, 1.0)],
            }],
            ..plot
        };
        let e = render_line_plot(&empty).unwrap_err().to_string();
        assert!(e.contains("no point"), "{e}");
    }
}
