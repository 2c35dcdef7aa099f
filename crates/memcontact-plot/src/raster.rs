//! The rasteriser: which triangle covers each pixel centre, and where (barycentric
//! coordinates), so that any nodal (P1) field can be read at every pixel by interpolation.
//!
//! Triangles are binned into bands of rows and the bands are filled in parallel, each by
//! one thread, with edge functions over the triangle's bounding box. An edge's function
//! is evaluated from its lower-numbered vertex in both triangles that share it, and a
//! pixel centre exactly on an edge belongs to the triangle on the edge's `+x` side (`+y`
//! for a horizontal edge): every pixel centre inside the mesh is covered by exactly one
//! triangle, so the result does not depend on the order of the triangles or on the number
//! of threads. Pixels outside the mesh (holes included) stay empty.
//!
//! Also here: marching triangles (the segments of a level line of a P1 field) and the
//! boundary edges of a triangle list.

use crate::canvas::PixelRect;
use crate::UserNumbering;
use rayon::prelude::*;

/// Rows per band of the parallel fill.
const BAND: usize = 8;
/// Marks a pixel that no triangle covers.
pub const EMPTY: u32 = u32::MAX;

/// The world ↔ pixel mapping of a map picture: equal scales on both axes, `y` up.
///
/// Pixel coordinates are continuous: pixel `(i, j)` (column, row from the top) covers
/// `[i, i + 1) × [j, j + 1)` and its centre is `(i + 0.5, j + 0.5)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapTransform {
    /// World x at the frame's left edge.
    pub x0: f64,
    /// World y at the frame's bottom edge.
    pub y0: f64,
    /// Pixels per unit length.
    pub scale: f64,
    /// Pixel x of the frame's left edge.
    pub left: f64,
    /// Pixel y of the frame's bottom edge.
    pub bottom: f64,
}

impl MapTransform {
    /// The transform that shows the box `[xmin, xmax] × [ymin, ymax]`, padded by 3 % of its
    /// larger side, as large as fits in `area` with equal scales, centred; returns it with
    /// the frame (the pixels of the padded box).
    pub fn fit(bbox: [f64; 4], area: PixelRect) -> (MapTransform, PixelRect) {
        let [xmin, xmax, ymin, ymax] = bbox;
        let pad = 0.03 * (xmax - xmin).max(ymax - ymin);
        let (x0, x1, y0, y1) = (xmin - pad, xmax + pad, ymin - pad, ymax + pad);
        let scale = (area.width() as f64 / (x1 - x0)).min(area.height() as f64 / (y1 - y0));
        let w = ((x1 - x0) * scale).floor() as i32;
        let h = ((y1 - y0) * scale).floor() as i32;
        let left = area.x0 + (area.width() - w) / 2;
        let top = area.y0 + (area.height() - h) / 2;
        let frame = PixelRect::new(left, top, w, h);
        (
            MapTransform {
                x0,
                y0,
                scale,
                left: left as f64,
                bottom: (top + h) as f64,
            },
            frame,
        )
    }

    /// The pixel coordinates of the world point `p`.
    #[inline]
    pub fn to_pixel(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.left + (p[0] - self.x0) * self.scale,
            self.bottom - (p[1] - self.y0) * self.scale,
        ]
    }

    /// The pixel (column, row) that contains the world point `p`.
    pub fn pixel_of(&self, p: [f64; 2]) -> (i32, i32) {
        let q = self.to_pixel(p);
        (q[0].floor() as i32, q[1].floor() as i32)
    }

    /// The world point at pixel coordinates `q`.
    pub fn to_world(&self, q: [f64; 2]) -> [f64; 2] {
        [
            self.x0 + (q[0] - self.left) / self.scale,
            self.y0 + (self.bottom - q[1]) / self.scale,
        ]
    }
}

/// For every pixel of a rectangle: the triangle covering its centre ([`EMPTY`] if none)
/// and the barycentric coordinates `(λ₁, λ₂)` of the centre in it (`λ₀ = 1 − λ₁ − λ₂`).
#[derive(Debug, Clone)]
pub struct Fragments {
    /// The rasterised rectangle.
    pub rect: PixelRect,
    /// Triangle index per pixel, row by row.
    pub tri: Vec<u32>,
    /// Barycentric coordinates of the second and third vertex, per pixel.
    pub bary: Vec<[f32; 2]>,
}

