//! The three map pictures: deflection, contact pressure and lift-off.
//!
//! All three share one [`MapLayout`]: the world → pixel transform, the rasterised mesh and
//! its boundary, computed once. Each picture fills the frame pixel by pixel from the P1
//! interpolants of its fields, then draws the mesh boundary, contour lines, outlines
//! (level ½ of the P1 interpolant of a 0/1 indicator, so that every vertex of the set lies
//! inside its outline and every other vertex outside), labels, axes, colour bar and legend.

use crate::axes::{self, hatch_color, Axes, Swatch};
use crate::canvas::{Canvas, Coverage, PixelRect, Rgb, WHITE};
use crate::colormap::{self, Colormap, Norm};
use crate::raster::{self, Fragments, MapTransform, EMPTY};
use crate::text::{self, Anchor, Style};
use crate::ticks;
use crate::{Error, Result};
use crate::{PlotData, PlotKind, PlotOptions, Units, MAP_HEIGHT, MAP_WIDTH};
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
/// Left edge and width of the right-hand column (colour bar labels, legend).
const COLUMN: (i32, i32) = (1075, 215);
/// Contact outline colour (deflection and lift-off maps).
pub const OUTLINE: Rgb = [220, 20, 60];
/// Contact outline colour on the pressure map.
pub const PRESSURE_OUTLINE: Rgb = [0, 70, 160];
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
        MapLayout::of(data.points, data.triangles, data.bbox())
    }

    /// Fits the triangles (bounding box `bbox`, `[xmin, xmax, ymin, ymax]`) into the map
    /// area and rasterises them.
    pub fn of(points: &[[f64; 2]], triangles: &[[u32; 3]], bbox: [f64; 4]) -> MapLayout {
        let (transform, frame) = MapTransform::fit(bbox, MAP_AREA);
        let pv: Vec<[f64; 2]> = points.par_iter().map(|&p| transform.to_pixel(p)).collect();
        let frags = raster::rasterise(&pv, triangles, frame);
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
    /// The colour bar's range (the data range of the mapped field), if there is a bar; for
    /// the profile, the range of u and φ along the line.
    pub range: Option<(f64, f64)>,
    /// For the profile: its axes (arc length × value → pixels).
    pub axes: Option<Axes>,
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

/// The level line `values = level` as a coverage mask.
fn level_mask(
    canvas: &Canvas,
    l: &MapLayout,
    tris: &[[u32; 3]],
    values: &[f64],
    level: f64,
    width: f64,
    dashed: bool,
) -> Coverage {
    let segs = raster::level_segments(&l.pv, tris, values, level);
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
    tris: &[[u32; 3]],
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
    let segs = raster::level_sets(&l.pv, tris, values, &levels);
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
    let f = &l.frags;
    let contact = indicator(n, |i| data.state[i] >= 0);
    let outline = |canvas: &mut Canvas, color: Rgb, width: f64| {
        let m = level_mask(canvas, l, tris, &contact, 0.5, width, false);
        canvas.composite(&m, color, 1.0);
    };
    let legend_y = BAR.y1 + 60;
    let mut markers = false;
    let bar_range;
    match kind {
        PlotKind::Deflection => {
            let (lo, hi) = range(data.u, |_| true).unwrap_or((0.0, 0.0));
            bar_range = Some((lo, hi));
            let norm = Norm::linear(lo, hi);
            let map = colormap::viridis();
            let pen = indicator(n, |i| data.state[i] == 1);
            fill(&mut canvas, l, |k, x, y| {
                if f.interp(k, tris, &contact) >= 0.5 {
                    let slash = f.interp(k, tris, &pen) >= 0.5 * f.interp(k, tris, &contact);
                    if let Some(c) = hatch_color(x, y, slash) {
                        return c;
                    }
                }
                map.at(norm.t(f.interp(k, tris, data.u)))
            });
            draw_boundary(&mut canvas, l);
            let labels = contours(&mut canvas, l, tris, data.u, (lo, hi), 8, &[]);
            outline(&mut canvas, OUTLINE, 2.6);
            markers = l.markers();
            if markers {
                for (st, fillc, ring) in [(1i8, PEN_MARK, MARK_LIGHT), (0, MARK_LIGHT, MARK_DARK)] {
                    let mut outer = Coverage::new(canvas.width, canvas.height, l.frame);
                    let mut inner = Coverage::new(canvas.width, canvas.height, l.frame);
                    for i in (0..n).filter(|&i| data.state[i] == st) {
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
            let n_pen = data.state.iter().filter(|&&st| st == 1).count();
            let n_touch = data.state.iter().filter(|&&st| st == 0).count();
            let mut entries = vec![(
                Swatch::Line(OUTLINE, 2.6),
                "contact zone outline".to_string(),
            )];
            if n_pen > 0 {
                entries.push((Swatch::Hatch(true), "penetrating (u > φ)".into()));
            }
            if n_touch > 0 {
                entries.push((Swatch::Hatch(false), "touching (u = φ)".into()));
            }
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
            entries.push((Swatch::None, counts(data)));
            axes::legend(
                &mut canvas,
                COLUMN.0,
                legend_y,
                COLUMN.1,
                &entries,
                &mut boxes,
            );
        }
        PlotKind::Pressure => {
            let unit = options.units.pressure_suffix();
            let (field, map, norm, label): (Vec<f64>, &Colormap, Norm, String);
            match options.allowable_pressure {
                Some(a) => {
                    field = data.pressure.par_iter().map(|p| p / a).collect();
                    let (lo, hi) = range(&field, |_| true).unwrap_or((0.0, 0.0));
                    // The hue changes at the allowable (ratio 1).
                    map = colormap::ratio();
                    norm = Norm::centered(lo, hi, 1.0);
                    label = "pressure / allowable".into();
                }
                None => {
                    field = data.pressure.to_vec();
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
            let labels = contours(&mut canvas, l, tris, &field, (lo, hi), 6, &[]);
            outline(&mut canvas, PRESSURE_OUTLINE, 2.0);
            let mut entries = vec![(
                Swatch::Line(PRESSURE_OUTLINE, 2.0),
                "contact zone outline".to_string(),
            )];
            if let Some(a) = options.allowable_pressure {
                let m = level_mask(&canvas, l, tris, &field, 1.0, 3.0, false);
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
                let above = data.pressure.iter().filter(|&&p| p > a).count();
                entries.push((
                    Swatch::None,
                    if above == 0 {
                        "all below the allowable".to_string()
                    } else {
                        format!("{above} vertices above allowable")
                    },
                ));
                entries.extend(range_entries("ratio", (lo, hi)));
                let (plo, phi) = range(data.pressure, |_| true).unwrap_or((0.0, 0.0));
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
            let m = level_mask(&canvas, l, tris, &covered, 0.5, 1.6, true);
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
    })
}

/// Colour of the contact zone on the lift-off map.
pub const CONTACT: Rgb = [244, 165, 96];
/// Colour of the area the body cannot touch on the lift-off map.
pub const NOT_COVERED: Rgb = [214, 214, 214];

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
        let mut nodal = vec![0.0; data.points.len()];
        for t in data.triangles {
            let [a, b, c] = t.map(|v| data.points[v as usize]);
            let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            for &v in t {
                nodal[v as usize] += area / 3.0;
            }
        }
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
    let labels = contours(&mut canvas, &l, triangles, values, (lo, hi), 8, &[]);
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
/// a body), titled `title`, with the vertex and triangle counts in the legend.
pub fn mesh_plot(
    points: &[[f64; 2]],
    triangles: &[[u32; 3]],
    contact: &[bool],
    title: &str,
    units: &Units,
) -> Result<Canvas> {
    if contact.len() != points.len()
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
    let f = &l.frags;
    fill(&mut canvas, &l, |k, _, _| {
        if f.interp(k, triangles, &inside) > 0.5 {
            [253, 226, 200]
        } else {
            [255, 255, 255]
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
    let outline = level_mask(&canvas, &l, triangles, &inside, 0.5, 2.2, false);
    canvas.composite(&outline, OUTLINE, 1.0);
    furniture(&mut canvas, &l, units, title, None, &mut boxes);
    let entries = vec![
        (Swatch::Line([90, 90, 90], 1.0), "mesh edges".to_string()),
        (
            Swatch::Line(OUTLINE, 2.2),
            "contact zone outline".to_string(),
        ),
        (Swatch::None, format!("{} vertices", points.len())),
        (Swatch::None, format!("{} triangles", triangles.len())),
    ];
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
