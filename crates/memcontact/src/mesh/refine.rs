//! Uniform refinement (every triangle into four) and the hierarchy of nested levels that
//! multigrid needs, with the prolongation between consecutive levels.

use super::{Mesh, Point};
use rayon::prelude::*;

/// How the vertices of a fine level come from the coarse one: fine vertex `v` has the
/// value `0.5 * (coarse[parents[v][0]] + coarse[parents[v][1]])` of a coarse P1 function
/// (`parents[v] = [c, c]` when `v` sits on coarse vertex `c`). This is the exact P1
/// prolongation for nested meshes.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// One pair of coarse vertices per fine vertex.
    pub parents: Vec<[u32; 2]>,
}

impl Refinement {
    /// Interpolates a coarse vertex vector onto the fine vertices.
    pub fn prolongate(&self, coarse: &[f64]) -> Vec<f64> {
        self.parents
            .iter()
            .map(|&[a, b]| 0.5 * (coarse[a as usize] + coarse[b as usize]))
            .collect()
    }
}

/// Nested meshes, coarsest first; `refinements[k]` maps level `k` to level `k + 1`.
#[derive(Debug, Clone)]
pub struct Hierarchy {
    /// The levels, coarsest first; the last one is the mesh the problem is solved on.
    pub levels: Vec<Mesh>,
    /// The vertex relations between consecutive levels.
    pub refinements: Vec<Refinement>,
}

impl Hierarchy {
    /// A hierarchy of one level (no multigrid possible).
    pub fn single(mesh: Mesh) -> Hierarchy {
        Hierarchy {
            levels: vec![mesh],
            refinements: vec![],
        }
    }

    /// The finest level.
    pub fn finest(&self) -> &Mesh {
        self.levels
            .last()
            .expect("a hierarchy has at least one level")
    }

    /// Number of levels.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// The number of vertices of every level, coarsest first (what multigrid's levels read
    /// of the coarser meshes, which may then be released).
    pub fn vertex_counts(&self) -> Vec<usize> {
        self.levels.iter().map(Mesh::n_vertices).collect()
    }
}

impl Hierarchy {
    /// `mesh` refined uniformly `times` times: `times + 1` nested levels for multigrid.
    pub fn refined(mesh: Mesh, times: usize) -> Hierarchy {
        let mut h = Hierarchy::single(mesh);
        h.refine(times);
        h
    }

    /// Appends `times` uniformly refined levels below the finest one.
    pub fn refine(&mut self, times: usize) {
        for _ in 0..times {
            let (fine, refinement) = refine_uniform(self.finest());
            self.levels.push(fine);
            self.refinements.push(refinement);
        }
    }

    /// The exact P1 prolongation of a vertex vector from level `level` to level `level + 1`.
    ///
    /// # Panics
    /// If `level + 1` is not a level or `coarse` is shorter than level `level`'s vertex count.
    pub fn prolongate(&self, level: usize, coarse: &[f64]) -> Vec<f64> {
        assert!(
            level + 1 < self.levels.len(),
            "prolongate from level {level}: the hierarchy has {} levels",
            self.levels.len()
        );
        assert_eq!(
            coarse.len(),
            self.levels[level].points.len(),
            "prolongate: the vector has the wrong length for level {level}"
        );
        self.refinements[level].prolongate(coarse)
    }
}

/// The edges of a mesh, numbered without hashing: `edge_of[3 k + e]` is the edge of
/// triangle `k` from corner `e` to corner `e + 1`; `ends[i]` are edge `i`'s endpoints
/// (smaller first) and `boundary[i]` tells whether only one triangle uses it.
struct Edges {
    edge_of: Vec<u32>,
    ends: Vec<[u32; 2]>,
    boundary: Vec<bool>,
}

