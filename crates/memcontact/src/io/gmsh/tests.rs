//! Tests of the MSH reader and writer.

use super::cursor::{find, Binary, RECORDS_PER_TASK};
use super::*;
use crate::mesh::Point;
use std::collections::BTreeMap;
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
    let expect: BTreeMap<u32, String> = BTreeMap::from([(1, "foam".into()), (2, "soil".into())]);
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

/// Nodes no triangle uses are dropped with a warning; the triangles and the boundary
/// curves are renumbered onto the nodes kept, in file order.
#[test]
fn unused_nodes_are_dropped_and_the_rest_renumbered() {
    let (kept, _) = read_msh(&write_text("sq22k.msh", SQUARE_22)).unwrap();
    let with_unused = SQUARE_22
        .replace("$Nodes\n5\n10 0 0 0\n", "$Nodes\n7\n5 3 3 0\n10 0 0 0\n")
        .replace("40 0 1 0\n", "40 0 1 0\n41 -2 5 0\n");
    let (m, w) = read_msh(&write_text("sq22u.msh", &with_unused)).unwrap();
    assert_eq!(m.points, kept.points);
    assert_eq!(m.triangles, kept.triangles);
    assert_eq!(m.regions, kept.regions);
    assert_eq!(m.boundary.edges, vec![[0, 1], [1, 2]]);
    assert_eq!(m.boundary.tags, vec![7, 7]);
    assert!(
        w.contains(&"dropped 2 of 7 nodes that no triangle uses".to_string()),
        "{w:?}"
    );
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
fn large_ascii_files_are_read_in_one_pass() {
    // 2 · 300² triangles in MSH 2.2 text: counting every element's line number from the
    // start of the file, as the reader once did, would take hours here.
    use crate::mesh::generate::{rectangle, Diagonal, RectangleSpec};
    let spec = RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: 300,
        ny: 300,
        diagonal: Diagonal::Alternate,
    };
    let mesh = rectangle(&spec).unwrap().levels.pop().unwrap();
    for (name, version) in [
        ("big22.msh", MshVersion::V22Ascii),
        ("big41.msh", MshVersion::V41Ascii),
    ] {
        let p = temp(name);
        write_msh(&p, &mesh, version).unwrap();
        let (read, _) = read_msh(&p).unwrap();
        assert_eq!(read.n_triangles(), 2 * 300 * 300, "{name}");
        assert_eq!(read.n_vertices(), 301 * 301, "{name}");
        assert_eq!(canonical(&read), canonical(&mesh), "{name}");
    }
}

#[test]
fn bad_files_are_clear_errors() {
    let err = |name: &str, text: &str| read_msh(&write_text(name, text)).unwrap_err().to_string();
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
    // a bad element tag: the line named is the element's
    let bad = SQUARE_22.replace("12 2 2 6 1 20 30 99", "1x 2 2 6 1 20 30 99");
    let line = 1 + bad[..bad.find("1x 2 2").unwrap()].matches('\n').count();
    let e = err("tag.msh", &bad);
    assert!(
        e.contains(&format!("line {line} ($Elements)")) && e.contains("`1x`"),
        "{e}"
    );
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
