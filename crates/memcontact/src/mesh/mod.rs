//! Triangular meshes: the type, its checks and quality report, the boundary and the map
//! between vertices and unknowns (docs/theory.md#triangulation: the unknowns are the
//! interior vertices).

pub(crate) mod boundary;
pub mod generate;
pub mod refine;
pub(crate) mod regions;
pub(crate) mod reorder;

pub use boundary::BoundaryRegions;

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// A point of the plane.
pub type Point = [f64; 2];

/// A conforming triangulation `T_n` of P1 triangles, counter-clockwise after [`Mesh::new`].
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Vertex coordinates.
    pub points: Vec<Point>,
    /// Triangles as three vertex indices, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// Region tag of every triangle (a Gmsh physical surface, a polygon part, ...).
    pub regions: Vec<u32>,
    /// Names of the region tags that have one.
    pub region_names: BTreeMap<u32, String>,
    /// The curved boundary the mesh approximates, if any: refinement moves new boundary
    /// vertices onto it so that Ω_n approaches Ω.
    pub curve: Option<Circle>,
    /// Named boundary regions (tagged boundary edges: Gmsh physical curves, generator
    /// sides), for boundary heights and free edges.
    pub boundary: BoundaryRegions,
    /// For a mesh renumbered for locality before assembly: how it was renumbered from the
    /// mesh the user gave (whose numbering nodal input data and all outputs use); `None`
    /// for a mesh in the user's own numbering.
    pub numbering: Option<std::sync::Arc<reorder::Reordering>>,
}

/// A circle: the boundary of a disc domain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre.
    pub center: Point,
    /// Radius.
    pub radius: f64,
}

impl Circle {
    /// The point of the circle closest to `p` (radial projection).
    pub fn project(&self, p: Point) -> Point {
        let (dx, dy) = (p[0] - self.center[0], p[1] - self.center[1]);
        let r = (dx * dx + dy * dy).sqrt();
        if r == 0.0 {
            return p;
        }
        let s = self.radius / r;
        [self.center[0] + dx * s, self.center[1] + dy * s]
    }
}

/// Geometric quality figures of a mesh (docs/theory.md#triangulation: `l_n`, `s_n`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeshQuality {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Number of unknowns: the vertices not on the boundary ∂Ω_n.
    pub unknowns: usize,
    /// `l_n`: the largest triangle diameter (longest edge).
    pub l_n: f64,
    /// `s_n`: the largest ratio diameter / inscribed-circle diameter.
    pub s_n: f64,
    /// The smallest interior angle, in degrees.
    pub min_angle_deg: f64,
    /// Total area of Ω_n.
    pub area: f64,
}

/// Which of `n` vertices the triangles use (all vertex indices below `n`), marked on all
/// threads.
pub(crate) fn used_vertices(n: usize, triangles: &[[u32; 3]]) -> Vec<bool> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let used: Vec<AtomicBool> = (0..n)
        .into_par_iter()
        .with_min_len(8192)
        .map(|_| AtomicBool::new(false))
        .collect();
    triangles.par_iter().with_min_len(8192).for_each(|t| {
        for &v in t {
            used[v as usize].store(true, Relaxed);
        }
    });
    used.into_par_iter().map(AtomicBool::into_inner).collect()
}

