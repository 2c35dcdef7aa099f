//! How many triangles the generators agree to build, and how a fine unstructured mesh is
//! made coarse and refined uniformly.

/// The largest number of triangles the unstructured generators ([`super::disk`], [`super::polygon`])
/// agree to build: Delaunay refinement of 10⁷ triangles takes minutes and GiBs.
pub const MAX_TRIANGLES: f64 = 1e7;

/// The largest number of triangles [`super::rectangle`] agrees to build (its finest level; all
/// levels together take about 40 bytes per finest triangle).
pub const MAX_STRUCTURED_TRIANGLES: f64 = 1.5e8;

/// The unstructured generators make at most about this many triangles by Delaunay
/// refinement: a finer mesh is made coarse and refined uniformly ([`super::disk_levels`],
/// [`super::polygon_levels`]), which is many times faster than Delaunay refinement, keeps every
/// angle of the coarse mesh and gives multigrid its levels.
pub const DELAUNAY_TRIANGLES: f64 = 1.5e5;

/// How many uniform refinements (each quarters the element area) bring a mesh of about
/// `estimate` triangles down to at most [`DELAUNAY_TRIANGLES`] on its coarsest level; at
/// least two when any, so that the levels make a multigrid hierarchy `auto` takes.
pub(super) fn uniform_levels(estimate: f64) -> u32 {
    let mut k = 0;
    let mut e = estimate;
    while e > DELAUNAY_TRIANGLES {
        e /= 4.0;
        k += 1;
    }
    if k > 0 {
        k.max(2)
    } else {
        0
    }
}

/// The triangle count that Delaunay refinement with area bound `size²·√3/4` typically
/// produces for a domain of `area` (the triangles come out about half the bound).
pub(super) fn estimated_triangles(area: f64, size: f64) -> f64 {
    2.0 * area / (size * size * 3f64.sqrt() / 4.0)
}
