//! What an MSH file holds, before it becomes a mesh, and the mesh made of it: node tags
//! resolved, unused nodes dropped, physical curves made boundary regions.

use crate::error::Error;
use crate::mesh::Mesh;
use std::collections::BTreeMap;

/// Number of nodes and a name for the Gmsh element types (reference manual, `$Elements`).
pub(super) fn element_type(t: i32) -> Option<(usize, &'static str)> {
    Some(match t {
        1 => (2, "2-node line"),
        2 => (3, "3-node triangle"),
        3 => (4, "4-node quadrangle"),
        4 => (4, "4-node tetrahedron"),
        5 => (8, "8-node hexahedron"),
        6 => (6, "6-node prism"),
        7 => (5, "5-node pyramid"),
        8 => (3, "3-node second order line"),
        9 => (6, "6-node second order triangle"),
        10 => (9, "9-node second order quadrangle"),
        11 => (10, "10-node second order tetrahedron"),
        12 => (27, "27-node second order hexahedron"),
        13 => (18, "18-node second order prism"),
        14 => (14, "14-node second order pyramid"),
        15 => (1, "1-node point"),
        16 => (8, "8-node second order quadrangle"),
        17 => (20, "20-node second order hexahedron"),
        18 => (15, "15-node second order prism"),
        19 => (13, "13-node second order pyramid"),
        20 => (9, "9-node third order incomplete triangle"),
        21 => (10, "10-node third order triangle"),
        22 => (12, "12-node fourth order incomplete triangle"),
        23 => (15, "15-node fourth order triangle"),
        24 => (15, "15-node fifth order incomplete triangle"),
        25 => (21, "21-node fifth order complete triangle"),
        26 => (4, "4-node third order edge"),
        27 => (5, "5-node fourth order edge"),
        28 => (6, "6-node fifth order edge"),
        29 => (20, "20-node third order tetrahedron"),
        30 => (35, "35-node fourth order tetrahedron"),
        31 => (56, "56-node fifth order tetrahedron"),
        92 => (64, "64-node third order hexahedron"),
        93 => (125, "125-node fourth order hexahedron"),
        _ => return None,
    })
}

/// What the file holds, before it becomes a mesh.
#[derive(Default)]
pub(super) struct Raw {
    /// (node tag, coordinates) in file order.
    pub(super) nodes: Vec<(u64, [f64; 3])>,
    /// (element tag, node tags, physical tag) of every 3-node triangle.
    pub(super) triangles: Vec<(u64, [u64; 3], u32)>,
    /// (node tags, physical tag) of every 2-node line of a physical curve.
    pub(super) lines: Vec<([u64; 2], u32)>,
    /// Physical names of dimension 2.
    pub(super) names: BTreeMap<u32, String>,
    /// Physical names of dimension 1 (curves).
    pub(super) curve_names: BTreeMap<u32, String>,
    /// Skipped elements per type.
    pub(super) skipped: BTreeMap<i32, usize>,
    pub(super) warnings: Vec<String>,
}

pub(super) enum ParseOrMesh {
    Parse(String),
    Mesh(Error, Vec<String>),
}