impl Mesh {
    /// Builds a mesh and checks it: finite coordinates, valid indices, no degenerate or
    /// inverted triangle, no duplicate or unused vertex, no non-manifold edge. A mesh whose
    /// triangles are all clockwise is reoriented; a mix of orientations is an error
    /// (the minority triangles are inverted). `regions` may be empty (all region 0).
    pub fn new(
        points: Vec<Point>,
        mut triangles: Vec<[u32; 3]>,
        mut regions: Vec<u32>,
        region_names: BTreeMap<u32, String>,
    ) -> Result<Mesh> {
        if regions.is_empty() {
            regions = vec![0; triangles.len()];
        }
        if regions.len() != triangles.len() {
            return Err(Error::Mesh(format!(
                "{} region tags for {} triangles",
                regions.len(),
                triangles.len()
            )));
        }
        if triangles.is_empty() {
            return Err(Error::Mesh("the mesh has no triangle".into()));
        }
        // The first offending vertex and triangle, searched on all threads.
        use crate::sparse::first_where;
        use rayon::prelude::*;
        let bad_point = first_where(&points, |p| !p[0].is_finite() | !p[1].is_finite());
        if let Some(i) = bad_point {
            let p = points[i];
            return Err(Error::Mesh(format!(
                "vertex {i} has a non-finite coordinate ({}, {})",
                p[0], p[1]
            )));
        }
        let n = points.len();
        let bad_triangle = first_where(&triangles, |t| {
            let out = t.iter().fold(false, |o, &v| o | (v as usize >= n));
            out | (t[0] == t[1]) | (t[1] == t[2]) | (t[0] == t[2])
        });
        if let Some(k) = bad_triangle {
            let t = triangles[k];
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::Mesh(format!(
                    "triangle {k} uses vertex {v}, but the mesh has only {n} vertices"
                )));
            }
            return Err(Error::Mesh(format!(
                "triangle {k} repeats a vertex: {:?}",
                t
            )));
        }
        // Degenerate and orientation checks: one parallel pass for the first degenerate
        // triangle and the number of clockwise ones.
        let (degenerate, negative) = triangles
            .par_iter()
            .enumerate()
            .with_min_len(8192)
            .fold(
                || (usize::MAX, 0usize),
                |(first, neg), (k, t)| {
                    let a = signed_area(&points, t);
                    let d2 = longest_edge_squared(&points, t);
                    // |2A| ≤ 2e-12 d², d the longest edge (squared lengths, no roots); an
                    // area or edge that overflows is refused with the degenerate ones.
                    let degenerate = !(a.is_finite() && d2.is_finite()) || a.abs() <= 1e-12 * d2;
                    (
                        if degenerate { first.min(k) } else { first },
                        neg + usize::from(a < 0.0),
                    )
                },
            )
            .reduce(|| (usize::MAX, 0), |x, y| (x.0.min(y.0), x.1 + y.1));
        if degenerate != usize::MAX {
            let t = triangles[degenerate];
            let (a, d2) = (signed_area(&points, &t), longest_edge_squared(&points, &t));
            if !(a.is_finite() && d2.is_finite()) {
                let far = t
                    .iter()
                    .map(|&v| points[v as usize])
                    .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
                return Err(Error::Mesh(format!(
                    "triangle {degenerate} (vertices {}, {}, {}) has coordinates up to {far:e}: \
                     its area overflows double precision; rescale the mesh (units)",
                    t[0], t[1], t[2]
                )));
            }
            return Err(Error::Mesh(format!(
                "triangle {degenerate} (vertices {}, {}, {}) is degenerate: area {:e}",
                t[0],
                t[1],
                t[2],
                signed_area(&points, &t)
            )));
        }
        if negative == triangles.len() {
            triangles
                .par_iter_mut()
                .with_min_len(8192)
                .for_each(|t| t.swap(1, 2));
        } else if negative > 0 {
            // The minority orientation is the inverted one.
            let inverted_is_negative = 2 * negative <= triangles.len();
            let (k, t) = triangles
                .par_iter()
                .enumerate()
                .with_min_len(8192)
                .find_first(|(_, t)| (signed_area(&points, t) < 0.0) == inverted_is_negative)
                .expect("some triangle has the minority orientation");
            let count = if inverted_is_negative {
                negative
            } else {
                triangles.len() - negative
            };
            return Err(Error::Mesh(format!(
                "triangle {k} (vertices {}, {}, {}) is inverted: its orientation is opposite \
                 to that of the other triangles ({count} of {} are inverted)",
                t[0],
                t[1],
                t[2],
                triangles.len()
            )));
        }
        let mesh = Mesh {
            points,
            triangles,
            regions,
            region_names,
            curve: None,
            boundary: BoundaryRegions::default(),
            numbering: None,
        };
        mesh.check_vertices()?;
        mesh.check_edges()?;
        Ok(mesh)
    }

    /// Unused and duplicate vertices are errors.
    fn check_vertices(&self) -> Result<()> {
        use rayon::prelude::*;
        let used = used_vertices(self.points.len(), &self.triangles);
        if let Some(v) = used.iter().position(|u| !u) {
            let count = used.iter().filter(|u| !**u).count();
            return Err(Error::Mesh(format!(
                "vertex {v} at ({}, {}) is used by no triangle ({count} unused vertices)",
                self.points[v][0], self.points[v][1]
            )));
        }
        // Duplicates: equal coordinates are neighbours once sorted (+0.0 normalises -0.0).
        let mut keys: Vec<(u64, u64, u32)> = self
            .points
            .par_iter()
            .enumerate()
            .with_min_len(8192)
            .map(|(i, p)| ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits(), i as u32))
            .collect();
        keys.par_sort_unstable();
        let duplicate = keys
            .par_windows(2)
            .filter(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1))
            .map(|w| (w[0].2.min(w[1].2), w[0].2.max(w[1].2)))
            .min();
        if let Some((j, i)) = duplicate {
            let p = self.points[i as usize];
            return Err(Error::Mesh(format!(
                "vertices {j} and {i} are duplicates at ({}, {})",
                p[0], p[1]
            )));
        }
        Ok(())
    }

    /// An edge shared by more than two triangles, or by two triangles that traverse it in
    /// the same direction (a fold), is an error. With the triangles oriented alike, both
    /// show as a directed edge `a → b` used twice: the out-edges of every vertex are
    /// gathered (a counting sort) and checked for repeats, in parallel; the error names the
    /// smallest offending edge.
    fn check_edges(&self) -> Result<()> {
        use rayon::prelude::*;
        let n = self.points.len();
        // Out-edges a → b of every vertex a (the head b alone: the triangles of an edge
        // found wrong are looked up afterwards).
        let (ptr, out) = crate::sparse::group_by_key(n, self.triangles.len(), |k| {
            let t = self.triangles[k];
            [0, 1, 2].map(|e| Some((t[e], t[(e + 1) % 3])))
        });
        let repeated = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .filter_map(|a| {
                let list = &out[ptr[a]..ptr[a + 1]];
                let a = a as u32;
                list.iter()
                    .enumerate()
                    .filter(|&(i, b)| list[i + 1..].contains(b))
                    .map(|(_, &b)| (a.min(b), a.max(b)))
                    .min()
            })
            .min();
        let Some((a, b)) = repeated else {
            return Ok(());
        };
        // All the triangles on the edge: three or more is non-manifold, else a fold.
        let users: Vec<u32> = (0..self.triangles.len() as u32)
            .filter(|&k| {
                let t = self.triangles[k as usize];
                t.contains(&a) && t.contains(&b)
            })
            .collect();
        if users.len() > 2 {
            Err(Error::Mesh(format!(
                "edge ({a}, {b}) is non-manifold: shared by triangles {users:?}"
            )))
        } else {
            Err(Error::Mesh(format!(
                "triangles {} and {} overlap across edge ({a}, {b})",
                users[0], users[1]
            )))
        }
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.points.len()
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The region tags of the triangles, sorted and without repetition (found on all
    /// threads: fields are bound to them once per data item).
    pub fn region_tags(&self) -> Vec<u32> {
        use rayon::prelude::*;
        let distinct = |c: &[u32]| {
            let mut seen = std::collections::BTreeSet::new();
            let mut last = None;
            for &t in c {
                if last != Some(t) {
                    seen.insert(t);
                    last = Some(t);
                }
            }
            seen
        };
        let seen =
            self.regions
                .par_chunks(1 << 16)
                .map(distinct)
                .reduce(Default::default, |mut a, b| {
                    a.extend(b);
                    a
                });
        seen.into_iter().collect()
    }

    /// The boundary edges ∂Ω_n: edges of exactly one triangle, as `(a, b)` in the
    /// triangle's (counter-clockwise) order, in triangle order. An edge `a → b` of a
    /// triangle is on the boundary when no other triangle around `a` contains `b`.
    pub fn boundary_edges(&self) -> Vec<[u32; 2]> {
        self.boundary_edges_with(&VertexTriangles::new(self))
    }

    /// [`Mesh::boundary_edges`] with a prebuilt vertex → triangles adjacency.
    pub fn boundary_edges_with(&self, adj: &VertexTriangles) -> Vec<[u32; 2]> {
        use rayon::prelude::*;
        self.triangles
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .flat_map_iter(|(k, t)| {
                let adj = &adj;
                (0..3).filter_map(move |e| {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    let shared = adj
                        .of(a as usize)
                        .iter()
                        .any(|&o| o as usize != k && self.triangles[o as usize].contains(&b));
                    (!shared).then_some([a, b])
                })
            })
            .collect()
    }

    /// `true` for every vertex on the boundary ∂Ω_n.
    pub fn boundary_vertices(&self) -> Vec<bool> {
        self.patches().1
    }

    /// The vertex → triangles adjacency (the patches `Q_i`) and the boundary vertices
    /// ([`Mesh::boundary_vertices_with`]): built once, shared by assembly, its data checks
    /// and the quality report.
    pub fn patches(&self) -> (VertexTriangles, Vec<bool>) {
        let adj = VertexTriangles::new(self);
        let boundary = self.boundary_vertices_with(&adj);
        (adj, boundary)
    }

    /// [`Mesh::boundary_vertices`] with a prebuilt vertex → triangles adjacency.
    ///
    /// The triangles are oriented alike and use every directed edge once ([`Mesh::new`]),
    /// so an edge `v → b` is shared exactly when `b → v` exists: v is interior when the
    /// vertices following it in its triangles are the vertices preceding it (its fan
    /// closes). One parallel pass over the vertices, without branches on the mesh's data
    /// for the usual fans of up to 16 triangles.
    pub fn boundary_vertices_with(&self, adj: &VertexTriangles) -> Vec<bool> {
        use rayon::prelude::*;
        const NEXT: [usize; 3] = [1, 2, 0];
        const PREV: [usize; 3] = [2, 0, 1];
        let tri = &self.triangles;
        (0..self.points.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|v| {
                let fan = adj.of(v);
                let v = v as u32;
                let ends = |k: u32| {
                    let t = tri[k as usize];
                    let a = corner(t, v);
                    (t[NEXT[a]], t[PREV[a]])
                };
                match fan.len() {
                    0..=8 => !fan_closes::<8>(fan, ends),
                    9..=SMALL_FAN => !fan_closes::<SMALL_FAN>(fan, ends),
                    _ => {
                        let (mut next, mut prev): (Vec<u32>, Vec<u32>) =
                            fan.iter().map(|&k| ends(k)).unzip();
                        next.sort_unstable();
                        prev.sort_unstable();
                        next != prev
                    }
                }
            })
            .collect()
    }

    /// Signed area of triangle `k` (positive: counter-clockwise).
    pub fn area(&self, k: usize) -> f64 {
        signed_area(&self.points, &self.triangles[k])
    }

    /// [`Mesh::area`] of every triangle, in one parallel pass (the load integrals of an
    /// assembly share it instead of gathering each triangle's corners once per use).
    pub fn areas(&self) -> Vec<f64> {
        use rayon::prelude::*;
        self.triangles
            .par_iter()
            .with_min_len(4096)
            .map(|t| signed_area(&self.points, t))
            .collect()
    }

    /// The three corner coordinates of triangle `k`.
    pub fn corners(&self, k: usize) -> [Point; 3] {
        let t = self.triangles[k];
        [
            self.points[t[0] as usize],
            self.points[t[1] as usize],
            self.points[t[2] as usize],
        ]
    }

    /// Total area of Ω_n.
    pub fn total_area(&self) -> f64 {
        (0..self.triangles.len()).map(|k| self.area(k)).sum()
    }

    /// The quality report: counts, `l_n`, `s_n`, smallest angle (one parallel pass over
    /// the triangles; the smallest angle comes from the largest cosine, one `acos` in all).
    pub fn quality(&self) -> MeshQuality {
        self.quality_with(&self.boundary_vertices())
    }

    /// [`Mesh::quality`] given the boundary vertices ([`Mesh::boundary_vertices`]).
    pub fn quality_with(&self, boundary: &[bool]) -> MeshQuality {
        use rayon::prelude::*;
        // Per block of triangles (fixed, so that the area sums alike for any thread count):
        // the longest edge, the largest diameter-to-inscribed-diameter ratio, the cosine of
        // the smallest angle (opposite the shortest edge) and the area.
        const BLOCK: usize = 4096;
        let block = |b: usize| {
            let mut acc = (0.0f64, 0.0f64, f64::NEG_INFINITY, 0.0);
            for k in b * BLOCK..((b + 1) * BLOCK).min(self.triangles.len()) {
                let c = self.corners(k);
                let e = [dist(c[1], c[2]), dist(c[2], c[0]), dist(c[0], c[1])];
                let a = self.area(k).abs();
                let d = e[0].max(e[1]).max(e[2]);
                // Inscribed circle: radius 2A / perimeter, so d / 2r = d · perimeter / 4A.
                let ratio = d * (e[0] + e[1] + e[2]) / (4.0 * a);
                let i = if e[0] <= e[1] && e[0] <= e[2] {
                    0
                } else if e[1] <= e[2] {
                    1
                } else {
                    2
                };
                let (opp, b, cc) = (e[i], e[(i + 1) % 3], e[(i + 2) % 3]);
                let cos = (b * b + cc * cc - opp * opp) / (2.0 * b * cc);
                acc = (acc.0.max(d), acc.1.max(ratio), acc.2.max(cos), acc.3 + a);
            }
            acc
        };
        let blocks: Vec<(f64, f64, f64, f64)> = (0..self.triangles.len().div_ceil(BLOCK))
            .into_par_iter()
            .map(block)
            .collect();
        let (l_n, s_n, max_cos, area) = blocks
            .iter()
            .fold((0.0f64, 0.0f64, f64::NEG_INFINITY, 0.0), |x, y| {
                (x.0.max(y.0), x.1.max(y.1), x.2.max(y.2), x.3 + y.3)
            });
        MeshQuality {
            vertices: self.points.len(),
            triangles: self.triangles.len(),
            unknowns: boundary.iter().filter(|b| !**b).count(),
            l_n,
            s_n,
            min_angle_deg: max_cos.clamp(-1.0, 1.0).acos().to_degrees(),
            area,
        }
    }

    /// The name of region `tag`, or the tag as text.
    pub fn region_name(&self, tag: u32) -> String {
        self.region_names
            .get(&tag)
            .cloned()
            .unwrap_or_else(|| tag.to_string())
    }
}

/// Whether a fan of at most `N` triangles closes: every vertex following the centre in
/// one of them (`ends(k).0`) precedes it in another (`ends(k).1`). The vertices following
/// the centre are distinct, and so are those preceding it, so it closes exactly when every
/// one finds its match. Compared in fixed-size buffers, without branches.
#[inline]
fn fan_closes<const N: usize>(fan: &[u32], ends: impl Fn(u32) -> (u32, u32)) -> bool {
    let (mut next, mut prev) = ([0; N], [u32::MAX; N]);
    for (i, &k) in fan.iter().enumerate() {
        (next[i], prev[i]) = ends(k);
    }
    let shared: usize = next[..fan.len()]
        .iter()
        .map(|&b| prev.iter().map(|&c| (b == c) as usize).sum::<usize>())
        .sum();
    shared == fan.len()
}

/// Fans of up to this many triangles are compared in fixed-size buffers by
/// [`Mesh::boundary_vertices_with`] (larger ones by sorting).
const SMALL_FAN: usize = 16;

/// The triangles around every vertex (the patch `Q_i` of the paper).
#[derive(Debug, Clone)]
pub struct VertexTriangles {
    /// The triangles of vertex `v` are `tri[ptr[v]..ptr[v + 1]]` (fewer than 2³² entries:
    /// three per triangle, and triangles are numbered by `u32`).
    ptr: Vec<u32>,
    tri: Vec<u32>,
}

impl VertexTriangles {
    /// Builds the adjacency of `mesh`, each vertex's triangles in increasing order (on
    /// all threads for large meshes, with the same result for any number of them).
    pub fn new(mesh: &Mesh) -> VertexTriangles {
        let (ptr, tri) = crate::sparse::group_by_key(mesh.n_vertices(), mesh.n_triangles(), |k| {
            mesh.triangles[k].map(|v| Some((v, k as u32)))
        });
        use rayon::prelude::*;
        let ptr = ptr
            .par_iter()
            .with_min_len(8192)
            .map(|&p| p as u32)
            .collect();
        VertexTriangles { ptr, tri }
    }

    /// The triangles having vertex `v`.
    #[inline]
    pub fn of(&self, v: usize) -> &[u32] {
        &self.tri[self.ptr[v] as usize..self.ptr[v + 1] as usize]
    }
}

/// The map between mesh vertices and unknowns: the unknowns are the interior vertices `a_1,
/// ..., a_m` (docs/theory.md#triangulation). Vectors over unknowns and over vertices are
/// different things; convert only through this type.
#[derive(Debug, Clone)]
pub struct DofMap {
    /// `vertex[i]`: the mesh vertex of unknown `i`.
    pub vertex: Vec<u32>,
    /// `dof[v]`: the unknown of vertex `v`, or [`DofMap::NONE`] on the boundary (four
    /// bytes per vertex; read through [`DofMap::of`]).
    dof: Vec<u32>,
}

impl DofMap {
    /// Numbers the interior vertices of `mesh` in vertex order.
    pub fn new(mesh: &Mesh) -> DofMap {
        DofMap::with_adjacency(mesh, &VertexTriangles::new(mesh))
    }

    /// `n` unknowns on `n` vertices, all interior: the unknowns of a level that is no mesh
    /// (an aggregation level of algebraic multigrid).
    pub fn all(n: usize) -> DofMap {
        DofMap {
            vertex: (0..n as u32).collect(),
            dof: (0..n as u32).collect(),
        }
    }

    /// The mark of a vertex without an unknown in `dof` (no mesh has 2³² − 1 vertices:
    /// they are numbered by `u32`).
    pub const NONE: u32 = u32::MAX;

    /// The unknowns `vertex` and, per vertex, its unknown or [`DofMap::NONE`].
    pub(crate) fn from_parts(vertex: Vec<u32>, dof: Vec<u32>) -> DofMap {
        DofMap { vertex, dof }
    }

    /// The unknown of vertex `v`, or `None` on the boundary.
    #[inline(always)]
    pub fn of(&self, v: usize) -> Option<u32> {
        let d = self.dof[v];
        (d != Self::NONE).then_some(d)
    }

    /// `true` when vertex `v` carries no unknown.
    #[inline(always)]
    pub fn is_fixed(&self, v: usize) -> bool {
        self.dof[v] == Self::NONE
    }

    /// Number of mesh vertices.
    pub fn n_vertices(&self) -> usize {
        self.dof.len()
    }

    /// Every vertex's unknown, or `None`, in vertex order.
    pub fn per_vertex(&self) -> impl ExactSizeIterator<Item = Option<u32>> + '_ {
        self.dof.iter().map(|&d| (d != Self::NONE).then_some(d))
    }

    /// `value(i)` at the vertex of every unknown i, `boundary` elsewhere (in parallel for
    /// large meshes).
    pub fn gather<T: Copy + Send + Sync>(
        &self,
        value: impl Fn(usize) -> T + Sync,
        boundary: T,
    ) -> Vec<T> {
        use rayon::prelude::*;
        let at = |&d: &u32| {
            if d == Self::NONE {
                boundary
            } else {
                value(d as usize)
            }
        };
        if self.dof.len() >= 1 << 16 {
            self.dof.par_iter().with_min_len(4096).map(at).collect()
        } else {
            self.dof.iter().map(at).collect()
        }
    }

    /// [`DofMap::new`] with a prebuilt vertex → triangles adjacency.
    pub fn with_adjacency(mesh: &Mesh, adj: &VertexTriangles) -> DofMap {
        let boundary = mesh.boundary_vertices_with(adj);
        let mut vertex = Vec::with_capacity(boundary.len());
        let mut dof = vec![Self::NONE; boundary.len()];
        for (v, &b) in boundary.iter().enumerate() {
            if !b {
                dof[v] = vertex.len() as u32;
                vertex.push(v as u32);
            }
        }
        DofMap { vertex, dof }
    }

    /// Number of unknowns `m`.
    pub fn len(&self) -> usize {
        self.vertex.len()
    }

    /// `true` when the mesh has no interior vertex.
    pub fn is_empty(&self) -> bool {
        self.vertex.is_empty()
    }

    /// A vector over unknowns extended to all vertices, with `boundary` on ∂Ω_n.
    pub fn to_vertices(&self, x: &[f64], boundary: f64) -> Vec<f64> {
        self.gather(|i| x[i], boundary)
    }

    /// A vector over all vertices restricted to the unknowns.
    pub fn to_unknowns(&self, x: &[f64]) -> Vec<f64> {
        use rayon::prelude::*;
        self.vertex
            .par_iter()
            .with_min_len(4096)
            .map(|&v| x[v as usize])
            .collect()
    }
}

