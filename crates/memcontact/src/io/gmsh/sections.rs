//! The sections of an MSH file: `$PhysicalNames`, `$Entities` (4.1), `$Nodes` and
//! `$Elements` in the 2.2 and 4.1 layouts.

use super::cursor::{Binary, Cursor, Parse, RECORDS_PER_TASK};
use super::raw::{element_type, Raw};
use std::collections::BTreeMap;

pub(super) fn read_physical_names(c: &mut Cursor, raw: &mut Raw) -> Parse<()> {
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
pub(super) struct Entities {
    /// Curves (dimension 1).
    pub(super) curves: BTreeMap<i32, Vec<i32>>,
    /// Surfaces (dimension 2).
    pub(super) surfaces: BTreeMap<i32, Vec<i32>>,
}

impl Entities {
    /// The physical tag the elements of entity `entity` of dimension `dim` get: the
    /// entity's first (0: none, or an entity that is neither a curve nor a surface).
    pub(super) fn physical(&self, dim: i32, entity: i32) -> i32 {
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
pub(super) fn read_entities(
    c: &mut Cursor,
    binary: bool,
    warnings: &mut Vec<String>,
) -> Parse<Entities> {
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

pub(super) fn read_nodes_v2(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
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

pub(super) fn read_nodes_v4(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
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

pub(super) fn read_elements_v2(c: &mut Cursor, binary: bool, raw: &mut Raw) -> Parse<()> {
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
        // The line number is counted only for the error: counting it for every element
        // would make reading quadratic in the file's size.
        let tag: i64 = tag_text.parse().map_err(|_| {
            let line = c.line(start);
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
pub(super) fn add_element(raw: &mut Raw, ty: i32, tag: i64, v: [u64; 3], phys: i64) -> Parse<()> {
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

pub(super) fn read_elements_v4(
    c: &mut Cursor,
    binary: bool,
    entities: &Entities,
    raw: &mut Raw,
) -> Parse<()> {
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
    // Room for every element as a triangle (usually most are), so that the blocks' triangles
    // are not moved as the array grows: capacity only, the pages unused are never touched.
    let total = c.check_count(
        head[1],
        if binary { 8 } else { 2 },
        "the number of elements",
    )?;
    raw.triangles.reserve(total);
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
