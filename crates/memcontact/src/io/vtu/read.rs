//! The reader of the VTK XML UnstructuredGrid (`.vtu`) files of triangle meshes that the
//! writer beside it writes (so that `memcontact plot` redraws a result directory): ASCII arrays, or one raw appended block
//! (`<AppendedData encoding="raw">`, `UInt32` or `UInt64` size headers, little-endian),
//! plain or zlib-compressed in blocks (`compressor="vtkZLibDataCompressor"`). Base64 and
//! other compressors are refused with a clear message.

use crate::error::{Error, Result};
use std::path::Path;

/// A data array of the file: name, VTK type, components, values (integers as exact f64).
#[derive(Debug, Clone, PartialEq)]
pub struct Array {
    /// The `Name` attribute.
    pub name: String,
    /// The VTK type (`Float64`, `Int32`, ...).
    pub vtk_type: String,
    /// Components per tuple.
    pub components: usize,
    /// The values, tuple by tuple.
    pub values: Vec<f64>,
}

/// A triangle mesh with its point and cell data, as read from a VTU file.
#[derive(Debug, Clone, Default)]
pub struct VtuMesh {
    /// Vertex coordinates (the file's z is dropped).
    pub points: Vec<[f64; 2]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Point data arrays.
    pub point_data: Vec<Array>,
    /// Cell data arrays.
    pub cell_data: Vec<Array>,
}

impl VtuMesh {
    /// The point data array called `name`, if any.
    pub fn point_array(&self, name: &str) -> Option<&Array> {
        self.point_data.iter().find(|a| a.name == name)
    }
}

/// Reads a VTU file of triangles.
pub fn read_vtu(path: &Path) -> Result<VtuMesh> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes).map_err(|message| Error::File {
        path: path.to_path_buf(),
        message,
    })
}

/// The value of attribute `key` in the tag text `tag`.
fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let i = tag.find(&pat)? + pat.len();
    let j = tag[i..].find('"')?;
    Some(&tag[i..i + j])
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Where an array's values are.
enum Source {
    Ascii(String),
    Appended(usize),
}

/// Size in bytes of a VTK scalar type.
fn type_size(t: &str) -> Option<usize> {
    Some(match t {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "Int16" | "UInt16" => 2,
        "Int8" | "UInt8" => 1,
        _ => return None,
    })
}

fn decode(t: &str, b: &[u8]) -> f64 {
    match t {
        "Float64" => f64::from_le_bytes(b.try_into().unwrap_or([0; 8])),
        "Float32" => f32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        "Int64" => i64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f64,
        "UInt64" => u64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f64,
        "Int32" => i32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        "UInt32" => u32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        "Int16" => i16::from_le_bytes(b.try_into().unwrap_or([0; 2])) as f64,
        "UInt16" => u16::from_le_bytes(b.try_into().unwrap_or([0; 2])) as f64,
        "Int8" => b[0] as i8 as f64,
        _ => b[0] as f64,
    }
}

fn parse_ascii(text: &str, name: &str) -> std::result::Result<Vec<f64>, String> {
    text.split_ascii_whitespace()
        .map(|w| match w {
            "nan" | "NaN" => Ok(f64::NAN),
            "inf" | "Infinity" => Ok(f64::INFINITY),
            "-inf" | "-Infinity" => Ok(f64::NEG_INFINITY),
            _ => w
                .parse::<f64>()
                .map_err(|_| format!("array `{name}`: `{w}` is not a number")),
        })
        .collect()
}

