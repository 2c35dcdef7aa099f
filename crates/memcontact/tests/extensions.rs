//! Beyond the paper's frame (boundary heights, free edges, rigid regions, a body below):
//! every extension reduces to the paper's model when its data are absent, the
//! formulations agree with certificates at the tolerance, and bad data is refused before
//! any solve. Correctness is checked against mathematics: linear functions that P1
//! reproduces exactly, a free edge against the mirrored fixed problem, the both-rigid
//! admissible set.

use memcontact::run::Discretization;
use memcontact::solve::{Method, Silent};
use memcontact::{Case, Settings};

/// A case from TOML text.
fn case(text: &str) -> Case {
    Case::from_toml_str(text, None).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The discretisation of a case.
fn disc(text: &str) -> Discretization {
    Discretization::new(&case(text).problem, &mut Silent).unwrap_or_else(|e| panic!("{e}"))
}

/// Solves with `method` to `tolerance`; the iterate over all vertices and the report.
fn solve(d: &Discretization, method: Method, tolerance: f64) -> (Vec<f64>, memcontact::Report) {
    let s = Settings {
        method,
        tolerance,
        ..Settings::default()
    };
    let r = d.solve(&s, &mut Silent).unwrap();
    assert!(
        r.accepted,
        "{}: {:?} {:?}",
        method.name(),
        r.status,
        r.message
    );
    (d.model.to_vertices(&r.u), r)
}

const BASE: &str = r#"
[mesh]
generator = "rectangle"
nx = 8
ny = 8

[membrane]
tension = 1.5
load = 0

[obstacle]
shape = 10
stiffness = 100
"#;

#[test]
fn linear_boundary_heights_are_reproduced_exactly() {
    // f = 0 and no contact: u is the harmonic extension of g; P1 reproduces linear
    // functions, so U = g at every vertex, whichever method solves.
    let g = |x: f64, y: f64| 0.3 + 0.2 * x - 0.1 * y;
    let text = format!("{BASE}\n[boundary]\nheight = \"0.3 + 0.2*x - 0.1*y\"\n");
    let d = disc(&text);
    assert!(!d.model.lift.is_empty());
    for method in [
        Method::ActiveSet,
        Method::Qp,
        Method::Coordinate,
        Method::Multigrid,
    ] {
        let (u, _) = solve(&d, method, 1e-12);
        for (p, ui) in d.mesh().points.iter().zip(&u) {
            assert!(
                (ui - g(p[0], p[1])).abs() < 1e-10,
                "{}: {p:?}",
                method.name()
            );
        }
    }
    // A free side: the natural condition holds for g = 0.3 + 0.2x on the top side.
    let text = format!("{BASE}\n[boundary]\nheight = \"0.3 + 0.2*x\"\nfree = [\"top\"]\n");
    let d = disc(&text);
    assert_eq!(d.model.n(), 7 * 8);
    let (u, _) = solve(&d, Method::ActiveSet, 1e-12);
    for (p, ui) in d.mesh().points.iter().zip(&u) {
        assert!((ui - (0.3 + 0.2 * p[0])).abs() < 1e-10, "{p:?}");
    }
}

#[test]
fn a_table_gives_each_side_its_height() {
    let text = format!(
        "{BASE}\n[boundary]\nheight = {{ left = 0.1, right = \"0.2*y\", default = 0 }}\n\
         free = [\"top\"]\n"
    );
    let d = disc(&text);
    let (u, _) = solve(&d, Method::ActiveSet, 1e-11);
    for (v, p) in d.mesh().points.iter().enumerate() {
        let fixed = d.model.dofs.dof[v].is_none();
        let expect = match (p[0], p[1]) {
            (0.0, 0.0) => Some(0.05), // left 0.1 and bottom 0
            (0.0, _) => Some(0.1),
            (1.0, 0.0) => Some(0.0),
            (1.0, y) => Some(0.2 * y),
            (_, 0.0) => Some(0.0),
            _ => None,
        };
        match expect {
            Some(g) => {
                assert!(fixed, "{p:?}");
                assert!((u[v] - g).abs() < 1e-15, "{p:?}: {} vs {g}", u[v]);
            }
            None => assert!(!fixed, "{p:?} carries an unknown"),
        }
    }
}

/// The free top edge of the unit square against the square [0, 1] × [0, 2] fixed on its
/// whole boundary with data symmetric about y = 1: on a mesh symmetric about that line
/// the discrete solutions coincide (the free edge's natural condition is the symmetry).
#[test]
fn a_free_edge_is_the_mirror_of_a_fixed_problem() {
    for foundation in ["consistent", "lumped"] {
        let data = format!(
            r#"
[membrane]
tension = 1.0
load = "12*(1 + 0.5*sin(3*x))"

[obstacle]
shape = "0.3 + 0.05*x + 0.2*(y - 1)^2"
stiffness = 800
foundation = "{foundation}"
"#
        );
        let half = format!(
            "[mesh]\ngenerator = \"rectangle\"\nnx = 12\nny = 12\ndiagonal = \"crossed\"\n\
             {data}\n[boundary]\nfree = [\"top\"]\n"
        );
        let whole = format!(
            "[mesh]\ngenerator = \"rectangle\"\nnx = 12\nny = 24\ny1 = 2\n\
             diagonal = \"crossed\"\n{data}"
        );
        let (dh, dw) = (disc(&half), disc(&whole));
        let (uh, rh) = solve(&dh, Method::ActiveSet, 1e-12);
        let (uw, _) = solve(&dw, Method::ActiveSet, 1e-12);
        assert!(rh.certificate.kkt() <= 1e-12);
        let states = dh.model.states(&rh.u);
        assert!(
            states.contains(&1) && states.contains(&-1),
            "contact and clear"
        );
        let mut checked = 0;
        for (p, ui) in dh.mesh().points.iter().zip(&uh) {
            let k = dw
                .mesh()
                .points
                .iter()
                .position(|q| q == p)
                .expect("the half mesh is part of the whole");
            assert!(
                (ui - uw[k]).abs() < 1e-11,
                "{foundation} {p:?}: {ui} vs {}",
                uw[k]
            );
            checked += 1;
        }
        assert_eq!(checked, dh.mesh().n_vertices());
    }
}

#[test]
fn absent_data_reproduce_the_paper_frame_bit_for_bit() {
    let paper = r#"
[mesh]
generator = "rectangle"
nx = 16

[membrane]
tension = 1.0
load = 20

[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = 1000
"#;
    let d0 = disc(paper);
    for extra in [
        "[boundary]\nheight = { default = 0 }\n",
        "[boundary]\nheight = 0\nfree = []\n",
        "[boundary]\nheight = { left = 0, right = \"0*x\", default = 0 }\n",
    ] {
        let d1 = disc(&format!("{paper}\n{extra}"));
        assert_eq!(d1.model.dofs.vertex, d0.model.dofs.vertex);
        assert_eq!(d1.model.d, d0.model.d, "{extra}");
        for method in [Method::ActiveSet, Method::Coordinate, Method::Multigrid] {
            let (u0, r0) = solve(&d0, method, 1e-11);
            let (u1, r1) = solve(&d1, method, 1e-11);
            assert_eq!(u0, u1, "{}: {extra}", method.name());
            assert_eq!(r0.energy, r1.energy);
        }
    }
}

fn refused(text: &str) -> String {
    match Case::from_toml_str(text, None) {
        Err(e) => e.to_string(),
        Ok(c) => match Discretization::new(&c.problem, &mut Silent) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("accepted:\n{text}"),
        },
    }
}

#[test]
fn bad_boundary_data_is_refused_before_any_solve() {
    let e = refused(&format!("{BASE}\n[boundary]\nfree = [\"lid\"]\n"));
    assert!(e.contains("boundary.free") && e.contains("'lid'"), "{e}");
    assert!(e.contains("bottom, right, top, left"), "{e}");
    let e = refused(&format!("{BASE}\n[boundary]\nheight = {{ lid = 1 }}\n"));
    assert!(e.contains("boundary.height.lid"), "{e}");
    let e = refused(&format!("{BASE}\n[boundary]\nheight = nan\n"));
    assert!(e.contains("boundary.height") && e.contains("finite"), "{e}");
    let e = refused(&format!("{BASE}\n[boundary]\nheight = \"sqrt(x - 0.5)\"\n"));
    assert!(e.contains("boundary.height g is NaN"), "{e}");
    // Nothing fixed and no body that can stop the membrane: refused, not a singular
    // factorisation.
    let all_free = "[boundary]\nfree = [\"left\", \"right\", \"top\", \"bottom\"]\n";
    let e = refused(&format!(
        "{}\n{all_free}",
        BASE.replace("stiffness = 100", "stiffness = 0")
    ));
    assert!(
        e.contains("the membrane is not held") && e.contains("no body"),
        "{e}"
    );
    // Held from above only while the load pushes it down, away from the body.
    let e = refused(&format!(
        "{}\n{all_free}",
        BASE.replace("load = 0", "load = -1")
    ));
    assert!(e.contains("does not push it up"), "{e}");
}

#[test]
fn generators_name_their_sides_and_refinement_keeps_them() {
    use memcontact::mesh::generate::{disk, polygon, PolygonSpec};
    use memcontact::mesh::{refine::Hierarchy, Mesh, VertexTriangles};
    // Every boundary edge's tag agrees with the geometry, on every refined level.
    let check = |m: &Mesh, side: &dyn Fn([f64; 2]) -> &'static str| {
        let adj = VertexTriangles::new(m);
        let t = m.tagged_boundary(&adj);
        assert_eq!(t.edges.len(), m.boundary_edges().len());
        for (e, &tag) in t.edges.iter().zip(&t.tags) {
            let (p, q) = (m.points[e[0] as usize], m.points[e[1] as usize]);
            let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
            assert_eq!(m.boundary.name(tag), side(mid), "edge at {mid:?}");
        }
    };
    let spec = case(&BASE.replace(
        "ny = 8",
        "ny = 8
refine = 2",
    ))
    .problem
    .mesh;
    let (h, _) = spec.build().unwrap();
    for m in &h.levels {
        check(m, &|p| match p {
            [_, 0.0] => "bottom",
            [1.0, _] => "right",
            [_, 1.0] => "top",
            _ => "left",
        });
    }
    let h = Hierarchy::refined(disk([0.0, 0.0], 1.0, 0.3).unwrap(), 2);
    for m in &h.levels {
        check(m, &|_| "outer");
    }
    let p = polygon(&PolygonSpec {
        outer: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]],
        holes: vec![
            vec![[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]],
            vec![[2.5, 1.0], [3.5, 1.0], [3.0, 2.0]],
        ],
        regions: vec![],
        size: 0.3,
        min_angle: 25.0,
    })
    .unwrap();
    let h = Hierarchy::refined(p, 1);
    for m in &h.levels {
        check(m, &|p| {
            if p[0] <= 1e-12 || p[1] <= 1e-12 || p[0] >= 4.0 - 1e-12 || p[1] >= 3.0 - 1e-12 {
                "outer"
            } else if p[0] < 2.25 {
                "hole1"
            } else {
                "hole2"
            }
        });
    }
}
