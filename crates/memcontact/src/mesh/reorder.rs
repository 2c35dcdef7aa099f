//! Vertex and triangle orders for memory locality. Every pass of the solver (assembly,
//! smoothing, residuals, transfers) walks the unknowns in order and reads their
//! neighbours: when neighbours are near in memory the pass runs from cache, when the order
//! is scattered (a mesh generator's or another tool's numbering, the midpoints of a
//! refinement) each neighbour is a miss. Meshes whose order is scattered are renumbered
//! along a Hilbert curve through their vertices (triangles by their first vertex on that
//! curve) before assembly; the outputs are mapped back to the user's order.

use super::refine::Hierarchy;
use super::{Mesh, Point};
use rayon::prelude::*;
use std::sync::Arc;

/// A permutation of `0..n`: `old_of_new[i]` is the old index of new entry `i`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Permutation {
    /// The old index of every new position.
    pub old_of_new: Vec<u32>,
    /// The new position of every old index.
    pub new_of_old: Vec<u32>,
}

impl Permutation {
    /// The permutation that puts old entry `old_of_new[i]` at position `i`.
    pub fn from_order(old_of_new: Vec<u32>) -> Permutation {
        let mut new_of_old = vec![0u32; old_of_new.len()];
        for (new, &old) in old_of_new.iter().enumerate() {
            new_of_old[old as usize] = new as u32;
        }
        Permutation {
            old_of_new,
            new_of_old,
        }
    }

    /// The identity on `0..n`.
    pub fn identity(n: usize) -> Permutation {
        let id: Vec<u32> = (0..n as u32).collect();
        Permutation {
            old_of_new: id.clone(),
            new_of_old: id,
        }
    }

    /// Length.
    pub fn len(&self) -> usize {
        self.old_of_new.len()
    }

    /// `true` for the permutation of nothing.
    pub fn is_empty(&self) -> bool {
        self.old_of_new.is_empty()
    }

    /// `true` when nothing moves.
    pub fn is_identity(&self) -> bool {
        self.old_of_new
            .iter()
            .enumerate()
            .all(|(i, &o)| o as usize == i)
    }

    /// Values in the new order from values in the old order.
    pub fn to_new<T: Copy + Send + Sync>(&self, old: &[T]) -> Vec<T> {
        self.old_of_new
            .par_iter()
            .with_min_len(8192)
            .map(|&o| old[o as usize])
            .collect()
    }

    /// Values in the old order from values in the new order.
    pub fn to_old<T: Copy + Send + Sync>(&self, new: &[T]) -> Vec<T> {
        self.new_of_old
            .par_iter()
            .with_min_len(8192)
            .map(|&n| new[n as usize])
            .collect()
    }
}

/// How a mesh was renumbered: its vertices and its triangles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reordering {
    /// Old = the user's vertex numbering, new = the internal one.
    pub vertices: Permutation,
    /// Old = the user's triangle numbering, new = the internal one.
    pub triangles: Permutation,
}

impl Reordering {
    /// No renumbering of a mesh of `n_vertices` and `n_triangles`.
    pub fn identity(n_vertices: usize, n_triangles: usize) -> Reordering {
        Reordering {
            vertices: Permutation::identity(n_vertices),
            triangles: Permutation::identity(n_triangles),
        }
    }

    /// `true` when nothing moves.
    pub fn is_identity(&self) -> bool {
        self.vertices.is_identity() && self.triangles.is_identity()
    }

    /// `mesh` (in the user's numbering) renumbered; the result records the renumbering in
    /// [`Mesh::numbering`].
    pub fn apply(&self, mesh: &Mesh) -> Mesh {
        Arc::new(self.clone()).apply_shared(mesh)
    }

    /// [`Reordering::apply`] recording this shared renumbering (not a copy).
    pub fn apply_shared(self: &Arc<Self>, mesh: &Mesh) -> Mesh {
        let v = &self.vertices;
        let mut m = self.map(
            mesh,
            (&v.new_of_old, &v.old_of_new),
            &self.triangles.old_of_new,
        );
        m.numbering = Some(self.clone());
        m
    }

