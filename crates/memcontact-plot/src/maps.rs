//! The three map pictures: deflection, contact pressure and lift-off.
//!
//! All three share one [`MapLayout`]: the world → pixel transform, the rasterised mesh and
//! its boundary, computed once. Each picture fills the frame pixel by pixel from the P1
//! interpolants of its fields, then draws the mesh boundary, contour lines, outlines
//! (level ½ of the P1 interpolant of a 0/1 indicator, so that every vertex of the set lies
//! inside its outline and every other vertex outside), labels, axes, colour bar and legend.
//!
//! With a body below ([`PlotData::lower`]) each body's contact zone has its own outline
//! (the obstacle's solid, the body below's dashed), and the lift-off map shows each body's
//! contact and gap in its own colours.

use crate::axes::{self, hatch_color, stripe_color, Axes, Swatch};
use crate::canvas::{Canvas, Coverage, PixelRect, Rgb, WHITE};
use crate::colormap::{self, Colormap, Norm};
use crate::raster::{self, Fragments, MapTransform, EMPTY};
use crate::text::{self, Anchor, Style};
use crate::ticks;
use crate::{
    BodyData, PlotData, PlotKind, PlotOptions, Units, UserNumbering, MAP_HEIGHT, MAP_WIDTH,
};
use crate::{Error, Result};
use rayon::prelude::*;

/// The area the map frame is fitted into.
const MAP_AREA: PixelRect = PixelRect {
    x0: 120,
    y0: 62,
    x1: 1040,
    y1: 872,
};
/// The colour bar.
const BAR: PixelRect = PixelRect {
    x0: 1085,
    y0: 100,
    x1: 1113,
    y1: 520,
};
/// The upper of two colour bars (the lift-off map's gap to the obstacle, when the gap to
/// the body below is shown too).
const BAR_TOP: PixelRect = PixelRect {
    x0: 1085,
    y0: 100,
    x1: 1113,
    y1: 290,
};
/// The lower of two colour bars (the gap to the body below).
const BAR_BOTTOM: PixelRect = PixelRect {
    x0: 1085,
    y0: 350,
    x1: 1113,
    y1: 540,
};
/// Left edge and width of the right-hand column (colour bar labels, legend).
const COLUMN: (i32, i32) = (1075, 215);
/// Contact outline colour (deflection and lift-off maps).
pub const OUTLINE: Rgb = [220, 20, 60];
/// Contact outline colour on the pressure map.
pub const PRESSURE_OUTLINE: Rgb = [0, 70, 160];
/// Outline of the contact with the body below (deflection and lift-off maps), dashed.
pub const LOWER_OUTLINE: Rgb = [255, 0, 255];
/// Outline of the contact with the body below on the pressure map, dashed.
pub const LOWER_PRESSURE_OUTLINE: Rgb = [110, 30, 160];
/// Width of the contact outlines on the deflection map, pixels.
const DEFLECTION_OUTLINE_WIDTH: f64 = 2.6;
/// Fill of a penetrating vertex's marker.
const PEN_MARK: Rgb = [255, 120, 0];
/// Light marker colour (not the hatching's pure white).
const MARK_LIGHT: Rgb = [250, 250, 250];
/// Dark marker colour (not the hatching's pure black).
const MARK_DARK: Rgb = [15, 15, 15];
/// Contour line colour.
const CONTOUR: Rgb = [25, 25, 25];
/// Mesh boundary colour.
const BOUNDARY: Rgb = [70, 70, 70];
/// Below this mean vertex spacing (pixels), vertices get no marker.
const MARKER_SPACING: f64 = 20.0;

/// What the three map pictures share: where the mesh lies on the canvas and which
/// triangle covers each pixel.
#[derive(Debug, Clone)]
pub struct MapLayout {
    /// World → pixel.
    pub transform: MapTransform,
    /// The frame: the pixels of the map.
    pub frame: PixelRect,
    /// Vertex positions in pixels.
    pub(crate) pv: Vec<[f64; 2]>,
    /// The rasterised mesh.
    pub(crate) frags: Fragments,
    /// Boundary edges (vertex pairs).
    pub(crate) boundary: Vec<[u32; 2]>,
    /// Mean distance between neighbouring vertices, pixels (about).
    pub vertex_spacing: f64,
}

impl MapLayout {
    /// Fits the mesh of `data` into the map area and rasterises it.
    pub fn new(data: &PlotData) -> MapLayout {
        MapLayout::numbered(data.points, data.triangles, data.bbox(), data.numbering)
    }

    /// Fits the triangles (bounding box `bbox`, `[xmin, xmax, ymin, ymax]`) into the map
    /// area and rasterises them.
    pub fn of(points: &[[f64; 2]], triangles: &[[u32; 3]], bbox: [f64; 4]) -> MapLayout {
        MapLayout::numbered(points, triangles, bbox, None)
    }

    /// [`MapLayout::of`] for a mesh renumbered from the user's `numbering`.
    fn numbered(
        points: &[[f64; 2]],
        triangles: &[[u32; 3]],
        bbox: [f64; 4],
        numbering: Option<UserNumbering>,
    ) -> MapLayout {
        let (transform, frame) = MapTransform::fit(bbox, MAP_AREA);
        let pv: Vec<[f64; 2]> = points.par_iter().map(|&p| transform.to_pixel(p)).collect();
        let frags = raster::rasterise(&pv, triangles, frame, numbering);
        let boundary = raster::boundary_edges(points.len(), triangles);
        let covered = frags.covered() as f64;
        let vertex_spacing = (covered / points.len().max(1) as f64).sqrt();
        MapLayout {
            transform,
            frame,
            pv,
            frags,
            boundary,
            vertex_spacing,
        }
    }

    /// The triangle whose interior holds the centre of canvas pixel `(x, y)`, if any.
    pub fn triangle_at(&self, x: i32, y: i32) -> Option<u32> {
        self.frags
            .index(x, y)
            .map(|i| self.frags.tri[i])
            .filter(|&t| t != EMPTY)
    }

    /// Vertex positions on the canvas (pixel coordinates).
    pub fn vertex_pixels(&self) -> &[[f64; 2]] {
        &self.pv
    }

    /// True when vertex markers are drawn (the mesh is coarse enough on the canvas).
    pub fn markers(&self) -> bool {
        self.vertex_spacing >= MARKER_SPACING
    }
}