impl Fragments {
    /// Index into [`Fragments::tri`] of the canvas pixel `(x, y)`, if inside the rectangle.
    #[inline]
    pub fn index(&self, x: i32, y: i32) -> Option<usize> {
        self.rect.contains(x, y).then(|| {
            (y - self.rect.y0) as usize * self.rect.width() as usize + (x - self.rect.x0) as usize
        })
    }

    /// The P1 interpolant of `values` at fragment `i` (NaN where no triangle covers it).
    #[inline]
    pub fn interp(&self, i: usize, triangles: &[[u32; 3]], values: &[f64]) -> f64 {
        let t = self.tri[i];
        if t == EMPTY {
            return f64::NAN;
        }
        let [a, b, c] = triangles[t as usize];
        let [l1, l2] = self.bary[i];
        let (l1, l2) = (l1 as f64, l2 as f64);
        (1.0 - l1 - l2) * values[a as usize] + l1 * values[b as usize] + l2 * values[c as usize]
    }

    /// Number of covered pixels.
    pub fn covered(&self) -> usize {
        self.tri.par_iter().filter(|&&t| t != EMPTY).count()
    }
}

/// The edge function of the directed edge `a → b` at `p`, evaluated from the end with the
/// lower user number (see [`UserNumbering`]) so that both triangles of a shared edge get
/// exactly opposite values.
#[inline]
fn edge(pv: &[[f64; 2]], a: u32, b: u32, p: [f64; 2], numbering: Option<UserNumbering>) -> f64 {
    EdgeFn::new(pv, a, b, numbering).at(p)
}

/// An edge function with its base point and direction taken once per triangle.
#[derive(Clone, Copy)]
struct EdgeFn {
    /// The end with the lower user number.
    base: [f64; 2],
    /// From that end to the other.
    d: [f64; 2],
    /// +1 when the base is the edge's start, −1 when it is its end.
    sign: f64,
}

impl EdgeFn {
    #[inline]
    fn new(pv: &[[f64; 2]], a: u32, b: u32, numbering: Option<UserNumbering>) -> EdgeFn {
        let lower = UserNumbering::vertex(numbering, a) < UserNumbering::vertex(numbering, b);
        let (i, j, sign) = if lower { (a, b, 1.0) } else { (b, a, -1.0) };
        let (pi, pj) = (pv[i as usize], pv[j as usize]);
        EdgeFn {
            base: pi,
            d: [pj[0] - pi[0], pj[1] - pi[1]],
            sign,
        }
    }

    #[inline]
    fn at(&self, p: [f64; 2]) -> f64 {
        self.sign * (self.d[0] * (p[1] - self.base[1]) - self.d[1] * (p[0] - self.base[0]))
    }
}

/// True when a point exactly on the edge `a → b` belongs to the triangle on the edge's
/// left (`e > 0` side): the owner is the side towards `+x`, or `+y` for a horizontal edge.
#[inline]
fn left_owns(pv: &[[f64; 2]], a: u32, b: u32) -> bool {
    let (pa, pb) = (pv[a as usize], pv[b as usize]);
    let d = [pb[0] - pa[0], pb[1] - pa[1]];
    // left normal (−d.y, d.x)
    -d[1] > 0.0 || (d[1] == 0.0 && d[0] > 0.0)
}