    /// The inverse of [`Reordering::apply`]: the mesh in the user's numbering from the
    /// renumbered one.
    pub fn undo(&self, internal: &Mesh) -> Mesh {
        let v = &self.vertices;
        self.map(
            internal,
            (&v.old_of_new, &v.new_of_old),
            &self.triangles.new_of_old,
        )
    }

    /// `mesh` with vertex `v` moved to `vertex_to[v]` (the vertex now at `i` taken from
    /// `vertex_from[i]`, the inverse) and the triangle now at position `k` taken from
    /// position `triangle_from[k]`.
    fn map(
        &self,
        mesh: &Mesh,
        (vertex_to, vertex_from): (&[u32], &[u32]),
        triangle_from: &[u32],
    ) -> Mesh {
        let points: Vec<Point> = vertex_from
            .par_iter()
            .with_min_len(8192)
            .map(|&v| mesh.points[v as usize])
            .collect();
        let triangles: Vec<[u32; 3]> = triangle_from
            .par_iter()
            .with_min_len(8192)
            .map(|&k| mesh.triangles[k as usize].map(|v| vertex_to[v as usize]))
            .collect();
        let regions: Vec<u32> = triangle_from
            .par_iter()
            .with_min_len(8192)
            .map(|&k| mesh.regions[k as usize])
            .collect();
        Mesh {
            points,
            triangles,
            regions,
            region_names: mesh.region_names.clone(),
            curve: mesh.curve,
            boundary: super::BoundaryRegions {
                edges: mesh
                    .boundary
                    .edges
                    .iter()
                    .map(|e| e.map(|v| vertex_to[v as usize]))
                    .collect(),
                tags: mesh.boundary.tags.clone(),
                names: mesh.boundary.names.clone(),
            },
            numbering: None,
        }
    }
}

impl Mesh {
    /// The mesh in the user's numbering: itself, or the renumbering undone.
    pub fn in_user_numbering(&self) -> std::borrow::Cow<'_, Mesh> {
        match &self.numbering {
            Some(r) => std::borrow::Cow::Owned(r.undo(self)),
            None => std::borrow::Cow::Borrowed(self),
        }
    }

    /// Values at this mesh's vertices in the user's vertex numbering.
    pub fn vertex_values_to_user<T: Copy + Send + Sync>(&self, values: &[T]) -> Vec<T> {
        match &self.numbering {
            Some(r) => r.vertices.to_old(values),
            None => values.to_vec(),
        }
    }

    /// Values given at the user's vertices, in this mesh's numbering.
    pub fn vertex_values_from_user<T: Copy + Send + Sync>(&self, values: &[T]) -> Vec<T> {
        match &self.numbering {
            Some(r) => r.vertices.to_new(values),
            None => values.to_vec(),
        }
    }
}

/// Bits per coordinate of the Hilbert curve (a 65 536 × 65 536 grid over the mesh's
/// bounding square).
const BITS: u32 = 16;

