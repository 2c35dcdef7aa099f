//! Newest-vertex bisection (SPEC §6, "Refinement"): local refinement that keeps the mesh
//! conforming, nested and shape-regular, for the adaptive loop.
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
//! meshes: a caller labels the start mesh of an adaptive run once with
//! [`label_longest_edge`], and must not label again between bisections (relabelling a
//! bisected mesh throws away the newest-vertex structure that bounds the shapes).
//!
//! **Closure.** [`bisect`] works on edges: the refinement edge of every marked triangle is
//! marked, and then, until nothing changes, the refinement edge of every triangle that has
//! a marked edge (Binev–Dahmen–DeVore's completion, the non-recursive form of Mitchell's
//! recursive bisection). Each marked edge is then split once, in both its triangles, so the
//! result is conforming whatever the labels; each triangle is cut into 1 (unchanged), 2, 3
//! or 4 triangles by at most three bisections. The labels decide the shapes: with the
//! longest-edge labelling of the start mesh every triangle ever produced is similar to one
//! of at most four per start triangle (Sewell, Mitchell), so the angles stay bounded below.
//! Everything is linear in the mesh size: one edge matching (a counting sort by the smaller
//! endpoint), a work list for the closure, one pass over the triangles.

use super::refine::Refinement;
use super::{BoundaryRegions, Circle, Mesh, Point};
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
/// adaptive run (SPEC §6). Orientation, triangle order, regions, boundary regions, curve
/// and numbering are kept (a rotation changes no triangle's index and no vertex).
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
    pub parent: Vec<u32>,
}

impl Bisection {
    /// Number of new vertices (fine vertices `coarse vertices ..` are new: the places where
    /// a local multigrid smooths).
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
    (super::dist(p, c.center) - c.radius).abs() <= 1e-9 * c.radius
}

/// Newest-vertex bisection of `mesh` (SPEC §6): every triangle of `marked` (indices, in
/// any order, repeats allowed) is bisected at least once, and its neighbours as often as
/// conformity needs (see the module's notes on the closure). The mesh's labels are its
/// vertex order (refinement edge first); label a start mesh with [`label_longest_edge`].
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
pub fn bisect(mesh: &Mesh, marked: &[u32]) -> Result<Bisection> {
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
        if let Some(k) = first_where(&triangles, |t| super::signed_area(&points, &t) <= 0.0) {
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
    Ok(Bisection {
        mesh: fine,
        refinement: Refinement { parents },
        parent,
    })
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
        debug_assert!(m1 == NONE && m2 == NONE, "a split edge without the refinement edge");
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