/// Rasterises `triangles` (vertices at pixel coordinates `pv`) into `rect`; with a
/// `numbering`, ties are decided by the user's numbers (a pixel centre covered by two
/// overlapping triangles goes to the one the user numbered last), so the result is the
/// same as for the mesh in the user's numbering.
pub fn rasterise(
    pv: &[[f64; 2]],
    triangles: &[[u32; 3]],
    rect: PixelRect,
    numbering: Option<UserNumbering>,
) -> Fragments {
    let w = rect.width().max(0) as usize;
    let h = rect.height().max(0) as usize;
    let mut tri = vec![EMPTY; w * h];
    let mut bary = vec![[0f32; 2]; w * h];
    if w == 0 || h == 0 {
        return Fragments { rect, tri, bary };
    }
    let n_bands = h.div_ceil(BAND);
    // Rows (relative to rect) of the pixel centres each triangle may cover.
    let rows: Vec<(u32, u32)> = triangles
        .par_iter()
        .map(|t| {
            let ys = t.map(|v| pv[v as usize][1]);
            let xs = t.map(|v| pv[v as usize][0]);
            let (ymin, ymax) = (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
            let (xmin, xmax) = (xs[0].min(xs[1]).min(xs[2]), xs[0].max(xs[1]).max(xs[2]));
            let j0 = ((ymin - 0.5).ceil() as i64).max(rect.y0 as i64);
            let j1 = ((ymax - 0.5).floor() as i64).min(rect.y1 as i64 - 1);
            let i0 = ((xmin - 0.5).ceil() as i64).max(rect.x0 as i64);
            let i1 = ((xmax - 0.5).floor() as i64).min(rect.x1 as i64 - 1);
            if j0 > j1 || i0 > i1 || !(ymin.is_finite() && xmin.is_finite()) {
                (u32::MAX, 0)
            } else {
                ((j0 - rect.y0 as i64) as u32, (j1 - rect.y0 as i64) as u32)
            }
        })
        .collect();
    // Counting sort of the triangles into bands (in triangle order within a band).
    let mut start = vec![0u32; n_bands + 1];
    for &(j0, j1) in &rows {
        if j0 != u32::MAX {
            for b in j0 as usize / BAND..=j1 as usize / BAND {
                start[b + 1] += 1;
            }
        }
    }
    for b in 0..n_bands {
        start[b + 1] += start[b];
    }
    let mut fill = start.clone();
    let mut binned = vec![0u32; start[n_bands] as usize];
    for (t, &(j0, j1)) in rows.iter().enumerate() {
        if j0 != u32::MAX {
            for b in j0 as usize / BAND..=j1 as usize / BAND {
                binned[fill[b] as usize] = t as u32;
                fill[b] += 1;
            }
        }
    }
    tri.par_chunks_mut(BAND * w)
        .zip(bary.par_chunks_mut(BAND * w))
        .enumerate()
        .for_each(|(b, (tri, bary))| {
            let band_j0 = (b * BAND) as u32;
            let band_j1 = band_j0 + (tri.len() / w) as u32 - 1;
            for &t in &binned[start[b] as usize..start[b + 1] as usize] {
                let [v0, v1, v2] = triangles[t as usize];
                let (p0, p1, p2) = (pv[v0 as usize], pv[v1 as usize], pv[v2 as usize]);
                let area = edge(pv, v0, v1, p2, numbering);
                if area == 0.0 || !area.is_finite() {
                    continue;
                }
                let (j0, j1) = rows[t as usize];
                let (j0, j1) = (j0.max(band_j0), j1.min(band_j1));
                let xmin = p0[0].min(p1[0]).min(p2[0]);
                let xmax = p0[0].max(p1[0]).max(p2[0]);
                let i0 = ((xmin - 0.5).ceil() as i64).max(rect.x0 as i64) as i32;
                let i1 = ((xmax - 0.5).floor() as i64).min(rect.x1 as i64 - 1) as i32;
                // Which side of each edge is inside, and whether that side owns the edge.
                let sign = area.signum();
                let own = [
                    left_owns(pv, v1, v2) == (sign > 0.0),
                    left_owns(pv, v2, v0) == (sign > 0.0),
                    left_owns(pv, v0, v1) == (sign > 0.0),
                ];
                let f = [
                    EdgeFn::new(pv, v1, v2, numbering),
                    EdgeFn::new(pv, v2, v0, numbering),
                    EdgeFn::new(pv, v0, v1, numbering),
                ];
                let user_t = UserNumbering::triangle(numbering, t);
                for j in j0..=j1 {
                    let y = rect.y0 as f64 + j as f64 + 0.5;
                    let row = (j - band_j0) as usize * w;
                    for i in i0..=i1 {
                        let p = [i as f64 + 0.5, y];
                        let e0 = sign * f[0].at(p);
                        let e1 = sign * f[1].at(p);
                        let e2 = sign * f[2].at(p);
                        let inside = |e: f64, o: bool| e > 0.0 || (e == 0.0 && o);
                        if inside(e0, own[0]) && inside(e1, own[1]) && inside(e2, own[2]) {
                            let k = row + (i - rect.x0) as usize;
                            // Of overlapping triangles, the one the user numbered last
                            // (in the user's numbering, the last drawn).
                            if numbering.is_some()
                                && tri[k] != EMPTY
                                && UserNumbering::triangle(numbering, tri[k]) > user_t
                            {
                                continue;
                            }
                            let a = area.abs();
                            tri[k] = t;
                            bary[k] = [(e1 / a) as f32, (e2 / a) as f32];
                        }
                    }
                }
            }
        });
    Fragments { rect, tri, bary }
}

/// The segments (pixel coordinates) of the level line `values = level` of the P1 field
/// `values` (marching triangles: a vertex is "above" when its value is ≥ the level).
/// Triangles with a non-finite value are skipped. Crossing points are computed from the
/// edge's end with the lower (user) number, so neighbouring segments meet exactly; the
/// segments come in the user's triangle order.
pub fn level_segments(
    pv: &[[f64; 2]],
    triangles: &[[u32; 3]],
    values: &[f64],
    level: f64,
    numbering: Option<UserNumbering>,
) -> Vec<[[f64; 2]; 2]> {
    level_sets(pv, triangles, values, &[level], numbering)
        .pop()
        .unwrap_or_default()
}

/// A level line's segment in a triangle, with the user's number of the triangle.
type NumberedSegment = (u32, [[f64; 2]; 2]);

/// [`level_segments`] for several levels in one pass over the triangles: one list of
/// segments per level.
pub fn level_sets(
    pv: &[[f64; 2]],
    triangles: &[[u32; 3]],
    values: &[f64],
    levels: &[f64],
    numbering: Option<UserNumbering>,
) -> Vec<Vec<[[f64; 2]; 2]>> {
    let user = |v: u32| UserNumbering::vertex(numbering, v);
    /// Triangles per task.
    const CHUNK: usize = 1 << 15;
    let chunks: Vec<Vec<Vec<NumberedSegment>>> = triangles
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut out = vec![Vec::new(); levels.len()];
            for (i, t) in chunk.iter().enumerate() {
                let f = t.map(|v| values[v as usize]);
                if !f.iter().all(|x| x.is_finite()) {
                    continue;
                }
                let lo = f[0].min(f[1]).min(f[2]);
                let hi = f[0].max(f[1]).max(f[2]);
                for (k, &level) in levels.iter().enumerate() {
                    // Mixed iff some vertex is below and some at or above.
                    if !(lo < level && hi >= level) {
                        continue;
                    }
                    let above = f.map(|x| x >= level);
                    let mut pts = [[0.0; 2]; 2];
                    let mut n = 0;
                    for e in 0..3 {
                        if above[e] != above[(e + 1) % 3] && n < 2 {
                            let (a, b) = (t[e], t[(e + 1) % 3]);
                            let (a, b) = if user(a) < user(b) { (a, b) } else { (b, a) };
                            let (fa, fb) = (values[a as usize], values[b as usize]);
                            let s = (level - fa) / (fb - fa);
                            let (pa, pb) = (pv[a as usize], pv[b as usize]);
                            pts[n] = [pa[0] + s * (pb[0] - pa[0]), pa[1] + s * (pb[1] - pa[1])];
                            n += 1;
                        }
                    }
                    let k_t = (c * CHUNK + i) as u32;
                    out[k].push((UserNumbering::triangle(numbering, k_t), pts));
                }
            }
            out
        })
        .collect();
    (0..levels.len())
        .map(|k| {
            let mut segs: Vec<NumberedSegment> =
                chunks.iter().flat_map(|c| c[k].iter().copied()).collect();
            // In the user's triangle order (each triangle gives one segment per level).
            if numbering.is_some() {
                segs.sort_unstable_by_key(|s| s.0);
            }
            segs.into_iter().map(|s| s.1).collect()
        })
        .collect()
}

