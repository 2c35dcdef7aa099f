//! Named boundary regions: tagged edges of ∂Ω_n (Gmsh physical curves, the generators'
//! sides `left`, `right`, `bottom`, `top`, `outer`, `hole1`, ...), and the split of the
//! boundary into its fixed part Γ_D (u = g) and its free part (the natural condition
//! t ∂u/∂n = 0) that decides which vertices carry unknowns.

use super::{DofMap, Mesh, VertexTriangles};
use crate::error::{Error, Result};
use std::collections::{BTreeMap, HashMap};

/// The tag of the boundary edges no region names (and of the whole boundary of a mesh
/// without boundary regions).
pub const UNTAGGED: u32 = 0;

/// Boundary regions of a mesh: plain arrays, so that a permutation of the vertices carries
/// them (map the vertex indices of `edges`). Boundary edges not listed belong to the
/// untagged region, tag 0 (named `"default"` unless `names` names it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BoundaryRegions {
    /// Boundary edges `[a, b]` (vertex indices, either order) that carry a tag.
    pub edges: Vec<[u32; 2]>,
    /// The tag of every edge of `edges`.
    pub tags: Vec<u32>,
    /// Names of the tags that have one (the keys of `[boundary]` tables).
    pub names: BTreeMap<u32, String>,
}

impl BoundaryRegions {
    /// `true` when no boundary edge is tagged.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// The name of tag `tag`: its own, `"default"` for the edges no region covers (tag 0),
    /// or the tag as text.
    pub fn name(&self, tag: u32) -> String {
        match self.names.get(&tag) {
            Some(name) => name.clone(),
            None if tag == UNTAGGED => UNTAGGED_NAME.to_string(),
            None => tag.to_string(),
        }
    }

    /// The names of the tags, with `"default"` for tag 0 (untagged) unless it has a name
    /// of its own (for messages).
    pub fn labels(&self) -> BTreeMap<u32, String> {
        let mut names = self.names.clone();
        names
            .entry(UNTAGGED)
            .or_insert_with(|| UNTAGGED_NAME.to_string());
        names
    }

    /// The tags named `key` (a name, `"default"` for the edges no region covers, or
    /// a tag written as a number), among `present`.
    pub fn resolve(&self, key: &str, present: &[u32]) -> Vec<u32> {
        let mut by_name: Vec<u32> = self
            .names
            .iter()
            .filter(|(&t, n)| n.as_str() == key && present.contains(&t))
            .map(|(&t, _)| t)
            .collect();
        if key == UNTAGGED_NAME && present.contains(&UNTAGGED) && !by_name.contains(&UNTAGGED) {
            by_name.insert(0, UNTAGGED);
        }
        if !by_name.is_empty() {
            return by_name;
        }
        match key.trim().parse::<u32>() {
            Ok(t) if present.contains(&t) && !self.names.values().any(|n| n == key) => vec![t],
            _ => Vec::new(),
        }
    }
}

/// The name of the boundary edges that no boundary region covers (tag [`UNTAGGED`]): the
/// key that `free` and `[boundary]` tables give them by.
pub const UNTAGGED_NAME: &str = super::regions::DEFAULT;

/// Warnings about boundary region names that `free` and `[boundary]` tables cannot address
/// plainly: a region named [`UNTAGGED_NAME`] (the name of the edges no region covers, and
/// the key of every other region's value in a table), or with an empty name.
pub fn boundary_name_warnings(names: &BTreeMap<u32, String>) -> Vec<String> {
    let mut warnings = Vec::new();
    for (&tag, name) in names {
        if name == UNTAGGED_NAME && tag != UNTAGGED {
            warnings.push(format!(
                "physical curve {tag} is named \"{UNTAGGED_NAME}\", the name of the boundary \
                 edges no physical curve covers: give it by its tag, \"{tag}\", or rename it"
            ));
        } else if name.trim().is_empty() {
            warnings.push(format!(
                "physical curve {tag} has an empty name: give it by its tag, \"{tag}\""
            ));
        }
    }
    warnings
}

