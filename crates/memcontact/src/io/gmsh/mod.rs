//! Gmsh MSH meshes: a reader for versions 2.2 and 4.1, ASCII and binary, and a writer.
//!
//! Only 3-node triangles (element type 2) make the mesh; physical surfaces become regions
//! (`$PhysicalNames` of dimension 2 name them). 2-node lines (element type 1) of physical
//! curves become boundary regions where they lie on the mesh's boundary (`$PhysicalNames`
//! of dimension 1 name them); lines inside the mesh are reported with a warning. Every
//! other element type is skipped with a warning. The format is described in the Gmsh
//! reference manual, section "MSH file format".

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;

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
    let bytes = crate::io::input::read_input(path, crate::io::input::MESH_FILE)?;
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

mod cursor;
mod raw;
mod sections;
#[cfg(test)]
mod tests;
mod write;

use cursor::{find, Cursor, Parse};
use raw::{ParseOrMesh, Raw};
use sections::{
    read_elements_v2, read_elements_v4, read_entities, read_nodes_v2, read_nodes_v4,
    read_physical_names, Entities,
};
pub use write::{write_msh, MshVersion};