fn parse(bytes: &[u8]) -> std::result::Result<VtuMesh, String> {
    let appended_at = find(bytes, b"<AppendedData");
    let header_bytes = &bytes[..appended_at.unwrap_or(bytes.len())];
    let header = std::str::from_utf8(header_bytes)
        .map_err(|_| "the XML part is not UTF-8 text".to_string())?;
    let vtk = header
        .find("<VTKFile")
        .map(|i| &header[i..i + header[i..].find('>').unwrap_or(0)])
        .ok_or("not a VTK XML file (no <VTKFile> tag)")?;
    if attr(vtk, "type") != Some("UnstructuredGrid") {
        return Err("not an UnstructuredGrid VTK file".into());
    }
    if attr(vtk, "byte_order").is_some_and(|b| b != "LittleEndian") {
        return Err("big-endian VTU files are not supported".into());
    }
    let zlib = match attr(vtk, "compressor") {
        None => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => return Err(format!("compressor {c} is not supported (zlib is)")),
    };
    let header_size = match attr(vtk, "header_type") {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(t) => return Err(format!("unsupported header_type {t}")),
    };
    if header.matches("<Piece").count() != 1 {
        return Err("expected exactly one <Piece>".into());
    }
    let piece = header
        .find("<Piece")
        .map(|i| &header[i..i + header[i..].find('>').unwrap_or(0)])
        .unwrap_or("");
    let count = |k: &str| -> std::result::Result<usize, String> {
        attr(piece, k)
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| format!("<Piece> has no valid {k}"))
    };
    let (n_points, n_cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);

    // Walk the tags, tracking the section.
    let mut section = "";
    let mut arrays: Vec<(String, Array, Source)> = Vec::new();
    let mut pos = 0;
    while let Some(i) = header[pos..].find('<') {
        let start = pos + i;
        let end = start + header[start..].find('>').ok_or("an unterminated tag")?;
        let tag = &header[start..end];
        pos = end + 1;
        for s in ["PointData", "CellData", "Points", "Cells"] {
            if tag == format!("<{s}") || tag.starts_with(&format!("<{s} ")) {
                section = s;
            } else if tag == format!("</{s}") {
                section = "";
            }
        }
        if !tag.starts_with("<DataArray") {
            continue;
        }
        let name = unescape(attr(tag, "Name").unwrap_or(""));
        let vtk_type = attr(tag, "type")
            .ok_or_else(|| format!("array `{name}` has no type"))?
            .to_string();
        if type_size(&vtk_type).is_none() {
            return Err(format!("array `{name}`: unsupported type {vtk_type}"));
        }
        let components = attr(tag, "NumberOfComponents")
            .and_then(|c| c.parse().ok())
            .unwrap_or(1);
        let source = match attr(tag, "format") {
            Some("ascii") => {
                let close = header[pos..]
                    .find("</DataArray>")
                    .ok_or_else(|| format!("array `{name}` is not closed"))?;
                let text = header[pos..pos + close].to_string();
                pos += close;
                Source::Ascii(text)
            }
            Some("appended") => Source::Appended(
                attr(tag, "offset")
                    .and_then(|o| o.trim().parse().ok())
                    .ok_or_else(|| format!("array `{name}` has no valid offset"))?,
            ),
            Some(f) => {
                return Err(format!(
                    "array `{name}`: format \"{f}\" is not supported (ascii or raw appended)"
                ))
            }
            None => return Err(format!("array `{name}` has no format")),
        };
        arrays.push((
            section.to_string(),
            Array {
                name,
                vtk_type,
                components,
                values: Vec::new(),
            },
            source,
        ));
    }
    // The appended block: after the '_' that follows <AppendedData ...>.
    let base = match appended_at {
        Some(a) => {
            let tag_end = a + find(&bytes[a..], b">").ok_or("unterminated <AppendedData>")?;
            let tag = std::str::from_utf8(&bytes[a..tag_end]).unwrap_or("");
            if attr(tag, "encoding") != Some("raw") {
                return Err("only raw appended data is supported (not base64)".into());
            }
            let u = tag_end
                + find(&bytes[tag_end..], b"_").ok_or("appended data without '_' marker")?;
            Some(u + 1)
        }
        None => None,
    };
    for (_, a, src) in arrays.iter_mut() {
        a.values = match src {
            Source::Ascii(text) => parse_ascii(text, &a.name)?,
            Source::Appended(off) => {
                let base = base.ok_or_else(|| {
                    format!(
                        "array `{}` is appended but the file has no appended data",
                        a.name
                    )
                })?;
                let at = base + *off;
                let data = if zlib {
                    inflate(bytes, at, header_size)
                        .map_err(|e| format!("array `{}`: {e}", a.name))?
                } else {
                    let nbytes = word(bytes, at, header_size).ok_or_else(|| {
                        format!("array `{}`: offset beyond the end of the file", a.name)
                    })?;
                    bytes
                        .get(at + header_size..at + header_size + nbytes)
                        .ok_or_else(|| {
                            format!("array `{}`: data runs past the end of the file", a.name)
                        })?
                        .to_vec()
                };
                let nbytes = data.len();
                let size = type_size(&a.vtk_type).unwrap_or(1);
                if nbytes % size != 0 {
                    return Err(format!(
                        "array `{}`: {nbytes} bytes is not a whole number of values",
                        a.name
                    ));
                }
                data.chunks_exact(size)
                    .map(|b| decode(&a.vtk_type, b))
                    .collect()
            }
        };
    }
    let take = |sec: &str, name: &str| {
        arrays
            .iter()
            .find(|(s, a, _)| s == sec && (name.is_empty() || a.name == name))
            .map(|(_, a, _)| a)
    };
    let pts = take("Points", "").ok_or("no <Points> array")?;
    if pts.values.len() != n_points * pts.components || !(2..=3).contains(&pts.components) {
        return Err(format!(
            "Points: {} values for {n_points} points of {} components",
            pts.values.len(),
            pts.components
        ));
    }
    let points = pts
        .values
        .chunks_exact(pts.components)
        .map(|c| [c[0], c[1]])
        .collect();
    let conn = take("Cells", "connectivity").ok_or("no connectivity array")?;
    let offsets = take("Cells", "offsets").ok_or("no offsets array")?;
    let types = take("Cells", "types").ok_or("no types array")?;
    if offsets.values.len() != n_cells
        || types.values.len() != n_cells
        || conn.values.len() != 3 * n_cells
    {
        return Err(format!(
            "the cell arrays do not describe {n_cells} triangles"
        ));
    }
    for (i, (&o, &t)) in offsets.values.iter().zip(&types.values).enumerate() {
        if t != 5.0 || o != 3.0 * (i + 1) as f64 {
            return Err(format!(
                "cell {i} is not a triangle (only triangle meshes are read)"
            ));
        }
    }
    let mut triangles = Vec::with_capacity(n_cells);
    for (i, c) in conn.values.chunks_exact(3).enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let v = c[k];
            if !(v >= 0.0 && v < n_points as f64 && v.fract() == 0.0) {
                return Err(format!(
                    "triangle {i} refers to vertex {v}, not one of the {n_points} points"
                ));
            }
            t[k] = v as u32;
        }
        triangles.push(t);
    }
    let mut point_data = Vec::new();
    let mut cell_data = Vec::new();
    for (s, a, _) in arrays {
        let (list, n) = match s.as_str() {
            "PointData" => (&mut point_data, n_points),
            "CellData" => (&mut cell_data, n_cells),
            _ => continue,
        };
        if a.values.len() != n * a.components {
            return Err(format!(
                "{s} array `{}` has {} values, expected {}",
                a.name,
                a.values.len(),
                n * a.components
            ));
        }
        list.push(a);
    }
    Ok(VtuMesh {
        points,
        triangles,
        point_data,
        cell_data,
    })
}

