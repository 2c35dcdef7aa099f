//! What a case asks of the mesh, checked before anything is solved: the data of every
//! load case bound to it (and assembled, when asked), and the profile line of `[output]`
//! crossing it.

use super::{assemble_model, bind_and_check};
use crate::case::Case;
use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Checks everything of `case` that needs the mesh beyond its base problem (bound and
/// checked by the discretisation): the load cases' data ([`check_load_cases_on_mesh`]) and
/// the profile line of `[output]`, which must cross the mesh for `profile.png`.
pub fn check_case_on_mesh(case: &Case, mesh: &Mesh, assemble: bool) -> Result<()> {
    check_load_cases_on_mesh(case, mesh, assemble)?;
    check_profile_on_mesh(case, mesh)
}

/// Checks the load cases' data on the mesh before any step is solved: binds each load
/// case's f, φ and h to the mesh's regions (or vertices) and checks them on the boundary;
/// with `assemble`, also assembles each load case's model (everything its step will
/// check). Errors name the load case's keys (`load_case.N.stiffness`, ...).
pub fn check_load_cases_on_mesh(case: &Case, mesh: &Mesh, assemble: bool) -> Result<()> {
    for (i, lc) in case.load_cases.iter().enumerate() {
        if !lc.assembles() {
            continue;
        }
        let p = lc.problem(&case.problem);
        let checked = if assemble {
            assemble_model(&p, mesh).map(drop)
        } else {
            bind_and_check(&p, mesh).map(drop)
        };
        checked.map_err(|e| lc.rename_error(i, e))?;
    }
    Ok(())
}

/// A given profile line must cross the mesh (else `profile.png` could not be drawn).
pub fn check_profile_on_mesh(case: &Case, mesh: &Mesh) -> Result<()> {
    let Some([a, b]) = case.output.profile else {
        return Ok(());
    };
    if memcontact_plot::segment::crosses(&mesh.points, &mesh.triangles, a, b) {
        return Ok(());
    }
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &mesh.points {
        (x0, x1) = (x0.min(p[0]), x1.max(p[0]));
        (y0, y1) = (y0.min(p[1]), y1.max(p[1]));
    }
    Err(Error::Case {
        file: None,
        line: None,
        key: "output.profile".into(),
        message: format!(
            "the line from ({}, {}) to ({}, {}) does not cross the mesh (its bounding box is \
             [{x0}, {x1}] × [{y0}, {y1}])",
            a[0], a[1], b[0], b[1]
        ),
    })
}
