//! Newest-vertex bisection (docs/theory.md#refinement): local refinement that keeps the
//! mesh conforming, nested and shape-regular, for the adaptive loop.
//!
//! **The refinement edge is stored in the vertex order.** Triangle `[a, b, c]`
//! (counter-clockwise, as everywhere) has refinement edge `(a, b)`, and `c` is its newest
//! vertex. Bisection puts the new vertex `m` at the middle of `(a, b)` and emits the
//! children `[c, a, m]` and `[b, c, m]`: counter-clockwise again, `m` their newest vertex,
//! their refinement edges the parent's other two edges. Meshes produced by [`bisect`] are
//! therefore labelled for the next call; nothing else has to be kept between calls.
//!
//! **What keeps the labels and what does not.** [`Mesh::new`] keeps a counter-clockwise
//! triangle as given (it swaps two vertices only when *every* triangle is clockwise, which a
//! labelled mesh is not); [`super::reorder`] renumbers vertices and triangles but keeps
//! the vertex order inside each triangle; boundary regions and region tags do not depend
//! on it. Uniform refinement ([`super::refine::refine_uniform`]) and the generators
//! (structured rectangles, Delaunay meshes, Gmsh files) do **not** produce labelled
//! meshes (the rectangles start with a leg, not the hypotenuse): a caller labels the start
//! mesh of an adaptive run once with
//! [`label_longest_edge`], and must not label again between bisections (relabelling a
//! bisected mesh throws away the newest-vertex structure that bounds the shapes).
//!
//! **Closure.** [`bisect`] works on edges: the refinement edge of every marked triangle is
//! marked, and then, until nothing changes, the refinement edge of every triangle that has
//! a marked edge (Binev–Dahmen–DeVore's completion, the non-recursive form of Mitchell's
//! recursive bisection). Each marked edge is then split once, in both its triangles, so the
//! result is conforming whatever the labels; each triangle is cut into 1 (unchanged), 2, 3
//! or 4 triangles by at most three bisections. Whatever the start labels, every triangle
//! ever produced is similar to one of at most four per start triangle (Sewell, Mitchell),
//! so the angles stay bounded below. The longest-edge labelling makes two neighbours whose
//! longest edge is their common edge a compatible pair (bisected together, no closure
//! beyond them) and keeps the classes close to the start shapes. Everything is linear in the mesh size: one edge matching (a counting sort by the smaller
//! endpoint), a work list for the closure, one pass over the triangles.

use crate::mesh::refine::Refinement;
use crate::mesh::{BoundaryRegions, Circle, Mesh, Point};
use crate::sparse::{first_where, group_by_key};
use crate::{Error, Result};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// No twin (a boundary half-edge), or an edge that is not split.
const NONE: u32 = u32::MAX;

/// An edge marked for splitting whose new vertex is not numbered yet.
const SPLIT: u32 = u32::MAX - 1;

/// The corner after corner `e` of a triangle.
const NEXT: [usize; 3] = [1, 2, 0];

/// Squared distance (symmetric to the bit: `(p - q)² = (q - p)²` in floating point, so an
/// edge measures the same from both its triangles).
#[inline]
fn dist2(p: Point, q: Point) -> f64 {
    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
}

/// Triangle `t` rotated so that its longest edge comes first (its refinement edge);
/// equal lengths are ordered by the edge's vertex indices (smaller endpoint, then larger,
/// the larger wins). This is a total order on the edges of the mesh, the same seen from
/// both triangles of an edge: two neighbours whose longest edge is their common edge both
/// choose it (a compatible pair, bisected together), and the closure's chains of
/// neighbours climb a total order.
pub fn longest_edge_first(points: &[Point], t: [u32; 3]) -> [u32; 3] {
    let key = |e: usize| {
        let (a, b) = (t[e], t[NEXT[e]]);
        (
            dist2(points[a as usize], points[b as usize]),
            a.min(b),
            a.max(b),
        )
    };
    let (k0, k1, k2) = (key(0), key(1), key(2));
    let bigger = |x: (f64, u32, u32), y: (f64, u32, u32)| {
        x.0 > y.0 || (x.0 == y.0 && (x.1, x.2) > (y.1, y.2))
    };
    let e = if bigger(k1, k0) {
        if bigger(k2, k1) {
            2
        } else {
            1
        }
    } else if bigger(k2, k0) {
        2
    } else {
        0
    };
    [t[e], t[NEXT[e]], t[NEXT[NEXT[e]]]]
}

/// `mesh` with every triangle rotated so that its refinement edge (the first two vertices)
/// is its longest edge ([`longest_edge_first`]): the labelling of the start mesh of an
/// adaptive run (docs/theory.md#refinement). Orientation, triangle order, regions, boundary
/// regions, curve and numbering are kept (a rotation changes no triangle's index and no
/// vertex).
pub fn label_longest_edge(mesh: &Mesh) -> Mesh {
    let triangles = mesh
        .triangles
        .par_iter()
        .with_min_len(8192)
        .map(|&t| longest_edge_first(&mesh.points, t))
        .collect();
    Mesh {
        triangles,
        ..mesh.clone()
    }
}

/// Whether every triangle's refinement edge is its longest edge as
/// [`longest_edge_first`] chooses it (the state [`label_longest_edge`] leaves; a mesh
/// after [`bisect`] usually is not, and need not be).
#[cfg(test)]
pub fn is_longest_edge_labelled(mesh: &Mesh) -> bool {
    mesh.triangles
        .par_iter()
        .with_min_len(8192)
        .all(|&t| longest_edge_first(&mesh.points, t) == t)
}