/// Chains segments that share end points (exactly, as [`level_segments`] makes them) into
/// polylines, in a deterministic order.
pub fn chain(segs: &[[[f64; 2]; 2]]) -> Vec<Vec<[f64; 2]>> {
    use std::collections::HashMap;
    let key = |p: [f64; 2]| (p[0].to_bits(), p[1].to_bits());
    let mut at: HashMap<(u64, u64), Vec<usize>> = HashMap::with_capacity(2 * segs.len());
    for (i, s) in segs.iter().enumerate() {
        at.entry(key(s[0])).or_default().push(i);
        at.entry(key(s[1])).or_default().push(i);
    }
    let mut used = vec![false; segs.len()];
    let mut out = Vec::new();
    for i in 0..segs.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut line = std::collections::VecDeque::from(vec![segs[i][0], segs[i][1]]);
        // Extend forwards from the last point, then backwards from the first.
        for dir in 0..2 {
            loop {
                let end = if dir == 0 {
                    *line.back().unwrap_or(&[0.0; 2])
                } else {
                    line[0]
                };
                let next = at
                    .get(&key(end))
                    .and_then(|v| v.iter().copied().find(|&j| !used[j]));
                let Some(j) = next else { break };
                used[j] = true;
                let s = segs[j];
                let p = if key(s[0]) == key(end) { s[1] } else { s[0] };
                if dir == 0 {
                    line.push_back(p);
                } else {
                    line.push_front(p);
                }
            }
        }
        out.push(line.into_iter().collect());
    }
    out
}

