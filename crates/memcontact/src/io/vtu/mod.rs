//! ParaView / VTK XML UnstructuredGrid (`.vtu`) writer for triangle meshes with nodal and
//! per-triangle fields.
//!
//! * Points are written in 3-D. [`write_vtu`] puts every vertex at `z = 0`;
//!   [`write_vtu_warped`] takes a nodal `z` (typically the deflection `u`) so that the
//!   deflected membrane is seen directly (in ParaView the same is obtained from a flat file
//!   with the *Warp By Scalar* filter).
//! * Cells are VTK triangles (cell type 5) with `Int32` `connectivity` and `offsets` arrays
//!   and a `UInt8` `types` array.
//! * [`VtuEncoding::Ascii`] writes every value as text: floats in the shortest form that
//!   reads back to the same `f64` (so the file round-trips exactly); non-finite values are
//!   written `nan`, `inf`, `-inf`, which some VTK readers reject: prefer the binary form for
//!   fields that may hold them.
//! * [`VtuEncoding::Binary`] writes one raw appended block (`<AppendedData
//!   encoding="raw">`, `header_type="UInt64"`, little-endian), each array preceded by its
//!   byte count: the fastest choice, exact for every value including NaN.
//! * [`VtuEncoding::Compressed`] writes the same appended block compressed with zlib, as
//!   ParaView reads it (`compressor="vtkZLibDataCompressor"`): each array is cut into
//!   blocks of about 1 MiB, compressed in parallel, and preceded by VTK's header (block
//!   count, block size, size of the last block, compressed size of each block). Exact,
//!   smaller, slower to write.
//!
//! The file is written atomically ([`crate::io::write_atomic`]).

mod read;

pub use read::{read_vtu, Array, VtuMesh};

use crate::error::{Error, Result};
pub use crate::io::numbers::DataArray;
use crate::io::numbers::{push_int, push_shortest};
use crate::io::Written;
use crate::mesh::Mesh;
use std::io::Write;
use std::path::Path;

/// How the arrays of a VTU file are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtuEncoding {
    /// Human-readable text, exact (shortest round-trip floats) but large and slow.
    Ascii,
    /// Raw little-endian appended data with `UInt64` size headers: fast and exact.
    #[default]
    Binary,
    /// The same appended data, zlib-compressed in blocks (VTK's `vtkZLibDataCompressor`).
    Compressed,
}

/// Writes `mesh` as a flat (`z = 0`) VTU file with the given nodal (`point_data`, one value
/// per vertex) and per-triangle (`cell_data`, one value per triangle) arrays.
///
/// Returns [`Error::Data`] naming the array whose length does not match, or a duplicate or
/// empty name, and [`Error::Io`] if the file cannot be written (then no file is left).
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    point_data: &[(&str, DataArray)],
    cell_data: &[(&str, DataArray)],
    encoding: VtuEncoding,
) -> Result<Written> {
    write_vtu_impl(path, mesh, None, point_data, cell_data, encoding, &[])
}

/// As [`write_vtu`], with text `field_data` (name, value) stored in the file's
/// `<FieldData>` as `UInt8` arrays of the text's bytes (how a result set's run id travels
/// with its `solution.vtu`: `bytes(array).decode()` reads it back).
pub fn write_vtu_with_field_data(
    path: &Path,
    mesh: &Mesh,
    point_data: &[(&str, DataArray)],
    cell_data: &[(&str, DataArray)],
    encoding: VtuEncoding,
    field_data: &[(&str, &str)],
) -> Result<Written> {
    write_vtu_impl(
        path, mesh, None, point_data, cell_data, encoding, field_data,
    )
}

/// As [`write_vtu`], but vertex `i` is placed at height `z[i]` (e.g. the deflection), so
/// that the file shows the deformed surface. `z` must have one value per vertex.
pub fn write_vtu_warped(
    path: &Path,
    mesh: &Mesh,
    z: &[f64],
    point_data: &[(&str, DataArray)],
    cell_data: &[(&str, DataArray)],
    encoding: VtuEncoding,
) -> Result<Written> {
    write_vtu_impl(path, mesh, Some(z), point_data, cell_data, encoding, &[])
}