/// Numbers the edges by bucketing the half-edges on their smaller endpoint (a counting
/// sort), then sorting each small bucket: O(E) time, no hash map, edges in lexicographic
/// order of their endpoints.
fn number_edges(n_vertices: usize, triangles: &[[u32; 3]]) -> Edges {
    let n_half = triangles.len() * 3;
    let mut start = vec![0usize; n_vertices + 1];
    for t in triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            start[a.min(b) as usize + 1] += 1;
        }
    }
    for v in 0..n_vertices {
        start[v + 1] += start[v];
    }
    // bucket entry: (larger endpoint, half-edge index)
    let mut bucket = vec![(0u32, 0u32); n_half];
    let mut fill = start.clone();
    for (k, t) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let lo = a.min(b) as usize;
            bucket[fill[lo]] = (a.max(b), (3 * k + e) as u32);
            fill[lo] += 1;
        }
    }
    drop(fill);
    let mut edge_of = vec![0u32; n_half];
    let mut ends = Vec::with_capacity(n_half / 2 + n_vertices);
    let mut boundary = Vec::with_capacity(n_half / 2 + n_vertices);
    for v in 0..n_vertices {
        let b = &mut bucket[start[v]..start[v + 1]];
        b.sort_unstable();
        let mut i = 0;
        while i < b.len() {
            let mut j = i + 1;
            while j < b.len() && b[j].0 == b[i].0 {
                j += 1;
            }
            let id = ends.len() as u32;
            for &(_, h) in &b[i..j] {
                edge_of[h as usize] = id;
            }
            ends.push([v as u32, b[i].0]);
            boundary.push(j - i == 1);
            i = j;
        }
    }
    Edges {
        edge_of,
        ends,
        boundary,
    }
}

/// Whether `p` lies on the circle (up to round-off): only boundary edges with both ends on
/// it are curved edges (a disc with a straight cut or a hole keeps its straight parts).
fn on_circle(c: &super::Circle, p: Point) -> bool {
    (super::dist(p, c.center) - c.radius).abs() <= 1e-9 * c.radius
}

/// Uniform ("red") refinement: every triangle into four by its edge midpoints. Coarse
/// vertices keep their indices and the midpoints follow, one per edge in lexicographic
/// order of the edge's endpoints; triangle `k` becomes triangles `4k .. 4k + 4` with its
/// region. When the mesh approximates a circle (`mesh.curve`), the midpoints of boundary
/// edges whose two ends lie on the circle are moved onto it so that Ω_n approaches the disc; the [`Refinement`] still gives
/// the two edge endpoints (the prolongation stays the P1 interpolation on the old edge).
///
/// The fine mesh is conforming and counter-clockwise if the coarse one is;
/// `V' = V + E`, `T' = 4 T`, `l_n` halves and the angles are unchanged (for straight
/// boundaries).
pub fn refine_uniform(mesh: &Mesh) -> (Mesh, Refinement) {
    let nv = mesh.points.len();
    let edges = number_edges(nv, &mesh.triangles);
    let ne = edges.ends.len();
    let mut points = Vec::with_capacity(nv + ne);
    points.extend_from_slice(&mesh.points);
    let curve = mesh.curve;
    let mids: Vec<Point> = edges
        .ends
        .par_iter()
        .zip(edges.boundary.par_iter())
        .map(|(&[a, b], &on_boundary)| {
            let (p, q) = (mesh.points[a as usize], mesh.points[b as usize]);
            let m = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
            match curve {
                Some(c) if on_boundary && on_circle(&c, p) && on_circle(&c, q) => c.project(m),
                _ => m,
            }
        })
        .collect();
    points.extend_from_slice(&mids);
    drop(mids);
    let mut parents: Vec<[u32; 2]> = Vec::with_capacity(nv + ne);
    parents.extend((0..nv as u32).map(|v| [v, v]));
    parents.extend_from_slice(&edges.ends);

    let nvu = nv as u32;
    let mut triangles = vec![[0u32; 3]; 4 * mesh.triangles.len()];
    triangles
        .par_chunks_mut(4)
        .zip(mesh.triangles.par_iter())
        .zip(edges.edge_of.par_chunks(3))
        .for_each(|((out, t), e)| {
            let [v0, v1, v2] = *t;
            let (m0, m1, m2) = (nvu + e[0], nvu + e[1], nvu + e[2]);
            out[0] = [v0, m0, m2];
            out[1] = [m0, v1, m1];
            out[2] = [m2, m1, v2];
            out[3] = [m0, m1, m2];
        });
    let mut regions = Vec::with_capacity(4 * mesh.regions.len());
    for &r in &mesh.regions {
        regions.extend_from_slice(&[r; 4]);
    }
    let boundary = refine_boundary_regions(&mesh.boundary, &edges.ends, nvu);
    let fine = Mesh {
        points,
        triangles,
        regions,
        region_names: mesh.region_names.clone(),
        curve,
        boundary,
        numbering: None,
    };
    (fine, Refinement { parents })
}

