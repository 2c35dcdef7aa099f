//! What a run agrees to allocate, checked before the work: the memory estimate of a mesh
//! and its refinements. The memory a run needs is estimated from the base mesh and the
//! number of uniform refinements before any refinement is made, and compared with the
//! memory available (`MemAvailable` of `/proc/meminfo`, the cgroup limit when lower, or the
//! `MEMCONTACT_MEMORY_LIMIT` environment variable); a run that would not fit is refused
//! with both numbers.

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// The counts of a triangle mesh, as floating-point numbers so that the counts of many
/// refinements never overflow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshSize {
    /// Vertices.
    pub vertices: f64,
    /// Edges.
    pub edges: f64,
    /// Triangles.
    pub triangles: f64,
}

impl MeshSize {
    /// The counts of `mesh` (edges from `3T + B = 2E`, B the boundary edges).
    pub fn of(mesh: &Mesh) -> MeshSize {
        let t = mesh.n_triangles() as f64;
        let b = mesh.boundary_edges().len() as f64;
        MeshSize {
            vertices: mesh.n_vertices() as f64,
            edges: (3.0 * t + b) / 2.0,
            triangles: t,
        }
    }

    /// The counts of a simply connected mesh with `vertices` and `triangles` (Euler:
    /// `V − E + T = 1`).
    pub fn simply_connected(vertices: f64, triangles: f64) -> MeshSize {
        MeshSize {
            vertices,
            edges: vertices + triangles - 1.0,
            triangles,
        }
    }

    /// The counts after `times` uniform refinements (each triangle into four: every edge
    /// gains a midpoint vertex and splits in two, each triangle adds three inner edges).
    pub fn refined(self, times: usize) -> MeshSize {
        let mut s = self;
        for _ in 0..times {
            s = MeshSize {
                vertices: s.vertices + s.edges,
                edges: 2.0 * s.edges + 3.0 * s.triangles,
                triangles: 4.0 * s.triangles,
            };
        }
        s
    }
}

/// Bytes per vertex of the finest mesh that a run takes besides its solver's own
/// factorisations, for any run: all mesh levels, the model (S, L, D, φ), a second body,
/// the multigrid transfer and smoother data, the result fields and the writers' buffers.
/// Kept for the runs not measured apart below (a second body, convergence studies, the
/// adaptive loop); a one-body run with the consistent foundation was measured at about
/// 470 bytes per vertex (the square, N = 2048, everything kept).
pub const RUN_BYTES_PER_VERTEX: f64 = 700.0;

/// The same for one body with the consistent foundation: measured at 465–470 bytes per
/// vertex (the square, N = 2048, every level and matrix kept), with a margin.
pub const CONSISTENT_BYTES_PER_VERTEX: f64 = 540.0;

/// The same for one body with a lumped or rigid foundation, whose Newton matrix is S and
/// a diagonal: measured at 330–350 bytes per vertex with every level and matrix kept (the
/// square, N = 2048), with a margin.
pub const LUMPED_BYTES_PER_VERTEX: f64 = 400.0;

/// The same for `memcontact solve` of one step with a lumped or rigid foundation, which
/// releases what its solve and its writers no longer read: measured at 258 bytes per
/// vertex at N = 8192 (16.5 GB), 282 at N = 4096 and 320 at N = 2048 (with the tool's
/// fixed 100 MB), with a margin.
pub const ONE_SOLVE_LUMPED_BYTES_PER_VERTEX: f64 = 320.0;

/// Bytes per unknown and per binary digit of the unknowns' count that a sparse Cholesky
/// factorisation of S (+ L) adds (nested-dissection fill grows like n log n): measured at
/// about 60 (1 M unknowns, active-set), with a margin.
pub const DIRECT_BYTES_PER_UNKNOWN_LOG: f64 = 70.0;

/// The same for the interior-point QP (its KKT system has the unknowns twice and is
/// factorised with its multipliers): measured at about 280 (66 k unknowns), with a margin.
pub const QP_BYTES_PER_UNKNOWN_LOG: f64 = 320.0;

/// Used when the available memory cannot be read (not Linux): 16 GiB.
pub const FALLBACK_MEMORY: u64 = 16 << 30;

/// The environment variable that sets the memory a run may use (bytes, or with a suffix
/// `K`, `M`, `G`, `T` for powers of 1024), overriding what the system reports.
pub const MEMORY_LIMIT_VAR: &str = "MEMCONTACT_MEMORY_LIMIT";

/// The memory a run may use, in bytes, and where the number comes from.
pub fn available_memory() -> (u64, String) {
    if let Ok(v) = std::env::var(MEMORY_LIMIT_VAR) {
        if let Some(b) = parse_bytes(&v) {
            return (b, format!("{MEMORY_LIMIT_VAR}={}", v.trim()));
        }
    }
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|rest| {
                rest.trim()
                    .trim_end_matches("kB")
                    .trim()
                    .parse::<u64>()
                    .ok()
            })
            .map(|kb| kb * 1024)
    });
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok())
        .map(|max| {
            let used = std::fs::read_to_string("/sys/fs/cgroup/memory.current")
                .ok()
                .and_then(|t| t.trim().parse::<u64>().ok())
                .unwrap_or(0);
            max.saturating_sub(used)
        });
    match (meminfo, cgroup) {
        (Some(m), Some(c)) if c < m => (c, "the memory limit of this control group".into()),
        (Some(m), _) => (m, "MemAvailable in /proc/meminfo".into()),
        (None, Some(c)) => (c, "the memory limit of this control group".into()),
        (None, None) => (
            FALLBACK_MEMORY,
            format!("a fixed limit (set {MEMORY_LIMIT_VAR} to change it)"),
        ),
    }
}