/// The index of cell `(x, y)` along the Hilbert curve of the `2^BITS × 2^BITS` grid.
pub fn hilbert_index(mut x: u32, mut y: u32) -> u32 {
    let n: u32 = 1 << BITS;
    let mut d: u64 = 0;
    let mut s = n / 2;
    while s > 0 {
        let rx = u32::from(x & s > 0);
        let ry = u32::from(y & s > 0);
        d += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        // Rotate the quadrant so that the curve inside it has the standard orientation.
        if ry == 0 {
            if rx == 1 {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d as u32
}

/// The order of `points` along the Hilbert curve of their bounding square (ties by
/// index: deterministic).
fn curve_order(points: &[Point]) -> Vec<u32> {
    let (lo, hi) = points
        .par_iter()
        .with_min_len(8192)
        .fold(
            || ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            },
        )
        .reduce(
            || ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(a, b), (c, d)| {
                (
                    [a[0].min(c[0]), a[1].min(c[1])],
                    [b[0].max(d[0]), b[1].max(d[1])],
                )
            },
        );
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let scale = if extent > 0.0 && extent.is_finite() {
        ((1u32 << BITS) - 1) as f64 / extent
    } else {
        0.0
    };
    let keys: Vec<u32> = points
        .par_iter()
        .with_min_len(8192)
        .map(|p| {
            let q = |d: usize| ((p[d] - lo[d]) * scale).clamp(0.0, ((1u32 << BITS) - 1) as f64);
            hilbert_index(q(0) as u32, q(1) as u32)
        })
        .collect();
    order_by_key(&keys)
}

/// The order of `triangles` by the first of their vertices in the new vertex order
/// `vertices` (ties by index): each vertex's triangles come together, where its fan is
/// assembled, and the triangles follow the vertices along the curve.
fn triangle_order(triangles: &[[u32; 3]], vertices: &Permutation) -> Vec<u32> {
    let new = &vertices.new_of_old;
    let keys: Vec<u32> = triangles
        .par_iter()
        .with_min_len(8192)
        .map(|t| t.map(|v| new[v as usize]).into_iter().min().unwrap_or(0))
        .collect();
    order_by_key(&keys)
}

/// The indices `0..keys.len()` ordered by `keys[i]`, ties by index. The indices are first
/// grouped by the leading bits of their keys, about one group per index, by the stable
/// counting sort [`crate::sparse::group_by_key`] (on all threads); each group, in index order, is then
/// sorted by its whole keys, stably. Linear time for keys spread over their range, and the
/// same order for any number of threads.
fn order_by_key(keys: &[u32]) -> Vec<u32> {
    let n = keys.len();
    if n == 0 {
        return Vec::new();
    }
    let (lo, hi) = keys
        .par_iter()
        .with_min_len(8192)
        .fold(|| (u32::MAX, 0), |(lo, hi), &k| (lo.min(k), hi.max(k)))
        .reduce(|| (u32::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    // Groups of the keys' leading bits: at most 2n of them (one when all keys are equal).
    let bits = u32::BITS - (hi - lo).leading_zeros();
    let group_bits = (usize::BITS - n.leading_zeros()).min(bits);
    let shift = bits - group_bits;
    let (ptr, mut order) = crate::sparse::group_by_key(1 << group_bits, n, |i| {
        [Some(((keys[i] - lo) >> shift, i as u32))]
    });
    if shift > 0 {
        // Blocks of groups, each sorting its own groups.
        const GROUPS: usize = 4096;
        let mut blocks = Vec::with_capacity(ptr.len().div_ceil(GROUPS));
        let mut rest = &mut order[..];
        for first in (0..ptr.len() - 1).step_by(GROUPS) {
            let last = (first + GROUPS).min(ptr.len() - 1);
            let (block, tail) = rest.split_at_mut(ptr[last] - ptr[first]);
            blocks.push((first, last, block));
            rest = tail;
        }
        blocks.into_par_iter().for_each(|(first, last, block)| {
            let base = ptr[first];
            for g in first..last {
                block[ptr[g] - base..ptr[g + 1] - base].sort_by_key(|&i| keys[i as usize]);
            }
        });
    }
    order
}

/// The mean distance `|i − j|` between the numbers of the two ends of an edge, in units of
/// `√n`: about 0.7 for a structured grid numbered row by row, of order `√n` for a
/// scattered numbering.
#[cfg(any(test, feature = "bench"))]
pub fn edge_span(mesh: &Mesh) -> f64 {
    span_of(mesh.n_vertices(), &mesh.triangles)
}

/// [`edge_span`] of `triangles` on `n_vertices` vertices.
fn span_of(n_vertices: usize, triangles: &[[u32; 3]]) -> f64 {
    let n = n_vertices.max(1) as f64;
    let total: f64 = triangles
        .par_iter()
        .with_min_len(8192)
        .map(|t| {
            let s = |a: u32, b: u32| (a as f64 - b as f64).abs();
            s(t[0], t[1]) + s(t[1], t[2]) + s(t[2], t[0])
        })
        .sum();
    total / (3.0 * triangles.len().max(1) as f64) / n.sqrt()
}

/// `true` when `triangles` on `n_vertices` vertices are numbered in a scattered order
/// (their mean edge span above [`LOCAL_SPAN`]): those [`locality_order`] renumbers. Reads the
/// triangles alone (an index out of range is no error here).
pub fn scattered(n_vertices: usize, triangles: &[[u32; 3]]) -> bool {
    span_of(n_vertices, triangles) > LOCAL_SPAN
}

/// Meshes whose [`edge_span`] is at most this are kept in their order (a row-by-row
/// structured grid, or a mesh already renumbered for locality).
pub const LOCAL_SPAN: f64 = 4.0;

/// The renumbering of `mesh` for locality: vertices along the Hilbert curve, triangles
/// by their first vertex on it; `None` when the mesh's own order is already local
/// ([`LOCAL_SPAN`]: nothing is built, a structured mesh of millions of vertices needs no
/// identity permutations).
pub fn renumbering_for_locality(mesh: &Mesh) -> Option<Reordering> {
    locality_order(&mesh.points, &mesh.triangles)
}

/// [`renumbering_for_locality`] of the triangles `triangles` on the vertices `points`
/// (every index in range): for arrays that are not a [`Mesh`], such as a result's
/// pictures.
pub fn locality_order(points: &[Point], triangles: &[[u32; 3]]) -> Option<Reordering> {
    if !scattered(points.len(), triangles) {
        return None;
    }
    let vertices = Permutation::from_order(curve_order(points));
    let triangles = Permutation::from_order(triangle_order(triangles, &vertices));
    Some(Reordering {
        vertices,
        triangles,
    })
}

impl Hierarchy {
    /// Every level renumbered for locality (vertices along the Hilbert curve, triangles by
    /// their first vertex on it; a level whose order is already local is kept), with the
    /// refinement relations renumbered to match; returns the renumberings, coarsest level
    /// first (`None` for a level kept in its order).
    pub fn reordered(self) -> (Hierarchy, Vec<Option<Arc<Reordering>>>) {
        let orders: Vec<Option<Arc<Reordering>>> = self
            .levels
            .iter()
            .map(|m| renumbering_for_locality(m).map(Arc::new))
            .collect();
        if orders.iter().all(Option::is_none) {
            return (self, orders);
        }
        let levels: Vec<Mesh> = self
            .levels
            .into_iter()
            .zip(&orders)
            .map(|(m, r)| match r {
                Some(r) => r.apply_shared(&m),
                None => m,
            })
            .collect();
        let refinements = self
            .refinements
            .iter()
            .enumerate()
            .map(|(k, rf)| {
                let (coarse, fine) = (&orders[k], &orders[k + 1]);
                let new_coarse = |c: u32| {
                    coarse
                        .as_ref()
                        .map_or(c, |r| r.vertices.new_of_old[c as usize])
                };
                let parents = (0..rf.parents.len())
                    .into_par_iter()
                    .with_min_len(8192)
                    .map(|v| {
                        let old = fine
                            .as_ref()
                            .map_or(v, |r| r.vertices.old_of_new[v] as usize);
                        rf.parents[old].map(new_coarse)
                    })
                    .collect();
                super::refine::Refinement { parents }
            })
            .collect();
        (
            Hierarchy {
                levels,
                refinements,
            },
            orders,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::disk;

    #[test]
    fn keys_are_ordered_as_by_a_comparison_sort() {
        // Pseudo-random keys with many ties, over the full range and over a narrow one
        // (digits shared by every key are skipped), against a sort by (key, index).
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for (n, mask, base) in [
            (0, 0, 0),
            (1, u32::MAX, 0),
            (5000, u32::MAX, 0),
            (5000, 0x3f, 0),
            (70_000, 0xffff, 0x7000_0000),
            // On all threads: keys spread over the full range, and keys of about one per
            // index (the grouping alone orders them).
            (300_000, u32::MAX, 0),
            (300_000, 0x3_ffff, 0),
        ] {
            let keys: Vec<u32> = (0..n).map(|_| base | (next() as u32 & mask)).collect();
            let mut expected: Vec<u32> = (0..n as u32).collect();
            expected.sort_by_key(|&i| (keys[i as usize], i));
            assert_eq!(order_by_key(&keys), expected, "n = {n}, mask = {mask:#x}");
        }
    }

    #[test]
    fn hilbert_curve_visits_neighbouring_cells_in_turn() {
        // On a 2^BITS grid, consecutive indices are adjacent cells: check a 64 × 64 corner.
        let mut cells: Vec<(u32, u32, u32)> = (0..64u32)
            .flat_map(|x| (0..64u32).map(move |y| (hilbert_index(x, y), x, y)))
            .collect();
        cells.sort_unstable();
        // The first 4096 indices fill the 64 × 64 corner exactly.
        assert_eq!(cells.last().unwrap().0, 4095);
        for w in cells.windows(2) {
            assert_eq!(w[1].0, w[0].0 + 1);
            let d = w[0].1.abs_diff(w[1].1) + w[0].2.abs_diff(w[1].2);
            assert_eq!(d, 1, "{w:?}");
        }
    }

    #[test]
    fn renumbering_is_local_and_undone_exactly() {
        // A disc, then scrambled: a scattered numbering.
        let m = disk([0.0, 0.0], 1.0, 0.03).unwrap();
        let n = m.n_vertices();
        let scramble = Permutation::from_order(
            (0..n as u32)
                .map(|i| ((i as u64 * 7919) % n as u64) as u32)
                .collect(),
        );
        assert!(
            !n.is_multiple_of(7919),
            "7919 is a prime: the scramble is a bijection"
        );
        let user = Reordering {
            vertices: scramble,
            triangles: Permutation::identity(m.n_triangles()),
        }
        .apply(&m);
        assert!(edge_span(&user) > 10.0, "{}", edge_span(&user));
        let r = renumbering_for_locality(&user).expect("a scrambled order is renumbered");
        let internal = r.apply(&user);
        assert!(edge_span(&internal) < 3.0, "{}", edge_span(&internal));
        // Triangles follow their first vertex in the new order.
        let first = |t: &[u32; 3]| t.iter().copied().min();
        assert!(internal
            .triangles
            .windows(2)
            .all(|w| first(&w[0]) <= first(&w[1])));
        // The same triangles (as point sets) with the same regions, and undone exactly.
        let back = r.undo(&internal);
        assert_eq!(back.points, user.points);
        assert_eq!(back.triangles, user.triangles);
        assert_eq!(back.regions, user.regions);
        let (a, b) = (internal.quality(), user.quality());
        assert!((a.area - b.area).abs() < 1e-14 * b.area);
        assert_eq!((a.l_n, a.s_n, a.unknowns), (b.l_n, b.s_n, b.unknowns));
        // A structured order is kept.
        let grid = crate::mesh::test_square(32);
        assert!(renumbering_for_locality(&grid).is_none());
    }

    #[test]
    fn renumbered_hierarchy_keeps_its_refinement_relations() {
        let h = Hierarchy::refined(disk([0.0, 0.0], 1.0, 0.2).unwrap(), 2);
        let (r, orders) = h.clone().reordered();
        assert_eq!(orders.len(), 3);
        for k in 0..2 {
            // Fine vertex = midpoint of its parents, in the renumbered meshes too (up to the
            // projection of new boundary vertices onto the circle).
            let (c, f) = (&r.levels[k], &r.levels[k + 1]);
            for (v, [a, b]) in r.refinements[k].parents.iter().enumerate() {
                let (pa, pb) = (c.points[*a as usize], c.points[*b as usize]);
                let mid = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
                let p = f.points[v];
                let on_circle = (p[0].hypot(p[1]) - 1.0).abs() < 1e-12;
                assert!(on_circle || (p[0] - mid[0]).abs() + (p[1] - mid[1]).abs() < 1e-14);
            }
        }
    }
}