/// Every boundary edge of a mesh with its boundary region tag.
#[derive(Debug, Clone)]
pub struct TaggedBoundary {
    /// The boundary edges `[a, b]` (counter-clockwise order of their triangle).
    pub edges: Vec<[u32; 2]>,
    /// Their tags ([`UNTAGGED`] where the mesh names none).
    pub tags: Vec<u32>,
}

impl TaggedBoundary {
    /// The tags present, sorted, without repetition.
    pub fn present(&self) -> Vec<u32> {
        let mut t = self.tags.clone();
        t.sort_unstable();
        t.dedup();
        t
    }
}

impl Mesh {
    /// Returns the mesh with boundary regions: `edges[k]` (boundary edges, either vertex
    /// order) carries `tags[k]`, `names` names the tags. Errors: lengths that differ, an
    /// edge that is not a boundary edge of the mesh, an edge given twice with two tags.
    pub fn with_boundary_regions(
        self,
        edges: Vec<[u32; 2]>,
        tags: Vec<u32>,
        names: BTreeMap<u32, String>,
    ) -> Result<Mesh> {
        if edges.len() != tags.len() {
            return Err(Error::Mesh(format!(
                "{} boundary region tags for {} boundary edges",
                tags.len(),
                edges.len()
            )));
        }
        let uses = self.edge_uses(edges.iter().copied());
        let mut seen: HashMap<(u32, u32), u32> = HashMap::with_capacity(edges.len());
        for ((&[a, b], &tag), &n) in edges.iter().zip(&tags).zip(&uses) {
            let key = (a.min(b), a.max(b));
            if n != 1 {
                return Err(Error::Mesh(format!(
                    "boundary region {}: edge ({a}, {b}) is not an edge of the mesh's boundary",
                    names.get(&tag).cloned().unwrap_or_else(|| tag.to_string())
                )));
            }
            if let Some(other) = seen.insert(key, tag) {
                if other != tag {
                    return Err(Error::Mesh(format!(
                        "boundary edge ({a}, {b}) belongs to two boundary regions ({} and {})",
                        names
                            .get(&other)
                            .cloned()
                            .unwrap_or_else(|| other.to_string()),
                        names.get(&tag).cloned().unwrap_or_else(|| tag.to_string())
                    )));
                }
            }
        }
        Ok(self.with_checked_boundary_regions(edges, tags, names))
    }

    /// [`Mesh::with_boundary_regions`] for edges known to be distinct boundary edges.
    pub(crate) fn with_checked_boundary_regions(
        mut self,
        edges: Vec<[u32; 2]>,
        tags: Vec<u32>,
        names: BTreeMap<u32, String>,
    ) -> Mesh {
        self.boundary = BoundaryRegions { edges, tags, names };
        self
    }

    /// How many triangles have each of `edges` as an edge (either vertex order): 1 on the
    /// boundary, 2 inside, 0 for a pair of vertices that is no edge (or a vertex index out
    /// of range). One pass over the triangles, looking up only the edges whose two ends
    /// are among the given edges' vertices.
    pub fn edge_uses(&self, edges: impl Iterator<Item = [u32; 2]>) -> Vec<u32> {
        use rayon::prelude::*;
        let n = self.n_vertices();
        let mut marked = vec![false; n];
        let mut index: HashMap<(u32, u32), usize> = HashMap::new();
        let slots: Vec<Option<usize>> = edges
            .map(|[a, b]| {
                if a as usize >= n || b as usize >= n || a == b {
                    return None;
                }
                marked[a as usize] = true;
                marked[b as usize] = true;
                let next = index.len();
                Some(*index.entry((a.min(b), a.max(b))).or_insert(next))
            })
            .collect();
        let counts = self
            .triangles
            .par_chunks(1 << 14)
            .fold(
                || vec![0u32; index.len()],
                |mut counts, chunk| {
                    for t in chunk {
                        for e in 0..3 {
                            let (a, b) = (t[e], t[(e + 1) % 3]);
                            if marked[a as usize] & marked[b as usize] {
                                if let Some(&k) = index.get(&(a.min(b), a.max(b))) {
                                    counts[k] += 1;
                                }
                            }
                        }
                    }
                    counts
                },
            )
            .reduce(
                || vec![0u32; index.len()],
                |mut x, y| {
                    x.iter_mut().zip(y).for_each(|(x, y)| *x += y);
                    x
                },
            );
        slots.iter().map(|s| s.map_or(0, |k| counts[k])).collect()
    }

