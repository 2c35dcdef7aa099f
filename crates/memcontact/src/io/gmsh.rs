//! Gmsh MSH meshes: a reader for versions 2.2 and 4.1, ASCII and binary, and a writer.
//!
//! Only 3-node triangles (element type 2) make the mesh; physical surfaces become regions
//! (`$PhysicalNames` of dimension 2 name them). 2-node lines (element type 1) of physical
//! curves become boundary regions where they lie on the mesh's boundary (`$PhysicalNames`
//! of dimension 1 name them); lines inside the mesh are reported with a warning. Every
//! other element type is skipped with a warning. The format is described in the Gmsh
//! reference manual, section "MSH file format".

use crate::mesh::Mesh;
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// The MSH flavours [`write_msh`] can produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MshVersion {
    /// MSH 2.2, text.
    V22Ascii,
    /// MSH 2.2, binary.
    V22Binary,
    /// MSH 4.1, text (Gmsh's default).
    V41Ascii,
    /// MSH 4.1, binary.
    V41Binary,
}

/// Reads a 2-D triangle mesh from a Gmsh MSH file (2.2 or 4.1, ASCII or binary).
///
/// Returns the mesh (vertices: the nodes used by triangles, in file order; regions: the
/// physical surface of each triangle, 0 if none; boundary regions: the physical curves of
/// the boundary edges) and warnings: skipped element types, dropped nodes, entities with
/// several physical tags, physical curves with lines that are not boundary edges. Parse failures are
/// [`Error::File`] with the line (ASCII) or section (binary) and what was expected; a
/// broken mesh (inverted, duplicate vertices...) is reported by [`Mesh::new`]'s checks.
pub fn read_msh(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let file_err = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let bytes = crate::resources::read_input(path, crate::resources::MESH_FILE)?;
    parse_msh(&bytes).map_err(file_err)
}

/// [`read_msh`] on the bytes of a file: the mesh and warnings, or what is wrong (with the
/// line or section).
pub fn parse_msh(bytes: &[u8]) -> std::result::Result<(Mesh, Vec<String>), String> {
    let raw = parse(bytes)?;
    raw.into_mesh().map_err(|e| match e {
        ParseOrMesh::Parse(m) => m,
        ParseOrMesh::Mesh(e, warnings) => format!(
            "{e} (triangles are numbered from 0 in file order, vertices from 0 in node \
             order){}",
            if warnings.is_empty() {
                String::new()
            } else {
                format!("; warnings: {}", warnings.join("; "))
            }
        ),
    })
}