impl Raw {
    /// Resolves node tags, keeps the nodes used by triangles, checks planarity and builds
    /// the mesh.
    pub(super) fn into_mesh(self) -> std::result::Result<(Mesh, Vec<String>), ParseOrMesh> {
        let Raw {
            nodes,
            triangles,
            lines,
            names,
            curve_names,
            skipped,
            mut warnings,
        } = self;
        if triangles.is_empty() {
            let others: usize = skipped.values().sum();
            return Err(ParseOrMesh::Parse(format!(
                "no 3-node triangle (element type 2) in $Elements ({others} other elements): \
                 a 2-D triangle mesh is needed"
            )));
        }
        use rayon::prelude::*;
        // Planarity: z must vanish up to round-off relative to the extent of the mesh.
        let extent = nodes
            .par_iter()
            .with_min_len(8192)
            .map(|(_, p)| p[0].abs().max(p[1].abs()))
            .reduce(|| 1.0, f64::max);
        let off_plane = |(_, p): (u64, [f64; 3])| p[2].is_nan() || p[2].abs() > 1e-12 * extent;
        if let Some(k) = crate::sparse::first_where(&nodes, off_plane) {
            let (tag, p) = nodes[k];
            return Err(ParseOrMesh::Parse(format!(
                "$Nodes: node {tag} at ({}, {}, {}) has z ≠ 0: the mesh must lie in the \
                 plane z = 0",
                p[0], p[1], p[2]
            )));
        }
        // Tag → file index: a table when the tags are dense (as Gmsh writes them), else
        // by sorting (node tags may be sparse and unordered).
        let lookup = TagLookup::new(&nodes).map_err(ParseOrMesh::Parse)?;
        // Straight into the triangle array on all threads (an indexed collect, in place),
        // `u32::MAX` for a missing node; a missing node is then named by a scan in file
        // order (the first triangle that references one).
        let mut tris: Vec<[u32; 3]> = triangles
            .par_iter()
            .with_min_len(8192)
            .map(|(_, t, _)| t.map(|tag| lookup.find(tag).unwrap_or(u32::MAX)))
            .collect();
        if tris
            .par_iter()
            .with_min_len(8192)
            .any(|t| t.contains(&u32::MAX))
        {
            let (etag, n) = triangles
                .iter()
                .find_map(|(etag, t, _)| {
                    t.iter()
                        .find(|&&n| lookup.find(n).is_none())
                        .map(|&n| (*etag, n))
                })
                .expect("a triangle references a missing node");
            return Err(ParseOrMesh::Parse(format!(
                "$Elements: triangle {etag} references node {n}, which is not in $Nodes"
            )));
        }
        let regions: Vec<u32> = triangles
            .par_iter()
            .with_min_len(8192)
            .map(|t| t.2)
            .collect();
        drop(triangles);
        // Keep the used nodes, in file order (usually all of them: then nothing moves).
        let used = crate::mesh::used_vertices(nodes.len(), &tris);
        // The new index of every node kept, when some are dropped.
        let (points, renumbered): (Vec<[f64; 2]>, Option<Vec<u32>>) = if used.iter().all(|&u| u) {
            let points = nodes
                .par_iter()
                .with_min_len(8192)
                .map(|(_, p)| [p[0], p[1]])
                .collect();
            (points, None)
        } else {
            let mut new_index = vec![u32::MAX; nodes.len()];
            let mut points = Vec::with_capacity(nodes.len());
            for (i, slot) in new_index.iter_mut().enumerate() {
                if used[i] {
                    *slot = points.len() as u32;
                    points.push([nodes[i].1[0], nodes[i].1[1]]);
                }
            }
            tris.par_iter_mut().with_min_len(8192).for_each(|t| {
                for v in t.iter_mut() {
                    *v = new_index[*v as usize];
                }
            });
            (points, Some(new_index))
        };
        drop(used);
        for (&t, &count) in &skipped {
            let name = element_type(t).map_or("unknown type", |e| e.1);
            warnings.push(format!("skipped {count} elements of type {t} ({name})"));
        }
        let dropped = nodes.len() - points.len();
        if dropped > 0 {
            warnings.push(format!(
                "dropped {dropped} of {} nodes that no triangle uses",
                nodes.len()
            ));
        }
        warnings.extend(crate::mesh::regions::region_name_warnings(&names, &regions));
        let mesh = match Mesh::new(points, tris, regions, names) {
            Ok(mesh) => mesh,
            Err(e) => return Err(ParseOrMesh::Mesh(e, warnings)),
        };
        // Lines of physical curves, as vertex pairs (`u32::MAX`: a node no triangle uses).
        let vertex = |tag: u64| {
            lookup.find(tag).map_or(u32::MAX, |i| {
                renumbered.as_ref().map_or(i, |r| r[i as usize])
            })
        };
        let lines: Vec<([u32; 2], u32)> = lines
            .iter()
            .map(|&([a, b], phys)| ([vertex(a), vertex(b)], phys))
            .collect();
        let mesh = curves_to_boundary_regions(mesh, &lines, curve_names, &mut warnings);
        Ok((mesh, warnings))
    }
}