    /// Every boundary edge with its region tag (0 where none is given).
    pub fn tagged_boundary(&self, adj: &VertexTriangles) -> TaggedBoundary {
        let edges = self.boundary_edges_with(adj);
        let tags = if self.boundary.is_empty() {
            vec![UNTAGGED; edges.len()]
        } else {
            let map: HashMap<(u32, u32), u32> = self
                .boundary
                .edges
                .iter()
                .zip(&self.boundary.tags)
                .map(|(&[a, b], &t)| ((a.min(b), a.max(b)), t))
                .collect();
            edges
                .iter()
                .map(|&[a, b]| *map.get(&(a.min(b), a.max(b))).unwrap_or(&UNTAGGED))
                .collect()
        };
        TaggedBoundary { edges, tags }
    }

    /// The names of the boundary regions present, for messages (`left, right, ...`).
    pub fn boundary_listing(&self, tagged: &TaggedBoundary) -> String {
        let names: Vec<String> = tagged
            .present()
            .iter()
            .map(|&t| self.boundary.name(t))
            .collect();
        names.join(", ")
    }

    /// The error for a key of `field` (`boundary.free`, `boundary.height`) that names no
    /// boundary region of the mesh: it lists the regions the mesh has with their kinds
    /// (boundary regions are curves, regions of triangles are surfaces), and says so when
    /// the key names a region of triangles.
    pub fn no_boundary_region(&self, field: &str, key: &str, tagged: &TaggedBoundary) -> Error {
        let surfaces: Vec<String> = self
            .region_tags()
            .iter()
            .map(|&t| self.region_name(t))
            .collect();
        let surface = surfaces.iter().any(|s| s == key);
        Error::Data(format!(
            "{field}: no boundary region named '{key}' in the mesh (boundary regions, \
             curves: {}; regions of triangles, surfaces: {}){}",
            self.boundary_listing(tagged),
            surfaces.join(", "),
            if surface {
                format!(
                    "; '{key}' is a region of triangles: boundary heights and free edges \
                     are given by boundary regions (Gmsh physical curves, generator sides)"
                )
            } else {
                String::new()
            }
        ))
    }

    /// Every boundary region present with its number of edges and its length, in tag
    /// order (the edges no region covers under tag 0).
    pub fn boundary_regions_summary(&self, tagged: &TaggedBoundary) -> Vec<BoundaryRegionSize> {
        let mut sizes: BTreeMap<u32, (usize, f64)> = BTreeMap::new();
        for (&[a, b], &tag) in tagged.edges.iter().zip(&tagged.tags) {
            let s = sizes.entry(tag).or_default();
            s.0 += 1;
            s.1 += super::dist(self.points[a as usize], self.points[b as usize]);
        }
        sizes
            .into_iter()
            .map(|(tag, (edges, length))| BoundaryRegionSize {
                tag,
                name: self.boundary.name(tag),
                edges,
                length,
            })
            .collect()
    }
}

/// A boundary region's size ([`Mesh::boundary_regions_summary`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryRegionSize {
    /// The tag.
    pub tag: u32,
    /// The name (the tag as text when it has none; `default` for the edges no region
    /// covers).
    pub name: String,
    /// The number of boundary edges.
    pub edges: usize,
    /// The total length of its edges.
    pub length: f64,
}

