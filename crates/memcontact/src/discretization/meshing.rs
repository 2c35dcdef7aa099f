//! The mesh levels a problem's `[mesh]` describes: read or generated, then refined, with
//! the memory of the run checked before the work.

use crate::error::Result;
use crate::limits::{check_mesh_fits_at, MeshSize, RUN_BYTES_PER_VERTEX};
use crate::mesh::generate::{self, Diagonal, PolygonSpec, RectangleSpec};
use crate::mesh::refine::Hierarchy;
use crate::problem::{MeshSource, MeshSpec};

/// Builds the mesh and its hierarchy of levels; warnings (from a Gmsh import) are
/// returned for the caller to show. The memory the run on the refined mesh needs is
/// checked before the base mesh is generated (when its size is known beforehand) and
/// again, exactly, before it is refined.
pub fn build_mesh(spec: &MeshSpec) -> Result<(Hierarchy, Vec<String>)> {
    build_mesh_checked(spec, Some(RUN_BYTES_PER_VERTEX))
}

/// [`build_mesh`] for a run that takes `per_vertex` bytes per vertex of the finest mesh
/// ([`bytes_per_vertex`]), or unchecked when `None` (a mesh built again for
/// the writers of a run that already holds its data is not checked against what is left).
pub(crate) fn build_mesh_checked(
    spec: &MeshSpec,
    per_vertex: Option<f64>,
) -> Result<(Hierarchy, Vec<String>)> {
    let check = |base: MeshSize| match per_vertex {
        Some(b) => check_mesh_fits_at(base, spec.refine, &describe_refinement(spec, &base), b),
        None => Ok(()),
    };
    if let Some(base) = expected_size(spec) {
        check(base)?;
    }
    let mut warnings = Vec::new();
    let mut hierarchy = match &spec.source {
        MeshSource::Given(g) => match &g.hierarchy {
            Some(h) => (**h).clone(),
            None => {
                return Err(crate::error::Error::Case {
                    file: None,
                    line: None,
                    key: "mesh.given".into(),
                    message: format!(
                        "the mesh given as data ({}) is not attached to this case (a case read \
                         back from its text holds only the mesh's description): give the mesh \
                         again",
                        g.description
                    ),
                })
            }
        },
        MeshSource::File(path) => {
            let (mesh, w) = crate::io::gmsh::read_msh(path)?;
            warnings.extend(w);
            Hierarchy::single(mesh)
        }
        &MeshSource::Rectangle {
            x0,
            y0,
            x1,
            y1,
            nx,
            ny,
            diagonal,
        } => generate::rectangle(&RectangleSpec {
            x0,
            y0,
            x1,
            y1,
            nx,
            ny,
            diagonal,
        })?,
        &MeshSource::Disk {
            center,
            radius,
            size,
        } => generate::disk_levels(center, radius, size)?,
        MeshSource::Polygon {
            outer,
            holes,
            regions,
            size,
            min_angle,
        } => generate::polygon_levels(&PolygonSpec {
            outer: outer.clone(),
            holes: holes.clone(),
            regions: regions
                .iter()
                .map(|r| (r.name.clone(), r.polygon.clone()))
                .collect(),
            size: *size,
            min_angle: *min_angle,
        })?,
    };
    if spec.refine > 0 {
        let base = MeshSize::of(hierarchy.finest());
        check(base)?;
        hierarchy.refine(spec.refine);
    }
    Ok((hierarchy, warnings))
}

/// The counts of the base mesh before it is built, where the generator knows them:
/// exactly for the rectangle, from the area and the element size for the disc
/// (`None` for a file or a polygon, counted once built).
fn expected_size(spec: &MeshSpec) -> Option<MeshSize> {
    match &spec.source {
        MeshSource::File(_) => None,
        MeshSource::Given(g) => g.hierarchy.as_ref().map(|h| MeshSize::of(h.finest())),
        &MeshSource::Rectangle {
            nx, ny, diagonal, ..
        } => {
            let cells = nx as f64 * ny as f64;
            let (vertices, triangles) = match diagonal {
                Diagonal::Crossed => ((nx as f64 + 1.0) * (ny as f64 + 1.0) + cells, 4.0 * cells),
                _ => ((nx as f64 + 1.0) * (ny as f64 + 1.0), 2.0 * cells),
            };
            Some(MeshSize::simply_connected(vertices, triangles))
        }
        &MeshSource::Disk { radius, size, .. } => {
            Some(delaunay_size(std::f64::consts::PI * radius * radius, size))
        }
        // The polygon's triangles are counted once generated (at most
        // `generate::MAX_TRIANGLES`).
        MeshSource::Polygon { .. } => None,
    }
}

/// What [`build_mesh`] would make, named for messages.
fn describe_refinement(spec: &MeshSpec, base: &MeshSize) -> String {
    format!(
        "mesh.refine = {} on a {} mesh of {:.0} triangles",
        spec.refine,
        spec.kind(),
        base.triangles
    )
}

/// The expected counts of a Delaunay mesh of `area` with elements of `size` (equilateral
/// triangles, two per vertex).
fn delaunay_size(area: f64, size: f64) -> MeshSize {
    let triangles = (area / (size * size * 3f64.sqrt() / 4.0)).max(1.0);
    MeshSize::simply_connected(triangles / 2.0, triangles)
}

/// Bytes per vertex of the finest mesh for a run of `problem` (the constants of
/// [`crate::limits`]): one body with a lumped or rigid foundation, one with the consistent
/// foundation, or anything else ([`RUN_BYTES_PER_VERTEX`]); `one_solve` for the lean
/// one-step run of `memcontact solve`.
pub(crate) fn bytes_per_vertex(problem: &crate::problem::Problem, one_solve: bool) -> f64 {
    use crate::limits::{
        CONSISTENT_BYTES_PER_VERTEX, LUMPED_BYTES_PER_VERTEX, ONE_SOLVE_LUMPED_BYTES_PER_VERTEX,
    };
    use crate::model::Foundation;
    if problem.lower.is_some() {
        return RUN_BYTES_PER_VERTEX;
    }
    let o = &problem.obstacle;
    let lean = o.foundation == Foundation::Lumped || o.stiffness.is_rigid();
    match (lean, one_solve) {
        (true, true) => ONE_SOLVE_LUMPED_BYTES_PER_VERTEX,
        (true, false) => LUMPED_BYTES_PER_VERTEX,
        (false, _) => CONSISTENT_BYTES_PER_VERTEX,
    }
}