/// Makes the lines of physical curves that lie on the mesh's boundary its boundary regions
/// (a boundary edge in two physical curves keeps the first), and warns about the lines that
/// are not boundary edges: inside the mesh (a seam), or not an edge of it at all.
pub(super) fn curves_to_boundary_regions(
    mesh: Mesh,
    lines: &[([u32; 2], u32)],
    curve_names: BTreeMap<u32, String>,
    warnings: &mut Vec<String>,
) -> Mesh {
    if lines.is_empty() {
        return mesh;
    }
    let uses = mesh.edge_uses(lines.iter().map(|l| l.0));
    let label = |tag: u32| match curve_names.get(&tag) {
        Some(name) => format!("physical curve \"{name}\" (tag {tag})"),
        None => format!("physical curve {tag}"),
    };
    // Per curve: lines inside the mesh, lines that are no edge of it.
    let mut inside: BTreeMap<u32, usize> = BTreeMap::new();
    let mut stray: BTreeMap<u32, usize> = BTreeMap::new();
    let mut twice: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    let mut first_tag: std::collections::HashMap<(u32, u32), u32> = Default::default();
    let (mut edges, mut tags) = (Vec::new(), Vec::new());
    for (&([a, b], tag), &n) in lines.iter().zip(&uses) {
        match n {
            1 => match first_tag.entry((a.min(b), a.max(b))) {
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(tag);
                    edges.push([a, b]);
                    tags.push(tag);
                }
                std::collections::hash_map::Entry::Occupied(e) => {
                    if *e.get() != tag {
                        *twice.entry((*e.get(), tag)).or_default() += 1;
                    }
                }
            },
            2 => *inside.entry(tag).or_default() += 1,
            _ => *stray.entry(tag).or_default() += 1,
        }
    }
    for (tag, n) in inside {
        warnings.push(format!(
            "{}: {n} line element{} inside the mesh, not on its boundary (a seam?): a \
             boundary region holds boundary edges only, these are ignored",
            label(tag),
            if n == 1 { " lies" } else { "s lie" }
        ));
    }
    for (tag, n) in stray {
        warnings.push(format!(
            "{}: {n} line element{} not an edge of any triangle: ignored",
            label(tag),
            if n == 1 { " is" } else { "s are" }
        ));
    }
    for ((first, other), n) in twice {
        warnings.push(format!(
            "{n} boundary edge{} of {} also belong{} to {}: {} keep{} the first",
            if n == 1 { "" } else { "s" },
            label(first),
            if n == 1 { "s" } else { "" },
            label(other),
            if n == 1 { "it" } else { "they" },
            if n == 1 { "s" } else { "" },
        ));
    }
    warnings.extend(crate::mesh::boundary::boundary_name_warnings(&curve_names));
    mesh.with_checked_boundary_regions(edges, tags, curve_names)
}

/// Node tag → index in file order.
pub(super) enum TagLookup {
    /// Tags in `[first, first + table.len())`: `table[tag − first]` (`u32::MAX`: none).
    Dense { first: u64, table: Vec<u32> },
    /// `(tag, index)` sorted by tag.
    Sorted(Vec<(u64, u32)>),
}

impl TagLookup {
    /// The lookup of `nodes`' tags; a tag given twice is an error.
    pub(super) fn new(nodes: &[(u64, [f64; 3])]) -> std::result::Result<TagLookup, String> {
        let twice = |tag: u64| format!("$Nodes: node tag {tag} appears twice");
        let (lo, hi) = nodes
            .iter()
            .fold((u64::MAX, 0), |(lo, hi), (t, _)| (lo.min(*t), hi.max(*t)));
        if !nodes.is_empty() && hi - lo < 4 * nodes.len() as u64 {
            let mut table = vec![u32::MAX; (hi - lo + 1) as usize];
            for (i, (t, _)) in nodes.iter().enumerate() {
                let slot = &mut table[(t - lo) as usize];
                if *slot != u32::MAX {
                    return Err(twice(*t));
                }
                *slot = i as u32;
            }
            return Ok(TagLookup::Dense { first: lo, table });
        }
        let mut by_tag: Vec<(u64, u32)> = nodes
            .iter()
            .enumerate()
            .map(|(i, (t, _))| (*t, i as u32))
            .collect();
        by_tag.sort_unstable();
        if let Some(w) = by_tag.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(twice(w[0].0));
        }
        Ok(TagLookup::Sorted(by_tag))
    }

    /// The file index of node `tag`.
    pub(super) fn find(&self, tag: u64) -> Option<u32> {
        match self {
            TagLookup::Dense { first, table } => tag
                .checked_sub(*first)
                .and_then(|k| table.get(k as usize))
                .copied()
                .filter(|&i| i != u32::MAX),
            TagLookup::Sorted(by_tag) => by_tag
                .binary_search_by_key(&tag, |e| e.0)
                .ok()
                .map(|k| by_tag[k].1),
        }
    }
}