/// The result of [`bisect`]: the fine mesh and how it sits in the coarse one.
#[derive(Debug, Clone)]
pub struct Bisection {
    /// The refined mesh, conforming and counter-clockwise, labelled for the next bisection.
    /// Coarse vertices keep their indices; new vertices follow, numbered in the order of
    /// the coarse triangle (and corner) that first holds their edge. `numbering` is `None`:
    /// the fine mesh is a new mesh in its own numbering (renumber it for locality as any
    /// other mesh, see [`super::reorder`]).
    pub mesh: Mesh,
    /// Fine vertex `v` from the coarse vertices: `[v, v]` for a coarse vertex, the coarse
    /// edge's ends for a new one (its midpoint, or the projection of the midpoint onto the
    /// curve); [`Refinement::prolongate`] is the P1 interpolation of coarse functions,
    /// exact on nested meshes with straight edges, as for uniform refinement.
    pub refinement: Refinement,
    /// The coarse triangle of every fine triangle (nondecreasing: the children of a coarse
    /// triangle are consecutive), for moving per-triangle data to the fine mesh.
    #[cfg_attr(not(test), allow(dead_code))]
    pub parent: Vec<u32>,
}

impl Bisection {
    /// Number of new vertices (fine vertices `coarse vertices ..` are new: the places where
    /// a local multigrid smooths).
    #[cfg(test)]
    pub fn new_vertices(&self) -> usize {
        self.refinement
            .parents
            .iter()
            .filter(|[a, b]| a != b)
            .count()
    }
}

/// Half-edges of a conforming mesh: half-edge `3 k + e` goes from corner `e` of triangle
/// `k` to corner `e + 1`.
struct HalfEdges {
    /// The opposite half-edge (the same edge in the neighbouring triangle), [`NONE`] on
    /// the boundary.
    twin: Vec<u32>,
    /// Half-edges grouped by their smaller endpoint: those of vertex `v` are
    /// `by_lo[ptr[v]..ptr[v + 1]]`, each as `(larger endpoint << 32) | half-edge`.
    ptr: Vec<usize>,
    by_lo: Vec<u64>,
}

impl HalfEdges {
    /// Matches the half-edges of `mesh` (a counting sort by smaller endpoint, then pairs
    /// within each vertex's short list, on all threads). Errors for an edge of three or
    /// more triangles or two triangles folded over an edge (not a [`Mesh::new`] mesh).
    fn new(mesh: &Mesh) -> Result<HalfEdges> {
        let tri = &mesh.triangles;
        let (ptr, by_lo) = group_by_key(mesh.n_vertices(), tri.len(), |k| {
            let t = tri[k];
            [0, 1, 2].map(|e| {
                let (a, b) = (t[e], t[NEXT[e]]);
                Some((a.min(b), (u64::from(a.max(b)) << 32) | (3 * k + e) as u64))
            })
        });
        let twin: Vec<AtomicU32> = (0..3 * tri.len())
            .into_par_iter()
            .with_min_len(8192)
            .map(|_| AtomicU32::new(NONE))
            .collect();
        let source = |h: u32| tri[h as usize / 3][h as usize % 3];
        let bad = (0..mesh.n_vertices())
            .into_par_iter()
            .with_min_len(4096)
            .filter_map(|v| {
                let list = &by_lo[ptr[v]..ptr[v + 1]];
                for (i, &x) in list.iter().enumerate() {
                    let h = x as u32;
                    let mut found = None;
                    for &y in &list[i + 1..] {
                        if y >> 32 != x >> 32 {
                            continue;
                        }
                        let g = y as u32;
                        if found.is_some() || twin[h as usize].load(Ordering::Relaxed) != NONE {
                            return Some((v as u32, (x >> 32) as u32, "non-manifold"));
                        }
                        if source(g) == source(h) {
                            return Some((v as u32, (x >> 32) as u32, "folded"));
                        }
                        found = Some(g);
                    }
                    if let Some(g) = found {
                        twin[h as usize].store(g, Ordering::Relaxed);
                        twin[g as usize].store(h, Ordering::Relaxed);
                    }
                }
                None
            })
            .min();
        if let Some((a, b, what)) = bad {
            return Err(Error::Mesh(format!(
                "bisection: edge ({a}, {b}) is {what} (three or more triangles, or two \
                 triangles on the same side)"
            )));
        }
        let twin = twin
            .into_par_iter()
            .with_min_len(8192)
            .map(AtomicU32::into_inner)
            .collect();
        Ok(HalfEdges { twin, ptr, by_lo })
    }

    /// The half-edge of edge `{a, b}` listed first (the one of the lower triangle), if
    /// the mesh has that edge.
    fn find(&self, a: u32, b: u32) -> Option<u32> {
        let (lo, hi) = (a.min(b) as usize, u64::from(a.max(b)));
        if lo + 1 >= self.ptr.len() {
            return None;
        }
        self.by_lo[self.ptr[lo]..self.ptr[lo + 1]]
            .iter()
            .find(|&&x| x >> 32 == hi)
            .map(|&x| x as u32)
    }
}

/// Whether `p` lies on the circle up to round-off (the tolerance of uniform refinement:
/// only boundary edges with both ends on it are arcs).
fn on_circle(c: &Circle, p: Point) -> bool {
    (crate::mesh::dist(p, c.center) - c.radius).abs() <= 1e-9 * c.radius
}

/// Newest-vertex bisection of `mesh` (docs/theory.md#refinement): every triangle of
/// `marked` (indices, in any order, repeats allowed) is bisected at least once, and its
/// neighbours as often as conformity needs (see the module's notes on the closure). The
/// mesh's labels are its vertex order (refinement edge first); label a start mesh with
/// [`label_longest_edge`].
///
/// Region tags follow the parent triangle, region names are copied; a tagged boundary
/// edge that is split becomes two edges with its tag. New vertices are edge midpoints,
/// except on a boundary edge whose two ends lie on `mesh.curve`: there the midpoint is
/// projected onto the circle (as [`super::refine::refine_uniform`] does), so children on
/// the boundary stick out of their parent by the arc's sagitta.
///
/// Errors: a marked index out of range, region tags of the wrong length, a vertex index
/// out of range, a non-manifold or folded edge, a boundary region edge that is no edge of
/// the mesh, more than `u32::MAX` vertices, or a triangle turned over by the projection
/// onto the curve (a start mesh too coarse for its circle).
#[cfg_attr(not(test), allow(dead_code))]
pub fn bisect(mesh: &Mesh, marked: &[u32]) -> Result<Bisection> {
    Ok(bisect_within(mesh, marked, usize::MAX)?.expect("no bound on the vertices"))
}

