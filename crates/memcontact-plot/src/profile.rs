//! The profile picture: u and φ along a straight line against arc length, exactly as the
//! P1 fields vary along it (one piece per triangle crossed), contact stretches shaded,
//! gaps where the line leaves the mesh. With a body below, its surface φ_low too, and
//! each body's contact stretches in its own shade (each surface drawn where its body
//! covers the membrane).

use crate::axes::{self, Axes, Swatch};
use crate::canvas::{Canvas, Coverage, PixelRect, Rgb};
use crate::ticks;
use crate::{Error, Result};
use crate::{Picture, PlotData, PlotKind, PlotOptions, PROFILE_HEIGHT, PROFILE_WIDTH};
use rayon::prelude::*;

/// Colour of u.
const U_COLOR: Rgb = [31, 90, 180];
/// Colour of φ.
const PHI_COLOR: Rgb = [140, 70, 20];
/// Colour of φ_low, the surface of the body below.
const PHI_LOW_COLOR: Rgb = [110, 40, 160];
/// Shade of the contact stretches (with a body below: of the contact with the obstacle).
pub const CONTACT_SHADE: Rgb = [253, 208, 162];
/// Shade of the stretches of contact with the body below.
pub const LOWER_SHADE: Rgb = [222, 206, 240];

/// One piece of the line inside one triangle: parameters, and u, φ, contact indicator at
/// both ends; with a body below, φ_low and its contact indicator (NaN and 0 without).
#[derive(Debug, Clone, Copy)]
struct Piece {
    /// The user's number of the triangle (ties along the line go to the lower).
    k: u32,
    t: [f64; 2],
    u: [f64; 2],
    phi: [f64; 2],
    c: [f64; 2],
    phi_low: [f64; 2],
    c_low: [f64; 2],
}

/// The profile line of `options` (default: through the middle of the bounding box,
/// horizontally, across it).
pub fn line_of(data: &PlotData, options: &PlotOptions) -> [[f64; 2]; 2] {
    options.profile.unwrap_or_else(|| {
        let b = data.bbox();
        let y = 0.5 * (b[2] + b[3]);
        [[b[0], y], [b[1], y]]
    })
}

/// The pieces of the segment `a → b` inside each triangle, sorted along it.
fn pieces(data: &PlotData, a: [f64; 2], b: [f64; 2]) -> Vec<Piece> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let contact = |i: usize| if data.state[i] >= 0 { 1.0 } else { 0.0 };
    // With a body below, each surface is drawn where its body covers the membrane.
    let phi = |i: usize| match data.lower {
        Some(_) if !data.covered[i] => f64::NAN,
        _ => data.phi[i],
    };
    let phi_low = |i: usize| match data.lower {
        Some(low) if low.covered[i] => low.phi[i],
        _ => f64::NAN,
    };
    let contact_low = |i: usize| match data.lower {
        Some(low) if low.state[i] >= 0 => 1.0,
        _ => 0.0,
    };
    /// Triangles per task.
    const CHUNK: usize = 1 << 14;
    let chunks: Vec<Vec<Piece>> = data
        .triangles
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut out = Vec::new();
            for (i, t) in chunk.iter().enumerate() {
                let Some(([lo, hi], ab)) =
                    crate::segment::clip(t.map(|v| data.points[v as usize]), a, d)
                else {
                    continue;
                };
                let eval = |f: &dyn Fn(usize) -> f64, s: f64| {
                    (0..3)
                        .map(|k| (ab[k][0] + ab[k][1] * s) * f(t[k] as usize))
                        .sum::<f64>()
                };
                let at = |f: &dyn Fn(usize) -> f64| [eval(f, lo), eval(f, hi)];
                out.push(Piece {
                    k: crate::UserNumbering::triangle(data.numbering, (c * CHUNK + i) as u32),
                    t: [lo, hi],
                    u: at(&|i| data.u[i]),
                    phi: at(&phi),
                    c: at(&contact),
                    phi_low: at(&phi_low),
                    c_low: at(&contact_low),
                });
            }
            out
        })
        .collect();
    let mut all = chunks.concat();
    all.sort_by(|p, q| {
        (p.t[0].total_cmp(&q.t[0]))
            .then(p.t[1].total_cmp(&q.t[1]))
            .then(p.k.cmp(&q.k))
    });
    all
}