/// The fixed part Γ_D of the boundary: which vertices are fixed (`u = g` there) and which
/// boundary regions are free.
#[derive(Debug, Clone)]
pub struct FixedBoundary {
    /// `fixed[v]`: vertex `v` lies on a fixed boundary edge.
    pub fixed: Vec<bool>,
    /// The boundary edges of Γ_D with their tags.
    pub edges: Vec<([u32; 2], u32)>,
    /// The tags of the fixed boundary regions, sorted.
    pub fixed_tags: Vec<u32>,
}

impl FixedBoundary {
    /// The whole boundary fixed (the paper's frame).
    #[cfg(test)]
    pub fn all(mesh: &Mesh, adj: &VertexTriangles) -> FixedBoundary {
        FixedBoundary::new(mesh, adj, &[]).expect("no free region to resolve")
    }

    /// The boundary of `mesh` without the regions named in `free` (names or tags as text).
    /// A name that is not a boundary region of the mesh is an error listing the regions.
    pub fn new(mesh: &Mesh, adj: &VertexTriangles, free: &[String]) -> Result<FixedBoundary> {
        let tagged = mesh.tagged_boundary(adj);
        let present = tagged.present();
        let mut free_tags = Vec::new();
        for key in free {
            let tags = mesh.boundary.resolve(key, &present);
            if tags.is_empty() {
                return Err(mesh.no_boundary_region("boundary.free", key, &tagged));
            }
            free_tags.extend(tags);
        }
        let mut fixed = vec![false; mesh.n_vertices()];
        let mut edges = Vec::new();
        for (&e, &tag) in tagged.edges.iter().zip(&tagged.tags) {
            if !free_tags.contains(&tag) {
                fixed[e[0] as usize] = true;
                fixed[e[1] as usize] = true;
                edges.push((e, tag));
            }
        }
        let mut fixed_tags: Vec<u32> = edges.iter().map(|e| e.1).collect();
        fixed_tags.sort_unstable();
        fixed_tags.dedup();
        Ok(FixedBoundary {
            fixed,
            edges,
            fixed_tags,
        })
    }

    /// Number of fixed vertices.
    #[cfg(test)]
    pub fn count(&self) -> usize {
        self.fixed.iter().filter(|&&f| f).count()
    }
}

impl DofMap {
    /// Numbers the vertices that are not fixed, in vertex order
    /// (docs/theory.md#boundary-data: the unknowns are all vertices not on Γ_D,
    /// free-boundary vertices included). Blocks of vertices are counted, then numbered, on
    /// all threads (the arrays are mostly fresh memory, whose first writes are page
    /// faults).
    pub fn from_fixed(fixed: &[bool]) -> DofMap {
        use rayon::prelude::*;
        const BLOCK: usize = 1 << 14;
        let counts: Vec<usize> = fixed
            .par_chunks(BLOCK)
            .map(|c| c.iter().filter(|&&f| !f).count())
            .collect();
        let mut vertex = crate::sparse::filled(counts.iter().sum(), 0u32);
        let mut dof = crate::sparse::filled(fixed.len(), DofMap::NONE);
        // Each block's unknowns: the next `count` entries of `vertex`, numbered from there.
        let mut parts = Vec::with_capacity(counts.len());
        let (mut rest, mut first) = (vertex.as_mut_slice(), 0u32);
        for &c in &counts {
            let (part, tail) = rest.split_at_mut(c);
            parts.push((first, part));
            (rest, first) = (tail, first + c as u32);
        }
        dof.par_chunks_mut(BLOCK)
            .zip(fixed.par_chunks(BLOCK))
            .zip(parts)
            .enumerate()
            .for_each(|(b, ((dof, fixed), (first, part)))| {
                let mut next = 0;
                for (k, (d, &f)) in dof.iter_mut().zip(fixed).enumerate() {
                    if !f {
                        *d = first + next as u32;
                        part[next] = (b * BLOCK + k) as u32;
                        next += 1;
                    }
                }
            });
        DofMap::from_parts(vertex, dof)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertices on the free part of the boundary only (they carry unknowns).
    fn free_vertices(mesh: &Mesh, adj: &VertexTriangles, b: &FixedBoundary) -> usize {
        let tagged = mesh.tagged_boundary(adj);
        let mut on = vec![false; mesh.n_vertices()];
        for e in &tagged.edges {
            on[e[0] as usize] = true;
            on[e[1] as usize] = true;
        }
        on.iter().zip(&b.fixed).filter(|(&o, &f)| o && !f).count()
    }
    use crate::mesh::generate::{rectangle, Diagonal, RectangleSpec};

    fn square(n: usize) -> Mesh {
        rectangle(&RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            nx: n,
            ny: n,
            diagonal: Diagonal::Right,
        })
        .unwrap()
        .finest()
        .clone()
    }