/// The local index (0, 1 or 2) of vertex `v` in triangle `t`, which must contain it
/// (computed without branches: assembly asks it for every triangle of every patch).
#[inline]
pub fn corner(t: [u32; 3], v: u32) -> usize {
    (t[1] == v) as usize + 2 * (t[2] == v) as usize
}

/// Twice-signed area / 2 of a triangle given by vertex indices.
pub fn signed_area(points: &[Point], t: &[u32; 3]) -> f64 {
    let [a, b, c] = [
        points[t[0] as usize],
        points[t[1] as usize],
        points[t[2] as usize],
    ];
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
}

/// The square of the longest edge of a triangle given by vertex indices.
fn longest_edge_squared(points: &[Point], t: &[u32; 3]) -> f64 {
    let p = |i: usize| points[t[i] as usize];
    let d2 = |a: Point, b: Point| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
    d2(p(0), p(1)).max(d2(p(1), p(2))).max(d2(p(2), p(0)))
}

/// Euclidean distance.
pub fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// The unit square cut into `n × n` cells, each into two triangles (tests of every
/// layer).
#[cfg(test)]
/// The unit square cut into `n × n` cells, each into two triangles.
pub(crate) fn test_square(n: usize) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([i as f64 / n as f64, j as f64 / n as f64]);
        }
    }
    let mut t = Vec::new();
    let w = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * w + i;
            t.push([a, a + 1, a + w + 1]);
            t.push([a, a + w + 1, a + w]);
        }
    }
    Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        let p = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]];
        let t = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
    }

    #[test]
    fn vertex_triangles_list_each_vertex_in_triangle_order_for_any_thread_count() {
        // A grid large enough to be built in ranges, its triangles in a scattered order.
        let w = 300;
        let points: Vec<Point> = (0..w * w)
            .map(|k| [(k % w) as f64, (k / w) as f64])
            .collect();
        let mut cells = Vec::new();
        for j in 0..w - 1 {
            for i in 0..w - 1 {
                let v = (j * w + i) as u32;
                let (r, u, ru) = (v + 1, v + w as u32, v + w as u32 + 1);
                cells.push([v, r, ru]);
                cells.push([v, ru, u]);
            }
        }
        let m = cells.len();
        let triangles: Vec<[u32; 3]> = (0..m).map(|k| cells[(k * 7919) % m]).collect();
        let mesh = Mesh::new(points, triangles, vec![], BTreeMap::new()).unwrap();
        let mut lists = vec![Vec::new(); mesh.n_vertices()];
        for (k, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                lists[v as usize].push(k as u32);
            }
        }
        for threads in [1, 2, 3] {
            let adj = crate::parallel::on_threads(threads, || VertexTriangles::new(&mesh));
            for (v, list) in lists.iter().enumerate() {
                assert_eq!(adj.of(v), &list[..], "vertex {v}, {threads} threads");
            }
        }
    }

    #[test]
    fn region_tags_are_the_distinct_tags_sorted() {
        let mut mesh = square();
        assert_eq!(mesh.region_tags(), vec![0]);
        // Many triangles with tags in runs and scattered, across several chunks.
        let n: usize = 300_000;
        mesh.regions = (0..n)
            .map(|k| {
                if k % 1000 < 900 {
                    7
                } else {
                    (k * 7919 % 13) as u32 * 3
                }
            })
            .collect();
        let mut expected = mesh.regions.clone();
        expected.sort_unstable();
        expected.dedup();
        assert_eq!(expected.len(), 14);
        assert_eq!(mesh.region_tags(), expected);
    }

    #[test]
    fn boundary_and_dofs() {
        let m = square();
        assert_eq!(m.boundary_edges().len(), 4);
        let d = DofMap::new(&m);
        assert_eq!(d.vertex, vec![4]);
        let q = m.quality();
        assert_eq!(q.unknowns, 1);
        assert!((q.area - 1.0).abs() < 1e-15);
        assert!((q.min_angle_deg - 45.0).abs() < 1e-12);
        assert!((q.l_n - 1.0).abs() < 1e-15);
    }

    #[test]
    fn quality_of_scalene_triangles() {
        // Two triangles with different smallest angles, each at a different corner.
        let p = vec![[0.0, 0.0], [4.0, 0.0], [1.0, 2.0], [5.0, 3.0]];
        let m = Mesh::new(
            p.clone(),
            vec![[0, 1, 2], [1, 3, 2]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap();
        let q = m.quality();
        let angle = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
            // At a, between b and c.
            let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
            (u[0] * v[1] - u[1] * v[0])
                .abs()
                .atan2(u[0] * v[0] + u[1] * v[1])
        };
        let mut smallest = f64::INFINITY;
        let mut ratio: f64 = 0.0;
        let (mut longest, mut area): (f64, f64) = (0.0, 0.0);
        for t in [[0, 1, 2], [1, 3, 2]] {
            let [a, b, c] = t.map(|i| p[i]);
            smallest = smallest
                .min(angle(a, b, c))
                .min(angle(b, c, a))
                .min(angle(c, a, b));
            let e = [dist(b, c), dist(c, a), dist(a, b)];
            let d = e[0].max(e[1]).max(e[2]);
            let t_area =
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            let r = 2.0 * t_area / (e[0] + e[1] + e[2]);
            ratio = ratio.max(d / (2.0 * r));
            longest = longest.max(d);
            area += t_area;
        }
        assert!(
            (q.min_angle_deg - smallest.to_degrees()).abs() < 1e-10,
            "{q:?}"
        );
        assert!((q.s_n - ratio).abs() < 1e-12 * ratio, "{q:?}");
        assert_eq!(q.l_n, longest);
        assert!((q.area - area).abs() < 1e-14);
    }

    /// The boundary vertices as the ends of the boundary edges (an edge of one triangle).
    fn ends_of_boundary_edges(m: &Mesh) -> Vec<bool> {
        let mut on = vec![false; m.n_vertices()];
        for [a, b] in m.boundary_edges() {
            on[a as usize] = true;
            on[b as usize] = true;
        }
        on
    }

    #[test]
    fn boundary_vertices_are_the_ends_of_boundary_edges() {
        let sq = |a: f64, b: f64| vec![[a, a], [b, a], [b, b], [a, b]];
        let holed = generate::polygon(&generate::PolygonSpec {
            outer: sq(0.0, 1.0),
            holes: vec![sq(0.3, 0.5), sq(0.6, 0.8)],
            regions: Vec::new(),
            size: 0.05,
            min_angle: 25.0,
        })
        .unwrap();
        // Fans larger than the small buffers: a wheel of 40 spokes around an interior
        // centre, and a half wheel of 20 around a boundary one.
        let wheel = |spokes: u32, turn: f64| {
            let mut p = vec![[0.0, 0.0]];
            p.extend((0..=spokes).map(|i| {
                let a = turn * i as f64 / spokes as f64;
                [a.cos(), a.sin()]
            }));
            let full = turn == std::f64::consts::TAU;
            if full {
                p.pop();
            }
            let t = (1..=spokes)
                .map(|i| [0, i, if full && i == spokes { 1 } else { i + 1 }])
                .collect();
            Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
        };
        // Two triangles touching at one vertex (a pinched boundary).
        let bowtie = Mesh::new(
            vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [-1.0, 0.0],
                [-1.0, -1.0],
            ],
            vec![[0, 1, 2], [0, 3, 4]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap();
        let meshes = [
            square(),
            generate::disk([0.0, 0.0], 1.0, 0.05).unwrap(),
            holed,
            wheel(40, std::f64::consts::TAU),
            wheel(20, std::f64::consts::PI),
            bowtie,
        ];
        for m in &meshes {
            let b = m.boundary_vertices();
            assert_eq!(b, ends_of_boundary_edges(m));
            assert!(b.iter().any(|&x| x));
        }
        for m in &meshes[..4] {
            assert!(m.boundary_vertices().iter().any(|&x| !x));
        }
        assert!(!meshes[3].boundary_vertices()[0]);
        assert!(meshes[4].boundary_vertices()[0]);
    }

    #[test]
    fn clockwise_mesh_is_reoriented() {
        let p = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let m = Mesh::new(p, vec![[0, 2, 1]], vec![], BTreeMap::new()).unwrap();
        assert!(m.area(0) > 0.0);
    }

    #[test]
    fn the_first_bad_vertex_or_triangle_is_named() {
        // Enough rows for the parallel searches, with two faults each: the first is named.
        let spec = generate::RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            nx: 200,
            ny: 200,
            diagonal: generate::Diagonal::Right,
        };
        let hierarchy = generate::rectangle(&spec).unwrap();
        let mesh = hierarchy.finest();
        let (n, m) = (mesh.points.len(), mesh.triangles.len());
        let build = |points: Vec<Point>, triangles: Vec<[u32; 3]>| {
            Mesh::new(points, triangles, vec![], BTreeMap::new())
                .unwrap_err()
                .to_string()
        };
        let mut p = mesh.points.clone();
        p[30_000][1] = f64::NAN;
        p[20_000][0] = f64::INFINITY;
        let e = build(p, mesh.triangles.clone());
        assert!(
            e.contains("vertex 20000 has a non-finite coordinate (inf"),
            "{e}"
        );
        let mut t = mesh.triangles.clone();
        t[m - 10][2] = n as u32 + 5;
        t[m - 20] = [7, 8, 7];
        let e = build(mesh.points.clone(), t.clone());
        assert!(
            e.contains(&format!("triangle {} repeats a vertex: [7, 8, 7]", m - 20)),
            "{e}"
        );
        t[m - 30][0] = n as u32;
        let e = build(mesh.points.clone(), t);
        assert!(
            e.contains(&format!(
                "triangle {} uses vertex {n}, but the mesh has only {n}",
                m - 30
            )),
            "{e}"
        );
    }

    #[test]
    fn broken_meshes_are_errors() {
        let p = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let e = Mesh::new(p.clone(), vec![[0, 1, 2]], vec![], BTreeMap::new()).unwrap_err();
        assert!(e.to_string().contains("vertex 3"), "{e}");
        let e = Mesh::new(
            vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
            vec![[0, 1, 2]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("degenerate"), "{e}");
        // Found by fuzzing: one vertex at 4.4e252 made the area overflow (NaN) and the
        // mesh was accepted with a total area of NaN.
        let e = Mesh::new(
            vec![[4.44e252, 4.82e228], [0.415, -0.910], [0.305, -0.819]],
            vec![[0, 1, 2]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
        let e = Mesh::new(
            p.clone(),
            vec![[0, 1, 2], [1, 2, 3]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("inverted"), "{e}");
        let mut p2 = p.clone();
        p2.push([1.0, 0.0]);
        let e = Mesh::new(p2, vec![[0, 1, 2], [4, 3, 2]], vec![], BTreeMap::new()).unwrap_err();
        assert!(e.to_string().contains("duplicates"), "{e}");
        let p3 = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [-1.0, -1.0]];
        let e = Mesh::new(
            p3,
            vec![[0, 1, 2], [1, 3, 2], [0, 4, 1]],
            vec![],
            BTreeMap::new(),
        );
        assert!(e.is_ok());
        let p4 = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, -1.0], [0.5, 2.0]];
        let e = Mesh::new(
            p4,
            vec![[0, 1, 2], [0, 3, 1], [0, 1, 4]],
            vec![],
            BTreeMap::new(),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "mesh: edge (0, 1) is non-manifold: shared by triangles [0, 1, 2]"
        );
        // A fold: two triangles on the same side of an edge, traversing it alike.
        let p5 = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.4, 0.5]];
        let e = Mesh::new(p5, vec![[0, 1, 2], [0, 1, 3]], vec![], BTreeMap::new()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "mesh: triangles 0 and 1 overlap across edge (0, 1)"
        );
    }
}