/// [`bisect`], or `None` as soon as the closure shows that the bisected mesh would have
/// more than `max_vertices` vertices: the mesh is then not built (an adaptive loop that
/// stops before such a mesh does not pay for it).
pub fn bisect_within(
    mesh: &Mesh,
    marked: &[u32],
    max_vertices: usize,
) -> Result<Option<Bisection>> {
    let (nv, nt) = (mesh.n_vertices(), mesh.n_triangles());
    if let Some(i) = first_where(marked, |k| k as usize >= nt) {
        return Err(Error::Mesh(format!(
            "bisection: marked triangle {} (entry {i}) does not exist: the mesh has {nt} \
             triangles",
            marked[i]
        )));
    }
    if mesh.regions.len() != nt {
        return Err(Error::Mesh(format!(
            "bisection: {} region tags for {nt} triangles",
            mesh.regions.len()
        )));
    }
    if let Some(k) = first_where(&mesh.triangles, |t| t.iter().any(|&v| v as usize >= nv)) {
        return Err(Error::Mesh(format!(
            "bisection: triangle {k} uses a vertex out of range ({:?}, {nv} vertices)",
            mesh.triangles[k]
        )));
    }
    let half = HalfEdges::new(mesh)?;
    let twin = &half.twin;

    // Closure: mark the refinement edge (half-edge 3k) of every marked triangle, then of
    // every triangle with a marked edge, until none is left.
    let mut mid = crate::sparse::filled(3 * nt, NONE);
    let mut stack: Vec<u32> = Vec::new();
    let split = |h: usize, mid: &mut [u32], stack: &mut Vec<u32>| {
        if mid[h] != NONE {
            return;
        }
        mid[h] = SPLIT;
        stack.push(h as u32 / 3);
        let g = twin[h];
        if g != NONE {
            mid[g as usize] = SPLIT;
            stack.push(g / 3);
        }
    };
    for &k in marked {
        split(3 * k as usize, &mut mid, &mut stack);
        while let Some(k) = stack.pop() {
            split(3 * k as usize, &mut mid, &mut stack);
        }
    }

    // Number the new vertices: one per split edge, at its first half-edge.
    let mut new_edges: Vec<u32> = Vec::new();
    for h in 0..3 * nt {
        if mid[h] == SPLIT {
            let id = nv + new_edges.len();
            if id >= NONE as usize - 1 {
                return Err(Error::Mesh(format!(
                    "bisection: more than {} vertices",
                    NONE - 2
                )));
            }
            mid[h] = id as u32;
            let g = twin[h];
            if g != NONE {
                mid[g as usize] = id as u32;
            }
            new_edges.push(h as u32);
        }
    }
    if nv + new_edges.len() > max_vertices {
        return Ok(None);
    }
    let ends = |h: u32| {
        let t = mesh.triangles[h as usize / 3];
        let e = h as usize % 3;
        [t[e], t[NEXT[e]]]
    };

    // New vertices: midpoints, projected onto the curve on its arcs.
    let curve = mesh.curve;
    let (new_points, projected): (Vec<Point>, Vec<bool>) = new_edges
        .par_iter()
        .with_min_len(4096)
        .map(|&h| {
            let [a, b] = ends(h);
            let (p, q) = (mesh.points[a as usize], mesh.points[b as usize]);
            let m = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
            match curve {
                Some(c) if twin[h as usize] == NONE && on_circle(&c, p) && on_circle(&c, q) => {
                    (c.project(m), true)
                }
                _ => (m, false),
            }
        })
        .unzip();
    let any_projected = projected.iter().any(|&p| p);
    drop(projected);
    let mut points = Vec::with_capacity(nv + new_edges.len());
    points.extend_from_slice(&mesh.points);
    points.extend_from_slice(&new_points);
    drop(new_points);
    let mut parents: Vec<[u32; 2]> = Vec::with_capacity(nv + new_edges.len());
    parents.extend((0..nv as u32).map(|v| [v, v]));
    parents.par_extend(new_edges.par_iter().with_min_len(4096).map(|&h| ends(h)));

    // Children, triangle by triangle.
    let (triangles, parent): (Vec<[u32; 3]>, Vec<u32>) = mesh
        .triangles
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .flat_map_iter(|(k, &t)| {
            let (out, n) = children(t, [mid[3 * k], mid[3 * k + 1], mid[3 * k + 2]]);
            out.into_iter().take(n).map(move |c| (c, k as u32))
        })
        .unzip();
    let regions: Vec<u32> = parent
        .par_iter()
        .with_min_len(8192)
        .map(|&k| mesh.regions[k as usize])
        .collect();
    if any_projected {
        if let Some(k) = first_where(&triangles, |t| crate::mesh::signed_area(&points, &t) <= 0.0) {
            return Err(Error::Mesh(format!(
                "bisection: triangle {} turned over when a new boundary vertex was moved \
                 onto the circle; refine the start mesh of the disc",
                parent[k]
            )));
        }
    }
    let boundary = split_boundary_regions(&mesh.boundary, &half, &mid)?;
    let fine = Mesh {
        points,
        triangles,
        regions,
        region_names: mesh.region_names.clone(),
        curve,
        boundary,
        numbering: None,
    };
    Ok(Some(Bisection {
        mesh: fine,
        refinement: Refinement { parents },
        parent,
    }))
}