/// A picture drawn in memory, with what is needed to check it.
#[derive(Debug, Clone)]
pub struct Picture {
    /// Which picture.
    pub kind: PlotKind,
    /// The pixels.
    pub canvas: Canvas,
    /// For maps: the world → pixel transform and the frame.
    pub map: Option<(MapTransform, PixelRect)>,
    /// Every text drawn (titles, ticks, labels, legend): none overlaps another.
    pub text_boxes: Vec<PixelRect>,
    /// Vertex markers were drawn (penetrating and touching vertices of the deflection map).
    pub markers: bool,
    /// The colour bar's range (the data range of the mapped field), if there is a bar; on
    /// the lift-off map with a body below, the range of both gaps shown (their colour bars
    /// share it); for the profile, the range of u and the surfaces along the line.
    pub range: Option<(f64, f64)>,
    /// For the profile: its axes (arc length × value → pixels).
    pub axes: Option<Axes>,
    /// The legend's entries, in order (as given, before any shrinking or cutting to fit).
    pub legend: Vec<String>,
}

/// The labels of legend entries.
pub(crate) fn legend_labels(entries: &[(Swatch, String)]) -> Vec<String> {
    entries.iter().map(|(_, s)| s.clone()).collect()
}

/// Minimum and maximum of the finite values in `v` over the vertices where `keep` holds.
fn range(v: &[f64], keep: impl Fn(usize) -> bool + Sync) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .par_iter()
        .enumerate()
        .filter(|(i, x)| x.is_finite() && keep(*i))
        .map(|(_, &x)| (x, x))
        .reduce(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    (lo <= hi).then_some((lo, hi))
}

/// A 0/1 indicator as a P1 field.
fn indicator(n: usize, f: impl Fn(usize) -> bool + Sync + Send) -> Vec<f64> {
    (0..n)
        .into_par_iter()
        .map(|i| if f(i) { 1.0 } else { 0.0 })
        .collect()
}

/// Fills the frame: `color(fragment index)` for covered pixels, white elsewhere.
fn fill(canvas: &mut Canvas, l: &MapLayout, color: impl Fn(usize, i32, i32) -> Rgb + Sync) {
    let f = &l.frags;
    let (w, x0, y0) = (canvas.width as usize, f.rect.x0, f.rect.y0);
    let fw = f.rect.width() as usize;
    canvas
        .rgb
        .par_chunks_mut(3 * w)
        .enumerate()
        .skip(y0.max(0) as usize)
        .take(f.rect.height() as usize)
        .for_each(|(y, row)| {
            let base = (y - y0 as usize) * fw;
            for i in 0..fw {
                let k = base + i;
                if f.tri[k] == EMPTY {
                    continue;
                }
                let x = x0 + i as i32;
                let c = color(k, x, y as i32);
                row[3 * x as usize..3 * x as usize + 3].copy_from_slice(&c);
            }
        });
}

/// Draws the mesh boundary (outer boundary and holes).
fn draw_boundary(canvas: &mut Canvas, l: &MapLayout) {
    let mut m = Coverage::new(canvas.width, canvas.height, l.frame);
    for e in &l.boundary {
        m.segment(l.pv[e[0] as usize], l.pv[e[1] as usize], 1.3);
    }
    canvas.composite(&m, BOUNDARY, 1.0);
}

/// The level line `values = level` as a coverage mask (`mesh`: the triangles and their
/// user numbering).
#[allow(clippy::too_many_arguments)]
fn level_mask(
    canvas: &Canvas,
    l: &MapLayout,
    (tris, numbering): (&[[u32; 3]], Option<UserNumbering>),
    values: &[f64],
    level: f64,
    width: f64,
    dashed: bool,
) -> Coverage {
    let segs = raster::level_segments(&l.pv, tris, values, level, numbering);
    let mut m = Coverage::new(canvas.width, canvas.height, l.frame);
    if dashed {
        // Dashes need a continuous arc length: chain the segments into polylines.
        for line in raster::chain(&segs) {
            m.dashed(&line, width, 7.0, 5.0);
        }
    } else {
        for s in &segs {
            m.segment(s[0], s[1], width);
        }
    }
    m
}

/// A label to put on a contour line.
struct Label {
    rect: PixelRect,
    text: String,
}

/// Contour lines of `values` at nice levels inside `(lo, hi)`, with labels placed on them
/// where they fit inside the frame without touching another label or `avoid`.
fn contours(
    canvas: &mut Canvas,
    l: &MapLayout,
    (tris, numbering): (&[[u32; 3]], Option<UserNumbering>),
    values: &[f64],
    (lo, hi): (f64, f64),
    count: usize,
    avoid: &[PixelRect],
) -> Vec<Label> {
    let levels = ticks::levels(lo, hi, count);
    if levels.is_empty() {
        return Vec::new();
    }
    let step = if levels.len() > 1 {
        levels[1] - levels[0]
    } else {
        ticks::nice_step(lo, hi, count + 1)
    };
    let segs = raster::level_sets(&l.pv, tris, values, &levels, numbering);
    let mut mask = Coverage::new(canvas.width, canvas.height, l.frame);
    for s in segs.iter().flatten() {
        mask.segment(s[0], s[1], 1.0);
    }
    // Labels: greedily, for each level, the candidate farthest from the labels placed so
    // far (and from the frame), at most two per level.
    let inner = l.frame.grow(-6);
    let diag = ((l.frame.width().pow(2) + l.frame.height().pow(2)) as f64).sqrt();
    let mut labels: Vec<Label> = Vec::new();
    let size = LABEL_TEXT;
    for (k, &c) in levels.iter().enumerate() {
        let s = &segs[k];
        if s.is_empty() {
            continue;
        }
        let txt = ticks::format(c, step);
        let n = s.len();
        let cand: Vec<[f64; 2]> = (0..n.min(600))
            .map(|j| {
                let q = &s[j * n / n.min(600)];
                [0.5 * (q[0][0] + q[1][0]), 0.5 * (q[0][1] + q[1][1])]
            })
            .collect();
        let mut mine: Vec<[f64; 2]> = Vec::new();
        for _ in 0..2 {
            let mut best: Option<(f64, [f64; 2], PixelRect)> = None;
            for &p in &cand {
                let r = text::text_box(&txt, size, p[0], p[1], Anchor::Center).grow(2);
                if !inner.contains_rect(&r)
                    || labels.iter().any(|o| o.rect.grow(8).overlaps(&r))
                    || avoid.iter().any(|o| o.overlaps(&r))
                {
                    continue;
                }
                let near = labels
                    .iter()
                    .map(|o| {
                        let oc = [
                            (o.rect.x0 + o.rect.x1) as f64 / 2.0,
                            (o.rect.y0 + o.rect.y1) as f64 / 2.0,
                        ];
                        ((oc[0] - p[0]).powi(2) + (oc[1] - p[1]).powi(2)).sqrt()
                    })
                    .fold(diag, f64::min);
                let border = ((p[0] - l.frame.x0 as f64).min(l.frame.x1 as f64 - p[0]))
                    .min((p[1] - l.frame.y0 as f64).min(l.frame.y1 as f64 - p[1]));
                let score = near.min(0.4 * diag) + 0.5 * border.min(0.15 * diag);
                if best.as_ref().is_none_or(|b| score > b.0) {
                    best = Some((score, p, r));
                }
            }
            let Some((_, p, r)) = best else { break };
            if let Some(q) = mine.first() {
                if ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt() < 0.35 * diag {
                    break;
                }
            }
            mine.push(p);
            labels.push(Label {
                rect: r,
                text: txt.clone(),
            });
        }
    }
    for lab in &labels {
        mask.clear(lab.rect);
    }
    canvas.composite(&mask, CONTOUR, 0.8);
    labels
}