/// Polylines `(s, value)` of one field, broken where pieces do not meet or the value is not
/// finite.
fn polylines(pieces: &[Piece], len: f64, f: impl Fn(&Piece) -> [f64; 2]) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    for p in pieces {
        let v = f(p);
        let ok = v[0].is_finite() && v[1].is_finite();
        let joined = (p.t[0] - last_t).abs() <= 1e-9;
        if !ok {
            last_t = f64::NEG_INFINITY;
            continue;
        }
        if !joined || out.is_empty() {
            out.push(Vec::new());
        }
        let line = out.last_mut().expect("a line was started");
        if line.is_empty() {
            line.push((p.t[0] * len, v[0]));
        }
        line.push((p.t[1] * len, v[1]));
        last_t = p.t[1];
    }
    out
}

/// The stretches `[s0, s1]` where the P1 contact indicator `c` is ≥ ½.
fn contact_stretches(
    pieces: &[Piece],
    len: f64,
    c: impl Fn(&Piece) -> [f64; 2],
) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for p in pieces {
        let [c0, c1] = c(p);
        let [t0, t1] = p.t;
        let cross = |c: f64| t0 + (t1 - t0) * (0.5 - c0) / (c - c0);
        let span = match (c0 >= 0.5, c1 >= 0.5) {
            (true, true) => Some((t0, t1)),
            (true, false) => Some((t0, cross(c1))),
            (false, true) => Some((cross(c1), t1)),
            (false, false) => None,
        };
        if let Some((a, b)) = span {
            let (a, b) = (a * len, b * len);
            match out.last_mut() {
                Some(last) if a <= last.1 + 1e-9 * len => last.1 = last.1.max(b),
                _ => out.push((a, b)),
            }
        }
    }
    out
}