    #[test]
    fn free_sides_carry_unknowns() {
        let m = square(4);
        let adj = VertexTriangles::new(&m);
        let all = FixedBoundary::all(&m, &adj);
        assert_eq!(all.count(), 16);
        assert_eq!(free_vertices(&m, &adj, &all), 0);
        // The whole boundary fixed: the same unknowns as the interior numbering.
        assert_eq!(
            DofMap::from_fixed(&all.fixed).vertex,
            DofMap::new(&m).vertex
        );
        let top = FixedBoundary::new(&m, &adj, &["top".into()]).unwrap();
        // The top side's 5 vertices minus its two corners (on left and right).
        assert_eq!(free_vertices(&m, &adj, &top), 3);
        assert_eq!(top.count(), 13);
        let e = FixedBoundary::new(&m, &adj, &["lid".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "invalid data: boundary.free: no boundary region named 'lid' in the mesh \
             (boundary regions, curves: bottom, right, top, left; regions of triangles, \
             surfaces: 0)"
        );
        let none = FixedBoundary::new(
            &m,
            &adj,
            &["left".into(), "right".into(), "top".into(), "bottom".into()],
        )
        .unwrap();
        assert_eq!(none.count(), 0);
        assert_eq!(free_vertices(&m, &adj, &none), 16);
    }

    #[test]
    fn unknowns_number_the_free_vertices_in_order_across_blocks() {
        // Long enough for several parallel blocks, with runs of fixed vertices crossing
        // block ends and a block with no free vertex at all.
        let n = 70_000;
        let fixed: Vec<bool> = (0..n)
            .map(|v| v % 7 == 3 || v % 11 == 0 || (16_000..33_000).contains(&v))
            .collect();
        let d = DofMap::from_fixed(&fixed);
        assert_eq!(d.n_vertices(), n);
        assert_eq!(d.vertex.len(), fixed.iter().filter(|&&f| !f).count());
        // Unknown i is the i-th free vertex: increasing vertices, each the inverse of dof.
        assert!(d.vertex.windows(2).all(|w| w[0] < w[1]));
        for (i, &v) in d.vertex.iter().enumerate() {
            assert!(!fixed[v as usize]);
            assert_eq!(d.of(v as usize), Some(i as u32));
        }
        for (v, &f) in fixed.iter().enumerate() {
            assert_eq!(d.is_fixed(v), f, "vertex {v}");
        }
    }

    #[test]
    fn bad_boundary_regions_are_errors() {
        let m = square(2);
        let e = m
            .clone()
            .with_boundary_regions(vec![[0, 4]], vec![1], BTreeMap::new())
            .unwrap_err();
        assert!(
            e.to_string().contains("not an edge of the mesh's boundary"),
            "{e}"
        );
        let e = m
            .clone()
            .with_boundary_regions(vec![[0, 1], [1, 0]], vec![1, 2], BTreeMap::new())
            .unwrap_err();
        assert!(e.to_string().contains("two boundary regions"), "{e}");
        let e = m
            .with_boundary_regions(vec![[0, 1]], vec![], BTreeMap::new())
            .unwrap_err();
        assert!(
            e.to_string().contains("0 boundary region tags for 1"),
            "{e}"
        );
    }
}