/// Draws contour labels (last, over outlines and markers).
fn draw_labels(canvas: &mut Canvas, labels: &[Label], boxes: &mut Vec<PixelRect>) {
    for lab in labels {
        canvas.fill_rect(lab.rect, WHITE, 0.6);
        let cx = (lab.rect.x0 + lab.rect.x1) as f64 / 2.0;
        let cy = (lab.rect.y0 + lab.rect.y1) as f64 / 2.0;
        boxes.push(text::draw(
            canvas,
            &lab.text,
            Style::new(LABEL_TEXT).color([10, 10, 10]),
            cx,
            cy,
            Anchor::Center,
        ));
    }
}

/// Size of contour labels, pixels.
const LABEL_TEXT: f32 = 13.0;

/// The common furniture: title, axes, colour bar.
#[allow(clippy::too_many_arguments)]
fn furniture(
    canvas: &mut Canvas,
    l: &MapLayout,
    units: &Units,
    title: &str,
    bar: Option<(&Colormap, &Norm, (f64, f64), String)>,
    boxes: &mut Vec<PixelRect>,
) {
    axes::title(canvas, title, 30.0, boxes);
    let xr = (
        l.transform.x0,
        l.transform.x0 + l.frame.width() as f64 / l.transform.scale,
    );
    let yr = (
        l.transform.y0,
        l.transform.y0 + l.frame.height() as f64 / l.transform.scale,
    );
    let unit = units.length_suffix();
    Axes {
        rect: l.frame,
        x: xr,
        y: yr,
    }
    .frame(canvas, &format!("x{unit}"), &format!("y{unit}"), boxes);
    if let Some((map, norm, r, label)) = bar {
        axes::colorbar(canvas, BAR, map, norm, r, &label, COLUMN.1, boxes);
    }
}

/// The range lines of a legend.
fn range_entries(name: &str, (lo, hi): (f64, f64)) -> Vec<(Swatch, String)> {
    vec![
        (
            Swatch::None,
            format!("{name} min {}", ticks::format_sig(lo, 5)),
        ),
        (
            Swatch::None,
            format!("{name} max {}", ticks::format_sig(hi, 5)),
        ),
    ]
}