/// Draws the profile picture.
pub(crate) fn render(data: &PlotData, options: &PlotOptions) -> Result<Picture> {
    let [a, b] = line_of(data, options);
    let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let ps = pieces(data, a, b);
    if ps.is_empty() || len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Data(format!(
            "profile: the line from ({}, {}) to ({}, {}) does not cross the mesh",
            a[0], a[1], b[0], b[1]
        )));
    }
    let u_lines = polylines(&ps, len, |p| p.u);
    let phi_lines = polylines(&ps, len, |p| p.phi);
    let phi_low_lines = polylines(&ps, len, |p| p.phi_low);
    let stretches = contact_stretches(&ps, len, |p| p.c);
    let lower_stretches = contact_stretches(&ps, len, |p| p.c_low);
    let vals = u_lines
        .iter()
        .chain(&phi_lines)
        .chain(&phi_low_lines)
        .flatten()
        .map(|p| p.1);
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |r, v| {
        (r.0.min(v), r.1.max(v))
    });
    let (lo, hi) = crate::colormap::widen(lo, hi);
    let pad = 0.06 * (hi - lo);

    let mut canvas = Canvas::new(PROFILE_WIDTH, PROFILE_HEIGHT);
    let mut boxes = Vec::new();
    let ax = Axes {
        rect: PixelRect {
            x0: 110,
            y0: 62,
            x1: 1040,
            y1: PROFILE_HEIGHT as i32 - 85,
        },
        x: (0.0, len),
        y: (lo - pad, hi + pad),
    };
    let title = match &options.title {
        Some(t) if !t.is_empty() => format!("Profile: {t}"),
        _ => "Profile".to_string(),
    };
    axes::title(&mut canvas, &title, 30.0, &mut boxes);
    let columns = |(s0, s1): (f64, f64)| {
        let x0 = ax.px(s0).round() as i32;
        let x1 = (ax.px(s1).round() as i32).max(x0 + 1);
        (x0, x1)
    };
    for &s in &lower_stretches {
        let (x0, x1) = columns(s);
        canvas.fill_rect(
            PixelRect {
                x0,
                y0: ax.rect.y0,
                x1,
                y1: ax.rect.y1,
            },
            LOWER_SHADE,
            1.0,
        );
    }
    for &(s0, s1) in &stretches {
        let (x0, x1) = columns((s0, s1));
        canvas.fill_rect(
            PixelRect {
                x0,
                y0: ax.rect.y0,
                x1,
                y1: ax.rect.y1,
            },
            CONTACT_SHADE,
            1.0,
        );
        // Squeezed between the bodies: the obstacle's shade above, the body below's below.
        for &(a, b) in &lower_stretches {
            let (a, b) = (a.max(s0), b.min(s1));
            if a < b {
                let (x0, x1) = columns((a, b));
                canvas.fill_rect(
                    PixelRect {
                        x0,
                        y0: (ax.rect.y0 + ax.rect.y1) / 2,
                        x1,
                        y1: ax.rect.y1,
                    },
                    LOWER_SHADE,
                    1.0,
                );
            }
        }
    }
    ax.grid(&mut canvas);
    let px = |l: &Vec<(f64, f64)>| {
        l.iter()
            .map(|&(s, v)| [ax.px(s), ax.py(v)])
            .collect::<Vec<_>>()
    };
    let mut m = Coverage::new(canvas.width, canvas.height, ax.rect);
    for l in &phi_lines {
        m.dashed(&px(l), 2.0, 9.0, 5.0);
    }
    canvas.composite(&m, PHI_COLOR, 1.0);
    if !phi_low_lines.is_empty() {
        let mut m = Coverage::new(canvas.width, canvas.height, ax.rect);
        for l in &phi_low_lines {
            m.dashed(&px(l), 2.0, 4.0, 4.0);
        }
        canvas.composite(&m, PHI_LOW_COLOR, 1.0);
    }
    let mut m = Coverage::new(canvas.width, canvas.height, ax.rect);
    for l in &u_lines {
        m.polyline(&px(l), 2.2);
    }
    canvas.composite(&m, U_COLOR, 1.0);
    let unit = options.units.length_suffix();
    let y_label = match data.lower {
        None => format!("u, φ{unit}"),
        Some(_) => format!("u, φ, φ_low{unit}"),
    };
    ax.frame(
        &mut canvas,
        &format!("arc length s{unit}"),
        &y_label,
        &mut boxes,
    );
    let f = |v: f64| ticks::format_sig(v, 4);
    let mut entries = vec![(Swatch::Line(U_COLOR, 2.2), "deflection u".to_string())];
    match data.lower {
        None => entries.extend([
            (Swatch::Dashed(PHI_COLOR, 2.0), "obstacle φ".to_string()),
            (Swatch::Patch(CONTACT_SHADE), "contact (u ≥ φ)".to_string()),
        ]),
        Some(low) => {
            let (up, down) = (
                data.covered.iter().any(|&c| c),
                low.covered.iter().any(|&c| c),
            );
            if up {
                entries.push((Swatch::Dashed(PHI_COLOR, 2.0), "obstacle φ".to_string()));
            }
            if down {
                entries.push((
                    Swatch::Dashed(PHI_LOW_COLOR, 2.0),
                    "body below φ_low".to_string(),
                ));
            }
            if up {
                entries.push((
                    Swatch::Patch(CONTACT_SHADE),
                    "contact with the obstacle".to_string(),
                ));
            }
            if down {
                entries.push((
                    Swatch::Patch(LOWER_SHADE),
                    "contact with the body below".to_string(),
                ));
            }
        }
    }
    entries.extend([
        (Swatch::None, format!("from ({}, {})", f(a[0]), f(a[1]))),
        (Swatch::None, format!("to ({}, {})", f(b[0]), f(b[1]))),
    ]);
    let covered: f64 = ps.iter().map(|p| p.t[1] - p.t[0]).sum::<f64>();
    if covered < 1.0 - 1e-6 {
        entries.push((Swatch::None, "gaps: outside the mesh".into()));
    }
    axes::legend(&mut canvas, 1070, ax.rect.y0, 220, &entries, &mut boxes);
    Ok(Picture {
        kind: PlotKind::Profile,
        canvas,
        map: None,
        text_boxes: boxes,
        markers: false,
        range: Some((lo, hi)),
        axes: Some(ax),
        legend: crate::maps::legend_labels(&entries),
    })
}

/// The contact stretches `[s0, s1]` (arc length) along the profile line of `options` (of
/// the contact with the obstacle): for checks, and for callers that report them.
pub fn contact_along(data: &PlotData, options: &PlotOptions) -> Vec<(f64, f64)> {
    let [a, b] = line_of(data, options);
    let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    contact_stretches(&pieces(data, a, b), len, |p| p.c)
}

/// The stretches `[s0, s1]` (arc length) of contact with the body below along the profile
/// line of `options` (none without a body below).
pub fn lower_contact_along(data: &PlotData, options: &PlotOptions) -> Vec<(f64, f64)> {
    let [a, b] = line_of(data, options);
    let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    contact_stretches(&pieces(data, a, b), len, |p| p.c_low)
}
