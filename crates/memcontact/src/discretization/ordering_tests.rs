//! Renumbering for locality is invisible to users: a mesh whose numbering is scattered (as
//! Gmsh writes it) is solved in a renumbered order, and every output comes back in the
//! user's numbering, equal to the answer computed without renumbering up to rounding.

use super::BoundData;
use crate::field::Field;
use crate::model::Model;
use crate::solve::{self, Method, Silent};
use crate::{run, Case};
use std::path::Path;

fn site_case(method: &str, load: Option<Field>) -> Case {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let text = format!(
        r#"
[mesh]
file = "site.msh"
[membrane]
tension = 1.0
load = "20 + 3*x"
[obstacle]
shape = "0.3 + 0.05*sin(2*pi*x)*cos(2*pi*y)"
stiffness = {{ foam = 100.0, soil = 1000.0 }}
[solver]
method = "{method}"
tolerance = 1e-12
"#
    );
    let mut case = Case::from_toml_str(&text, Some(&data.join("case.toml"))).unwrap();
    if let Some(f) = load {
        case.problem.membrane.load = f;
    }
    case
}

#[test]
fn renumbered_solve_answers_in_the_users_numbering() {
    let user = crate::io::gmsh::read_msh(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/site.msh"),
    )
    .unwrap()
    .0;
    assert!(
        crate::mesh::reorder::edge_span(&user) > 4.0,
        "a scattered numbering"
    );
    // The load as nodal values in the file's vertex order: 20 + 3x is linear, so its P1
    // interpolant is the expression itself.
    let nodal: Vec<f64> = user.points.iter().map(|p| 20.0 + 3.0 * p[0]).collect();
    for method in ["active-set", "multigrid"] {
        for load in [None, Some(Field::Nodal(nodal.clone().into()))] {
            let case = site_case(method, load);
            let outcome = run(&case, &mut Silent).unwrap();
            assert!(outcome.report.accepted, "{method}");
            // Solved in another numbering ...
            let internal = outcome.discretization.mesh();
            assert!(internal.numbering.is_some());
            assert_ne!(internal.points, user.points);
            // ... answered in the user's.
            let mesh = outcome.mesh();
            assert_eq!(mesh.points, user.points);
            assert_eq!(mesh.triangles, user.triangles);
            assert_eq!(mesh.regions, user.regions);
            let (fields, _) = outcome.fields();
            // The reference: the same problem assembled and solved on the file's mesh as it
            // is, without renumbering.
            let bound = BoundData::new(&case.problem, &user).unwrap();
            let model = Model::assemble(&user, &bound.data(&case.problem)).unwrap();
            let mut settings = case.settings.clone();
            settings.method = Method::ActiveSet;
            let reference = solve::solve(&model, None, &settings, &mut Silent).unwrap();
            let u_ref = model.dofs.to_vertices(&reference.u, 0.0);
            let scale = u_ref.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (v, (a, b)) in fields.u.iter().zip(&u_ref).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-10 * scale,
                    "{method}: vertex {v}: {a} vs {b}"
                );
            }
            let phi_ref = &model.phi_vertices();
            for (a, b) in fields.phi.iter().zip(phi_ref) {
                assert_eq!(a, b);
            }
        }
    }
}
