//! Beyond the paper's frame (boundary heights, free edges, rigid regions, a body below):
//! every extension reduces to the paper's model when its data are absent, the
//! formulations agree with certificates at the tolerance, and bad data is refused before
//! any solve. Correctness is checked against mathematics: linear functions that P1
//! reproduces exactly, a free edge against the mirrored fixed problem, the both-rigid
//! admissible set.

use memcontact::discretization::Discretization;
use memcontact::solve::{HierarchyChoice, Method, Silent};
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
    solve_on(d, method, HierarchyChoice::Auto, tolerance)
}

/// [`solve`] with the multigrid levels chosen.
fn solve_on(
    d: &Discretization,
    method: Method,
    hierarchy: HierarchyChoice,
    tolerance: f64,
) -> (Vec<f64>, memcontact::Report) {
    let s = Settings {
        method,
        tolerance,
        hierarchy,
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
        let fixed = d.model.dofs.is_fixed(v);
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
    use memcontact::mesh::generate::{
        disk, polygon, rectangle, Diagonal, PolygonSpec, RectangleSpec,
    };
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
    // A generated square (the generator of `[mesh] nx, ny`), refined twice as `refine = 2`
    // does.
    let mut h = rectangle(&RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: 8,
        ny: 8,
        diagonal: Diagonal::Right,
    })
    .unwrap();
    h.refine(2);
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

/// The formulations (docs/theory.md#formulations-agree) with the extensions
/// (docs/theory.md#extensions) on one case: active set (2f), the QP with the extra
/// variables (2c), coordinate descent (2b) and multigrid agree to 1e-8 with certificates ≤
/// 1e-9. Returns the active-set report and the largest difference.
fn agree(name: &str, text: &str) -> (Discretization, memcontact::Report, f64) {
    let d = disc(text);
    let (ua, ra) = solve(&d, Method::ActiveSet, 1e-11);
    let scale = ua.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    let mut worst = 0.0f64;
    let others = [
        (Method::Qp, HierarchyChoice::Auto),
        (Method::Coordinate, HierarchyChoice::Auto),
        (Method::Multigrid, HierarchyChoice::Auto),
        (Method::Multigrid, HierarchyChoice::Algebraic),
    ];
    for (method, hierarchy) in others {
        let (u, r) = solve_on(&d, method, hierarchy, 1e-11);
        let c = d.model.certificate(&r.u);
        assert!(
            c.residual_2e <= 1e-9 && c.residual_2f <= 1e-9,
            "{name} {} {hierarchy:?}: {c:?}",
            method.name()
        );
        let diff = u
            .iter()
            .zip(&ua)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale;
        assert!(
            diff <= 1e-8,
            "{name} {} {hierarchy:?}: {diff:e}",
            method.name()
        );
        assert!(
            (r.energy - ra.energy).abs() <= 1e-9 * ra.energy.abs().max(1e-300),
            "{name} {}",
            method.name()
        );
        worst = worst.max(diff);
    }
    let c = d.model.certificate(&ra.u);
    assert!(c.kkt() <= 1e-9, "{name} active-set: {c:?}");
    eprintln!(
        "{name}: max |U − U_active-set| / max|U| = {worst:.1e}, certificate {:.1e}",
        c.kkt()
    );
    (d, ra, worst)
}

/// The square with a 16 × 16 grid and its multigrid levels.
const SQUARE16: &str = r#"
[mesh]
generator = "rectangle"
nx = 16
ny = 16
"#;

/// A square site with a region `core` in the middle (polygon generator, refined once so
/// that multigrid has levels).
const SITE: &str = r#"
[mesh]
generator = "polygon"
outer = [[0, 0], [1, 0], [1, 1], [0, 1]]
regions = [{ name = "core", polygon = [[0.35, 0.3], [0.65, 0.3], [0.65, 0.7], [0.35, 0.7]] }]
size = 0.12
refine = 1
"#;

/// The cases of the issue's list, each with consistent and lumped foundations.
fn cases(foundation: &str) -> Vec<(String, String)> {
    let f = format!("foundation = \"{foundation}\"");
    vec![
        (
            format!("boundary heights ({foundation})"),
            format!(
                r#"{SQUARE16}
[membrane]
tension = 1.0
load = 16

[obstacle]
shape = "0.45 + 0.1*x"
stiffness = 600
{f}

[boundary]
height = {{ left = 0.2, right = "0.1 + 0.2*y", bottom = "0.05*sin(pi*x)", top = 0.25 }}
"#
            ),
        ),
        (
            format!("free edge ({foundation})"),
            format!(
                r#"{SQUARE16}
[membrane]
tension = 1.0
load = "14*(1 + x)"

[obstacle]
shape = "0.3 + 0.1*y"
stiffness = 800
{f}

[boundary]
height = "0.1*x"
free = ["top"]
"#
            ),
        ),
        (
            format!("elastic body below ({foundation})"),
            format!(
                r#"{SQUARE16}
[membrane]
tension = 1.0
load = "40*sin(2*pi*x)*(0.5 + y)"

[obstacle]
shape = 0.25
stiffness = 500
{f}

[lower]
shape = "-0.2 + 0.05*y"
stiffness = 300
{f}

[boundary]
height = "0.05*y"
"#
            ),
        ),
        (
            format!("both rigid, squeezed ({foundation})"),
            format!(
                r#"{SITE}
[membrane]
tension = 1.0
load = "30*(x - 0.45)"

[obstacle]
shape = "0.06 + 0.3*(x - 0.5)^2"
stiffness = "rigid"

[lower]
shape = "min(0.06 + 0.3*(x - 0.5)^2, 0.2 - 2*((x - 0.5)^2 + (y - 0.5)^2))"
stiffness = {{ core = "rigid", default = 400 }}
{f}
"#
            ),
        ),
        (
            format!("rigid region next to elastic ({foundation})"),
            format!(
                r#"{SITE}
[membrane]
tension = 1.0
load = 14

[obstacle]
shape = "0.2 + 0.06*x"
stiffness = {{ core = "rigid", default = 350 }}
{f}
"#
            ),
        ),
    ]
}

#[test]
fn formulations_agree_beyond_the_paper_frame() {
    for foundation in ["consistent", "lumped"] {
        for (name, text) in cases(foundation) {
            let (d, r, _) = agree(&name, &text);
            let m = &d.model;
            let up = m.states(&r.u);
            let low = m.lower_states(&r.u);
            // Each case exercises what it names.
            if name.starts_with("both rigid") {
                let squeezed = up
                    .iter()
                    .zip(&low)
                    .filter(|(&a, &b)| a == 0 && b == 0)
                    .count();
                assert!(squeezed >= 3, "{name}: {squeezed} squeezed vertices");
            }
            if name.starts_with("elastic body below") {
                assert!(
                    low.contains(&1) && up.contains(&1),
                    "{name}: both bodies act"
                );
            }
            if name.starts_with("rigid region") {
                let rigid = m.rigid.as_ref().expect("rigid vertices");
                let on_rigid = (0..m.n()).filter(|&i| rigid[i] && up[i] == 0).count();
                let pen = (0..m.n()).filter(|&i| !rigid[i] && up[i] == 1).count();
                assert!(
                    on_rigid > 0 && pen > 0,
                    "{name}: {on_rigid} held, {pen} in foam"
                );
                // The rigid vertices never penetrate.
                assert!((0..m.n()).all(|i| !rigid[i] || r.u[i] <= m.phi[i]));
            }
            if name.starts_with("free edge") {
                assert!(m.n() > 15 * 15, "{name}: the free side carries unknowns");
            }
        }
    }
}

/// The body below is the mirror of the obstacle: the lower body (φ_low, h) under the load
/// f and heights g has the solution −U of the obstacle (−φ_low, h) under −f and −g.
#[test]
fn the_body_below_is_the_mirrored_obstacle() {
    for stiffness in ["300", "\"rigid\""] {
        for foundation in ["consistent", "lumped"] {
            let lower = format!(
                r#"{SQUARE16}
[membrane]
tension = 1.2
load = "-20*(1 + 0.3*x)"

[obstacle]
shape = 0
stiffness = 0

[lower]
shape = "-0.2 - 0.1*x*y"
stiffness = {stiffness}
foundation = "{foundation}"

[boundary]
height = "-0.02*x"
"#
            );
            let upper = format!(
                r#"{SQUARE16}
[membrane]
tension = 1.2
load = "20*(1 + 0.3*x)"

[obstacle]
shape = "0.2 + 0.1*x*y"
stiffness = {stiffness}
foundation = "{foundation}"

[boundary]
height = "0.02*x"
"#
            );
            let (dl, du) = (disc(&lower), disc(&upper));
            for method in [Method::ActiveSet, Method::Multigrid, Method::Qp] {
                let (ul, rl) = solve(&dl, method, 1e-12);
                let (uu, ru) = solve(&du, method, 1e-12);
                let scale = uu.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (a, b) in ul.iter().zip(&uu) {
                    assert!((a + b).abs() <= 1e-10 * scale, "{stiffness} {foundation}");
                }
                assert!((rl.energy - ru.energy).abs() <= 1e-10 * ru.energy.abs());
                let states = dl.model.lower_states(&rl.u);
                assert!(states.contains(&0) || states.contains(&1), "the body acts");
            }
        }
    }
}

/// Extension data that change nothing give the paper's answer to rounding through the
/// general code paths: a body below that never touches, a stiffness table whose rigid
/// region holds nothing the answer needs (here: rigid far below the membrane is refused,
/// so a body below with h = 0).
#[test]
fn inactive_extensions_reduce_to_the_paper_model() {
    let paper = format!(
        r#"{SQUARE16}
[membrane]
tension = 1.0
load = 20

[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = 1000
"#
    );
    let d0 = disc(&paper);
    for extra in [
        "[lower]\nshape = -10\nstiffness = 500\n",
        "[lower]\nshape = 0.3\nstiffness = 0\n",
        "[lower]\nshape = -10\nstiffness = \"rigid\"\n",
    ] {
        let d1 = disc(&format!("{paper}\n{extra}"));
        assert!(d1.model.is_extended());
        for method in [
            Method::ActiveSet,
            Method::Coordinate,
            Method::Multigrid,
            Method::Qp,
        ] {
            let (u0, r0) = solve(&d0, method, 1e-11);
            let (u1, r1) = solve(&d1, method, 1e-11);
            let diff = u0
                .iter()
                .zip(&u1)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-12, "{extra} {}: {diff:e}", method.name());
            assert!((r0.energy - r1.energy).abs() <= 1e-12 * r0.energy.abs());
        }
    }
}

#[test]
fn overlapping_rigid_bodies_are_refused_with_their_vertices() {
    let e = refused(&format!(
        r#"{SQUARE16}
[membrane]
tension = 1.0
load = 1

[obstacle]
shape = "0.1"
stiffness = "rigid"

[lower]
shape = "0.2*exp(-50*((x-0.5)^2 + (y-0.5)^2)) - 0.05"
stiffness = "rigid"
"#
    ));
    assert!(e.contains("both bodies are rigid and overlap"), "{e}");
    assert!(e.contains("vertex") && e.contains("φ_low = "), "{e}");
    // Rigid bodies that leave no room at the fixed boundary are refused too.
    let e = refused(&format!(
        "{SQUARE16}\n[membrane]\ntension = 1\nload = 1\n\n[obstacle]\nshape = 1\n\
         stiffness = 10\n\n[lower]\nshape = 0.1\nstiffness = \"rigid\"\n"
    ));
    assert!(
        e.contains("lower.shape") && e.contains("above the fixed boundary"),
        "{e}"
    );
}