/// One array of the file, user-supplied or derived from the mesh.
enum Block<'a> {
    Data(DataArray<'a>),
    Points(&'a [[f64; 2]], Option<&'a [f64]>),
    Connectivity(&'a [[u32; 3]]),
    Offsets(usize),
    Types(usize),
}

impl Block<'_> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Block::Data(DataArray::F64(_)) | Block::Points(..) => "Float64",
            Block::Data(DataArray::I32(_)) | Block::Connectivity(_) | Block::Offsets(_) => "Int32",
            Block::Data(DataArray::I8(_)) => "Int8",
            Block::Types(_) => "UInt8",
        }
    }

    /// The number of values (tuples: a point, a triangle) of the payload.
    fn len(&self) -> usize {
        match self {
            Block::Data(DataArray::F64(v)) => v.len(),
            Block::Data(DataArray::I32(v)) => v.len(),
            Block::Data(DataArray::I8(v)) => v.len(),
            Block::Points(p, _) => p.len(),
            Block::Connectivity(t) => t.len(),
            Block::Offsets(n) | Block::Types(n) => *n,
        }
    }

    /// The bytes of one value (tuple) of the payload.
    fn value_size(&self) -> usize {
        match self {
            Block::Data(DataArray::F64(_)) => 8,
            Block::Data(DataArray::I32(_)) | Block::Offsets(_) => 4,
            Block::Data(DataArray::I8(_)) | Block::Types(_) => 1,
            Block::Points(..) => 24,
            Block::Connectivity(_) => 12,
        }
    }

    /// Size of the binary payload in bytes.
    fn byte_len(&self) -> usize {
        self.value_size() * self.len()
    }

    /// Writes the payload as raw little-endian bytes.
    fn write_binary(&self, w: &mut dyn Write) -> std::io::Result<()> {
        self.write_binary_range(0..self.len(), w)
    }

    /// Writes the values `range` of the payload as raw little-endian bytes.
    fn write_binary_range(
        &self,
        range: std::ops::Range<usize>,
        w: &mut dyn Write,
    ) -> std::io::Result<()> {
        match *self {
            Block::Data(DataArray::F64(v)) => write_le(w, &v[range], f64::to_le_bytes),
            Block::Data(DataArray::I32(v)) => write_le(w, &v[range], i32::to_le_bytes),
            Block::Data(DataArray::I8(v)) => write_le(w, &v[range], i8::to_le_bytes),
            Block::Points(p, z) => {
                let mut buf = Vec::with_capacity(CHUNK);
                let first = range.start;
                for (k, chunk) in p[range].chunks(CHUNK / 24).enumerate() {
                    buf.clear();
                    buf.resize(24 * chunk.len(), 0);
                    let base = first + k * (CHUNK / 24);
                    for (i, (dst, q)) in buf.chunks_exact_mut(24).zip(chunk).enumerate() {
                        let zi = z.map_or(0.0, |z| z[base + i]);
                        dst[0..8].copy_from_slice(&q[0].to_le_bytes());
                        dst[8..16].copy_from_slice(&q[1].to_le_bytes());
                        dst[16..24].copy_from_slice(&zi.to_le_bytes());
                    }
                    w.write_all(&buf)?;
                }
                Ok(())
            }
            Block::Connectivity(t) => write_le(w, &t[range], |t: [u32; 3]| {
                // Indices were checked to fit in an i32: the bit pattern is the same.
                let mut b = [0u8; 12];
                b[0..4].copy_from_slice(&t[0].to_le_bytes());
                b[4..8].copy_from_slice(&t[1].to_le_bytes());
                b[8..12].copy_from_slice(&t[2].to_le_bytes());
                b
            }),
            Block::Offsets(_) => {
                let mut buf = Vec::with_capacity(CHUNK);
                let (mut i, n) = (range.start, range.end);
                while i < n {
                    let m = (n - i).min(CHUNK / 4);
                    buf.clear();
                    for j in i..i + m {
                        buf.extend_from_slice(&(3 * (j as i32 + 1)).to_le_bytes());
                    }
                    w.write_all(&buf)?;
                    i += m;
                }
                Ok(())
            }
            Block::Types(_) => {
                let buf = vec![TRIANGLE; range.len().min(CHUNK)];
                let mut left = range.len();
                while left > 0 {
                    let m = left.min(buf.len());
                    w.write_all(&buf[..m])?;
                    left -= m;
                }
                Ok(())
            }
        }
    }

    /// The payload zlib-compressed as VTK stores it: the header (block count, bytes of a
    /// block, bytes of the last block when it is shorter, else 0, then each block's
    /// compressed bytes) and the compressed blocks, made in parallel.
    fn compress(&self) -> std::io::Result<Compressed> {
        use rayon::prelude::*;
        let size = self.value_size();
        let per = (ZBLOCK / size).max(1);
        let n = self.len();
        let starts: Vec<usize> = (0..n).step_by(per).collect();
        let blocks = starts
            .par_iter()
            .map(|&s| {
                let mut raw = Vec::with_capacity(per * size);
                self.write_binary_range(s..(s + per).min(n), &mut raw)?;
                let mut z = flate2::write::ZlibEncoder::new(
                    Vec::with_capacity(raw.len() / 2),
                    flate2::Compression::fast(),
                );
                z.write_all(&raw)?;
                z.finish()
            })
            .collect::<std::io::Result<Vec<Vec<u8>>>>()?;
        let mut header = vec![
            blocks.len() as u64,
            (per * size) as u64,
            ((n % per) * size) as u64,
        ];
        header.extend(blocks.iter().map(|b| b.len() as u64));
        Ok(Compressed { header, blocks })
    }

    /// Writes the payload as text lines (between the DataArray tags).
    fn write_ascii(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let mut buf: Vec<u8> = Vec::with_capacity(CHUNK + 1024);
        let flush = |buf: &mut Vec<u8>, w: &mut dyn Write, force: bool| {
            if force || buf.len() >= CHUNK {
                w.write_all(buf)?;
                buf.clear();
            }
            std::io::Result::Ok(())
        };
        const PER_LINE: usize = 6;
        match *self {
            Block::Data(DataArray::F64(v)) => {
                for (i, &x) in v.iter().enumerate() {
                    push_f64(&mut buf, x);
                    push_sep(&mut buf, i, PER_LINE);
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Data(DataArray::I32(v)) => {
                for (i, &x) in v.iter().enumerate() {
                    push_int(&mut buf, x as i64);
                    push_sep(&mut buf, i, PER_LINE);
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Data(DataArray::I8(v)) => {
                for (i, &x) in v.iter().enumerate() {
                    push_int(&mut buf, x as i64);
                    push_sep(&mut buf, i, PER_LINE);
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Points(p, z) => {
                for (i, q) in p.iter().enumerate() {
                    push_f64(&mut buf, q[0]);
                    buf.push(b' ');
                    push_f64(&mut buf, q[1]);
                    buf.push(b' ');
                    push_f64(&mut buf, z.map_or(0.0, |z| z[i]));
                    buf.push(b'\n');
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Connectivity(t) => {
                for tri in t {
                    for (k, &v) in tri.iter().enumerate() {
                        push_int(&mut buf, v as i64);
                        buf.push(if k == 2 { b'\n' } else { b' ' });
                    }
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Offsets(n) => {
                for i in 0..n {
                    push_int(&mut buf, 3 * (i as i64 + 1));
                    push_sep(&mut buf, i, PER_LINE);
                    flush(&mut buf, w, false)?;
                }
            }
            Block::Types(n) => {
                for i in 0..n {
                    push_int(&mut buf, TRIANGLE as i64);
                    push_sep(&mut buf, i, PER_LINE);
                    flush(&mut buf, w, false)?;
                }
            }
        }
        if buf.last().is_some_and(|&c| c != b'\n') {
            buf.push(b'\n');
        }
        flush(&mut buf, w, true)
    }
}

/// VTK cell type of a linear triangle.
const TRIANGLE: u8 = 5;
/// Size of the staging buffers, in bytes.
const CHUNK: usize = 1 << 16;
/// Bytes of raw data in a block of a compressed array (rounded down to whole values).
const ZBLOCK: usize = 1 << 20;

/// An array's payload compressed for the file: VTK's header and the compressed blocks.
struct Compressed {
    header: Vec<u64>,
    blocks: Vec<Vec<u8>>,
}

impl Compressed {
    /// Bytes in the file: the header's numbers and the blocks.
    fn byte_len(&self) -> usize {
        8 * self.header.len() + self.blocks.iter().map(Vec::len).sum::<usize>()
    }

    /// Writes the header (little-endian `UInt64`s) and the blocks.
    fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let mut head = Vec::with_capacity(8 * self.header.len());
        for h in &self.header {
            head.extend_from_slice(&h.to_le_bytes());
        }
        w.write_all(&head)?;
        for b in &self.blocks {
            w.write_all(b)?;
        }
        Ok(())
    }
}

/// Writes `data` as little-endian bytes through a staging buffer (no per-value formatting).
fn write_le<T: Copy, const N: usize>(
    w: &mut dyn Write,
    data: &[T],
    to_bytes: impl Fn(T) -> [u8; N],
) -> std::io::Result<()> {
    let mut buf = vec![0u8; (CHUNK / N) * N];
    for chunk in data.chunks(CHUNK / N) {
        let bytes = &mut buf[..N * chunk.len()];
        for (dst, &x) in bytes.chunks_exact_mut(N).zip(chunk) {
            dst.copy_from_slice(&to_bytes(x));
        }
        w.write_all(bytes)?;
    }
    Ok(())
}

/// Appends `x` in its shortest round-trip form (`nan`, `inf`, `-inf` when not finite).
fn push_f64(buf: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        push_shortest(buf, x);
    } else if x.is_nan() {
        buf.extend_from_slice(b"nan");
    } else if x > 0.0 {
        buf.extend_from_slice(b"inf");
    } else {
        buf.extend_from_slice(b"-inf");
    }
}

fn push_sep(buf: &mut Vec<u8>, i: usize, per_line: usize) {
    buf.push(if i % per_line == per_line - 1 {
        b'\n'
    } else {
        b' '
    });
}

/// Escapes the five XML special characters of an attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Checks names (non-empty, unique within their section) and lengths of user arrays.
fn check_arrays(arrays: &[(&str, DataArray)], expected: usize, what: &str) -> Result<()> {
    for (i, (name, data)) in arrays.iter().enumerate() {
        if name.is_empty() {
            return Err(Error::Data(format!(
                "VTU {what} array #{i} has an empty name"
            )));
        }
        if arrays[..i].iter().any(|(n, _)| n == name) {
            return Err(Error::Data(format!(
                "VTU {what} array `{name}` is given twice"
            )));
        }
        if data.len() != expected {
            let unit = if what == "point data" {
                "vertices"
            } else {
                "triangles"
            };
            return Err(Error::Data(format!(
                "VTU {what} array `{name}` has {} values, the mesh has {expected} {unit}",
                data.len()
            )));
        }
    }
    Ok(())
}

fn write_vtu_impl(
    path: &Path,
    mesh: &Mesh,
    z: Option<&[f64]>,
    point_data: &[(&str, DataArray)],
    cell_data: &[(&str, DataArray)],
    encoding: VtuEncoding,
    field_data: &[(&str, &str)],
) -> Result<Written> {
    let n_points = mesh.points.len();
    let n_cells = mesh.triangles.len();
    check_arrays(point_data, n_points, "point data")?;
    check_arrays(cell_data, n_cells, "cell data")?;
    if let Some(z) = z {
        if z.len() != n_points {
            return Err(Error::Data(format!(
                "VTU point heights `z` have {} values, the mesh has {n_points} vertices",
                z.len()
            )));
        }
    }
    if n_points > i32::MAX as usize || 3 * n_cells > i32::MAX as usize {
        return Err(Error::Data(format!(
            "VTU: {n_points} vertices / {n_cells} triangles exceed the Int32 cell arrays"
        )));
    }
    if let Some((t, tri)) = mesh
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n_points))
    {
        return Err(Error::Data(format!(
            "VTU: triangle {t} {tri:?} refers to a vertex beyond the {n_points} vertices"
        )));
    }

    // (section, name or attribute text, block) in file order.
    let mut blocks: Vec<(Section, String, Block)> = Vec::new();
    for (name, data) in point_data {
        let attrs = format!(r#"Name="{}""#, xml_escape(name));
        blocks.push((Section::PointData, attrs, Block::Data(*data)));
    }
    for (name, data) in cell_data {
        let attrs = format!(r#"Name="{}""#, xml_escape(name));
        blocks.push((Section::CellData, attrs, Block::Data(*data)));
    }
    blocks.push((
        Section::Points,
        r#"Name="Points" NumberOfComponents="3""#.into(),
        Block::Points(&mesh.points, z),
    ));
    blocks.push((
        Section::Cells,
        r#"Name="connectivity""#.into(),
        Block::Connectivity(&mesh.triangles),
    ));
    blocks.push((
        Section::Cells,
        r#"Name="offsets""#.into(),
        Block::Offsets(n_cells),
    ));
    blocks.push((
        Section::Cells,
        r#"Name="types""#.into(),
        Block::Types(n_cells),
    ));

    // Compressed arrays are made before the XML, which gives their offsets.
    let compressed: Vec<Compressed> = if encoding == VtuEncoding::Compressed {
        blocks
            .iter()
            .map(|(_, _, b)| b.compress())
            .collect::<std::io::Result<_>>()
            .map_err(|source| Error::Io {
                path: path.to_path_buf(),
                source,
            })?
    } else {
        Vec::new()
    };
    crate::io::write_atomic(path, |w| {
        let header_type = match encoding {
            VtuEncoding::Ascii => "",
            VtuEncoding::Binary => r#" header_type="UInt64""#,
            VtuEncoding::Compressed => {
                r#" header_type="UInt64" compressor="vtkZLibDataCompressor""#
            }
        };
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            w,
            r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian"{header_type}>"#
        )?;
        writeln!(w, "  <UnstructuredGrid>")?;
        if !field_data.is_empty() {
            writeln!(w, "    <FieldData>")?;
            for (name, text) in field_data {
                let codes: Vec<String> = text.bytes().map(|b| b.to_string()).collect();
                writeln!(
                    w,
                    r#"      <DataArray type="UInt8" Name="{}" NumberOfTuples="{}" format="ascii">{}</DataArray>"#,
                    xml_escape(name),
                    codes.len(),
                    codes.join(" ")
                )?;
            }
            writeln!(w, "    </FieldData>")?;
        }
        writeln!(
            w,
            r#"    <Piece NumberOfPoints="{n_points}" NumberOfCells="{n_cells}">"#
        )?;
        let mut offset = 0usize;
        let mut open: Option<Section> = None;
        for (k, (section, attrs, block)) in blocks.iter().enumerate() {
            if open != Some(*section) {
                if let Some(s) = open {
                    writeln!(w, "      </{}>", s.tag())?;
                }
                writeln!(w, "      <{}>", section.tag())?;
                open = Some(*section);
            }
            let ty = block.vtk_type();
            match encoding {
                VtuEncoding::Ascii => {
                    writeln!(
                        w,
                        r#"        <DataArray type="{ty}" {attrs} format="ascii">"#
                    )?;
                    block.write_ascii(w)?;
                    writeln!(w, "        </DataArray>")?;
                }
                VtuEncoding::Binary | VtuEncoding::Compressed => {
                    writeln!(
                        w,
                        r#"        <DataArray type="{ty}" {attrs} format="appended" offset="{offset}"/>"#
                    )?;
                    offset += match compressed.get(k) {
                        Some(c) => c.byte_len(),
                        None => 8 + block.byte_len(),
                    };
                }
            }
        }
        if let Some(s) = open {
            writeln!(w, "      </{}>", s.tag())?;
        }
        writeln!(w, "    </Piece>")?;
        writeln!(w, "  </UnstructuredGrid>")?;
        if encoding != VtuEncoding::Ascii {
            writeln!(w, r#"  <AppendedData encoding="raw">"#)?;
            w.write_all(b"   _")?;
            if encoding == VtuEncoding::Compressed {
                for c in &compressed {
                    c.write(w)?;
                }
            } else {
                for (_, _, block) in &blocks {
                    w.write_all(&(block.byte_len() as u64).to_le_bytes())?;
                    block.write_binary(w)?;
                }
            }
            writeln!(w)?;
            writeln!(w, "  </AppendedData>")?;
        }
        writeln!(w, "</VTKFile>")?;
        Ok(())
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Section {
    PointData,
    CellData,
    Points,
    Cells,
}

impl Section {
    fn tag(self) -> &'static str {
        match self {
            Section::PointData => "PointData",
            Section::CellData => "CellData",
            Section::Points => "Points",
            Section::Cells => "Cells",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A parsed `<DataArray>`: its section, attributes and values (ints as f64, exact).
    #[derive(Debug)]
    struct Parsed {
        section: String,
        name: String,
        ty: String,
        components: usize,
        values: Vec<f64>,
    }

    fn attr(tag: &str, key: &str) -> Option<String> {
        let pat = format!(" {key}=\"");
        let i = tag.find(&pat)? + pat.len();
        let j = tag[i..].find('"')?;
        Some(tag[i..i + j].to_string())
    }

    /// Checks that the tags of `xml` nest properly and returns the tag names opened.
    fn check_tags(xml: &str) -> Vec<String> {
        let mut stack: Vec<String> = Vec::new();
        let mut seen = Vec::new();
        let mut rest = xml;
        while let Some(i) = rest.find('<') {
            let j = rest[i..].find('>').expect("unclosed tag") + i;
            let tag = &rest[i + 1..j];
            rest = &rest[j + 1..];
            if tag.starts_with('?') {
                assert!(tag.ends_with('?'), "bad declaration <{tag}>");
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().expect("closing tag without opening");
                assert_eq!(open, name.trim(), "mismatched tags");
                continue;
            }
            let name = tag.split_whitespace().next().unwrap().trim_end_matches('/');
            seen.push(name.to_string());
            if !tag.ends_with('/') {
                stack.push(name.to_string());
            }
        }
        assert!(stack.is_empty(), "unclosed tags {stack:?}");
        seen
    }

    /// A minimal VTU reader for the files this module writes.
    fn read_vtu(bytes: &[u8]) -> (usize, usize, Vec<Parsed>) {
        // Split off the raw appended block, if any, and keep the XML around it.
        let marker = b"<AppendedData encoding=\"raw\">";
        let (xml, raw): (String, &[u8]) =
            match bytes.windows(marker.len()).position(|w| w == marker) {
                None => (String::from_utf8(bytes.to_vec()).unwrap(), &[]),
                Some(p) => {
                    let us = p + bytes[p..].iter().position(|&c| c == b'_').unwrap();
                    let raw = &bytes[us + 1..];
                    // Walk the size headers to find the end of the raw data.
                    let mut total = 0;
                    let head = String::from_utf8(bytes[..p].to_vec()).unwrap();
                    let zlib = head.contains(r#"compressor="vtkZLibDataCompressor""#);
                    let blocks = head.matches("format=\"appended\"").count();
                    for _ in 0..blocks {
                        total += payload(raw, total, zlib).1;
                    }
                    let tail = String::from_utf8(raw[total..].to_vec()).unwrap();
                    assert_eq!(tail.trim(), "</AppendedData>\n</VTKFile>", "tail");
                    (
                        format!(
                            "{head}{}{tail}",
                            std::str::from_utf8(&bytes[p..=us]).unwrap()
                        ),
                        raw,
                    )
                }
            };
        let tags = check_tags(&xml);
        assert_eq!(tags[0], "VTKFile");
        let piece_at = xml.find("<Piece").unwrap();
        let piece = &xml[piece_at..piece_at + xml[piece_at..].find('>').unwrap()];
        let np: usize = attr(piece, "NumberOfPoints").unwrap().parse().unwrap();
        let nc: usize = attr(piece, "NumberOfCells").unwrap().parse().unwrap();
        let mut out = Vec::new();
        let mut section = String::new();
        let mut rest = xml.as_str();
        while let Some(i) = rest.find('<') {
            let j = rest[i..].find('>').unwrap() + i;
            let tag = rest[i..j].to_string();
            rest = &rest[j + 1..];
            for s in ["PointData", "CellData", "Points", "Cells"] {
                if tag == format!("<{s}") {
                    section = s.to_string();
                }
            }
            if !tag.starts_with("<DataArray") {
                continue;
            }
            let ty = attr(&tag, "type").unwrap();
            let values = match attr(&tag, "format").unwrap().as_str() {
                "ascii" => {
                    let end = rest.find("</DataArray>").unwrap();
                    let v = rest[..end]
                        .split_whitespace()
                        .map(|s| s.parse::<f64>().unwrap())
                        .collect();
                    rest = &rest[end..];
                    v
                }
                "appended" => {
                    let off: usize = attr(&tag, "offset").unwrap().parse().unwrap();
                    let zlib = xml.contains(r#"compressor="vtkZLibDataCompressor""#);
                    let (data, _) = payload(raw, off, zlib);
                    let data = data.as_slice();
                    match ty.as_str() {
                        "Float64" => data
                            .chunks_exact(8)
                            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                            .collect(),
                        "Int32" => data
                            .chunks_exact(4)
                            .map(|c| i32::from_le_bytes(c.try_into().unwrap()) as f64)
                            .collect(),
                        "Int8" => data.iter().map(|&c| c as i8 as f64).collect(),
                        "UInt8" => data.iter().map(|&c| c as f64).collect(),
                        t => panic!("type {t}"),
                    }
                }
                f => panic!("format {f}"),
            };
            out.push(Parsed {
                section: section.clone(),
                name: attr(&tag, "Name").unwrap_or_default(),
                ty,
                components: attr(&tag, "NumberOfComponents").map_or(1, |c| c.parse().unwrap()),
                values,
            });
        }
        (np, nc, out)
    }

    /// The bytes of the appended array at `off` and the bytes it takes in the file: raw
    /// (a size, then the bytes) or zlib-compressed (VTK's block header, then the blocks,
    /// each decompressed and checked against the sizes the header gives).
    fn payload(raw: &[u8], off: usize, zlib: bool) -> (Vec<u8>, usize) {
        let word = |k: usize| u64::from_le_bytes(raw[k..k + 8].try_into().unwrap()) as usize;
        if !zlib {
            let n = word(off);
            return (raw[off + 8..off + 8 + n].to_vec(), 8 + n);
        }
        let (nb, bs, last) = (word(off), word(off + 8), word(off + 16));
        let mut at = off + 8 * (3 + nb);
        let mut out = Vec::new();
        for b in 0..nb {
            let c = word(off + 8 * (3 + b));
            let mut block = Vec::new();
            std::io::Read::read_to_end(
                &mut flate2::read::ZlibDecoder::new(&raw[at..at + c]),
                &mut block,
            )
            .unwrap();
            let want = if b + 1 == nb && last != 0 { last } else { bs };
            assert_eq!(block.len(), want, "block {b} of {nb}");
            out.extend_from_slice(&block);
            at += c;
        }
        (out, at - off)
    }

    fn same(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
    }

    fn square_mesh() -> Mesh {
        // Unit square split in two triangles plus one extra triangle: 5 vertices.
        Mesh {
            points: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [0.0, 1.0],
                [0.1 + 0.2, 1.0 / 3.0],
            ],
            triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
            regions: vec![0, 0, 1, 1],
            ..Default::default()
        }
    }

    fn tmp(name: &str) -> crate::io::TmpPath {
        crate::io::TmpPath::new(name)
    }

    fn round_trip(encoding: VtuEncoding, warped: bool) {
        let mesh = square_mesh();
        let u = [0.0, -1e-300, 6.02214076e23, std::f64::consts::PI, -0.0];
        let flags: [i8; 5] = [0, 1, -1, 127, -128];
        let special = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            5e-324,
        ];
        let region: Vec<i32> = mesh.regions.iter().map(|&r| r as i32).collect();
        let area = [0.5, 0.25, 1.0 / 7.0, f64::MAX];
        let z = [1.0, 2.0, 3.0, 4.0, 0.1];
        let mut point_data = vec![
            ("u", DataArray::F64(&u)),
            ("in contact", DataArray::I8(&flags)),
        ];
        if encoding != VtuEncoding::Ascii {
            point_data.push(("special <&\">", DataArray::F64(&special)));
        }
        let cell_data = [
            ("region", DataArray::I32(&region)),
            ("area", DataArray::F64(&area)),
        ];
        let path = tmp(&format!("rt-{encoding:?}-{warped}.vtu"));
        if warped {
            write_vtu_warped(&path, &mesh, &z, &point_data, &cell_data, encoding).unwrap();
        } else {
            write_vtu(&path, &mesh, &point_data, &cell_data, encoding).unwrap();
        }
        let (np, nc, arrays) = read_vtu(&std::fs::read(&path).unwrap());
        assert_eq!((np, nc), (5, 4));
        let get = |name: &str| {
            arrays
                .iter()
                .find(|a| a.name == name)
                .unwrap_or_else(|| panic!("{name}"))
        };
        let a = get("u");
        assert_eq!(
            (a.section.as_str(), a.ty.as_str()),
            ("PointData", "Float64")
        );
        assert!(same(&a.values, &u));
        let a = get("in contact");
        assert_eq!(a.ty, "Int8");
        assert!(same(&a.values, &flags.map(|f| f as f64)));
        if encoding != VtuEncoding::Ascii {
            assert!(same(&get("special &lt;&amp;&quot;&gt;").values, &special));
        }
        let a = get("region");
        assert_eq!((a.section.as_str(), a.ty.as_str()), ("CellData", "Int32"));
        assert!(same(&a.values, &[0.0, 0.0, 1.0, 1.0]));
        assert!(same(&get("area").values, &area));
        let p = get("Points");
        assert_eq!((p.section.as_str(), p.components), ("Points", 3));
        let want: Vec<f64> = mesh
            .points
            .iter()
            .enumerate()
            .flat_map(|(i, q)| [q[0], q[1], if warped { z[i] } else { 0.0 }])
            .collect();
        assert!(same(&p.values, &want), "{:?}", p.values);
        let c = get("connectivity");
        let want: Vec<f64> = mesh.triangles.iter().flatten().map(|&v| v as f64).collect();
        assert_eq!((c.section.as_str(), c.values.clone()), ("Cells", want));
        assert_eq!(get("offsets").values, vec![3.0, 6.0, 9.0, 12.0]);
        let t = get("types");
        assert_eq!((t.ty.as_str(), t.values.clone()), ("UInt8", vec![5.0; 4]));
        // For an independent look: MEMCONTACT_KEEP_VTU=dir, then scripts/check_vtu.py.
        if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_VTU") {
            std::fs::copy(&path, Path::new(&keep).join(path.file_name().unwrap())).unwrap();
        }
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn ascii_round_trips_exactly() {
        round_trip(VtuEncoding::Ascii, false);
        round_trip(VtuEncoding::Ascii, true);
    }

    #[test]
    fn binary_round_trips_exactly() {
        round_trip(VtuEncoding::Binary, false);
        round_trip(VtuEncoding::Binary, true);
    }

    #[test]
    fn compressed_round_trips_exactly() {
        round_trip(VtuEncoding::Compressed, false);
        round_trip(VtuEncoding::Compressed, true);
    }

    #[test]
    fn binary_round_trips_across_staging_chunks() {
        chunks(VtuEncoding::Binary, 3 * CHUNK / 8 + 7);
    }

    #[test]
    fn compressed_round_trips_across_blocks() {
        // Points span three compression blocks and a partial one; `u` exactly two.
        chunks(VtuEncoding::Compressed, 2 * ZBLOCK / 8);
        chunks(VtuEncoding::Compressed, 3 * ZBLOCK / 8 + 7);
    }

    fn chunks(encoding: VtuEncoding, n: usize) {
        // Enough values that every array spans several staging buffers.
        let points: Vec<[f64; 2]> = (0..n).map(|i| [i as f64, (i as f64).sqrt()]).collect();
        let triangles: Vec<[u32; 3]> = (0..n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        let mesh = Mesh {
            points,
            triangles,
            ..Default::default()
        };
        let u: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let c: Vec<i32> = (0..mesh.triangles.len() as i32)
            .map(|i| i * 7 - 3)
            .collect();
        let path = tmp(&format!("chunks-{encoding:?}-{n}.vtu"));
        write_vtu(
            &path,
            &mesh,
            &[("u", DataArray::F64(&u))],
            &[("c", DataArray::I32(&c))],
            encoding,
        )
        .unwrap();
        let (_, nc, arrays) = read_vtu(&std::fs::read(&path).unwrap());
        assert_eq!(nc, n - 2);
        assert!(same(&arrays[0].values, &u));
        assert!(same(
            &arrays[1].values,
            &c.iter().map(|&x| x as f64).collect::<Vec<_>>()
        ));
        let offsets = &arrays.iter().find(|a| a.name == "offsets").unwrap().values;
        assert!(offsets
            .iter()
            .enumerate()
            .all(|(i, &o)| o == 3.0 * (i + 1) as f64));
        let pts = &arrays.iter().find(|a| a.name == "Points").unwrap().values;
        assert_eq!(pts[3 * (n - 1)], (n - 1) as f64);
        assert_eq!(pts[3 * (n - 1) + 1], ((n - 1) as f64).sqrt());
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn wrong_lengths_are_named_and_leave_no_file() {
        let mesh = square_mesh();
        let short = [1.0; 4];
        let path = tmp("bad.vtu");
        let e = write_vtu(
            &path,
            &mesh,
            &[("deflection", DataArray::F64(&short))],
            &[],
            VtuEncoding::Binary,
        )
        .unwrap_err();
        assert!(
            matches!(&e, Error::Data(m) if m.contains("`deflection`") && m.contains("5 vertices")),
            "{e}"
        );
        let flags = [1i8; 5];
        let e = write_vtu(
            &path,
            &mesh,
            &[],
            &[("pressure", DataArray::I8(&flags))],
            VtuEncoding::Ascii,
        )
        .unwrap_err();
        assert!(
            matches!(&e, Error::Data(m) if m.contains("`pressure`") && m.contains("4 triangles")),
            "{e}"
        );
        let e = write_vtu_warped(&path, &mesh, &short, &[], &[], VtuEncoding::Ascii).unwrap_err();
        assert!(matches!(&e, Error::Data(m) if m.contains("`z`")), "{e}");
        let u = [0.0; 5];
        let e = write_vtu(
            &path,
            &mesh,
            &[("u", DataArray::F64(&u)), ("u", DataArray::F64(&u))],
            &[],
            VtuEncoding::Ascii,
        )
        .unwrap_err();
        assert!(matches!(&e, Error::Data(m) if m.contains("twice")), "{e}");
        assert!(!path.exists());
    }

    /// Release-mode timing: `cargo test --release -p memcontact vtu_speed -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn vtu_speed_one_million_vertices() {
        let m = 1000;
        let n = m + 1;
        let h = 1.0 / m as f64;
        let points: Vec<[f64; 2]> = (0..n * n)
            .map(|k| [(k % n) as f64 * h, (k / n) as f64 * h])
            .collect();
        let mut triangles = Vec::with_capacity(2 * m * m);
        for j in 0..m {
            for i in 0..m {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + n as u32 + 1, a + n as u32);
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        let mesh = Mesh {
            points,
            triangles,
            ..Default::default()
        };
        let fields: Vec<Vec<f64>> = (0..6)
            .map(|f| {
                mesh.points
                    .iter()
                    .map(|p| (p[0] * (f + 1) as f64).sin() * p[1])
                    .collect()
            })
            .collect();
        let names = ["u", "phi", "penetration", "pressure", "x1", "residual"];
        let point_data: Vec<(&str, DataArray)> = names
            .iter()
            .zip(&fields)
            .map(|(n, f)| (*n, DataArray::F64(f)))
            .collect();
        let path = tmp("speed.vtu");
        let t = std::time::Instant::now();
        let cpu = crate::io::numbers::cpu_seconds();
        write_vtu(&path, &mesh, &point_data, &[], VtuEncoding::Binary).unwrap();
        let dt = t.elapsed();
        let cpu = crate::io::numbers::cpu_seconds() - cpu;
        let size = std::fs::metadata(&path).unwrap().len();
        eprintln!(
            "binary VTU: {} vertices, {} triangles, 6 arrays: {:.3} s wall, {cpu:.2} s CPU, {:.1} MB",
            mesh.points.len(),
            mesh.triangles.len(),
            dt.as_secs_f64(),
            size as f64 / 1e6
        );
        let t = std::time::Instant::now();
        write_vtu(&path, &mesh, &point_data, &[], VtuEncoding::Ascii).unwrap();
        eprintln!(
            "ascii VTU: {:.3} s, {:.1} MB",
            t.elapsed().as_secs_f64(),
            std::fs::metadata(&path).unwrap().len() as f64 / 1e6
        );
        std::fs::remove_file(&path).unwrap();
    }
}