/// Draws one of the map pictures.
pub(crate) fn render(
    kind: PlotKind,
    l: &MapLayout,
    data: &PlotData,
    options: &PlotOptions,
) -> Result<Picture> {
    let mut canvas = Canvas::new(MAP_WIDTH, MAP_HEIGHT);
    let mut boxes = Vec::new();
    let n = data.points.len();
    let tris = data.triangles;
    let mesh = (tris, data.numbering);
    let f = &l.frags;
    let contact = indicator(n, |i| data.state[i] >= 0);
    let outline = |canvas: &mut Canvas, color: Rgb, width: f64| {
        let m = level_mask(canvas, l, mesh, &contact, 0.5, width, false);
        canvas.composite(&m, color, 1.0);
    };
    // The body below's contact zone, outlined dashed.
    let lower_contact = data.lower.map(|low| indicator(n, |i| low.state[i] >= 0));
    let lower_outline = |canvas: &mut Canvas, color: Rgb, width: f64| {
        if let Some(c) = &lower_contact {
            let m = level_mask(canvas, l, mesh, c, 0.5, width, true);
            canvas.composite(&m, color, 1.0);
        }
    };
    // A vertex's class for hatching and markers: 1 penetrating a body, 0 touching one,
    // −1 clear of both.
    let class = |i: usize| -> i8 {
        if data.penetrating(i) {
            1
        } else if data.in_contact(i) {
            0
        } else {
            -1
        }
    };
    let legend_y = BAR.y1 + 60;
    let mut markers = false;
    let bar_range;
    let legend;
    match kind {
        PlotKind::Deflection => {
            let (lo, hi) = range(data.u, |_| true).unwrap_or((0.0, 0.0));
            bar_range = Some((lo, hi));
            let norm = Norm::linear(lo, hi);
            let map = colormap::viridis();
            // Hatched: contact with either body.
            let either_owned;
            let either: &[f64] = if data.lower.is_some() {
                either_owned = indicator(n, |i| data.in_contact(i));
                &either_owned
            } else {
                &contact
            };
            let pen = indicator(n, |i| data.penetrating(i));
            fill(&mut canvas, l, |k, x, y| {
                if f.interp(k, tris, either) >= 0.5 {
                    let slash = f.interp(k, tris, &pen) >= 0.5 * f.interp(k, tris, either);
                    if let Some(c) = hatch_color(x, y, slash) {
                        return c;
                    }
                }
                map.at(norm.t(f.interp(k, tris, data.u)))
            });
            draw_boundary(&mut canvas, l);
            let labels = contours(&mut canvas, l, mesh, data.u, (lo, hi), 8, &[]);
            outline(&mut canvas, OUTLINE, DEFLECTION_OUTLINE_WIDTH);
            lower_outline(&mut canvas, LOWER_OUTLINE, DEFLECTION_OUTLINE_WIDTH);
            markers = l.markers();
            if markers {
                for (st, fillc, ring) in [(1i8, PEN_MARK, MARK_LIGHT), (0, MARK_LIGHT, MARK_DARK)] {
                    let mut outer = Coverage::new(canvas.width, canvas.height, l.frame);
                    let mut inner = Coverage::new(canvas.width, canvas.height, l.frame);
                    for i in (0..n).filter(|&i| class(i) == st) {
                        outer.disc(l.pv[i], 4.4);
                        inner.disc(l.pv[i], 2.8);
                    }
                    canvas.composite(&outer, ring, 1.0);
                    canvas.composite(&inner, fillc, 1.0);
                }
            }
            draw_labels(&mut canvas, &labels, &mut boxes);
            let unit = options.units.length_suffix();
            furniture(
                &mut canvas,
                l,
                &options.units,
                &titled("Deflection u", options),
                Some((map, &norm, (lo, hi), format!("u{unit}"))),
                &mut boxes,
            );
            let n_pen = (0..n).filter(|&i| class(i) == 1).count();
            let n_touch = (0..n).filter(|&i| class(i) == 0).count();
            let mut entries = match data.lower {
                None => vec![
                    (
                        Swatch::Line(OUTLINE, DEFLECTION_OUTLINE_WIDTH),
                        "contact zone outline".to_string(),
                    ),
                    (Swatch::Hatch(true), "penetrating (u > φ)".into()),
                    (Swatch::Hatch(false), "touching (u = φ)".into()),
                ],
                Some(low) => two_body_deflection_entries(data, &low),
            };
            // The hatchings that appear.
            entries.retain(|(sw, _)| match sw {
                Swatch::Hatch(true) => n_pen > 0,
                Swatch::Hatch(false) => n_touch > 0,
                _ => true,
            });
            if markers && n_pen > 0 {
                entries.push((
                    Swatch::Disc(PEN_MARK, MARK_LIGHT),
                    "penetrating vertex".into(),
                ));
            }
            if markers && n_touch > 0 {
                entries.push((
                    Swatch::Disc(MARK_LIGHT, MARK_DARK),
                    "touching vertex".into(),
                ));
            }
            entries.push((Swatch::Line(CONTOUR, 1.0), "contour of u".into()));
            entries.extend(range_entries("u", (lo, hi)));
            match data.lower {
                None => entries.push((Swatch::None, counts(data))),
                Some(low) => entries.extend(
                    two_body_counts(data, &low)
                        .into_iter()
                        .map(|c| (Swatch::None, c)),
                ),
            }
            axes::legend(
                &mut canvas,
                COLUMN.0,
                legend_y,
                COLUMN.1,
                &entries,
                &mut boxes,
            );
            legend = legend_labels(&entries);
        }
        PlotKind::Pressure => {
            let unit = options.units.pressure_suffix();
            // With a body below, the pressure of whichever body presses (their sum).
            let summed;
            let pressure: &[f64] = match data.lower {
                Some(low) => {
                    summed = data
                        .pressure
                        .par_iter()
                        .zip(low.pressure)
                        .map(|(a, b)| a + b)
                        .collect::<Vec<f64>>();
                    &summed
                }
                None => data.pressure,
            };
            let (field, map, norm, label): (Vec<f64>, &Colormap, Norm, String);
            match options.allowable_pressure {
                Some(a) => {
                    field = pressure.par_iter().map(|p| p / a).collect();
                    let (lo, hi) = range(&field, |_| true).unwrap_or((0.0, 0.0));
                    // The hue changes at the allowable (ratio 1).
                    map = colormap::ratio();
                    norm = Norm::centered(lo, hi, 1.0);
                    label = "pressure / allowable".into();
                }
                None => {
                    field = pressure.to_vec();
                    let (lo, hi) = range(&field, |_| true).unwrap_or((0.0, 0.0));
                    map = colormap::yellow_red();
                    norm = Norm::linear(lo, hi);
                    label = format!("contact pressure{unit}");
                }
            }
            let (lo, hi) = range(&field, |_| true).unwrap_or((0.0, 0.0));
            bar_range = Some((lo, hi));
            fill(&mut canvas, l, |k, _, _| {
                map.at(norm.t(f.interp(k, tris, &field)))
            });
            draw_boundary(&mut canvas, l);
            let labels = contours(&mut canvas, l, mesh, &field, (lo, hi), 6, &[]);
            outline(&mut canvas, PRESSURE_OUTLINE, 2.0);
            lower_outline(&mut canvas, LOWER_PRESSURE_OUTLINE, 2.0);
            let mut entries = match data.lower {
                None => vec![(
                    Swatch::Line(PRESSURE_OUTLINE, 2.0),
                    "contact zone outline".to_string(),
                )],
                Some(low) => body_entries(
                    data,
                    &low,
                    Swatch::Line(PRESSURE_OUTLINE, 2.0),
                    Swatch::Dashed(LOWER_PRESSURE_OUTLINE, 2.0),
                ),
            };
            if let Some(a) = options.allowable_pressure {
                let m = level_mask(&canvas, l, mesh, &field, 1.0, 3.0, false);
                canvas.composite(&m, [0, 0, 0], 1.0);
                entries.push((Swatch::Line([0, 0, 0], 3.0), "pressure = allowable".into()));
                entries.push((
                    Swatch::None,
                    format!(
                        "allowable {}{}",
                        ticks::format_sig(a, 5),
                        unit.replace(['[', ']'], "")
                    ),
                ));
                let above = pressure.iter().filter(|&&p| p > a).count();
                entries.push((
                    Swatch::None,
                    if above == 0 {
                        "all below the allowable".to_string()
                    } else {
                        format!("{above} vertices above allowable")
                    },
                ));
                entries.extend(range_entries("ratio", (lo, hi)));
                let (plo, phi) = range(pressure, |_| true).unwrap_or((0.0, 0.0));
                entries.push((
                    Swatch::None,
                    format!("pressure max {}", ticks::format_sig(phi.max(plo), 5)),
                ));
            } else {
                entries.push((Swatch::Line(CONTOUR, 1.0), "contour of pressure".into()));
                entries.extend(range_entries("pressure", (lo, hi)));
            }
            draw_labels(&mut canvas, &labels, &mut boxes);
            furniture(
                &mut canvas,
                l,
                &options.units,
                &titled("Contact pressure", options),
                Some((map, &norm, (lo, hi), label)),
                &mut boxes,
            );
            axes::legend(
                &mut canvas,
                COLUMN.0,
                legend_y,
                COLUMN.1,
                &entries,
                &mut boxes,
            );
            legend = legend_labels(&entries);
        }
        PlotKind::Liftoff if data.lower.is_some() => {
            let low = data.lower.expect("a body below");
            (bar_range, legend) =
                liftoff_two_bodies(&mut canvas, l, data, &low, options, &mut boxes);
        }
        PlotKind::Liftoff => {
            let covered = indicator(n, |i| data.covered[i]);
            let gap: Vec<f64> = (0..n)
                .into_par_iter()
                .map(|i| {
                    if data.covered[i] {
                        data.phi[i] - data.u[i]
                    } else {
                        f64::NAN
                    }
                })
                .collect();
            let gr = range(&gap, |i| data.covered[i] && data.state[i] < 0);
            let (glo, ghi) = gr
                .map(|(a, b)| (a.max(0.0), b.max(0.0)))
                .unwrap_or((0.0, 0.0));
            let norm = Norm::linear(glo, ghi);
            let map = colormap::blues();
            fill(&mut canvas, l, |k, _, _| {
                if f.interp(k, tris, &covered) < 0.5 {
                    NOT_COVERED
                } else if f.interp(k, tris, &contact) >= 0.5 {
                    CONTACT
                } else {
                    let g = f.interp(k, tris, &gap);
                    if g.is_finite() {
                        map.at(norm.t(g))
                    } else {
                        NOT_COVERED
                    }
                }
            });
            draw_boundary(&mut canvas, l);
            let m = level_mask(&canvas, l, mesh, &covered, 0.5, 1.6, true);
            canvas.composite(&m, [60, 60, 60], 1.0);
            outline(&mut canvas, OUTLINE, 2.4);
            bar_range = gr.map(|_| (glo, ghi));
            let unit = options.units.length_suffix();
            let bar = gr.map(|_| (map, &norm, (glo, ghi), format!("gap φ − u{unit}")));
            furniture(
                &mut canvas,
                l,
                &options.units,
                &titled("Lift-off", options),
                bar,
                &mut boxes,
            );
            let areas = Areas::of(data);
            let pct = |a: f64| {
                if areas.covered > 0.0 {
                    100.0 * a / areas.covered
                } else {
                    0.0
                }
            };
            let aunit = match &options.units.length {
                Some(u) if !u.trim().is_empty() => format!(" {}²", u.trim()),
                _ => String::new(),
            };
            let mut entries = vec![
                (
                    Swatch::Patch(CONTACT),
                    format!("contact (u ≥ φ) {:.1} %", pct(areas.contact)),
                ),
                (
                    Swatch::Patch(colormap::blues().at(0.6)),
                    format!("lift-off (u < φ) {:.1} %", pct(areas.liftoff)),
                ),
                (Swatch::Line(OUTLINE, 2.4), "contact zone outline".into()),
                (
                    Swatch::None,
                    format!(
                        "lift-off area {}{aunit}",
                        ticks::format_sig(areas.liftoff, 4)
                    ),
                ),
                (
                    Swatch::None,
                    format!(
                        "covered area {}{aunit}",
                        ticks::format_sig(areas.covered, 4)
                    ),
                ),
            ];
            if data.covered.iter().any(|&c| !c) {
                entries.insert(2, (Swatch::Patch(NOT_COVERED), "body cannot touch".into()));
                entries.insert(
                    4,
                    (Swatch::Dashed([60, 60, 60], 1.6), "edge of the body".into()),
                );
            }
            if gr.is_none() {
                entries.push((Swatch::None, "no lift-off".into()));
            } else {
                entries.extend(range_entries("gap", (glo, ghi)));
            }
            let y = if gr.is_some() { legend_y } else { BAR.y0 };
            axes::legend(&mut canvas, COLUMN.0, y, COLUMN.1, &entries, &mut boxes);
            legend = legend_labels(&entries);
        }
        PlotKind::Profile => unreachable!("the profile is not a map"),
    }
    Ok(Picture {
        kind,
        canvas,
        map: Some((l.transform, l.frame)),
        text_boxes: boxes,
        markers,
        range: bar_range,
        axes: None,
        legend,
    })
}