/// The size header (`UInt32` or `UInt64`, little-endian) at `at`, if the file has it.
fn word(bytes: &[u8], at: usize, size: usize) -> Option<usize> {
    let b = bytes.get(at..at.checked_add(size)?)?;
    Some(match size {
        8 => u64::from_le_bytes(b.try_into().ok()?) as usize,
        _ => u32::from_le_bytes(b.try_into().ok()?) as usize,
    })
}

/// The bytes of a zlib-compressed appended array at `at`: VTK's header (block count,
/// block size, size of a shorter last block or 0, each block's compressed size), then
/// the blocks, each inflated and checked against the size the header gives.
fn inflate(bytes: &[u8], at: usize, size: usize) -> std::result::Result<Vec<u8>, String> {
    use std::io::Read;
    let head = |k: usize| {
        word(bytes, at + k * size, size).ok_or("the compression header runs past the end")
    };
    let (blocks, block, last) = (head(0)?, head(1)?, head(2)?);
    if blocks > bytes.len() / size {
        return Err(format!("a compression header of {blocks} blocks"));
    }
    let mut data = at + (3 + blocks) * size;
    let mut out = Vec::with_capacity(block.saturating_mul(blocks).min(bytes.len() * 64));
    for b in 0..blocks {
        let c = head(3 + b)?;
        let z = bytes
            .get(data..data.saturating_add(c))
            .ok_or("compressed data runs past the end of the file")?;
        let want = if b + 1 == blocks && last != 0 {
            last
        } else {
            block
        };
        let before = out.len();
        flate2::read::ZlibDecoder::new(z)
            .take(want as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("block {b} does not inflate: {e}"))?;
        if out.len() - before != want {
            return Err(format!(
                "block {b} inflates to {} bytes, the header says {want}",
                out.len() - before
            ));
        }
        data += c;
    }
    Ok(out)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::vtu::{write_vtu, DataArray, VtuEncoding};
    use crate::mesh::Mesh;

    #[test]
    fn reads_back_what_the_library_writes_exactly() {
        let mesh = Mesh::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
            vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
            vec![],
            Default::default(),
        )
        .unwrap();
        let u = [0.1, -2.5e-300, f64::MAX, 1.0 / 3.0, 0.0];
        let nan = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1.0, 2.0];
        let s = [-1, 0, 1, 1, -1];
        let flags = [1i8, 0, 1, 0, 1];
        let region = [0, 1, 2, 3];
        let dir = tempfile::tempdir().unwrap();
        for enc in [
            VtuEncoding::Binary,
            VtuEncoding::Ascii,
            VtuEncoding::Compressed,
        ] {
            let path = dir.path().join("a <&>.vtu");
            write_vtu(
                &path,
                &mesh,
                &[
                    ("u", DataArray::F64(&u)),
                    ("odd <name>", DataArray::F64(&nan)),
                    ("state", DataArray::I32(&s)),
                    ("flag", DataArray::I8(&flags)),
                ],
                &[("region", DataArray::I32(&region))],
                enc,
            )
            .unwrap();
            let r = read_vtu(&path).unwrap();
            assert_eq!(r.points, mesh.points);
            assert_eq!(r.triangles, mesh.triangles);
            let get = |n: &str| r.point_array(n).unwrap().values.clone();
            assert_eq!(
                get("u").iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                u.map(f64::to_bits).to_vec()
            );
            let odd = get("odd <name>");
            assert!(odd[0].is_nan() && odd[1] == f64::INFINITY && odd[2] == f64::NEG_INFINITY);
            assert_eq!(get("state"), vec![-1.0, 0.0, 1.0, 1.0, -1.0]);
            assert_eq!(r.point_array("flag").unwrap().vtk_type, "Int8");
            assert_eq!(r.cell_data[0].values, vec![0.0, 1.0, 2.0, 3.0]);
        }
    }

    #[test]
    fn broken_files_are_named_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.vtu");
        std::fs::write(&p, "<?xml version=\"1.0\"?>\n<html></html>").unwrap();
        let e = read_vtu(&p).unwrap_err().to_string();
        assert!(e.contains("bad.vtu") && e.contains("VTK"), "{e}");
        std::fs::write(
            &p,
            r#"<VTKFile type="UnstructuredGrid" byte_order="LittleEndian"><UnstructuredGrid><Piece NumberOfPoints="1" NumberOfCells="0"><Points><DataArray type="Float64" NumberOfComponents="3" format="binary">AAAA</DataArray></Points></Piece></UnstructuredGrid></VTKFile>"#,
        )
        .unwrap();
        let e = read_vtu(&p).unwrap_err().to_string();
        assert!(e.contains("not supported"), "{e}");
        let e = read_vtu(&dir.path().join("missing.vtu"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.vtu"), "{e}");
        // A compressed file cut short, or with a damaged block, is an error, not a panic.
        let n = 20_000;
        let mesh = Mesh::new(
            (0..n).map(|i| [i as f64, (i % 2) as f64]).collect(),
            (0..n as u32 - 2)
                .map(|i| {
                    if i % 2 == 0 {
                        [i, i + 2, i + 1]
                    } else {
                        [i, i + 1, i + 2]
                    }
                })
                .collect(),
            vec![],
            Default::default(),
        )
        .unwrap();
        let u: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let good = dir.path().join("z.vtu");
        let u_data = [("u", DataArray::F64(&u))];
        write_vtu(&good, &mesh, &u_data, &[], VtuEncoding::Compressed).unwrap();
        assert_eq!(read_vtu(&good).unwrap().point_array("u").unwrap().values, u);
        let bytes = std::fs::read(&good).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        assert!(read_vtu(&p).is_err());
        let mut damaged = bytes.clone();
        let mid = bytes.len() * 3 / 4;
        for b in &mut damaged[mid..mid + 64] {
            *b ^= 0x5a;
        }
        std::fs::write(&p, &damaged).unwrap();
        let e = read_vtu(&p).unwrap_err().to_string();
        assert!(e.contains("block") || e.contains("inflate"), "{e}");
    }
}