/// The children of triangle `[a, b, c]` (refinement edge `ab`) given the new vertices on
/// its edges `ab`, `bc`, `ca` ([`NONE`] where the edge is not split; `bc` or `ca` split
/// imply `ab` split, the closure's invariant). Bisection of `[a, b, c]` at `m` gives
/// `[c, a, m]` and `[b, c, m]`, whose refinement edges are `ca` and `bc`.
#[inline]
fn children(t: [u32; 3], m: [u32; 3]) -> ([[u32; 3]; 4], usize) {
    let [a, b, c] = t;
    let [m0, m1, m2] = m;
    let mut out = [[0u32; 3]; 4];
    if m0 == NONE {
        debug_assert!(
            m1 == NONE && m2 == NONE,
            "a split edge without the refinement edge"
        );
        out[0] = t;
        return (out, 1);
    }
    let mut n = 0;
    if m2 == NONE {
        out[0] = [c, a, m0];
        n += 1;
    } else {
        out[0] = [m0, c, m2];
        out[1] = [a, m0, m2];
        n += 2;
    }
    if m1 == NONE {
        out[n] = [b, c, m0];
        n += 1;
    } else {
        out[n] = [m0, b, m1];
        out[n + 1] = [c, m0, m1];
        n += 2;
    }
    (out, n)
}