/// The boundary regions of the refined mesh: every tagged edge `[a, b]` becomes `[a, m]`
/// and `[m, b]` with its tag, `m = nv + (the edge's number)` its midpoint. `ends` are the
/// coarse edges in lexicographic order (as [`number_edges`] gives them).
fn refine_boundary_regions(
    coarse: &super::BoundaryRegions,
    ends: &[[u32; 2]],
    nv: u32,
) -> super::BoundaryRegions {
    let mut edges = Vec::with_capacity(2 * coarse.edges.len());
    let mut tags = Vec::with_capacity(2 * coarse.tags.len());
    for (&[a, b], &tag) in coarse.edges.iter().zip(&coarse.tags) {
        let key = [a.min(b), a.max(b)];
        let Ok(id) = ends.binary_search(&key) else {
            continue; // not an edge of the mesh: validated away by construction
        };
        let m = nv + id as u32;
        edges.extend([[a, m], [m, b]]);
        tags.extend([tag, tag]);
    }
    super::BoundaryRegions {
        edges,
        tags,
        names: coarse.names.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Circle;
    use std::collections::BTreeMap;

    /// An L-shaped domain of 6 triangles with two regions.
    fn l_shape() -> Mesh {
        let p = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
            [0.0, 2.0],
            [1.0, 2.0],
        ];
        let t = vec![
            [0, 1, 4],
            [0, 4, 3],
            [1, 2, 5],
            [1, 5, 4],
            [3, 4, 7],
            [3, 7, 6],
        ];
        let names = BTreeMap::from([(1, "a".to_string()), (2, "b".to_string())]);
        Mesh::new(p, t, vec![1, 1, 2, 2, 1, 1], names).unwrap()
    }

    fn revalidate(m: &Mesh) -> Mesh {
        Mesh::new(
            m.points.clone(),
            m.triangles.clone(),
            m.regions.clone(),
            m.region_names.clone(),
        )
        .unwrap()
    }

    #[test]
    fn refinement_counts_area_angles_and_size() {
        let mut m = l_shape();
        for _ in 0..4 {
            let q = m.quality();
            let n_edges = (3 * m.triangles.len() + m.boundary_edges().len()) / 2;
            let (f, r) = refine_uniform(&m);
            let checked = revalidate(&f);
            assert_eq!(checked.triangles, f.triangles, "refinement must stay CCW");
            let qf = f.quality();
            assert_eq!(qf.vertices, q.vertices + n_edges);
            assert_eq!(qf.triangles, 4 * q.triangles);
            assert_eq!(r.parents.len(), qf.vertices);
            assert!((qf.area - 3.0).abs() < 1e-12);
            assert!((qf.l_n - 0.5 * q.l_n).abs() < 1e-12);
            assert!((qf.min_angle_deg - q.min_angle_deg).abs() < 1e-9);
            assert_eq!(f.region_names, m.region_names);
            for k in 0..m.triangles.len() {
                for c in 0..4 {
                    assert_eq!(f.regions[4 * k + c], m.regions[k]);
                }
            }
            // Each child triangle lies in its parent: its centroid is inside.
            m = f;
        }
    }

    #[test]
    fn parents_are_edge_endpoints_and_prolongation_is_exact_for_linear() {
        let h = Hierarchy::refined(l_shape(), 3);
        assert_eq!(h.depth(), 4);
        for level in 0..3 {
            let (c, f) = (&h.levels[level], &h.levels[level + 1]);
            let lin = |p: Point| 3.0 * p[0] - 2.0 * p[1] + 0.25;
            let coarse: Vec<f64> = c.points.iter().map(|&p| lin(p)).collect();
            let fine = h.prolongate(level, &coarse);
            for (v, p) in f.points.iter().enumerate() {
                assert!((fine[v] - lin(*p)).abs() < 1e-12);
                let [a, b] = h.refinements[level].parents[v];
                let (pa, pb) = (c.points[a as usize], c.points[b as usize]);
                assert_eq!(p[0], 0.5 * (pa[0] + pb[0]));
                assert_eq!(p[1], 0.5 * (pa[1] + pb[1]));
            }
        }
    }

    #[test]
    fn disc_refinement_follows_the_circle() {
        // A hexagon inscribed in the unit circle centred at (1, 2).
        let c = [1.0, 2.0];
        let mut p = vec![c];
        for i in 0..6 {
            let a = i as f64 * std::f64::consts::PI / 3.0;
            p.push([c[0] + a.cos(), c[1] + a.sin()]);
        }
        let t: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        let mut m = Mesh::new(p, t, vec![], BTreeMap::new()).unwrap();
        let circle = Circle {
            center: c,
            radius: 1.0,
        };
        m.curve = Some(circle);
        let mut h = Hierarchy::single(m);
        h.refine(5);
        let pi = std::f64::consts::PI;
        let mut prev_err = f64::INFINITY;
        for level in &h.levels {
            let bv = level.boundary_vertices();
            for (v, p) in level.points.iter().enumerate() {
                let r = super::super::dist(*p, c);
                if bv[v] {
                    assert!((r - 1.0).abs() < 1e-14, "boundary vertex {v} at r = {r}");
                } else {
                    assert!(r < 1.0);
                }
            }
            let checked = revalidate(level);
            assert_eq!(checked.triangles, level.triangles);
            let err = pi - level.total_area();
            assert!(err > 0.0 && err < prev_err);
            prev_err = err;
        }
        // The boundary has 6·2^5 chords: the inscribed polygon area.
        let n = 6.0 * 32.0;
        let polygon = 0.5 * n * (2.0 * pi / n).sin();
        assert!((h.finest().total_area() - polygon).abs() < 1e-12);
        assert_eq!(h.finest().curve, Some(circle));
    }
    #[test]
    fn straight_boundary_edges_of_a_curved_mesh_stay_straight() {
        // Half a hexagon: the arc is curved, the diameter through the centre is not.
        let c = [0.0, 0.0];
        let mut p = vec![c];
        for i in 0..4 {
            let a = i as f64 * std::f64::consts::PI / 3.0;
            p.push([a.cos(), a.sin()]);
        }
        let t = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        let mut m = Mesh::new(p, t, vec![], BTreeMap::new()).unwrap();
        m.curve = Some(Circle {
            center: c,
            radius: 1.0,
        });
        let (f, _) = refine_uniform(&m);
        let bv = f.boundary_vertices();
        let on_diameter = f
            .points
            .iter()
            .zip(&bv)
            .filter(|(p, b)| **b && p[1].abs() < 1e-15);
        assert_eq!(on_diameter.count(), 5); // -1, -0.5, 0, 0.5, 1
        let on_arc = f
            .points
            .iter()
            .zip(&bv)
            .filter(|(p, b)| **b && (p[0].hypot(p[1]) - 1.0).abs() < 1e-15);
        assert_eq!(on_arc.count(), 7);
    }
}