/// `123`, `512M`, `4G`, `1.5T` as bytes.
fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let (number, shift) = match t.char_indices().last()? {
        (i, 'k' | 'K') => (&t[..i], 10),
        (i, 'm' | 'M') => (&t[..i], 20),
        (i, 'g' | 'G') => (&t[..i], 30),
        (i, 't' | 'T') => (&t[..i], 40),
        _ => (t, 0),
    };
    let v: f64 = number.trim().parse().ok()?;
    (v.is_finite() && v >= 0.0).then(|| (v * (1u64 << shift) as f64) as u64)
}

/// `1.23 GB`.
pub fn human_bytes(b: f64) -> String {
    const UNITS: [&str; 6] = ["bytes", "KB", "MB", "GB", "TB", "PB"];
    let mut v = b;
    let mut k = 0;
    while v >= 1024.0 && k + 1 < UNITS.len() {
        v /= 1024.0;
        k += 1;
    }
    if k == 0 {
        format!("{v:.0} {}", UNITS[0])
    } else {
        format!("{v:.2} {}", UNITS[k])
    }
}

/// The memory estimate of a run on a mesh of `finest` counts: [`RUN_BYTES_PER_VERTEX`].
pub fn run_bytes(finest: MeshSize) -> f64 {
    RUN_BYTES_PER_VERTEX * finest.vertices
}

/// Refuses a mesh of `base` counts refined `refinements` more times when the run on it
/// would not fit in the available memory (or its vertices would not fit the 32-bit
/// indices of the mesh). `what` names the source of the size in the message (`"mesh.refine
/// = 12 on a mesh of 128 triangles"`). Called before anything is refined.
pub fn check_mesh_fits(base: MeshSize, refinements: usize, what: &str) -> Result<()> {
    check_mesh_fits_at(base, refinements, what, RUN_BYTES_PER_VERTEX)
}

/// [`check_mesh_fits`] for a run that takes `per_vertex` bytes per vertex of the finest
/// mesh (the discretisation picks it for its problem and kind of run).
pub fn check_mesh_fits_at(
    base: MeshSize,
    refinements: usize,
    what: &str,
    per_vertex: f64,
) -> Result<()> {
    let finest = base.refined(refinements);
    if finest.vertices > u32::MAX as f64 || finest.triangles > u32::MAX as f64 {
        return Err(Error::Data(format!(
            "{what} would make {:.3e} vertices and {:.3e} triangles, more than a mesh can \
             index (2³² − 1): use fewer refinements or a coarser mesh",
            finest.vertices, finest.triangles
        )));
    }
    check_bytes(per_vertex * finest.vertices, finest, what)
}

/// Refuses `need` bytes for a mesh of `finest` counts when more than is available.
fn check_bytes(need: f64, finest: MeshSize, what: &str) -> Result<()> {
    let (available, source) = available_memory();
    if need > available as f64 {
        return Err(Error::Data(format!(
            "{what} would make {:.3e} vertices and {:.3e} triangles; solving on it needs \
             about {} of memory, more than the {} available ({source}): use fewer \
             refinements or a coarser mesh",
            finest.vertices,
            finest.triangles,
            human_bytes(need),
            human_bytes(available as f64),
        )));
    }
    Ok(())
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refined_counts_are_exact() {
        // The unit square cut into 2 triangles, refined k times: (2^k + 1)² vertices.
        let square = MeshSize::simply_connected(4.0, 2.0);
        assert_eq!(square.edges, 5.0);
        for k in 0..8 {
            let s = square.refined(k);
            let n = (1u64 << k) as f64 + 1.0;
            assert_eq!(s.vertices, n * n, "k = {k}");
            assert_eq!(s.triangles, 2.0 * 4f64.powi(k as i32));
        }
        // The counts of a real mesh agree with its refinement.
        let mesh = crate::mesh::generate::disk([0.0, 0.0], 1.0, 0.3).unwrap();
        let predicted = MeshSize::of(&mesh).refined(2);
        let h = crate::mesh::refine::Hierarchy::refined(mesh, 2);
        let actual = MeshSize::of(h.finest());
        assert_eq!(predicted, actual);
    }

    #[test]
    fn byte_sizes_parse() {
        assert_eq!(parse_bytes("123"), Some(123));
        assert_eq!(parse_bytes("2K"), Some(2048));
        assert_eq!(parse_bytes(" 1.5G "), Some(3 << 29));
        assert_eq!(parse_bytes("x"), None);
        assert_eq!(parse_bytes("-1M"), None);
        assert_eq!(human_bytes(3.0 * 1024.0 * 1024.0 * 1024.0), "3.00 GB");
    }

    #[test]
    fn runs_beyond_memory_are_refused_with_the_estimate() {
        // 12 refinements of an 8 × 8 square: about 1.1e9 vertices.
        let base = MeshSize::simply_connected(81.0, 128.0);
        let e = check_mesh_fits(base, 12, "mesh.refine = 12").unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("mesh.refine = 12") && m.contains("available"),
            "{m}"
        );
        assert!(check_mesh_fits(base, 2, "mesh.refine = 2").is_ok());
        let e = check_mesh_fits(base, 15, "15").unwrap_err().to_string();
        assert!(e.contains("index"), "{e}");
    }
}