/// The boundary regions after bisection: a tagged edge that was split becomes its two
/// halves with its tag (in the edge's own vertex order), the others stay.
fn split_boundary_regions(
    coarse: &BoundaryRegions,
    half: &HalfEdges,
    mid: &[u32],
) -> Result<BoundaryRegions> {
    let mut edges = Vec::with_capacity(coarse.edges.len());
    let mut tags = Vec::with_capacity(coarse.tags.len());
    for (&[a, b], &tag) in coarse.edges.iter().zip(&coarse.tags) {
        let Some(h) = half.find(a, b) else {
            return Err(Error::Mesh(format!(
                "bisection: boundary region edge ({a}, {b}) is not an edge of the mesh"
            )));
        };
        match mid[h as usize] {
            NONE => {
                edges.push([a, b]);
                tags.push(tag);
            }
            m => {
                edges.extend([[a, m], [m, b]]);
                tags.extend([tag, tag]);
            }
        }
    }
    Ok(BoundaryRegions {
        edges,
        tags,
        names: coarse.names.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{disk, polygon, rectangle, Diagonal, PolygonSpec, RectangleSpec};
    use crate::mesh::refine::refine_uniform;
    use std::collections::{BTreeMap, HashMap};

    /// A small deterministic generator (xorshift64*), for marking at random.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }

        /// Each triangle of `n` with probability `p`.
        fn mark(&mut self, n: usize, p: f64) -> Vec<u32> {
            (0..n as u32)
                .filter(|_| (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p)
                .collect()
        }
    }

    fn rect(nx: usize, ny: usize, diagonal: Diagonal) -> Mesh {
        let spec = RectangleSpec {
            x0: -0.3,
            y0: 0.1,
            x1: 1.7,
            y1: 0.7,
            nx,
            ny,
            diagonal,
        };
        rectangle(&spec).unwrap().levels.pop().unwrap()
    }

    /// The L shape (0, 2)² minus [1, 2] × [1, 2], unstructured, re-entrant corner (1, 1).
    fn l_shape(size: f64) -> Mesh {
        polygon(&PolygonSpec {
            outer: vec![
                [0.0, 0.0],
                [2.0, 0.0],
                [2.0, 1.0],
                [1.0, 1.0],
                [1.0, 2.0],
                [0.0, 2.0],
            ],
            holes: vec![],
            regions: vec![(
                "left".to_string(),
                vec![[0.0, 0.0], [0.7, 0.0], [0.7, 2.0], [0.0, 2.0]],
            )],
            size,
            min_angle: 25.0,
        })
        .unwrap()
    }

    fn len2(m: &Mesh, [a, b]: [u32; 2]) -> f64 {
        dist2(m.points[a as usize], m.points[b as usize])
    }

    /// The directed edges of a mesh and how often each is used.
    fn directed_edges(m: &Mesh) -> HashMap<(u32, u32), u32> {
        let mut uses = HashMap::new();
        for t in &m.triangles {
            for e in 0..3 {
                *uses.entry((t[e], t[NEXT[e]])).or_insert(0) += 1;
            }
        }
        uses
    }

    /// The edges of one triangle only (the boundary of the domain, for a conforming mesh).
    fn unmatched(m: &Mesh) -> Vec<[u32; 2]> {
        let uses = directed_edges(m);
        let mut out: Vec<[u32; 2]> = uses
            .keys()
            .filter(|(a, b)| !uses.contains_key(&(*b, *a)))
            .map(|&(a, b)| [a, b])
            .collect();
        out.sort_unstable();
        out
    }

    /// Checks that `b.mesh` is a conforming refinement of `coarse` with straight edges
    /// (`curved = false`) or with new boundary vertices moved onto a curve. `brute`: also
    /// look for a vertex inside an edge by comparing every vertex with every edge.
    fn check_conforming(coarse: &Mesh, b: &Bisection, curved: bool, brute: bool) {
        let fine = &b.mesh;
        let checked = Mesh::new(
            fine.points.clone(),
            fine.triangles.clone(),
            fine.regions.clone(),
            fine.region_names.clone(),
        )
        .expect("Mesh::new accepts the bisected mesh");
        assert_eq!(checked.triangles, fine.triangles, "kept counter-clockwise");
        // Every directed edge once; an edge without its reverse lies on ∂Ω. A hanging
        // vertex m on an edge ab shows as three unmatched edges am, mb, ba inside Ω:
        // more boundary length and more boundary edges than the coarse mesh has.
        assert!(directed_edges(fine).values().all(|&n| n == 1));
        let (cb, fb) = (unmatched(coarse), unmatched(fine));
        let split: std::collections::HashSet<[u32; 2]> = b.refinement.parents
            [coarse.n_vertices()..]
            .iter()
            .map(|&[x, y]| [x.min(y), x.max(y)])
            .collect();
        let new_on_boundary = cb
            .iter()
            .filter(|&&[x, y]| split.contains(&[x.min(y), x.max(y)]))
            .count();
        assert_eq!(fb.len(), cb.len() + new_on_boundary, "boundary edges");
        if !curved {
            let length =
                |m: &Mesh, e: &[[u32; 2]]| -> f64 { e.iter().map(|&e| len2(m, e).sqrt()).sum() };
            let (lc, lf) = (length(coarse, &cb), length(fine, &fb));
            assert!(
                (lc - lf).abs() <= 1e-12 * lc,
                "boundary length {lc} -> {lf}"
            );
            let (ac, af) = (coarse.total_area(), fine.total_area());
            assert!((ac - af).abs() <= 1e-12 * ac, "area {ac} -> {af}");
        }
        if brute {
            let uses = directed_edges(fine);
            for &(a, c) in uses.keys() {
                let (p, q) = (fine.points[a as usize], fine.points[c as usize]);
                let l2 = dist2(p, q);
                for (v, &x) in fine.points.iter().enumerate() {
                    if v as u32 == a || v as u32 == c {
                        continue;
                    }
                    let cross = (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0]);
                    let along = (q[0] - p[0]) * (x[0] - p[0]) + (q[1] - p[1]) * (x[1] - p[1]);
                    let inside = cross.abs() <= 1e-12 * l2 && along > 0.0 && along < l2;
                    assert!(!inside, "vertex {v} lies inside edge ({a}, {c})");
                }
            }
        }
    }

    /// Checks nesting (straight edges): each fine triangle inside its parent, the children's
    /// areas summing to the parent's, regions inherited, parents listed in order, new
    /// vertices at the exact midpoints of their coarse edges, the prolongation exact for
    /// linear functions.
    fn check_nested(coarse: &Mesh, b: &Bisection) {
        let fine = &b.mesh;
        assert_eq!(b.parent.len(), fine.n_triangles());
        assert!(b.parent.windows(2).all(|w| w[0] <= w[1]));
        let mut area = vec![0.0; coarse.n_triangles()];
        for (k, &p) in b.parent.iter().enumerate() {
            let p = p as usize;
            assert_eq!(fine.regions[k], coarse.regions[p]);
            area[p] += fine.area(k);
            let [x, y, z] = coarse.corners(p);
            let twice = 2.0 * coarse.area(p);
            for q in fine.corners(k) {
                let l = [
                    (y[0] - q[0]) * (z[1] - q[1]) - (z[0] - q[0]) * (y[1] - q[1]),
                    (z[0] - q[0]) * (x[1] - q[1]) - (x[0] - q[0]) * (z[1] - q[1]),
                    (x[0] - q[0]) * (y[1] - q[1]) - (y[0] - q[0]) * (x[1] - q[1]),
                ];
                assert!(
                    l.iter().all(|&l| l >= -1e-12 * twice),
                    "fine triangle {k} sticks out of its parent {p}"
                );
            }
        }
        for (p, a) in area.iter().enumerate() {
            let c = coarse.area(p);
            assert!((a - c).abs() <= 1e-12 * c, "triangle {p}: {c} -> {a}");
        }
        assert_eq!(b.refinement.parents.len(), fine.n_vertices());
        assert_eq!(&fine.points[..coarse.n_vertices()], &coarse.points[..]);
        let uses = directed_edges(coarse);
        for (v, &[x, y]) in b.refinement.parents.iter().enumerate() {
            let (p, q) = (coarse.points[x as usize], coarse.points[y as usize]);
            assert_eq!(fine.points[v], [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
            if v < coarse.n_vertices() {
                assert_eq!([x, y], [v as u32; 2]);
            } else {
                assert!(uses.contains_key(&(x, y)) || uses.contains_key(&(y, x)));
            }
        }
        let lin = |p: Point| 3.0 * p[0] - 2.0 * p[1] + 0.25;
        let coarse_values: Vec<f64> = coarse.points.iter().map(|&p| lin(p)).collect();
        let fine_values = b.refinement.prolongate(&coarse_values);
        for (v, &p) in fine.points.iter().enumerate() {
            assert!((fine_values[v] - lin(p)).abs() < 1e-12, "vertex {v}");
        }
    }

    /// The distinct triangle shapes up to similarity (and reflection): the edge lengths
    /// sorted and divided by the longest, equal within `1e-9`.
    fn shapes(m: &Mesh) -> usize {
        shapes_of(m, 0..m.n_triangles())
    }

    /// [`shapes`] among the triangles `ks` of `m`.
    fn shapes_of(m: &Mesh, ks: impl Iterator<Item = usize>) -> usize {
        let mut reps: Vec<[f64; 2]> = Vec::new();
        for k in ks {
            let t = m.triangles[k];
            let mut l = [0, 1, 2].map(|e| len2(m, [t[e], t[NEXT[e]]]).sqrt());
            l.sort_by(f64::total_cmp);
            let key = [l[0] / l[2], l[1] / l[2]];
            let near = |r: &[f64; 2]| (r[0] - key[0]).abs() < 1e-9 && (r[1] - key[1]).abs() < 1e-9;
            if !reps.iter().any(near) {
                reps.push(key);
            }
        }
        reps.len()
    }

    #[test]
    fn labelling_puts_the_longest_edge_first_whatever_the_rotation() {
        let m = l_shape(0.3);
        let labelled = label_longest_edge(&m);
        assert!(is_longest_edge_labelled(&labelled));
        let again = Mesh::new(
            labelled.points.clone(),
            labelled.triangles.clone(),
            labelled.regions.clone(),
            labelled.region_names.clone(),
        )
        .unwrap();
        assert_eq!(
            again.triangles, labelled.triangles,
            "Mesh::new keeps the labels"
        );
        for (k, (&t, &l)) in m.triangles.iter().zip(&labelled.triangles).enumerate() {
            let rotations = [t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
            assert!(rotations.contains(&l), "triangle {k} only rotated");
            for r in rotations {
                assert_eq!(longest_edge_first(&m.points, r), l);
            }
            let longest = [0, 1, 2]
                .map(|e| len2(&m, [t[e], t[NEXT[e]]]))
                .into_iter()
                .fold(0.0, f64::max);
            assert_eq!(len2(&m, [l[0], l[1]]), longest);
        }
        // Ties go to the larger vertex pair: the legs of an isosceles triangle.
        let p = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 3.0]];
        assert_eq!(longest_edge_first(&p, [0, 1, 2]), [1, 2, 0]);
        assert_eq!(longest_edge_first(&p, [2, 0, 1]), [1, 2, 0]);
        // The generators' rectangles start with a leg: not labelled.
        let r = rect(4, 4, Diagonal::Right);
        assert!(!is_longest_edge_labelled(&r));
        assert!(is_longest_edge_labelled(&label_longest_edge(&r)));
    }

    #[test]
    fn bisection_is_conforming_and_nested() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let starts = [
            l_shape(0.4),
            rect(5, 3, Diagonal::Alternate),
            rect(4, 4, Diagonal::Crossed),
            // Unlabelled on purpose: any labels give a conforming refinement.
            rect(3, 3, Diagonal::Left),
        ];
        for (i, start) in starts.into_iter().enumerate() {
            let mut m = if i < 3 {
                label_longest_edge(&start)
            } else {
                start
            };
            for step in 0..6 {
                let marked = rng.mark(m.n_triangles(), 0.15);
                let b = bisect(&m, &marked).unwrap();
                check_conforming(&m, &b, false, m.n_triangles() < 600);
                check_nested(&m, &b);
                // Marked triangles are bisected; a triangle with no split edge is kept.
                let mut count = vec![0; m.n_triangles()];
                for &p in &b.parent {
                    count[p as usize] += 1;
                }
                assert!(
                    marked.iter().all(|&k| count[k as usize] >= 2),
                    "step {step}"
                );
                assert!(count.iter().all(|&c| (1..=4).contains(&c)));
                // A kept triangle keeps its labels; a child has a new vertex as its newest.
                for (k, &p) in b.parent.iter().enumerate() {
                    let t = b.mesh.triangles[k];
                    if count[p as usize] == 1 {
                        assert_eq!(t, m.triangles[p as usize]);
                    } else {
                        assert!(t[2] as usize >= m.n_vertices(), "child {k}: {t:?}");
                    }
                }
                assert_eq!(b.new_vertices(), b.mesh.n_vertices() - m.n_vertices());
                m = b.mesh;
            }
        }
    }

    #[test]
    fn a_bound_on_the_vertices_stops_before_the_mesh_is_built() {
        let m = label_longest_edge(&l_shape(0.5));
        let marked: Vec<u32> = (0..m.n_triangles() as u32).step_by(3).collect();
        let full = bisect(&m, &marked).unwrap();
        let n = full.mesh.n_vertices();
        assert!(n > m.n_vertices());
        let within = bisect_within(&m, &marked, n)
            .unwrap()
            .expect("fits exactly");
        assert_eq!(within.mesh.triangles, full.mesh.triangles);
        assert_eq!(within.mesh.points, full.mesh.points);
        assert_eq!(within.refinement.parents, full.refinement.parents);
        assert!(bisect_within(&m, &marked, n - 1).unwrap().is_none());
        // Bad input is still an error, not a stop.
        assert!(bisect_within(&m, &[u32::MAX], 0).is_err());
    }

    #[test]
    fn nothing_marked_changes_nothing_and_repeats_count_once() {
        let m = label_longest_edge(&l_shape(0.5));
        let b = bisect(&m, &[]).unwrap();
        assert_eq!(b.mesh.triangles, m.triangles);
        assert_eq!(b.mesh.points, m.points);
        assert_eq!(b.new_vertices(), 0);
        let once = bisect(&m, &[3, 1]).unwrap();
        let repeated = bisect(&m, &[1, 3, 3, 1, 1]).unwrap();
        assert_eq!(once.mesh.triangles, repeated.mesh.triangles);
        assert_eq!(once.mesh.points, repeated.mesh.points);
    }

    #[test]
    fn uniform_marking_twice_is_one_red_refinement() {
        for diagonal in [Diagonal::Right, Diagonal::Left] {
            let m = label_longest_edge(&rect(6, 4, diagonal));
            let all = |m: &Mesh| (0..m.n_triangles() as u32).collect::<Vec<_>>();
            let b1 = bisect(&m, &all(&m)).unwrap();
            // Every cell's two triangles share their hypotenuse: each is bisected once.
            assert_eq!(b1.mesh.n_triangles(), 2 * m.n_triangles());
            let b2 = bisect(&b1.mesh, &all(&b1.mesh)).unwrap();
            assert_eq!(b2.mesh.n_triangles(), 4 * m.n_triangles());
            check_conforming(&b1.mesh, &b2, false, true);
            // Four grandchildren per triangle, and the vertices of red refinement.
            let mut count = vec![0; m.n_triangles()];
            for &p in &b2.parent {
                count[b1.parent[p as usize] as usize] += 1;
            }
            assert!(count.iter().all(|&c| c == 4));
            let (red, _) = refine_uniform(&m);
            let sorted = |m: &Mesh| {
                let mut p: Vec<[u64; 2]> = m.points.iter().map(|p| p.map(f64::to_bits)).collect();
                p.sort_unstable();
                p
            };
            assert_eq!(sorted(&b2.mesh), sorted(&red));
            let q = b2.mesh.quality();
            assert!((q.min_angle_deg - m.quality().min_angle_deg).abs() < 1e-9);
            assert!(q.l_n < m.quality().l_n);
        }
    }

    /// Smallest angle of a mesh, in degrees.
    fn min_angle(m: &Mesh) -> f64 {
        m.quality().min_angle_deg
    }

    #[test]
    fn refining_towards_the_reentrant_corner_keeps_the_shapes() {
        let start = label_longest_edge(&l_shape(0.35));
        let corner = start.points.iter().position(|&p| p == [1.0, 1.0]).unwrap() as u32;
        let (angle0, shapes0) = (min_angle(&start), shapes(&start));
        let classes = 4 * start.n_triangles();
        let mut m = start.clone();
        for step in 0..20 {
            let marked: Vec<u32> = (0..m.n_triangles() as u32)
                .filter(|&k| m.triangles[k as usize].contains(&corner))
                .collect();
            let b = bisect(&m, &marked).unwrap();
            check_conforming(&m, &b, false, false);
            check_nested(&m, &b);
            m = b.mesh;
            assert!(
                min_angle(&m) >= 0.5 * angle0,
                "step {step}: {}",
                min_angle(&m)
            );
            assert!(shapes(&m) <= classes, "step {step}: {} shapes", shapes(&m));
        }
        // The corner's triangles shrank by 2^-20 at least (each step bisects them).
        let at_corner = (0..m.n_triangles())
            .filter(|&k| m.triangles[k].contains(&corner))
            .map(|k| m.area(k))
            .fold(0.0, f64::max);
        let largest = (0..start.n_triangles())
            .map(|k| start.area(k))
            .fold(0.0, f64::max);
        assert!(at_corner <= largest * 0.5f64.powi(20), "{at_corner}");
        // Local: far fewer triangles than uniform refinement would make.
        assert!(
            m.n_triangles() < 40 * start.n_triangles(),
            "{}",
            m.n_triangles()
        );
        eprintln!(
            "L shape towards the corner: {} -> {} triangles, smallest angle {angle0:.2}° -> {:.2}°, \
             shapes {shapes0} -> {} (bound {classes})",
            start.n_triangles(),
            m.n_triangles(),
            min_angle(&m),
            shapes(&m)
        );
    }

    #[test]
    fn random_marking_keeps_the_shapes() {
        let start = label_longest_edge(&l_shape(0.35));
        let angle0 = min_angle(&start);
        let classes = 4 * start.n_triangles();
        let mut rng = Rng(12345);
        let mut m = start.clone();
        // The start triangle of every triangle.
        let mut root: Vec<u32> = (0..start.n_triangles() as u32).collect();
        for step in 0..10 {
            let marked = rng.mark(m.n_triangles(), 0.2);
            let b = bisect(&m, &marked).unwrap();
            check_conforming(&m, &b, false, false);
            root = b.parent.iter().map(|&p| root[p as usize]).collect();
            m = b.mesh;
            assert!(
                min_angle(&m) >= 0.5 * angle0,
                "step {step}: {}",
                min_angle(&m)
            );
            assert!(shapes(&m) <= classes, "step {step}: {} shapes", shapes(&m));
        }
        assert!(m.n_triangles() > 10 * start.n_triangles());
        // At most four similarity classes among the descendants of each start triangle.
        let mut family = vec![Vec::new(); start.n_triangles()];
        for (k, &r) in root.iter().enumerate() {
            family[r as usize].push(k);
        }
        let deep = family.iter().filter(|f| f.len() >= 16).count();
        assert!(
            2 * deep > family.len(),
            "{deep} start triangles refined deeply"
        );
        for (r, f) in family.iter().enumerate() {
            let n = shapes_of(&m, f.iter().copied());
            assert!(n <= 4, "start triangle {r}: {n} shapes among {}", f.len());
        }
        eprintln!(
            "L shape, random marking: {} -> {} triangles, smallest angle {angle0:.2}° -> {:.2}°, \
             shapes {} -> {} (bound {classes})",
            start.n_triangles(),
            m.n_triangles(),
            min_angle(&m),
            shapes(&start),
            shapes(&m)
        );
    }

    #[test]
    fn regions_and_boundary_regions_follow_the_parents() {
        // Two regions; the left side untagged.
        let mut m = label_longest_edge(&rect(6, 4, Diagonal::Alternate));
        for k in 0..m.n_triangles() {
            let c = m.corners(k);
            m.regions[k] = if c[0][0] + c[1][0] + c[2][0] < 3.0 * 0.7 {
                1
            } else {
                2
            };
        }
        m.region_names = BTreeMap::from([(1, "soft".to_string()), (2, "hard".to_string())]);
        let (edges, tags): (Vec<[u32; 2]>, Vec<u32>) = m
            .boundary
            .edges
            .iter()
            .zip(&m.boundary.tags)
            .filter(|(_, &t)| t != 4)
            .unzip();
        (m.boundary.edges, m.boundary.tags) = (edges, tags);
        let per_tag = |m: &Mesh| {
            let mut l = BTreeMap::new();
            for (&e, &t) in m.boundary.edges.iter().zip(&m.boundary.tags) {
                *l.entry(t).or_insert(0.0) += len2(m, e).sqrt();
            }
            l
        };
        let lengths = per_tag(&m);
        assert_eq!(lengths.len(), 3);
        let mut rng = Rng(77);
        for _ in 0..5 {
            // Mark near the boundary as well as at random.
            let mut marked = rng.mark(m.n_triangles(), 0.1);
            marked.extend((0..m.n_triangles() as u32).filter(|&k| {
                let c = m.corners(k as usize);
                c.iter().any(|p| p[0] < -0.29 || p[1] > 0.69)
            }));
            let b = bisect(&m, &marked).unwrap();
            check_nested(&m, &b);
            let f = b.mesh;
            assert_eq!(f.region_names, m.region_names);
            assert_eq!(f.boundary.names, m.boundary.names);
            for (t, l) in per_tag(&f) {
                assert!((l - lengths[&t]).abs() < 1e-12, "tag {t}: {l}");
            }
            // The tagged edges are boundary edges of the fine mesh (validated), and no
            // edge of the left side got a tag.
            let f = f
                .clone()
                .with_boundary_regions(
                    f.boundary.edges.clone(),
                    f.boundary.tags.clone(),
                    f.boundary.names.clone(),
                )
                .unwrap();
            for &[a, c] in &f.boundary.edges {
                let (p, q) = (f.points[a as usize], f.points[c as usize]);
                assert!(!(p[0] == -0.3 && q[0] == -0.3), "left side tagged");
            }
            m = f;
        }
        let left = unmatched(&m)
            .iter()
            .filter(|&&[a, c]| m.points[a as usize][0] == -0.3 && m.points[c as usize][0] == -0.3)
            .count();
        assert!(left > 4, "the left side was refined: {left} edges");
        assert!(per_tag(&m).len() == 3);
    }

    #[test]
    fn disc_boundary_vertices_go_onto_the_circle() {
        let (c, r) = ([0.5, -1.0], 2.0);
        let mut m = label_longest_edge(&disk(c, r, 0.8).unwrap());
        let circle = m.curve.unwrap();
        let mut rng = Rng(4242);
        let mut area = m.total_area();
        for _ in 0..6 {
            let bv = m.boundary_vertices();
            let mut marked = rng.mark(m.n_triangles(), 0.1);
            // All triangles on the boundary.
            marked.extend(
                (0..m.n_triangles() as u32)
                    .filter(|&k| m.triangles[k as usize].iter().any(|&v| bv[v as usize])),
            );
            let b = bisect(&m, &marked).unwrap();
            check_conforming(&m, &b, true, false);
            let f = &b.mesh;
            assert_eq!(f.curve, Some(circle));
            let fbv = f.boundary_vertices();
            let n_old = m.n_vertices();
            let mut moved = 0;
            for (v, &[x, y]) in b.refinement.parents.iter().enumerate().skip(n_old) {
                let (p, q) = (m.points[x as usize], m.points[y as usize]);
                let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                if fbv[v] {
                    let d = crate::mesh::dist(f.points[v], c);
                    assert!((d - r).abs() < 1e-14 * r, "vertex {v} at r = {d}");
                    moved += 1;
                } else {
                    assert_eq!(f.points[v], mid, "interior vertex {v} at the midpoint");
                }
            }
            assert!(moved > 0);
            // Every boundary edge keeps the tag "outer".
            assert_eq!(f.boundary.edges.len(), f.boundary_edges().len());
            assert!(f.boundary.tags.iter().all(|&t| t == 1));
            let a = f.total_area();
            assert!(a > area && a < std::f64::consts::PI * r * r);
            area = a;
            m = b.mesh;
        }
    }

    #[test]
    fn straight_boundary_edges_of_a_disc_stay_straight() {
        // Half a hexagon: the arc is curved, the diameter through the centre is not.
        let mut p = vec![[0.0, 0.0]];
        for i in 0..4 {
            let a = i as f64 * std::f64::consts::PI / 3.0;
            p.push([a.cos(), a.sin()]);
        }
        let t = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        let mut m = Mesh::new(p, t, vec![], BTreeMap::new()).unwrap();
        m.curve = Some(Circle {
            center: [0.0, 0.0],
            radius: 1.0,
        });
        let mut m = label_longest_edge(&m);
        for _ in 0..4 {
            let all: Vec<u32> = (0..m.n_triangles() as u32).collect();
            m = bisect(&m, &all).unwrap().mesh;
        }
        let bv = m.boundary_vertices();
        let mut on_diameter = 0;
        for (v, p) in m.points.iter().enumerate().filter(|(v, _)| bv[*v]) {
            let r = p[0].hypot(p[1]);
            if p[1].abs() < 1e-15 {
                on_diameter += 1;
            } else {
                assert!((r - 1.0).abs() < 1e-15, "vertex {v} at {p:?}");
            }
        }
        assert!(on_diameter > 3, "{on_diameter}");
    }

    #[test]
    fn the_result_does_not_depend_on_the_number_of_threads() {
        // Large enough for the parallel edge matching (≥ 2^16 vertices).
        let m = label_longest_edge(&rect(300, 240, Diagonal::Alternate));
        let marked = Rng(5).mark(m.n_triangles(), 0.05);
        let on = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| bisect(&m, &marked).unwrap())
        };
        let (one, two) = (on(1), on(3));
        assert_eq!(one.mesh.triangles, two.mesh.triangles);
        assert_eq!(one.mesh.points, two.mesh.points);
        assert_eq!(one.parent, two.parent);
        assert_eq!(one.refinement.parents, two.refinement.parents);
        let b = one;
        check_nested(&m, &b);
        Mesh::new(b.mesh.points, b.mesh.triangles, vec![], BTreeMap::new()).unwrap();
    }

    #[test]
    fn bad_input_is_an_error() {
        let m = label_longest_edge(&l_shape(0.5));
        let n = m.n_triangles();
        let e = bisect(&m, &[0, n as u32, 2]).unwrap_err().to_string();
        assert!(
            e.contains(&format!("marked triangle {n} (entry 1) does not exist")),
            "{e}"
        );
        let mut broken = m.clone();
        broken.regions.pop();
        assert!(bisect(&broken, &[0])
            .unwrap_err()
            .to_string()
            .contains("region tags"));
        let mut broken = m.clone();
        broken.boundary.edges.push([0, 0]);
        broken.boundary.tags.push(9);
        let e = bisect(&broken, &[0]).unwrap_err().to_string();
        assert!(e.contains("boundary region edge (0, 0)"), "{e}");
        // Three triangles on one edge.
        let p = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, -1.0], [0.5, 2.0]];
        let fan = Mesh {
            points: p,
            triangles: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
            regions: vec![0; 3],
            ..Mesh::default()
        };
        let e = bisect(&fan, &[0]).unwrap_err().to_string();
        assert!(e.contains("edge (0, 1) is non-manifold"), "{e}");
    }

    /// Timings for the report:
    /// `cargo test --release -p memcontact --lib bisect::tests::timings -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timings() {
        use std::time::Instant;
        for diagonal in [Diagonal::Right, Diagonal::Alternate] {
            let m = rect(708, 708, diagonal);
            let t = Instant::now();
            let m = label_longest_edge(&m);
            let label = t.elapsed();
            let marked = Rng(1).mark(m.n_triangles(), 0.1);
            let t = Instant::now();
            let b = bisect(&m, &marked).unwrap();
            let once = t.elapsed();
            let all: Vec<u32> = (0..m.n_triangles() as u32).collect();
            let t = Instant::now();
            let u = bisect(&m, &all).unwrap();
            let every = t.elapsed();
            eprintln!(
                "{diagonal:?} {} triangles: label {label:?}; 10% marked ({}) -> {} triangles, \
                 {} new vertices in {once:?}; all marked -> {} triangles in {every:?}",
                m.n_triangles(),
                marked.len(),
                b.mesh.n_triangles(),
                b.new_vertices(),
                u.mesh.n_triangles()
            );
        }
    }
}