/// The boundary edges of a triangle list (edges of exactly one triangle), in triangle
/// order: the outer boundary and the holes.
///
/// Each vertex lists the far ends of the edges its triangles leave it by (`a → b` for the
/// triangle edges in their own orientation); `a → b` is interior when `b → a` is listed
/// at `b` (the neighbour, consistently oriented) or `a → b` twice at `a` (a neighbour of
/// the opposite orientation).
pub fn boundary_edges(n_vertices: usize, triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut start = vec![0u32; n_vertices + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n_vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut next = vec![0u32; start[n_vertices] as usize];
    for t in triangles {
        for e in 0..3 {
            let a = t[e] as usize;
            next[fill[a] as usize] = t[(e + 1) % 3];
            fill[a] += 1;
        }
    }
    let out = |v: u32| &next[start[v as usize] as usize..start[v as usize + 1] as usize];
    let chunks: Vec<Vec<[u32; 2]>> = triangles
        .par_chunks(1 << 15)
        .map(|chunk| {
            let mut found = Vec::new();
            for t in chunk {
                for e in 0..3 {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    let interior =
                        out(b).contains(&a) || out(a).iter().filter(|&&x| x == b).count() > 1;
                    if !interior {
                        found.push([a, b]);
                    }
                }
            }
            found
        })
        .collect();
    chunks.concat()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The n × n grid of the unit square, two triangles per cell.
    fn grid(n: usize) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let m = n + 1;
        let pts = (0..m * m)
            .map(|k| [(k % m) as f64 / n as f64, (k / m) as f64 / n as f64])
            .collect();
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = (j * m + i) as u32;
                let (b, c, d) = (a + 1, a + m as u32 + 1, a + m as u32);
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        (pts, tris)
    }

    #[test]
    fn every_pixel_centre_is_covered_once_and_interpolation_is_exact() {
        // A grid whose vertices fall exactly on pixel centres and edges: ties everywhere.
        let (pts, tris) = grid(8);
        let rect = PixelRect::new(0, 0, 64, 64);
        let pv: Vec<[f64; 2]> = pts
            .iter()
            .map(|p| [0.5 + 62.0 * p[0], 63.5 - 62.0 * p[1]])
            .collect();
        let f = rasterise(&pv, &tris, rect, None);
        // Pixels whose centres lie inside the closed square [0.5, 62.5]²: covered once.
        for y in 0..64 {
            for x in 0..64 {
                let i = f.index(x, y).unwrap();
                let inside = (0..=62).contains(&x) && (1..=63).contains(&y);
                if (1..=61).contains(&x) && (2..=62).contains(&y) {
                    assert_ne!(f.tri[i], EMPTY, "({x}, {y}) left empty");
                }
                if !inside {
                    assert_eq!(f.tri[i], EMPTY, "({x}, {y}) outside but covered");
                }
            }
        }
        // Count coverage independently: each interior pixel centre is claimed by exactly
        // one triangle when each triangle is rasterised alone.
        let mut count = vec![0u8; 64 * 64];
        for t in 0..tris.len() {
            let g = rasterise(&pv, &tris[t..t + 1], rect, None);
            for (c, &k) in count.iter_mut().zip(&g.tri) {
                *c += (k != EMPTY) as u8;
            }
        }
        for y in 2..=62 {
            for x in 1..=61 {
                assert_eq!(count[(y * 64 + x) as usize], 1, "({x}, {y})");
            }
        }
        // A linear field is reproduced exactly.
        let u: Vec<f64> = pts.iter().map(|p| 2.0 * p[0] - 3.0 * p[1] + 0.5).collect();
        for y in 5..60 {
            for x in 5..60 {
                let i = f.index(x, y).unwrap();
                let px = (x as f64 + 0.5 - 0.5) / 62.0;
                let py = (63.5 - (y as f64 + 0.5)) / 62.0;
                let want = 2.0 * px - 3.0 * py + 0.5;
                assert!((f.interp(i, &tris, &u) - want).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn the_result_does_not_depend_on_triangle_order_or_threads() {
        let (pts, tris) = grid(37);
        let t = MapTransform::fit([0.0, 1.0, 0.0, 1.0], PixelRect::new(10, 10, 300, 200)).0;
        let pv: Vec<[f64; 2]> = pts.iter().map(|&p| t.to_pixel(p)).collect();
        let rect = PixelRect::new(0, 0, 320, 220);
        let a = rasterise(&pv, &tris, rect, None);
        let mut rev = tris.clone();
        rev.reverse();
        let b = rasterise(&pv, &rev, rect, None);
        let n = tris.len() as u32;
        for (x, y) in a.tri.iter().zip(&b.tri) {
            assert_eq!(*x == EMPTY, *y == EMPTY);
            if *x != EMPTY {
                assert_eq!(*x, n - 1 - *y);
            }
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let c = pool.install(|| rasterise(&pv, &tris, rect, None));
        assert_eq!(a.tri, c.tri);
        assert_eq!(a.bary, c.bary);
    }

    #[test]
    fn transform_round_trips_and_keeps_equal_scales() {
        let (t, frame) =
            MapTransform::fit([0.0, 12.0, 0.0, 8.0], PixelRect::new(100, 50, 900, 800));
        assert!(frame.width() <= 900 && frame.height() <= 800);
        let p = t.to_pixel([3.0, 2.0]);
        let q = t.to_world(p);
        assert!((q[0] - 3.0).abs() < 1e-12 && (q[1] - 2.0).abs() < 1e-12);
        let a = t.to_pixel([0.0, 0.0]);
        let b = t.to_pixel([1.0, 1.0]);
        assert!(
            ((b[0] - a[0]) + (b[1] - a[1])).abs() < 1e-9,
            "equal scales, y up"
        );
    }

    #[test]
    fn level_lines_and_boundary() {
        let (pts, tris) = grid(10);
        let u: Vec<f64> = pts.iter().map(|p| p[0]).collect();
        let segs = level_segments(&pts, &tris, &u, 0.55, None);
        assert!(!segs.is_empty());
        for s in &segs {
            for p in s {
                assert!((p[0] - 0.55).abs() < 1e-12);
            }
        }
        let b = boundary_edges(pts.len(), &tris);
        assert_eq!(b.len(), 40);
    }
}