/// Colour of the contact zone on the lift-off map.
pub const CONTACT: Rgb = [244, 165, 96];
/// Colour of the area the body cannot touch on the lift-off map.
pub const NOT_COVERED: Rgb = [214, 214, 214];

/// Colour of the contact with the body below on the lift-off map.
pub const LOWER_CONTACT: Rgb = [180, 140, 220];

/// A legend entry for the outline of each body's contact zone (of the bodies the membrane
/// touches): `upper` for the contact with the obstacle, `lower` with the body below.
fn body_entries(
    data: &PlotData,
    low: &BodyData,
    upper: Swatch,
    lower: Swatch,
) -> Vec<(Swatch, String)> {
    let mut entries = Vec::new();
    if data.state.iter().any(|&s| s >= 0) {
        entries.push((upper, "contact with the obstacle".to_string()));
    }
    if low.state.iter().any(|&s| s >= 0) {
        entries.push((lower, "contact with the body below".to_string()));
    }
    entries
}

/// The deflection map's outline and hatching entries with a body below: each body's
/// outline named, the hatchings' labels naming the conditions that occur.
fn two_body_deflection_entries(data: &PlotData, low: &BodyData) -> Vec<(Swatch, String)> {
    let mut entries = body_entries(
        data,
        low,
        Swatch::Line(OUTLINE, DEFLECTION_OUTLINE_WIDTH),
        Swatch::Dashed(LOWER_OUTLINE, DEFLECTION_OUTLINE_WIDTH),
    );
    let either = |up: bool, down: bool, a: &str, b: &str| match (up, down) {
        (true, true) => format!("{a} or {b}"),
        (true, false) => a.to_string(),
        _ => b.to_string(),
    };
    let n = data.points.len();
    let pen_up = data.state.contains(&1);
    let pen_low = low.state.contains(&1);
    let touch_up = (0..n).any(|i| data.state[i] == 0 && !data.penetrating(i));
    let touch_low = (0..n).any(|i| low.state[i] == 0 && !data.penetrating(i));
    entries.push((
        Swatch::Hatch(true),
        format!(
            "penetrating ({})",
            either(pen_up, pen_low, "u > φ", "u < φ_low")
        ),
    ));
    entries.push((
        Swatch::Hatch(false),
        format!(
            "touching ({})",
            either(touch_up, touch_low, "u = φ", "u = φ_low")
        ),
    ));
    entries
}

/// The contact counts of each body that can touch the membrane, and of the vertices
/// squeezed between the two.
fn two_body_counts(data: &PlotData, low: &BodyData) -> Vec<String> {
    let count = |state: &[i8], s: i8| state.iter().filter(|&&x| x == s).count();
    let mut lines = Vec::new();
    if data.covered.iter().any(|&c| c) {
        lines.push(format!(
            "obstacle: {} penetrating, {} touching",
            count(data.state, 1),
            count(data.state, 0)
        ));
    }
    if low.covered.iter().any(|&c| c) {
        lines.push(format!(
            "body below: {} penetrating, {} touching",
            count(low.state, 1),
            count(low.state, 0)
        ));
    }
    let squeezed = (0..data.points.len())
        .filter(|&i| data.state[i] >= 0 && low.state[i] >= 0)
        .count();
    if squeezed > 0 {
        lines.push(format!("squeezed between both: {squeezed}"));
    }
    lines
}

