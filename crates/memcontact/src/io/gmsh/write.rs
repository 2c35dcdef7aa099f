//! The MSH writer: a mesh as MSH 2.2 or 4.1, ASCII or binary.

use crate::error::Result;
use crate::mesh::Mesh;
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

pub(super) fn write_header(
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

pub(super) fn write_v22(w: &mut dyn Write, mesh: &Mesh, binary: bool) -> std::io::Result<()> {
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

pub(super) fn write_v41(w: &mut dyn Write, mesh: &Mesh, binary: bool) -> std::io::Result<()> {
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