/// Number of nodes and a name for the Gmsh element types (reference manual, `$Elements`).
fn element_type(t: i32) -> Option<(usize, &'static str)> {
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
struct Raw {
    /// (node tag, coordinates) in file order.
    nodes: Vec<(u64, [f64; 3])>,
    /// (element tag, node tags, physical tag) of every 3-node triangle.
    triangles: Vec<(u64, [u64; 3], u32)>,
    /// (node tags, physical tag) of every 2-node line of a physical curve.
    lines: Vec<([u64; 2], u32)>,
    /// Physical names of dimension 2.
    names: BTreeMap<u32, String>,
    /// Physical names of dimension 1 (curves).
    curve_names: BTreeMap<u32, String>,
    /// Skipped elements per type.
    skipped: BTreeMap<i32, usize>,
    warnings: Vec<String>,
}

enum ParseOrMesh {
    Parse(String),
    Mesh(Error, Vec<String>),
}

impl Raw {
    /// Resolves node tags, keeps the nodes used by triangles, checks planarity and builds
    /// the mesh.
    fn into_mesh(self) -> std::result::Result<(Mesh, Vec<String>), ParseOrMesh> {
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
        // Planarity: z must vanish up to round-off relative to the extent of the mesh.
        let extent = nodes
            .iter()
            .map(|(_, p)| p[0].abs().max(p[1].abs()))
            .fold(1.0, f64::max);
        for (tag, p) in &nodes {
            if p[2].is_nan() || p[2].abs() > 1e-12 * extent {
                return Err(ParseOrMesh::Parse(format!(
                    "$Nodes: node {tag} at ({}, {}, {}) has z ≠ 0: the mesh must lie in the \
                     plane z = 0",
                    p[0], p[1], p[2]
                )));
            }
        }
        // Tag → file index: a table when the tags are dense (as Gmsh writes them), else
        // by sorting (node tags may be sparse and unordered).
        let lookup = TagLookup::new(&nodes).map_err(ParseOrMesh::Parse)?;
        let mut new_index = vec![u32::MAX; nodes.len()];
        let resolve = |t: &[u64; 3]| -> Option<[u32; 3]> {
            Some([lookup.find(t[0])?, lookup.find(t[1])?, lookup.find(t[2])?])
        };
        // Straight into the triangle array on all threads; a missing node is then named
        // by a scan in file order (the first triangle that references one).
        let resolved: Option<Vec<[u32; 3]>> = {
            use rayon::prelude::*;
            triangles
                .par_iter()
                .with_min_len(8192)
                .map(|(_, t, _)| resolve(t))
                .collect()
        };
        let Some(mut tris) = resolved else {
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
        };
        let regions: Vec<u32> = triangles.iter().map(|t| t.2).collect();
        drop(triangles);
        // Keep the used nodes, in file order (usually all of them: then nothing moves).
        for t in &tris {
            for &v in t {
                new_index[v as usize] = 0;
            }
        }
        let mut points = Vec::with_capacity(nodes.len());
        for (i, slot) in new_index.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = points.len() as u32;
                points.push([nodes[i].1[0], nodes[i].1[1]]);
            }
        }
        if points.len() < nodes.len() {
            use rayon::prelude::*;
            tris.par_iter_mut().with_min_len(8192).for_each(|t| {
                for v in t.iter_mut() {
                    *v = new_index[*v as usize];
                }
            });
        }
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
        warnings.extend(crate::field::region_name_warnings(&names, &regions));
        let mesh = match Mesh::new(points, tris, regions, names) {
            Ok(mesh) => mesh,
            Err(e) => return Err(ParseOrMesh::Mesh(e, warnings)),
        };
        // Lines of physical curves, as vertex pairs (`u32::MAX`: a node no triangle uses).
        let vertex = |tag: u64| lookup.find(tag).map_or(u32::MAX, |i| new_index[i as usize]);
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
fn curves_to_boundary_regions(
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
enum TagLookup {
    /// Tags in `[first, first + table.len())`: `table[tag − first]` (`u32::MAX`: none).
    Dense { first: u64, table: Vec<u32> },
    /// `(tag, index)` sorted by tag.
    Sorted(Vec<(u64, u32)>),
}

impl TagLookup {
    /// The lookup of `nodes`' tags; a tag given twice is an error.
    fn new(nodes: &[(u64, [f64; 3])]) -> std::result::Result<TagLookup, String> {
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
    fn find(&self, tag: u64) -> Option<u32> {
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

/// A cursor over the file: whitespace-separated tokens for the text parts, little- or
/// big-endian numbers for the binary ones.
struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
    /// Binary numbers are byte-swapped (the file was written on the other endianness).
    swap: bool,
    /// Size of `size_t` in 4.1 binary files.
    size_t: usize,
    /// The section being read, for messages.
    section: &'static str,
}

type Parse<T> = std::result::Result<T, String>;

impl<'a> Cursor<'a> {
    fn line(&self, pos: usize) -> usize {
        1 + self.buf[..pos.min(self.buf.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    /// The next whitespace-separated token and the line it is on.
    fn token(&mut self) -> Option<(&'a str, usize)> {
        while self.pos < self.buf.len() && self.buf[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if self.pos >= self.buf.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < self.buf.len() && !self.buf[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let text = std::str::from_utf8(&self.buf[start..self.pos]).unwrap_or("<not text>");
        Some((text, start))
    }

    /// The next token parsed as `T`, `what` naming it in the error.
    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Parse<T> {
        match self.token() {
            Some((text, start)) => text.parse().map_err(|_| {
                format!(
                    "line {} ({}): expected {what}, found `{}`",
                    self.line(start),
                    self.section,
                    text.chars().take(40).collect::<String>()
                )
            }),
            None => Err(format!(
                "unexpected end of file in {}: expected {what}",
                self.section
            )),
        }
    }

    /// Requires the token `word` (a section end, ...).
    fn expect(&mut self, word: &str) -> Parse<()> {
        match self.token() {
            Some((t, _)) if t == word => Ok(()),
            Some((t, start)) => Err(format!(
                "line {}: expected `{word}`, found `{}`",
                self.line(start),
                t.chars().take(40).collect::<String>()
            )),
            None => Err(format!("unexpected end of file: expected `{word}`")),
        }
    }

    /// Skips the rest of the current line, its newline included (binary data follows).
    fn end_line(&mut self) {
        while self.pos < self.buf.len() && self.buf[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.buf.len());
    }

    /// The next `len` bytes of binary data (`what` names them in the error).
    fn take(&mut self, len: usize, what: &str) -> Parse<&'a [u8]> {
        let end = self.pos.saturating_add(len);
        if end > self.buf.len() {
            return Err(format!(
                "unexpected end of file in the binary data of {} (byte {}): expected {what}",
                self.section, self.pos
            ));
        }
        let b = &self.buf[self.pos..end];
        self.pos = end;
        Ok(b)
    }

    fn bytes<const N: usize>(&mut self, what: &str) -> Parse<[u8; N]> {
        Ok(Binary::of(self).array(self.take(N, what)?))
    }

    fn int(&mut self, what: &str) -> Parse<i32> {
        Ok(i32::from_ne_bytes(self.bytes::<4>(what)?))
    }

    fn double(&mut self, what: &str) -> Parse<f64> {
        Ok(f64::from_ne_bytes(self.bytes::<8>(what)?))
    }

    fn size(&mut self, what: &str) -> Parse<u64> {
        let b = Binary::of(self);
        Ok(b.size(self.take(b.size_t, what)?))
    }

    /// A count the rest of the file can hold, each item taking at least `min_bytes` bytes
    /// (separators included): what is reserved for the items is bounded by a small multiple
    /// of the file's size, never by a declared count alone.
    fn check_count(&self, n: u64, min_bytes: u64, what: &str) -> Parse<usize> {
        let rest = (self.buf.len() - self.pos.min(self.buf.len())) as u64 + 1;
        if n > rest / min_bytes.max(1) {
            return Err(format!(
                "{}: {what} = {n} is more than the file can hold (truncated or corrupt file?)",
                self.section
            ));
        }
        Ok(n as usize)
    }
}

/// How binary numbers are stored: byte order and the size of `size_t`. Decodes numbers
/// from slices, so that the fixed-size records of a block can be read in parallel.
#[derive(Clone, Copy)]
struct Binary {
    swap: bool,
    size_t: usize,
}

impl Binary {
    fn of(c: &Cursor) -> Binary {
        Binary {
            swap: c.swap,
            size_t: c.size_t,
        }
    }

    /// The `N` bytes of `b` (exactly `N` long) in native order.
    #[inline(always)]
    fn array<const N: usize>(self, b: &[u8]) -> [u8; N] {
        let mut a: [u8; N] = b.try_into().expect("length N");
        if self.swap {
            a.reverse();
        }
        a
    }

    /// A `size_t` from its `size_t` bytes.
    #[inline(always)]
    fn size(self, b: &[u8]) -> u64 {
        if self.size_t == 4 {
            u32::from_ne_bytes(self.array(b)) as u64
        } else {
            u64::from_ne_bytes(self.array(b))
        }
    }

    #[inline(always)]
    fn double(self, b: &[u8]) -> f64 {
        f64::from_ne_bytes(self.array(b))
    }
}

/// Records per task when the records of a binary block are decoded in parallel.
const RECORDS_PER_TASK: usize = 8192;

/// The MSH flavour named by `$MeshFormat`.
#[derive(Clone, Copy, PartialEq)]
enum Flavour {
    V2,
    V4,
}

fn parse(buf: &[u8]) -> Parse<Raw> {
    let mut c = Cursor {
        buf,
        pos: 0,
        swap: false,
        size_t: 8,
        section: "$MeshFormat",
    };
    match c.token() {
        Some(("$MeshFormat", _)) => {}
        Some((t, _)) => {
            return Err(format!(
                "line 1: expected `$MeshFormat`, found `{}`: not a Gmsh MSH file",
                t.chars().take(40).collect::<String>()
            ))
        }
        None => return Err("the file is empty: expected `$MeshFormat`".into()),
    }
    let (version, vpos) = c
        .token()
        .ok_or("unexpected end of file in $MeshFormat: expected the version")?;
    let flavour = match version {
        "2.2" | "2.1" | "2" | "2.0" => Flavour::V2,
        "4.1" => Flavour::V4,
        v => {
            return Err(format!(
                "line {}: MSH version {v} is not supported (2.2 and 4.1 are)",
                c.line(vpos)
            ))
        }
    };
    let file_type: i32 = c.parse("the file type (0 ASCII, 1 binary)")?;
    let data_size: usize = c.parse("the data size")?;
    let binary = match file_type {
        0 => false,
        1 => true,
        t => {
            return Err(format!(
                "$MeshFormat: file type {t} is neither 0 (ASCII) nor 1 (binary)"
            ))
        }
    };
    if binary {
        if flavour == Flavour::V4 && data_size != 4 && data_size != 8 {
            return Err(format!(
                "$MeshFormat: data size {data_size} is not supported (4 or 8)"
            ));
        }
        c.size_t = data_size;
        c.end_line();
        let one = c.bytes::<4>("the endianness check (int 1)")?;
        if i32::from_ne_bytes(one) == 1 {
            c.swap = false;
        } else if i32::from_ne_bytes(one).swap_bytes() == 1 {
            c.swap = true;
        } else {
            return Err(
                "$MeshFormat: the binary endianness check is not the integer 1".to_string(),
            );
        }
    }
    c.expect("$EndMeshFormat")?;

    let mut raw = Raw::default();
    let mut entities = Entities::default();
    let mut saw_nodes = false;
    let mut saw_elements = false;
    while let Some((tok, start)) = c.token() {
        match tok {
            "$PhysicalNames" => {
                c.section = "$PhysicalNames";
                read_physical_names(&mut c, &mut raw)?;
            }
            "$Entities" if flavour == Flavour::V4 => {
                c.section = "$Entities";
                if binary {
                    c.end_line();
                }
                entities = read_entities(&mut c, binary, &mut raw.warnings)?;
                c.expect("$EndEntities")?;
            }
            "$Nodes" => {
                c.section = "$Nodes";
                match flavour {
                    Flavour::V2 => read_nodes_v2(&mut c, binary, &mut raw)?,
                    Flavour::V4 => {
                        if binary {
                            c.end_line();
                        }
                        read_nodes_v4(&mut c, binary, &mut raw)?
                    }
                }
                c.expect("$EndNodes")?;
                saw_nodes = true;
            }
            "$Elements" => {
                c.section = "$Elements";
                match flavour {
                    Flavour::V2 => read_elements_v2(&mut c, binary, &mut raw)?,
                    Flavour::V4 => {
                        if binary {
                            c.end_line();
                        }
                        read_elements_v4(&mut c, binary, &entities, &mut raw)?
                    }
                }
                c.expect("$EndElements")?;
                saw_elements = true;
            }
            t if t.starts_with('$') && !t.starts_with("$End") => {
                // An unknown or unused section ($Periodic, $NodeData, ...): skip it.
                let end = format!("$End{}", &t[1..]);
                let rest = &buf[c.pos..];
                match find(rest, end.as_bytes()) {
                    Some(k) => c.pos += k + end.len(),
                    None => {
                        return Err(format!(
                            "line {}: section {t} has no `{end}`",
                            c.line(start)
                        ))
                    }
                }
            }
            t => {
                return Err(format!(
                    "line {}: expected a section header such as `$Nodes`, found `{}`",
                    c.line(start),
                    t.chars().take(40).collect::<String>()
                ))
            }
        }
    }
    if !saw_nodes {
        return Err("the file has no $Nodes section".into());
    }
    if !saw_elements {
        return Err("the file has no $Elements section".into());
    }
    Ok(raw)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn read_physical_names(c: &mut Cursor, raw: &mut Raw) -> Parse<()> {
    let n: usize = c.parse("the number of physical names")?;
    for _ in 0..n {
        let dim: i32 = c.parse("a physical dimension")?;
        let tag: i64 = c.parse("a physical tag")?;
        // The name: a quoted string, possibly with spaces.
        while c.pos < c.buf.len() && (c.buf[c.pos] == b' ' || c.buf[c.pos] == b'\t') {
            c.pos += 1;
        }
        let line = c.line(c.pos);
        if c.buf.get(c.pos) != Some(&b'"') {
            return Err(format!(
                "line {line} ($PhysicalNames): expected a quoted name after `{dim} {tag}`"
            ));
        }
        let start = c.pos + 1;
        let len = c.buf[start..]
            .iter()
            .position(|&b| b == b'"' || b == b'\n')
            .filter(|&k| c.buf[start + k] == b'"')
            .ok_or_else(|| format!("line {line} ($PhysicalNames): unterminated name"))?;
        let name = String::from_utf8_lossy(&c.buf[start..start + len]).into_owned();
        c.pos = start + len + 1;
        if dim == 1 || dim == 2 {
            let tag = u32::try_from(tag)
                .map_err(|_| format!("line {line} ($PhysicalNames): bad physical tag {tag}"))?;
            let names = if dim == 2 {
                &mut raw.names
            } else {
                &mut raw.curve_names
            };
            names.insert(tag, name);
        }
    }
    c.expect("$EndPhysicalNames")
}

/// The physical tags of the entities of `$Entities` (4.1), by dimension and entity tag.
#[derive(Default)]
struct Entities {
    /// Curves (dimension 1).
    curves: BTreeMap<i32, Vec<i32>>,
    /// Surfaces (dimension 2).
    surfaces: BTreeMap<i32, Vec<i32>>,
}

impl Entities {
    /// The physical tag the elements of entity `entity` of dimension `dim` get: the
    /// entity's first (0: none, or an entity that is neither a curve nor a surface).
    fn physical(&self, dim: i32, entity: i32) -> i32 {
        let map = match dim {
            1 => &self.curves,
            2 => &self.surfaces,
            _ => return 0,
        };
        map.get(&entity)
            .and_then(|p| p.first())
            .copied()
            .unwrap_or(0)
    }
}

/// `$Entities` (4.1): the physical tags of every curve and surface.
fn read_entities(c: &mut Cursor, binary: bool, warnings: &mut Vec<String>) -> Parse<Entities> {
    let mut counts = [0usize; 4];
    for (k, what) in ["points", "curves", "surfaces", "volumes"]
        .iter()
        .enumerate()
    {
        let n = if binary {
            c.size(&format!("the number of {what}"))?
        } else {
            c.parse(&format!("the number of {what}"))?
        };
        // An entity is at least a tag and a bounding box.
        let min = if binary { 28 } else { 8 };
        counts[k] = c.check_count(n, min, &format!("the number of {what}"))?;
    }
    let mut entities = Entities::default();
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..count {
            let tag: i32 = if binary {
                c.int("an entity tag")?
            } else {
                c.parse("an entity tag")?
            };
            let n_coords = if dim == 0 { 3 } else { 6 };
            for _ in 0..n_coords {
                if binary {
                    c.double("an entity bounding box coordinate")?;
                } else {
                    c.parse::<f64>("an entity bounding box coordinate")?;
                }
            }
            let n_phys = if binary {
                c.size("the number of physical tags")?
            } else {
                c.parse("the number of physical tags")?
            };
            let n_phys = c.check_count(
                n_phys,
                if binary { 4 } else { 2 },
                "the number of physical tags",
            )?;
            let mut phys = Vec::with_capacity(n_phys);
            for _ in 0..n_phys {
                phys.push(if binary {
                    c.int("a physical tag")?
                } else {
                    c.parse("a physical tag")?
                });
            }
            if dim > 0 {
                let n_bound = if binary {
                    c.size("the number of bounding entities")?
                } else {
                    c.parse("the number of bounding entities")?
                };
                let n_bound = c.check_count(
                    n_bound,
                    if binary { 4 } else { 2 },
                    "the number of bounding entities",
                )?;
                for _ in 0..n_bound {
                    if binary {
                        c.int("a bounding entity tag")?;
                    } else {
                        c.parse::<i32>("a bounding entity tag")?;
                    }
                }
            }
            if dim == 1 || dim == 2 {
                let (kind, elements, map) = if dim == 2 {
                    ("surface", "triangles", &mut entities.surfaces)
                } else {
                    ("curve", "lines", &mut entities.curves)
                };
                if phys.len() > 1 {
                    warnings.push(format!(
                        "{kind} {tag} has {} physical tags; its {elements} get the first ({})",
                        phys.len(),
                        phys[0]
                    ));
                }
                map.insert(tag, phys);
            }
        }
    }
    Ok(entities)
}

fn read_nodes_v2(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
    let n: u64 = c.parse("the number of nodes")?;
    // A node is a tag and three coordinates: "1 0 0 0\n", or 4 + 3 × 8 bytes.
    let n = c.check_count(n, if binary { 28 } else { 8 }, "the number of nodes")?;
    raw.nodes.reserve(n);
    if binary {
        c.end_line();
    }
    for _ in 0..n {
        if binary {
            let tag = c.int("a node tag")?;
            let p = [c.double("x")?, c.double("y")?, c.double("z")?];
            let tag = u64::try_from(tag).map_err(|_| format!("$Nodes: bad node tag {tag}"))?;
            raw.nodes.push((tag, p));
        } else {
            let tag: u64 = c.parse("a node tag")?;
            let p = [c.parse("x")?, c.parse("y")?, c.parse("z")?];
            raw.nodes.push((tag, p));
        }
    }
    Ok(())
}

fn read_nodes_v4(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
    let mut head = [0u64; 4];
    for (h, what) in head.iter_mut().zip([
        "the number of node blocks",
        "the number of nodes",
        "the smallest node tag",
        "the largest node tag",
    ]) {
        *h = if binary {
            c.size(what)?
        } else {
            c.parse(what)?
        };
    }
    let blocks = c.check_count(head[0], 8, "the number of node blocks")?;
    let total = c.check_count(head[1], 8, "the number of nodes")?;
    raw.nodes.reserve(total);
    for _ in 0..blocks {
        let (dim, parametric, n) = if binary {
            let dim = c.int("an entity dimension")?;
            c.int("an entity tag")?;
            let parametric = c.int("the parametric flag")?;
            (dim, parametric, c.size("the number of nodes in the block")?)
        } else {
            let dim: i32 = c.parse("an entity dimension")?;
            c.parse::<i32>("an entity tag")?;
            let parametric: i32 = c.parse("the parametric flag")?;
            (
                dim,
                parametric,
                c.parse("the number of nodes in the block")?,
            )
        };
        let n = c.check_count(n, 8, "the number of nodes in the block")?;
        let params = if parametric != 0 {
            dim.max(0) as usize
        } else {
            0
        };
        if binary {
            // Fixed-size records: the tags, then the coordinates (and parametric ones).
            use rayon::prelude::*;
            let bin = Binary::of(c);
            let tags = c.take(n * bin.size_t, "the node tags of a block")?;
            let rec = (3 + params) * 8;
            let coords = c.take(n * rec, "the node coordinates of a block")?;
            raw.nodes.par_extend(
                tags.par_chunks_exact(bin.size_t)
                    .zip(coords.par_chunks_exact(rec))
                    .with_min_len(RECORDS_PER_TASK)
                    .map(|(t, x)| {
                        let p = [0, 1, 2].map(|k| bin.double(&x[8 * k..8 * k + 8]));
                        (bin.size(t), p)
                    }),
            );
            continue;
        }
        let first = raw.nodes.len();
        for _ in 0..n {
            let tag = if binary {
                c.size("a node tag")?
            } else {
                c.parse("a node tag")?
            };
            raw.nodes.push((tag, [0.0; 3]));
        }
        for k in 0..n {
            let mut p = [0.0; 3];
            for x in &mut p {
                *x = if binary {
                    c.double("a node coordinate")?
                } else {
                    c.parse("a node coordinate")?
                };
            }
            for _ in 0..params {
                if binary {
                    c.double("a parametric coordinate")?;
                } else {
                    c.parse::<f64>("a parametric coordinate")?;
                }
            }
            raw.nodes[first + k].1 = p;
        }
    }
    if raw.nodes.len() != total {
        return Err(format!(
            "$Nodes: the header announces {total} nodes but the blocks hold {}",
            raw.nodes.len()
        ));
    }
    Ok(())
}

fn read_elements_v2(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
    let n: u64 = c.parse("the number of elements")?;
    let n = c.check_count(n, if binary { 8 } else { 6 }, "the number of elements")?;
    if binary {
        c.end_line();
        let mut done = 0;
        while done < n {
            let ty = c.int("an element type")?;
            let count = c.int("the number of elements that follow")?;
            let n_tags = c.int("the number of tags")?;
            let (nodes, _) = element_type(ty).ok_or_else(|| {
                format!("$Elements: unknown element type {ty}: cannot skip it in binary data")
            })?;
            let count = usize::try_from(count)
                .ok()
                .filter(|&k| k <= n - done)
                .ok_or_else(|| format!("$Elements: bad block size {count}"))?;
            let n_tags = usize::try_from(n_tags)
                .map_err(|_| format!("$Elements: bad number of tags {n_tags}"))?;
            for _ in 0..count {
                let tag = c.int("an element tag")?;
                let mut phys = 0;
                for k in 0..n_tags {
                    let t = c.int("an element tag")?;
                    if k == 0 {
                        phys = t;
                    }
                }
                let mut v = [0u64; 3];
                for k in 0..nodes {
                    let node = c.int("an element node")?;
                    if let Some(slot) = v.get_mut(k) {
                        *slot = u64::try_from(node)
                            .map_err(|_| format!("$Elements: element {tag}: bad node {node}"))?;
                    }
                }
                add_element(raw, ty, tag as i64, v, phys as i64)?;
            }
            done += count;
        }
        return Ok(());
    }
    for _ in 0..n {
        let (tag_text, start) = c
            .token()
            .ok_or("unexpected end of file in $Elements: expected an element")?;
        let line = c.line(start);
        let tag: i64 = tag_text.parse().map_err(|_| {
            format!("line {line} ($Elements): expected an element tag, found `{tag_text}`")
        })?;
        let ty: i32 = c.parse("an element type")?;
        let n_tags: usize = c.parse("the number of tags")?;
        let mut phys = 0;
        for k in 0..n_tags {
            let t: i64 = c.parse("an element tag")?;
            if k == 0 {
                phys = t;
            }
        }
        match element_type(ty) {
            Some((nodes, _)) => {
                let mut v = [0u64; 3];
                for k in 0..nodes {
                    let node: u64 = c.parse("a node tag")?;
                    if let Some(slot) = v.get_mut(k) {
                        *slot = node;
                    }
                }
                add_element(raw, ty, tag, v, phys)?;
            }
            None => {
                // Unknown type: the element is the rest of its line.
                c.end_line();
                *raw.skipped.entry(ty).or_default() += 1;
            }
        }
    }
    Ok(())
}

/// Records a triangle or a line of a physical curve, or counts a skipped element.
fn add_element(raw: &mut Raw, ty: i32, tag: i64, v: [u64; 3], phys: i64) -> Parse<()> {
    if ty == 1 {
        // A line of no physical curve (all elements saved) marks nothing.
        if phys != 0 {
            let phys = u32::try_from(phys)
                .map_err(|_| format!("$Elements: line {tag}: bad physical tag {phys}"))?;
            raw.lines.push(([v[0], v[1]], phys));
        }
        return Ok(());
    }
    if ty != 2 {
        *raw.skipped.entry(ty).or_default() += 1;
        return Ok(());
    }
    let phys = u32::try_from(phys)
        .map_err(|_| format!("$Elements: triangle {tag}: bad physical tag {phys}"))?;
    raw.triangles.push((tag as u64, v, phys));
    Ok(())
}

fn read_elements_v4(c: &mut Cursor, binary: bool, entities: &Entities, raw: &mut Raw) -> Parse<()> {
    let mut head = [0u64; 4];
    for (h, what) in head.iter_mut().zip([
        "the number of element blocks",
        "the number of elements",
        "the smallest element tag",
        "the largest element tag",
    ]) {
        *h = if binary {
            c.size(what)?
        } else {
            c.parse(what)?
        };
    }
    let blocks = c.check_count(head[0], 8, "the number of element blocks")?;
    for _ in 0..blocks {
        let (dim, entity, ty, n) = if binary {
            (
                c.int("an entity dimension")?,
                c.int("an entity tag")?,
                c.int("an element type")?,
                c.size("the number of elements in the block")?,
            )
        } else {
            (
                c.parse::<i32>("an entity dimension")?,
                c.parse::<i32>("an entity tag")?,
                c.parse::<i32>("an element type")?,
                c.parse::<u64>("the number of elements in the block")?,
            )
        };
        let n = c.check_count(
            n,
            if binary { 8 } else { 2 },
            "the number of elements in the block",
        )?;
        let phys = entities.physical(dim, entity);
        let known = element_type(ty);
        if known.is_none() {
            if binary {
                return Err(format!(
                    "$Elements: unknown element type {ty}: cannot skip it in binary data"
                ));
            }
            for _ in 0..n {
                c.token();
                c.end_line();
            }
            *raw.skipped.entry(ty).or_default() += n;
            continue;
        }
        let nodes = known.map_or(0, |k| k.0);
        let triangle_phys = u32::try_from(phys).ok().filter(|_| ty == 2);
        if let (Some(phys), true) = (triangle_phys, binary) {
            // Fixed-size records (a tag and three nodes), decoded in parallel.
            use rayon::prelude::*;
            let bin = Binary::of(c);
            let st = bin.size_t;
            let data = c.take(n * 4 * st, "the triangles of a block")?;
            raw.triangles.par_extend(
                data.par_chunks_exact(4 * st)
                    .with_min_len(RECORDS_PER_TASK)
                    .map(|r| {
                        let v = [1, 2, 3].map(|k| bin.size(&r[k * st..(k + 1) * st]));
                        (bin.size(&r[..st]), v, phys)
                    }),
            );
            continue;
        }
        if ty == 2 {
            raw.triangles.reserve(n);
        }
        for _ in 0..n {
            let tag = if binary {
                c.size("an element tag")?
            } else {
                c.parse("an element tag")?
            };
            let mut v = [0u64; 3];
            for k in 0..nodes {
                let node = if binary {
                    c.size("an element node")?
                } else {
                    c.parse("an element node")?
                };
                if let Some(slot) = v.get_mut(k) {
                    *slot = node;
                }
            }
            add_element(raw, ty, tag as i64, v, phys as i64)?;
        }
    }
    Ok(())
}

/// Writes `mesh` as a Gmsh MSH file: region tags become physical surfaces (one
/// elementary surface per region), with `region_names` as `$PhysicalNames`. Useful to
/// convert meshes and to look at them in Gmsh. Written atomically.
pub fn write_msh(path: &Path, mesh: &Mesh, version: MshVersion) -> Result<()> {
    crate::io::write_atomic(path, |w| match version {
        MshVersion::V22Ascii => write_v22(w, mesh, false),
        MshVersion::V22Binary => write_v22(w, mesh, true),
        MshVersion::V41Ascii => write_v41(w, mesh, false),
        MshVersion::V41Binary => write_v41(w, mesh, true),
    })
    .map(|_| ())
}

fn write_header(
    w: &mut dyn Write,
    version: &str,
    binary: bool,
    mesh: &Mesh,
) -> std::io::Result<()> {
    writeln!(w, "$MeshFormat")?;
    writeln!(w, "{version} {} 8", binary as u8)?;
    if binary {
        w.write_all(&1i32.to_ne_bytes())?;
        writeln!(w)?;
    }
    writeln!(w, "$EndMeshFormat")?;
    if !mesh.region_names.is_empty() {
        writeln!(w, "$PhysicalNames")?;
        writeln!(w, "{}", mesh.region_names.len())?;
        for (tag, name) in &mesh.region_names {
            writeln!(w, "2 {tag} \"{}\"", name.replace(['"', '\n'], "'"))?;
        }
        writeln!(w, "$EndPhysicalNames")?;
    }
    Ok(())
}

fn write_v22(w: &mut dyn Write, mesh: &Mesh, binary: bool) -> std::io::Result<()> {
    write_header(w, "2.2", binary, mesh)?;
    writeln!(w, "$Nodes")?;
    writeln!(w, "{}", mesh.points.len())?;
    for (i, p) in mesh.points.iter().enumerate() {
        if binary {
            w.write_all(&(i as i32 + 1).to_ne_bytes())?;
            for x in [p[0], p[1], 0.0] {
                w.write_all(&x.to_ne_bytes())?;
            }
        } else {
            writeln!(w, "{} {} {} 0", i + 1, p[0], p[1])?;
        }
    }
    if binary {
        writeln!(w)?;
    }
    writeln!(w, "$EndNodes")?;
    writeln!(w, "$Elements")?;
    writeln!(w, "{}", mesh.triangles.len())?;
    if binary {
        for x in [2i32, mesh.triangles.len() as i32, 2] {
            w.write_all(&x.to_ne_bytes())?;
        }
    }
    for (k, t) in mesh.triangles.iter().enumerate() {
        let r = mesh.regions.get(k).copied().unwrap_or(0);
        // tags: physical = region, elementary = region + 1 (elementary tags are positive)
        let row = [k as u32 + 1, r, r + 1, t[0] + 1, t[1] + 1, t[2] + 1];
        if binary {
            for x in row {
                w.write_all(&(x as i32).to_ne_bytes())?;
            }
        } else {
            writeln!(
                w,
                "{} 2 2 {} {} {} {} {}",
                row[0], row[1], row[2], row[3], row[4], row[5]
            )?;
        }
    }
    if binary {
        writeln!(w)?;
    }
    writeln!(w, "$EndElements")
}

fn write_v41(w: &mut dyn Write, mesh: &Mesh, binary: bool) -> std::io::Result<()> {
    write_header(w, "4.1", binary, mesh)?;
    let size = |w: &mut dyn Write, x: usize| w.write_all(&(x as u64).to_ne_bytes());
    let int = |w: &mut dyn Write, x: i32| w.write_all(&x.to_ne_bytes());
    let dbl = |w: &mut dyn Write, x: f64| w.write_all(&x.to_ne_bytes());
    // One surface per region tag, numbered 1, 2, ... in tag order.
    let mut per_region: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for k in 0..mesh.triangles.len() {
        per_region
            .entry(mesh.regions.get(k).copied().unwrap_or(0))
            .or_default()
            .push(k);
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &mesh.points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    writeln!(w, "$Entities")?;
    if binary {
        for x in [0, 0, per_region.len(), 0] {
            size(w, x)?;
        }
    } else {
        writeln!(w, "0 0 {} 0", per_region.len())?;
    }
    for (s, &r) in per_region.keys().enumerate() {
        let phys: &[i32] = if r == 0 { &[] } else { &[r as i32] };
        if binary {
            int(w, s as i32 + 1)?;
            for x in [lo[0], lo[1], 0.0, hi[0], hi[1], 0.0] {
                dbl(w, x)?;
            }
            size(w, phys.len())?;
            for &p in phys {
                int(w, p)?;
            }
            size(w, 0)?;
        } else {
            write!(
                w,
                "{} {} {} 0 {} {} 0 {}",
                s + 1,
                lo[0],
                lo[1],
                hi[0],
                hi[1],
                phys.len()
            )?;
            for p in phys {
                write!(w, " {p}")?;
            }
            writeln!(w, " 0")?;
        }
    }
    if binary {
        writeln!(w)?;
    }
    writeln!(w, "$EndEntities")?;
    let n = mesh.points.len();
    writeln!(w, "$Nodes")?;
    if binary {
        for x in [1, n, 1, n] {
            size(w, x)?;
        }
        int(w, 2)?;
        int(w, 1)?;
        int(w, 0)?;
        size(w, n)?;
        for i in 0..n {
            size(w, i + 1)?;
        }
        for p in &mesh.points {
            for x in [p[0], p[1], 0.0] {
                dbl(w, x)?;
            }
        }
        writeln!(w)?;
    } else {
        writeln!(w, "1 {n} 1 {n}")?;
        writeln!(w, "2 1 0 {n}")?;
        for i in 0..n {
            writeln!(w, "{}", i + 1)?;
        }
        for p in &mesh.points {
            writeln!(w, "{} {} 0", p[0], p[1])?;
        }
    }
    writeln!(w, "$EndNodes")?;
    let nt = mesh.triangles.len();
    writeln!(w, "$Elements")?;
    if binary {
        for x in [per_region.len(), nt, 1, nt] {
            size(w, x)?;
        }
    } else {
        writeln!(w, "{} {nt} 1 {nt}", per_region.len())?;
    }
    let mut tag = 1;
    for (s, list) in per_region.values().enumerate() {
        if binary {
            int(w, 2)?;
            int(w, s as i32 + 1)?;
            int(w, 2)?;
            size(w, list.len())?;
        } else {
            writeln!(w, "2 {} 2 {}", s + 1, list.len())?;
        }
        for &k in list {
            let t = mesh.triangles[k];
            if binary {
                for x in [tag, t[0] as usize + 1, t[1] as usize + 1, t[2] as usize + 1] {
                    size(w, x)?;
                }
            } else {
                writeln!(w, "{tag} {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
            }
            tag += 1;
        }
    }
    if binary {
        writeln!(w)?;
    }
    writeln!(w, "$EndElements")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Point;
    use std::path::PathBuf;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name)
    }

    fn temp(name: &str) -> crate::io::TmpPath {
        crate::io::TmpPath::new(name)
    }

    /// The triangles as sorted triples of corner coordinates (bit patterns) with their
    /// region: a description independent of the vertex and triangle numbering.
    fn canonical(m: &Mesh) -> Vec<([[u64; 2]; 3], u32)> {
        let key = |p: Point| [p[0].to_bits(), p[1].to_bits()];
        let mut v: Vec<_> = (0..m.triangles.len())
            .map(|k| {
                let mut c = m.corners(k).map(key);
                c.sort();
                (c, m.regions[k])
            })
            .collect();
        v.sort();
        v
    }

    #[test]
    fn gmsh_fixtures_agree_in_all_four_flavours() {
        let names = [
            "disk_v22_ascii.msh",
            "disk_v22_binary.msh",
            "disk_v41_ascii.msh",
            "disk_v41_binary.msh",
        ];
        let meshes: Vec<(Mesh, Vec<String>)> =
            names.iter().map(|n| read_msh(&data(n)).unwrap()).collect();
        let (first, warnings) = &meshes[0];
        // Region names: dimension 2 only ("rim" is a curve).
        let expect: BTreeMap<u32, String> =
            BTreeMap::from([(1, "foam".into()), (2, "soil".into())]);
        assert_eq!(first.region_names, expect);
        assert!(warnings.is_empty(), "{warnings:?}");
        // The physical curve "rim" covers the whole boundary.
        let adj = crate::mesh::VertexTriangles::new(first);
        let tagged = first.tagged_boundary(&adj);
        assert!(
            tagged.tags.iter().all(|&t| t == 3),
            "{:?}",
            tagged.present()
        );
        assert_eq!(first.boundary.edges.len(), tagged.edges.len());
        assert_eq!(
            first.boundary.names,
            BTreeMap::from([(3, "rim".to_string())])
        );
        // Geometry: the disc of radius 1 (inscribed polygon), the foam disc of radius 0.5.
        let pi = std::f64::consts::PI;
        let area = first.total_area();
        assert!(area < pi && area > pi - 0.02, "{area}");
        let foam: f64 = (0..first.triangles.len())
            .filter(|&k| first.regions[k] == 1)
            .map(|k| first.area(k))
            .sum();
        assert!(foam < pi / 4.0 && foam > pi / 4.0 - 0.01, "{foam}");
        assert!(first.regions.iter().all(|&r| r == 1 || r == 2));
        assert!(first.triangles.len() > 250 && first.triangles.len() < 600);
        for (p, v) in first.points.iter().zip(first.boundary_vertices()) {
            if v {
                assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-12);
            }
        }
        for (name, (m, w)) in names.iter().zip(&meshes).skip(1) {
            assert_eq!(m.points.len(), first.points.len(), "{name}");
            assert!(same_mesh(m, first, 1e-14), "{name}: not the same triangles");
            assert_eq!(m.region_names, first.region_names, "{name}");
            assert_eq!(w, warnings, "{name}");
            assert_eq!(
                boundary_by_coordinates(m),
                boundary_by_coordinates(first),
                "{name}"
            );
        }
    }

    /// An edge by its end coordinates (in units of 1e-9), sorted.
    type EdgeKey = [(i64, i64); 2];

    /// The tagged boundary edges as sorted pairs of end coordinates (rounded to 1e-9) with
    /// their tags and names: a description independent of the numbering.
    fn boundary_by_coordinates(m: &Mesh) -> Vec<(EdgeKey, u32, String)> {
        let key = |v: u32| {
            let p = m.points[v as usize];
            ((p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64)
        };
        let mut v: Vec<_> = m
            .boundary
            .edges
            .iter()
            .zip(&m.boundary.tags)
            .map(|(&[a, b], &t)| {
                let mut e = [key(a), key(b)];
                e.sort();
                (e, t, m.boundary.name(t))
            })
            .collect();
        v.sort();
        v
    }

    #[test]
    fn curve_tags_survive_refinement_and_renumbering() {
        use crate::mesh::refine::Hierarchy;
        let side = |p: Point| match p {
            [_, y] if y.abs() < 1e-9 => "bottom",
            [_, y] if (y - 1.0).abs() < 1e-9 => "top",
            [x, _] if x.abs() < 1e-9 => "left",
            [x, _] if (x - 2.0).abs() < 1e-9 => "right",
            _ => "inside",
        };
        for flavour in ["v22_binary", "v41_ascii"] {
            let (mesh, _) = read_msh(&data(&format!("rect_{flavour}.msh"))).unwrap();
            let (h, orders) = Hierarchy::refined(mesh, 2).reordered();
            // The refined levels' numbering (new vertices after the old) is scattered.
            assert!(orders[1..].iter().all(Option::is_some), "{flavour}");
            for (level, m) in h.levels.iter().enumerate() {
                let adj = crate::mesh::VertexTriangles::new(m);
                let tagged = m.tagged_boundary(&adj);
                // Every boundary edge carries the tag of the side it lies on.
                assert_eq!(tagged.edges.len(), 48 << level);
                for (&[a, b], &tag) in tagged.edges.iter().zip(&tagged.tags) {
                    let (p, q) = (m.points[a as usize], m.points[b as usize]);
                    let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                    assert_eq!(m.boundary.name(tag), side(mid), "{flavour}, level {level}");
                }
            }
        }
    }

    /// Whether two meshes have the same vertices (within `tol`; text files round the
    /// coordinates to 16 digits, binary ones do not) and the same triangles with the same
    /// regions, whatever the numbering.
    fn same_mesh(a: &Mesh, b: &Mesh, tol: f64) -> bool {
        if a.points.len() != b.points.len() || a.triangles.len() != b.triangles.len() {
            return false;
        }
        let order = |m: &Mesh| {
            let key = |p: Point| ((p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64);
            let mut o: Vec<usize> = (0..m.points.len()).collect();
            o.sort_by_key(|&i| key(m.points[i]));
            o
        };
        let (oa, ob) = (order(a), order(b));
        // rank[v]: the position of vertex v in the sorted order, common to both meshes.
        let mut rank_a = vec![0u32; oa.len()];
        let mut rank_b = vec![0u32; ob.len()];
        for (r, (&i, &j)) in oa.iter().zip(&ob).enumerate() {
            let (p, q) = (a.points[i], b.points[j]);
            if (p[0] - q[0]).abs() > tol || (p[1] - q[1]).abs() > tol {
                return false;
            }
            rank_a[i] = r as u32;
            rank_b[j] = r as u32;
        }
        let tris = |m: &Mesh, rank: &[u32]| {
            let mut v: Vec<([u32; 3], u32)> = m
                .triangles
                .iter()
                .zip(&m.regions)
                .map(|(t, &r)| {
                    let mut k = t.map(|v| rank[v as usize]);
                    k.sort();
                    (k, r)
                })
                .collect();
            v.sort();
            v
        };
        tris(a, &rank_a) == tris(b, &rank_b)
    }

    /// A unit square of 4 triangles around a centre node written by hand from the format
    /// documentation: sparse node tags, a point element to skip, two physical surfaces, a
    /// name with a space, a physical curve "edge" on two sides (and a line that is no edge
    /// of the mesh), an unnamed physical curve 8 inside the mesh.
    const SQUARE_22: &str = "$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
3
1 7 \"edge\"
2 5 \"left half\"
2 6 \"right\"
$EndPhysicalNames
$Nodes
5
10 0 0 0
20 1 0 0
30 1 1 0
40 0 1 0
99 0.5 0.5 0
$EndNodes
$Elements
9
1 15 2 0 1 10
2 1 2 7 1 10 20
3 1 2 7 1 20 30
4 1 2 8 1 10 99
5 1 2 7 1 10 30
11 2 2 5 1 10 20 99
12 2 2 6 1 20 30 99
13 2 2 6 2 30 40 99
14 2 2 5 2 40 10 99
$EndElements
";

    const SQUARE_41: &str = "$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 5 \"left half\"
2 6 \"right\"
$EndPhysicalNames
$Entities
0 1 2 0
3 0 0 0 1 0 0 1 7 0
1 0 0 0 1 1 0 1 5 0
2 0 0 0 1 1 0 1 6 0
$EndEntities
$Nodes
2 5 10 99
2 1 0 3
10
20
99
0 0 0
1 0 0
0.5 0.5 0
2 2 0 2
30
40
1 1 0
0 1 0
$EndNodes
$Elements
3 6 1 14
1 3 1 1
2 10 20
2 1 2 2
11 10 20 99
14 40 10 99
2 2 2 3
12 20 30 99
13 30 40 99
15 30 99 10
$EndElements
";

    fn write_text(name: &str, text: &str) -> crate::io::TmpPath {
        let p = temp(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn hand_written_files_read_independently_of_the_writer() {
        let (m2, w2) = read_msh(&write_text("sq22.msh", SQUARE_22)).unwrap();
        assert_eq!(m2.points.len(), 5);
        assert_eq!(m2.points[4], [0.5, 0.5]);
        assert_eq!(m2.triangles.len(), 4);
        assert_eq!(m2.regions, vec![5, 6, 6, 5]);
        assert_eq!(m2.region_name(5), "left half");
        assert_eq!(m2.region_name(6), "right");
        assert!(!m2.region_names.contains_key(&7));
        assert!((m2.total_area() - 1.0).abs() < 1e-15);
        // The curve's boundary lines are boundary edges; the others are reported.
        assert_eq!(m2.boundary.edges, vec![[0, 1], [1, 2]]);
        assert_eq!(m2.boundary.tags, vec![7, 7]);
        assert_eq!(m2.boundary.names, BTreeMap::from([(7, "edge".to_string())]));
        assert_eq!(
            w2,
            vec![
                "skipped 1 elements of type 15 (1-node point)".to_string(),
                "physical curve 8: 1 line element lies inside the mesh, not on its boundary \
                 (a seam?): a boundary region holds boundary edges only, these are ignored"
                    .to_string(),
                "physical curve \"edge\" (tag 7): 1 line element is not an edge of any \
                 triangle: ignored"
                    .to_string(),
            ]
        );

        // 4.1: the third triangle block element 15 would overlap; drop it for the good case.
        let good41 = SQUARE_41
            .replace("3 6 1 14", "3 5 1 14")
            .replace("2 2 2 3\n", "2 2 2 2\n")
            .replace("15 30 99 10\n", "");
        let (m4, w4) = read_msh(&write_text("sq41.msh", &good41)).unwrap();
        assert_eq!(m4.points.len(), 5);
        assert_eq!(canonical(&m4), canonical(&m2));
        assert_eq!(m4.region_names, m2.region_names);
        // Curve entity 3 of physical curve 7 (no name in this file) holds edge 10-20.
        assert_eq!(m4.boundary.edges, vec![[0, 1]]);
        assert_eq!(m4.boundary.tags, vec![7]);
        assert!(m4.boundary.names.is_empty());
        assert!(w4.is_empty(), "{w4:?}");
        // The overlapping extra triangle is caught by the mesh checks.
        let e = read_msh(&write_text("sq41bad.msh", SQUARE_41)).unwrap_err();
        assert!(e.to_string().contains("sq41bad.msh"), "{e}");
    }

    #[test]
    fn writer_round_trips_in_all_flavours() {
        let (mesh, _) = read_msh(&data("disk_v41_ascii.msh")).unwrap();
        let mut mesh = mesh;
        mesh.region_names.insert(0, "default".into());
        mesh.regions[0] = 0;
        for (v, name) in [
            (MshVersion::V22Ascii, "w22a.msh"),
            (MshVersion::V22Binary, "w22b.msh"),
            (MshVersion::V41Ascii, "w41a.msh"),
            (MshVersion::V41Binary, "w41b.msh"),
        ] {
            let p = temp(name);
            write_msh(&p, &mesh, v).unwrap();
            let (back, warnings) = read_msh(&p).unwrap();
            assert!(warnings.is_empty(), "{warnings:?}");
            assert_eq!(back.points, mesh.points, "{name}");
            assert_eq!(canonical(&back), canonical(&mesh), "{name}");
            assert_eq!(back.region_names, mesh.region_names, "{name}");
        }
    }

    #[test]
    fn large_binary_blocks_keep_the_file_order() {
        // Blocks of many records are decoded in parallel: vertices, triangles and regions
        // must come back in file order, as the ASCII reader (record by record) gives them
        // (the writer groups the triangles by region: one block per region).
        let mut mesh = crate::mesh::generate::rectangle(&crate::mesh::generate::RectangleSpec {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            nx: 130,
            ny: 170,
            diagonal: crate::mesh::generate::Diagonal::Right,
        })
        .unwrap()
        .finest()
        .clone();
        assert!(mesh.points.len() > 2 * RECORDS_PER_TASK);
        for (k, r) in mesh.regions.iter_mut().enumerate() {
            *r = 1 + (k / 1000 % 3) as u32;
        }
        for t in 1..=3 {
            mesh.region_names.insert(t, format!("part{t}"));
        }
        let p = temp("large41b.msh");
        write_msh(&p, &mesh, MshVersion::V41Binary).unwrap();
        let (binary, _) = read_msh(&p).unwrap();
        let q = temp("large41a.msh");
        write_msh(&q, &mesh, MshVersion::V41Ascii).unwrap();
        let (ascii, _) = read_msh(&q).unwrap();
        assert!(binary.points == ascii.points && binary.points == mesh.points);
        assert!(binary.triangles == ascii.triangles && binary.regions == ascii.regions);
        assert!(canonical(&binary) == canonical(&mesh));
    }

    #[test]
    fn binary_numbers_decode_in_either_byte_order() {
        let v: u64 = 0x0102_0304_0506_0708;
        let x = -1.25e-7f64;
        for swap in [false, true] {
            let order = |b: Vec<u8>| {
                if swap {
                    b.into_iter().rev().collect()
                } else {
                    b
                }
            };
            let b8 = Binary { swap, size_t: 8 };
            assert_eq!(b8.size(&order(v.to_ne_bytes().to_vec())), v);
            assert_eq!(
                b8.double(&order(x.to_ne_bytes().to_vec())).to_bits(),
                x.to_bits()
            );
            let b4 = Binary { swap, size_t: 4 };
            assert_eq!(
                b4.size(&order(0x0a0b_0c0du32.to_ne_bytes().to_vec())),
                0x0a0b_0c0d
            );
        }
    }

    #[test]
    fn byte_swapped_binary_is_read() {
        // Write a 2.2 binary file, then swap every binary number by hand.
        let (mesh, _) = read_msh(&write_text("sw.msh", SQUARE_22)).unwrap();
        let p = temp("sw22b.msh");
        write_msh(&p, &mesh, MshVersion::V22Binary).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let text_end = |tag: &[u8], from: usize| find(&bytes[from..], tag).unwrap() + from;
        let mut out = bytes.clone();
        let swap = |out: &mut Vec<u8>, from: usize, to: usize, widths: &[usize]| {
            let mut pos = from;
            let mut k = 0;
            while pos < to {
                let w = widths[k % widths.len()];
                out[pos..pos + w].reverse();
                pos += w;
                k += 1;
            }
        };
        let one = text_end(b"2.2 1 8\n", 0) + 8;
        swap(&mut out, one, one + 4, &[4]);
        let nodes = text_end(b"$Nodes\n5\n", 0) + 9;
        swap(&mut out, nodes, nodes + 5 * 28, &[4, 8, 8, 8]);
        let elems = text_end(b"$Elements\n4\n", 0) + 12;
        swap(&mut out, elems, elems + 12 + 4 * 24, &[4]);
        let q = temp("sw22b_swapped.msh");
        std::fs::write(&q, out).unwrap();
        let (back, _) = read_msh(&q).unwrap();
        assert_eq!(canonical(&back), canonical(&mesh));
    }

    #[test]
    fn bad_files_are_clear_errors() {
        let err =
            |name: &str, text: &str| read_msh(&write_text(name, text)).unwrap_err().to_string();
        // truncated in the middle of $Elements
        let cut = &SQUARE_22[..SQUARE_22.find("13 2 2").unwrap()];
        let e = err("trunc.msh", cut);
        assert!(e.contains("trunc.msh") && e.contains("end of file"), "{e}");
        // truncated binary
        let (mesh, _) = read_msh(&write_text("ok.msh", SQUARE_22)).unwrap();
        let p = temp("truncb.msh");
        write_msh(&p, &mesh, MshVersion::V41Binary).unwrap();
        let b = std::fs::read(&p).unwrap();
        std::fs::write(&p, &b[..b.len() - 40]).unwrap();
        let e = read_msh(&p).unwrap_err().to_string();
        assert!(e.contains("$Elements") && e.contains("end of file"), "{e}");
        // bad header
        let e = err("hdr.msh", "$MeshFormt\n2.2 0 8\n$EndMeshFormat\n");
        assert!(e.contains("line 1") && e.contains("$MeshFormat"), "{e}");
        let e = err("ver.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n");
        assert!(e.contains("version 3.0"), "{e}");
        let e = err("num.msh", &SQUARE_22.replace("20 1 0 0", "20 1 zero 0"));
        assert!(e.contains("line 13") && e.contains("zero"), "{e}");
        // missing node
        let e = err(
            "miss.msh",
            &SQUARE_22.replace("12 2 2 6 1 20 30 99", "12 2 2 6 1 20 31 99"),
        );
        assert!(e.contains("triangle 12") && e.contains("node 31"), "{e}");
        // non-planar
        let e = err("z.msh", &SQUARE_22.replace("30 1 1 0", "30 1 1 0.25"));
        assert!(e.contains("node 30") && e.contains("plane"), "{e}");
        // no triangles
        let lines_only = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n\
                          $EndNodes\n$Elements\n1\n1 1 2 0 1 1 2\n$EndElements\n";
        let e = err("lines.msh", lines_only);
        assert!(e.contains("no 3-node triangle"), "{e}");
        // duplicate node tags
        let e = err(
            "dup.msh",
            &SQUARE_22.replace("99 0.5 0.5 0", "40 0.5 0.5 0"),
        );
        assert!(e.contains("node tag 40 appears twice"), "{e}");
        // no such file
        let e = read_msh(Path::new("/nonexistent/x.msh"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read"), "{e}");
        // an inverted triangle: reported by the mesh checks, with the file name
        let e = err("inv.msh", &SQUARE_22.replace("20 30 99", "30 20 99"));
        assert!(e.contains("inv.msh") && e.contains("inverted"), "{e}");
    }
}