/// Nodal areas |Qᵢ|/3 (as the library's contact area).
fn nodal_areas(data: &PlotData) -> Vec<f64> {
    let mut nodal = vec![0.0; data.points.len()];
    for t in data.triangles {
        let [a, b, c] = t.map(|v| data.points[v as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
        for &v in t {
            nodal[v as usize] += area / 3.0;
        }
    }
    nodal
}

/// The lift-off map of a membrane between two bodies: the contact with the obstacle and
/// the contact with the body below in their own colours (stripes of both where the
/// membrane is squeezed between them), and where the membrane is clear, the gap to the
/// nearer of the bodies that cover the vertex (φ − u to the obstacle in blues, u − φ_low
/// to the body below in greens, over one range, so that equal gaps are equally dark),
/// each with its colour bar. Returns the range of the gaps shown and the legend's labels.
fn liftoff_two_bodies(
    canvas: &mut Canvas,
    l: &MapLayout,
    data: &PlotData,
    low: &BodyData,
    options: &PlotOptions,
    boxes: &mut Vec<PixelRect>,
) -> (Option<(f64, f64)>, Vec<String>) {
    let n = data.points.len();
    let tris = data.triangles;
    let mesh = (tris, data.numbering);
    let f = &l.frags;
    let covered = indicator(n, |i| data.covered[i] || low.covered[i]);
    let up = indicator(n, |i| data.state[i] >= 0);
    let down = indicator(n, |i| low.state[i] >= 0);
    let gap = |cov: &[bool], g: &(dyn Fn(usize) -> f64 + Sync)| -> Vec<f64> {
        (0..n)
            .into_par_iter()
            .map(|i| if cov[i] { g(i) } else { f64::NAN })
            .collect()
    };
    let gap_up = gap(data.covered, &|i| data.phi[i] - data.u[i]);
    let gap_low = gap(low.covered, &|i| data.u[i] - low.phi[i]);
    // The body whose gap a vertex shows: the nearer of those that cover it (the obstacle
    // on a tie).
    let nearer_low = |i: usize| low.covered[i] && (!data.covered[i] || gap_low[i] < gap_up[i]);
    let shows_low = indicator(n, nearer_low);
    let clear = |i: usize| data.state[i] < 0 && low.state[i] < 0;
    let clamp = |r: Option<(f64, f64)>| r.map(|(a, b)| (a.max(0.0), b.max(0.0)));
    let gr_up = clamp(range(&gap_up, |i| {
        clear(i) && data.covered[i] && !nearer_low(i)
    }));
    let gr_low = clamp(range(&gap_low, |i| clear(i) && nearer_low(i)));
    let shown = gr_up
        .into_iter()
        .chain(gr_low)
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
    let (glo, ghi) = shown.unwrap_or((0.0, 0.0));
    let norm = Norm::linear(glo, ghi);
    let (map_up, map_low) = (colormap::blues(), colormap::greens());
    fill(canvas, l, |k, x, y| {
        if f.interp(k, tris, &covered) < 0.5 {
            return NOT_COVERED;
        }
        match (
            f.interp(k, tris, &up) >= 0.5,
            f.interp(k, tris, &down) >= 0.5,
        ) {
            (true, true) => stripe_color(x, y, CONTACT, LOWER_CONTACT),
            (true, false) => CONTACT,
            (false, true) => LOWER_CONTACT,
            (false, false) => {
                let above = || {
                    let g = f.interp(k, tris, &gap_up);
                    g.is_finite().then(|| map_up.at(norm.t(g)))
                };
                let below = || {
                    let g = f.interp(k, tris, &gap_low);
                    g.is_finite().then(|| map_low.at(norm.t(g)))
                };
                if f.interp(k, tris, &shows_low) >= 0.5 {
                    below().or_else(above)
                } else {
                    above().or_else(below)
                }
                .unwrap_or(NOT_COVERED)
            }
        }
    });
    draw_boundary(canvas, l);
    let some_uncovered = (0..n).any(|i| !(data.covered[i] || low.covered[i]));
    let m = level_mask(canvas, l, mesh, &covered, 0.5, 1.6, true);
    canvas.composite(&m, [60, 60, 60], 1.0);
    let m = level_mask(canvas, l, mesh, &up, 0.5, 2.4, false);
    canvas.composite(&m, OUTLINE, 1.0);
    let m = level_mask(canvas, l, mesh, &down, 0.5, 2.4, true);
    canvas.composite(&m, LOWER_OUTLINE, 1.0);
    furniture(
        canvas,
        l,
        &options.units,
        &titled("Lift-off", options),
        None,
        boxes,
    );
    let unit = options.units.length_suffix();
    let label_up = format!("gap φ − u{unit}");
    let label_low = format!("gap u − φ_low{unit}");
    let bars: Vec<(PixelRect, &Colormap, &String)> = match (gr_up, gr_low) {
        (Some(_), Some(_)) => vec![
            (BAR_TOP, map_up, &label_up),
            (BAR_BOTTOM, map_low, &label_low),
        ],
        (Some(_), None) => vec![(BAR, map_up, &label_up)],
        (None, Some(_)) => vec![(BAR, map_low, &label_low)],
        (None, None) => Vec::new(),
    };
    for &(rect, map, label) in &bars {
        axes::colorbar(canvas, rect, map, &norm, (glo, ghi), label, COLUMN.1, boxes);
    }
    // Areas, as shares of the area either body covers.
    let nodal = nodal_areas(data);
    let area = |keep: &dyn Fn(usize) -> bool| -> f64 {
        // (A fold from +0: an empty sum is 0, not −0.)
        (0..n).filter(|&i| keep(i)).fold(0.0, |a, i| a + nodal[i])
    };
    let cov_area = area(&|i| data.covered[i] || low.covered[i]);
    let pct = |a: f64| {
        if cov_area > 0.0 {
            100.0 * a / cov_area
        } else {
            0.0
        }
    };
    let contact_up = area(&|i| data.covered[i] && data.state[i] >= 0);
    let contact_low = area(&|i| low.covered[i] && low.state[i] >= 0);
    let squeezed = area(&|i| data.state[i] >= 0 && low.state[i] >= 0);
    let covered_clear = |i: usize| (data.covered[i] || low.covered[i]) && clear(i);
    let gap_area_up = area(&|i| covered_clear(i) && !nearer_low(i));
    let gap_area_low = area(&|i| covered_clear(i) && nearer_low(i));
    let aunit = match &options.units.length {
        Some(u) if !u.trim().is_empty() => format!(" {}²", u.trim()),
        _ => String::new(),
    };
    let (has_up, has_low) = (
        data.covered.iter().any(|&c| c),
        low.covered.iter().any(|&c| c),
    );
    let mut entries = Vec::new();
    if has_up {
        entries.push((
            Swatch::Patch(CONTACT),
            format!("obstacle: contact {:.1} %", pct(contact_up)),
        ));
    }
    if has_low {
        entries.push((
            Swatch::Patch(LOWER_CONTACT),
            format!("body below: contact {:.1} %", pct(contact_low)),
        ));
    }
    if squeezed > 0.0 {
        entries.push((
            Swatch::Stripes(CONTACT, LOWER_CONTACT),
            format!("both: squeezed {:.1} %", pct(squeezed)),
        ));
    }
    if gr_up.is_some() {
        entries.push((
            Swatch::Patch(map_up.at(0.6)),
            format!("obstacle: gap {:.1} %", pct(gap_area_up)),
        ));
    }
    if gr_low.is_some() {
        entries.push((
            Swatch::Patch(map_low.at(0.6)),
            format!("body below: gap {:.1} %", pct(gap_area_low)),
        ));
    }
    if some_uncovered {
        entries.push((Swatch::Patch(NOT_COVERED), "no body can touch".into()));
    }
    if contact_up > 0.0 {
        entries.push((Swatch::Line(OUTLINE, 2.4), "obstacle: contact edge".into()));
    }
    if contact_low > 0.0 {
        entries.push((
            Swatch::Dashed(LOWER_OUTLINE, 2.4),
            "body below: contact edge".into(),
        ));
    }
    if some_uncovered {
        entries.push((
            Swatch::Dashed([60, 60, 60], 1.6),
            "edge of the bodies".into(),
        ));
    }
    entries.push((
        Swatch::None,
        format!(
            "lift-off area {}{aunit}",
            ticks::format_sig(gap_area_up + gap_area_low, 4)
        ),
    ));
    entries.push((
        Swatch::None,
        format!("covered area {}{aunit}", ticks::format_sig(cov_area, 4)),
    ));
    for (r, name) in [(gr_up, "gap φ − u"), (gr_low, "gap u − φ_low")] {
        if let Some((_, hi)) = r {
            entries.push((
                Swatch::None,
                format!("{name} max {}", ticks::format_sig(hi, 5)),
            ));
        }
    }
    if bars.is_empty() {
        entries.push((Swatch::None, "no lift-off".into()));
    }
    let y = match bars.len() {
        0 => BAR.y0,
        1 => BAR.y1 + 60,
        _ => BAR_BOTTOM.y1 + 50,
    };
    axes::legend(canvas, COLUMN.0, y, COLUMN.1, &entries, boxes);
    (shown, legend_labels(&entries))
}

/// "N contact vertices (P penetrating, T touching)".
fn counts(data: &PlotData) -> String {
    let pen = data.state.iter().filter(|&&s| s == 1).count();
    let touch = data.state.iter().filter(|&&s| s == 0).count();
    format!("contact: {pen} penetrating, {touch} touching")
}

/// Nodal areas summed by class (|Qᵢ|/3 per vertex, as the library's contact area).
struct Areas {
    covered: f64,
    contact: f64,
    liftoff: f64,
}

impl Areas {
    fn of(data: &PlotData) -> Areas {
        let nodal = nodal_areas(data);
        let mut r = Areas {
            covered: 0.0,
            contact: 0.0,
            liftoff: 0.0,
        };
        for (i, a) in nodal.iter().enumerate() {
            if data.covered[i] {
                r.covered += a;
                if data.state[i] >= 0 {
                    r.contact += a;
                } else {
                    r.liftoff += a;
                }
            }
        }
        r
    }
}

/// `"<name>: <case>"`, or the name alone without a case title.
pub(crate) fn titled(name: &str, options: &PlotOptions) -> String {
    match &options.title {
        Some(t) if !t.is_empty() => format!("{name}: {t}"),
        _ => name.to_string(),
    }
}

/// Draws a colour map of any nodal field over a triangle mesh as a
/// [`MAP_WIDTH`] × [`MAP_HEIGHT`] PNG: smooth (P1-interpolated) viridis colours, labelled
/// contour lines, the mesh boundary, axes of equal scale and a colour bar over the data
/// range, titled `title`. For a quick look at a field the four standard pictures do not
/// show. Errors: `values` not one per point, a triangle referring to a missing point, no
/// finite value.
pub fn field_plot(
    points: &[[f64; 2]],
    triangles: &[[u32; 3]],
    values: &[f64],
    title: &str,
) -> Result<Canvas> {
    if values.len() != points.len() {
        return Err(Error::Data(format!(
            "field plot {}: {} values for {} points",
            title,
            values.len(),
            points.len()
        )));
    }
    if let Some((k, t)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= points.len()))
    {
        return Err(Error::Data(format!(
            "field plot {}: triangle {k} {t:?} refers to a missing point",
            title
        )));
    }
    let Some((lo, hi)) = range(values, |_| true) else {
        return Err(Error::Data(format!(
            "field plot {}: no finite value",
            title
        )));
    };
    if triangles.is_empty()
        || points
            .iter()
            .any(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::Data(format!(
            "field plot {}: the mesh has no triangle or a non-finite coordinate",
            title
        )));
    }
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        b = [
            b[0].min(p[0]),
            b[1].max(p[0]),
            b[2].min(p[1]),
            b[3].max(p[1]),
        ];
    }
    let (bx, by) = (
        crate::colormap::widen(b[0], b[1]),
        crate::colormap::widen(b[2], b[3]),
    );
    let l = MapLayout::of(points, triangles, [bx.0, bx.1, by.0, by.1]);
    let mut canvas = Canvas::new(MAP_WIDTH, MAP_HEIGHT);
    let mut boxes = Vec::new();
    let norm = Norm::linear(lo, hi);
    let map = colormap::viridis();
    let f = &l.frags;
    fill(&mut canvas, &l, |k, _, _| {
        map.at(norm.t(f.interp(k, triangles, values)))
    });
    draw_boundary(&mut canvas, &l);
    let labels = contours(&mut canvas, &l, (triangles, None), values, (lo, hi), 8, &[]);
    draw_labels(&mut canvas, &labels, &mut boxes);
    let units = Units::default();
    furniture(
        &mut canvas,
        &l,
        &units,
        title,
        Some((map, &norm, (lo, hi), "value".into())),
        &mut boxes,
    );
    let entries = range_entries("value", (lo, hi));
    axes::legend(
        &mut canvas,
        COLUMN.0,
        BAR.y1 + 60,
        COLUMN.1,
        &entries,
        &mut boxes,
    );
    Ok(canvas)
}

/// The mesh picture of an adaptive run (`mesh.png`): every edge of the mesh, the
/// boundary, and the outline of the contact zone (`contact`: per vertex, in contact with
/// the obstacle), titled `title`, with the vertex and triangle counts in the legend. With
/// a body below, `contact_low` (per vertex, in contact with it): each body's contact zone
/// lightly filled in its own colour and outlined (the body below's dashed), named.
pub fn mesh_plot(
    points: &[[f64; 2]],
    triangles: &[[u32; 3]],
    contact: &[bool],
    contact_low: Option<&[bool]>,
    title: &str,
    units: &Units,
) -> Result<Canvas> {
    if contact.len() != points.len()
        || contact_low.is_some_and(|c| c.len() != points.len())
        || triangles.is_empty()
        || points
            .iter()
            .any(|p| !(p[0].is_finite() && p[1].is_finite()))
        || triangles
            .iter()
            .any(|t| t.iter().any(|&v| v as usize >= points.len()))
    {
        return Err(Error::Data(format!(
            "mesh picture {}: {} contact flags, {} points, {} triangles (a triangle out of \
             range or a non-finite coordinate?)",
            title,
            contact.len(),
            points.len(),
            triangles.len()
        )));
    }
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        b = [
            b[0].min(p[0]),
            b[1].max(p[0]),
            b[2].min(p[1]),
            b[3].max(p[1]),
        ];
    }
    let (bx, by) = (
        crate::colormap::widen(b[0], b[1]),
        crate::colormap::widen(b[2], b[3]),
    );
    let l = MapLayout::of(points, triangles, [bx.0, bx.1, by.0, by.1]);
    let mut canvas = Canvas::new(MAP_WIDTH, MAP_HEIGHT);
    let mut boxes = Vec::new();
    // The contact zone, lightly filled, under the edges.
    let inside = indicator(points.len(), |v| contact[v]);
    let inside_low = contact_low.map(|c| indicator(points.len(), |v| c[v]));
    let f = &l.frags;
    const LIGHT_CONTACT: Rgb = [253, 226, 200];
    const LIGHT_LOWER: Rgb = [232, 220, 246];
    fill(&mut canvas, &l, |k, x, y| {
        let up = f.interp(k, triangles, &inside) > 0.5;
        let low = inside_low
            .as_ref()
            .is_some_and(|c| f.interp(k, triangles, c) > 0.5);
        match (up, low) {
            (true, true) => stripe_color(x, y, LIGHT_CONTACT, LIGHT_LOWER),
            (true, false) => LIGHT_CONTACT,
            (false, true) => LIGHT_LOWER,
            (false, false) => [255, 255, 255],
        }
    });
    // Every inside edge once (its two triangles run along it in opposite directions);
    // the boundary is drawn after.
    let mut edges = Coverage::new(canvas.width, canvas.height, l.frame);
    let width = (0.4 * l.vertex_spacing).clamp(0.25, 1.0);
    for t in triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            if a < b {
                edges.segment(l.pv[a as usize], l.pv[b as usize], width);
            }
        }
    }
    canvas.composite(&edges, [90, 90, 90], 0.85);
    draw_boundary(&mut canvas, &l);
    let outline = level_mask(&canvas, &l, (triangles, None), &inside, 0.5, 2.2, false);
    canvas.composite(&outline, OUTLINE, 1.0);
    if let Some(c) = &inside_low {
        let outline = level_mask(&canvas, &l, (triangles, None), c, 0.5, 2.2, true);
        canvas.composite(&outline, LOWER_OUTLINE, 1.0);
    }
    furniture(&mut canvas, &l, units, title, None, &mut boxes);
    let mut entries = vec![(Swatch::Line([90, 90, 90], 1.0), "mesh edges".to_string())];
    match contact_low {
        None => entries.push((
            Swatch::Line(OUTLINE, 2.2),
            "contact zone outline".to_string(),
        )),
        Some(low) => {
            if contact.iter().any(|&c| c) {
                entries.push((
                    Swatch::Line(OUTLINE, 2.2),
                    "contact with the obstacle".to_string(),
                ));
            }
            if low.iter().any(|&c| c) {
                entries.push((
                    Swatch::Dashed(LOWER_OUTLINE, 2.2),
                    "contact with the body below".to_string(),
                ));
            }
        }
    }
    entries.extend([
        (Swatch::None, format!("{} vertices", points.len())),
        (Swatch::None, format!("{} triangles", triangles.len())),
    ]);
    axes::legend(
        &mut canvas,
        COLUMN.0,
        BAR.y0 + 60,
        COLUMN.1,
        &entries,
        &mut boxes,
    );
    Ok(canvas)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BodyData;

    /// A 20 × 20 grid on the unit square (two triangles per cell).
    fn grid() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let m = 20u32;
        let points = (0..=m)
            .flat_map(|j| (0..=m).map(move |i| [i as f64 / m as f64, j as f64 / m as f64]))
            .collect();
        let v = |i: u32, j: u32| j * (m + 1) + i;
        let triangles = (0..m)
            .flat_map(|j| {
                (0..m).flat_map(move |i| {
                    [
                        [v(i, j), v(i + 1, j), v(i + 1, j + 1)],
                        [v(i, j), v(i + 1, j + 1), v(i, j + 1)],
                    ]
                })
            })
            .collect();
        (points, triangles)
    }

    #[test]
    fn the_body_below_is_validated_and_each_body_outlined_on_the_mesh() {
        let (points, triangles) = grid();
        let n = points.len();
        // u rises to the right: the obstacle touched on the right, the body below on the left.
        let u: Vec<f64> = points.iter().map(|p| p[0] - 0.5).collect();
        let phi = vec![0.3; n];
        let phi_low = vec![-0.3; n];
        let state: Vec<i8> = u.iter().map(|&u| if u > 0.3 { 1 } else { -1 }).collect();
        let state_low: Vec<i8> = u.iter().map(|&u| if u < -0.3 { 1 } else { -1 }).collect();
        let pressure = vec![0.0; n];
        let covered = vec![true; n];
        let lower = BodyData {
            phi: &phi_low,
            state: &state_low,
            pressure: &pressure,
            covered: &covered,
        };
        let data = PlotData {
            points: &points,
            triangles: &triangles,
            u: &u,
            phi: &phi,
            state: &state,
            pressure: &pressure,
            covered: &covered,
            lower: Some(lower),
            numbering: None,
        };
        data.validate().unwrap();
        let short = &state_low[1..];
        let e = PlotData {
            lower: Some(BodyData {
                state: short,
                ..lower
            }),
            ..data
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("state_low"), "{e}");
        let mut bad = state_low.clone();
        bad[3] = 2;
        let e = PlotData {
            lower: Some(BodyData {
                state: &bad,
                ..lower
            }),
            ..data
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("vertex 3 has state_low 2"), "{e}");
        // The mesh picture: each body's outline on its own side.
        let up: Vec<bool> = state.iter().map(|&s| s >= 0).collect();
        let low: Vec<bool> = state_low.iter().map(|&s| s >= 0).collect();
        let canvas = mesh_plot(
            &points,
            &triangles,
            &up,
            Some(&low),
            "two bodies",
            &Units::default(),
        )
        .unwrap();
        let l = MapLayout::of(&points, &triangles, [0.0, 1.0, 0.0, 1.0]);
        let mid = (l.frame.x0 + l.frame.x1) / 2;
        let (mut left, mut right) = ([0usize; 2], [0usize; 2]);
        for y in l.frame.y0..l.frame.y1 {
            for x in l.frame.x0..l.frame.x1 {
                let c = canvas.get(x as u32, y as u32);
                let side = if x < mid { &mut left } else { &mut right };
                side[0] += (c == OUTLINE) as usize;
                side[1] += (c == LOWER_OUTLINE) as usize;
            }
        }
        assert!(left[0] == 0 && left[1] > 20, "{left:?}");
        assert!(right[1] == 0 && right[0] > 20, "{right:?}");
        // The mesh picture without a body below has no dashed outline.
        let one = mesh_plot(
            &points,
            &triangles,
            &up,
            None,
            "one body",
            &Units::default(),
        )
        .unwrap();
        assert!(one.rgb.chunks(3).all(|c| c != LOWER_OUTLINE));
    }
}
