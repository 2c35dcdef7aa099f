//! The adaptive loop (docs/theory.md#adaptivity) against mathematics: the exact free
//! boundary of PETSc's ex9 ball, the optimal rate of the energy error on an L-shaped domain
//! (against a reference J extrapolated from uniform refinements), the estimator's
//! reliability and efficiency on manufactured solutions (a free edge and a body below among
//! them), a rigid region, and the loop's own guarantees (nested meshes, certified steps,
//! bounded iterations).

use memcontact::adapt::AdaptRow;
use memcontact::case::Case;
use memcontact::mesh::Mesh;
use memcontact::outcome::Outcome;
use memcontact::run::{run_adapt, AdaptRun, AdaptStop};
use memcontact::solve::Silent;
use memcontact::verify::exact::{ExactSolution, Manufactured, ManufacturedCosine};
use memcontact::verify::norms::error_norms;

/// What a test reads of every step: the loop's run, whether each step's certificate
/// passed, and each step's H¹ seminorm error against `exact` (when given).
struct Steps {
    run: AdaptRun,
    accepted: Vec<bool>,
    h1_errors: Vec<f64>,
}

fn adapt(text: &str, exact: Option<&dyn ExactSolution>) -> Steps {
    let case = Case::from_toml_str(text, None).expect("the case parses");
    let mut accepted = Vec::new();
    let mut h1_errors = Vec::new();
    let mut on_step = |row: &AdaptRow, outcome: &Outcome, eta2: &[f64]| {
        let mesh = outcome.mesh();
        assert_eq!(eta2.len(), mesh.n_triangles(), "one indicator per triangle");
        assert!(
            (eta2.iter().sum::<f64>().sqrt() - row.estimator).abs() <= 1e-12 * row.estimator,
            "the row's estimator is (Σ η_T²)^½"
        );
        accepted.push(
            outcome.report.accepted && outcome.report.certificate.kkt() <= outcome.report.tolerance,
        );
        if let Some(exact) = exact {
            let (fields, _) = outcome.fields();
            h1_errors.push(error_norms(&mesh, &fields.u, exact).unwrap().h1_semi);
        }
        Ok(())
    };
    let run = run_adapt(&case, &mut Silent, &mut on_step).expect("the loop runs");
    Steps {
        run,
        accepted,
        h1_errors,
    }
}

/// The least-squares slope of log y against log x.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = x.iter().zip(y).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

fn check_loop_guarantees(steps: &Steps) {
    assert!(
        steps.accepted.iter().all(|&a| a),
        "every step's certificate passes: {:?}",
        steps.accepted
    );
    for row in &steps.run.rows[2.min(steps.run.rows.len())..] {
        assert!(
            row.iterations <= 10,
            "step {}: {} iterations (at most 10 after the second step)",
            row.step,
            row.iterations
        );
    }
    let v: Vec<usize> = steps.run.rows.iter().map(|r| r.vertices).collect();
    assert!(
        v.windows(2).all(|w| w[1] > w[0]),
        "every step refines: {v:?}"
    );
}

/// PETSc SNES ex9 in this project's sign convention (docs/theory.md#obstacle-benchmarks):
/// the exact solution.
fn ex9_exact(p: [f64; 2]) -> f64 {
    let a = 0.697965148223374_f64;
    let big_a = a * a / (1.0 - a * a).sqrt();
    let b = big_a * 2f64.ln();
    let r = p[0].hypot(p[1]);
    let psi = if r <= 0.9 {
        (1.0 - r * r).max(0.0).sqrt()
    } else {
        0.19f64.sqrt() - 0.9 / 0.19f64.sqrt() * (r - 0.9)
    };
    if r <= a {
        -psi
    } else {
        -(-big_a * r.ln() + b)
    }
}

const EX9: &str = r#"
[mesh]
generator = "rectangle"
x0 = -2.0
y0 = -2.0
x1 = 2.0
y1 = 2.0
nx = 16
ny = 16

[membrane]
tension = 1.0
load = 0.0

[obstacle]
shape = "-if(r <= 0.9, sqrt(1 - r^2), sqrt(0.19) - 0.9/sqrt(0.19)*(r - 0.9))"
stiffness = "rigid"

[boundary]
height = "-0.697965148223374^2/sqrt(1 - 0.697965148223374^2)*ln(2/r)"

[solver]
tolerance = 1e-10

[adapt]
max_vertices = 30000
steps = 30
"#;

/// The discrete free boundary (the midpoints of the edges between a contact and a clear
/// vertex) against the exact circle r = a: the Hausdorff distance, both ways.
fn free_boundary_hausdorff(mesh: &Mesh, contact: &[bool], a: f64) -> f64 {
    let mut points = Vec::new();
    for t in &mesh.triangles {
        for e in 0..3 {
            let (i, j) = (t[e] as usize, t[(e + 1) % 3] as usize);
            if contact[i] != contact[j] {
                let (p, q) = (mesh.points[i], mesh.points[j]);
                points.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0]);
            }
        }
    }
    assert!(!points.is_empty(), "a free boundary");
    let to_circle = points
        .iter()
        .map(|p| (p[0].hypot(p[1]) - a).abs())
        .fold(0.0, f64::max);
    let from_circle = (0..2000)
        .map(|k| {
            let th = k as f64 * std::f64::consts::TAU / 2000.0;
            let c = [a * th.cos(), a * th.sin()];
            points
                .iter()
                .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    to_circle.max(from_circle)
}

#[test]
fn ex9_free_boundary_is_found_within_5e_3_with_at_most_30000_vertices() {
    let steps = adapt(EX9, None);
    check_loop_guarantees(&steps);
    assert_eq!(steps.run.stop, AdaptStop::MaxVertices);
    let outcome = &steps.run.outcome;
    let mesh = outcome.mesh();
    assert!(mesh.n_vertices() <= 30_000);
    let (fields, _) = outcome.fields();
    let nodal = mesh
        .points
        .iter()
        .zip(&fields.u)
        .map(|(&p, &u)| (u - ex9_exact(p)).abs())
        .fold(0.0, f64::max);
    assert!(nodal <= 1e-3, "max nodal error {nodal:.3e}");
    let contact: Vec<bool> = fields.state.iter().map(|&s| s >= 0).collect();
    let d = free_boundary_hausdorff(&mesh, &contact, 0.697965148223374);
    assert!(d <= 5e-3, "free-boundary Hausdorff distance {d:.3e}");
    // The start grid (h = 0.25) cannot place it better than about h/2.
    let first = steps.run.rows[0].estimator;
    assert!(steps.run.rows.last().unwrap().estimator < first / 5.0);
}

/// An L-shaped roof membrane pressed into an elastic soil (a body below), the re-entrant
/// corner at the origin.
const L_SHAPE: &str = r#"
[mesh]
generator = "polygon"
outer = [[-1.0, -1.0], [0.0, -1.0], [0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [-1.0, 1.0]]
size = 0.25

[membrane]
tension = 1.0
load = -10.0

[obstacle]
shape = 1.0
stiffness = 0.0

[lower]
shape = -0.2
stiffness = 100.0

[solver]
tolerance = 1e-11
"#;

/// J* by extrapolation of uniform refinements k = 4, 5, 6 of the start mesh (up to 360 000
/// vertices), fitting J_k = J* + a 2^{-4k/3} + b 4^{-k}: the corner's r^{2/3} term and the
/// smooth part.
fn l_shape_reference() -> f64 {
    let j = |k: u32| {
        let text = L_SHAPE.replace("[mesh]\n", &format!("[mesh]\nrefine = {k}\n"));
        let case = Case::from_toml_str(&text, None).unwrap();
        let outcome = memcontact::run(&case, &mut Silent).unwrap();
        assert!(outcome.report.accepted);
        outcome.report.energy
    };
    let rows: Vec<[f64; 4]> = (4..=6)
        .map(|k| {
            let kf = k as f64;
            [1.0, 2f64.powf(-4.0 * kf / 3.0), 4f64.powf(-kf), j(k)]
        })
        .collect();
    // Cramer's rule for the 3 × 3 system.
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let a: [[f64; 3]; 3] = std::array::from_fn(|i| [rows[i][0], rows[i][1], rows[i][2]]);
    let mut a0 = a;
    for i in 0..3 {
        a0[i][0] = rows[i][3];
    }
    det(a0) / det(a)
}

#[test]
fn l_shape_energy_error_falls_at_the_optimal_rate() {
    let reference = l_shape_reference();
    let text = format!("{L_SHAPE}\n[adapt]\nmax_vertices = 45000\nsteps = 40\n");
    let steps = adapt(&text, None);
    check_loop_guarantees(&steps);
    let rows = &steps.run.rows;
    // Nested P1 spaces, g = 0: J(U) cannot increase from step to step.
    for w in rows.windows(2) {
        assert!(
            w[1].energy <= w[0].energy + 1e-10,
            "J rose from step {} to {}: {} → {}",
            w[0].step,
            w[1].step,
            w[0].energy,
            w[1].energy
        );
    }
    let late: Vec<&AdaptRow> = rows.iter().filter(|r| r.vertices >= 1000).collect();
    assert!(late.len() >= 6, "{} steps past 1000 vertices", late.len());
    let n: Vec<f64> = late.iter().map(|r| r.vertices as f64).collect();
    // J(u_h) − J* ≥ ½‖u − u_h‖², so e = (2 (J(u_h) − J*))^½ is the energy error.
    let e: Vec<f64> = late
        .iter()
        .map(|r| {
            assert!(r.energy > reference, "J(U) above J* = {reference}");
            (2.0 * (r.energy - reference)).sqrt()
        })
        .collect();
    let s = slope(&n, &e);
    assert!(
        s <= -0.45,
        "energy error slope {s:.3} in vertices (uniform: about -1/3)"
    );
    let index: Vec<f64> = late.iter().zip(&e).map(|(r, e)| r.estimator / e).collect();
    let (lo, hi) = index
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        lo >= 1.0,
        "the estimator bounds the error: η/e down to {lo:.2}"
    );
    assert!(hi / lo <= 4.0, "η/e from {lo:.2} to {hi:.2}");
}

/// A manufactured case (docs/theory.md#manufactured-solutions) on the unit square: u =
/// sin(πx) sin(πy), t = 1.5, φ and h varying, the load f = −tΔu + h (u − φ)⁺ written as an
/// expression.
fn manufactured_case(nx: usize, adapt_section: &str) -> String {
    format!(
        r#"
[mesh]
generator = "rectangle"
nx = {nx}
ny = {nx}

[membrane]
tension = 1.5
load = "1.5*2*pi^2*sin(pi*x)*sin(pi*y) + 50*(1 + y)*max(sin(pi*x)*sin(pi*y) - (0.55 + 0.3*(x - 0.5)^2 + 0.1*y), 0)"

[obstacle]
shape = "0.55 + 0.3*(x - 0.5)^2 + 0.1*y"
stiffness = "50*(1 + y)"

[solver]
tolerance = 1e-11

{adapt_section}
"#
    )
}

/// For a case with a manufactured solution `exact` (`case(nx, adapt_section)`): on uniform
/// meshes nx = 8, …, 128 and along 12 adaptive steps from nx = 8, η / (t^½ |u − u_h|_{H¹})
/// stays in a band (at least 1, spread at most 3: the estimator is reliable and efficient),
/// and the adaptive error falls like N^{-1/2} (u is smooth). Returns the adaptive run.
fn check_estimator_and_rate(
    case: fn(usize, &str) -> String,
    exact: &dyn ExactSolution,
    tension: f64,
) -> Steps {
    let mut index: Vec<f64> = [8, 16, 32, 64, 128]
        .iter()
        .map(|&nx| {
            let s = adapt(&case(nx, "[adapt]\nsteps = 1\n"), Some(exact));
            assert_eq!(s.run.stop, AdaptStop::Steps);
            s.run.rows[0].estimator / (tension.sqrt() * s.h1_errors[0])
        })
        .collect();
    let adaptive = adapt(&case(8, "[adapt]\nsteps = 12\n"), Some(exact));
    check_loop_guarantees(&adaptive);
    index.extend(
        adaptive
            .run
            .rows
            .iter()
            .zip(&adaptive.h1_errors)
            .map(|(r, e)| r.estimator / (tension.sqrt() * e)),
    );
    let (lo, hi) = index
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(lo >= 1.0, "η/e down to {lo:.2}: {index:?}");
    assert!(hi / lo <= 3.0, "η/e from {lo:.2} to {hi:.2}: {index:?}");
    let n: Vec<f64> = adaptive
        .run
        .rows
        .iter()
        .map(|r| r.vertices as f64)
        .collect();
    let s = slope(&n[3..], &adaptive.h1_errors[3..]);
    assert!(s <= -0.45, "H¹ error slope {s:.3}");
    adaptive
}

#[test]
fn manufactured_estimator_is_reliable_and_efficient() {
    let exact = Manufactured::rectangle(0.0, 0.0, 1.0, 1.0, 1.0).unwrap();
    check_estimator_and_rate(manufactured_case, &exact, 1.5);
}

/// The manufactured cosine (docs/theory.md#manufactured-solutions) with a free top edge (t
/// ∂u/∂n = 0 there), the other sides held at g = u, an elastic obstacle above and an
/// elastic body below.
fn free_edge_case(nx: usize, adapt_section: &str) -> String {
    let u = "0.1*(cos(pi*x)*cos(pi*y) + 0.5*cos(2*pi*y))";
    format!(
        r#"
[mesh]
generator = "rectangle"
nx = {nx}
ny = {nx}

[membrane]
tension = 1.0
load = "0.1*2*pi^2*(cos(pi*x)*cos(pi*y) + cos(2*pi*y)) + 200*max({u} - 0.12, 0) - 300*max(-0.06 - ({u}), 0)"

[obstacle]
shape = 0.12
stiffness = 200.0

[lower]
shape = -0.06
stiffness = 300.0

[boundary]
height = "{u}"
free = ["top"]

[solver]
tolerance = 1e-11

{adapt_section}
"#
    )
}

#[test]
fn free_edge_and_body_below_adapt_with_a_reliable_efficient_estimator() {
    let exact = ManufacturedCosine::rectangle(0.0, 0.0, 1.0, 1.0, 0.1).unwrap();
    let adaptive = check_estimator_and_rate(free_edge_case, &exact, 1.0);
    // The free top edge is refined with the rest: its vertices stay on y = 1 and are
    // unknowns (not held).
    let mesh = adaptive.run.outcome.mesh();
    let top = mesh.points.iter().filter(|p| p[1] == 1.0).count();
    assert!(top > 9, "the top edge was refined: {top} vertices");
}

#[test]
fn a_rigid_region_adapts_towards_a_fine_reference() {
    let case = r#"
[mesh]
generator = "polygon"
outer = [[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]
regions = [{ name = "plinth", polygon = [[1.2, 0.6], [1.8, 0.6], [1.8, 1.4], [1.2, 1.4]] }]
size = 0.25

[membrane]
tension = 2.0
load = "-1.5 - 6*exp(-((x - 2.2)^2 + (y - 1.0)^2)/0.05)"

[obstacle]
shape = 10.0
stiffness = 0

[lower]
shape = "-0.02 - 0.01*x"
stiffness = { plinth = "rigid", default = 150.0 }

[solver]
tolerance = 1e-11
"#;
    let steps = adapt(&format!("{case}\n[adapt]\nmax_vertices = 11000\n"), None);
    check_loop_guarantees(&steps);
    let rows = &steps.run.rows;
    assert!(rows.last().unwrap().estimator < rows[0].estimator / 4.0);
    // The regions keep their areas (a triangle's children keep its tag).
    let area_of = |mesh: &Mesh, tag: u32| -> f64 {
        (0..mesh.n_triangles())
            .filter(|&k| mesh.regions[k] == tag)
            .map(|k| mesh.area(k))
            .sum()
    };
    let mesh = steps.run.outcome.mesh();
    let plinth = *mesh
        .region_names
        .iter()
        .find(|(_, n)| n.as_str() == "plinth")
        .unwrap()
        .0;
    assert!((area_of(&mesh, plinth) - 0.48).abs() < 1e-12);
    // Against a fine uniform solve (three refinements: 64 times the start triangles): with
    // fewer vertices the adapted J comes within a hundredth of the start's distance.
    let fine =
        Case::from_toml_str(&case.replace("[mesh]\n", "[mesh]\nrefine = 3\n"), None).unwrap();
    let fine = memcontact::run(&fine, &mut Silent).unwrap();
    assert!(fine.report.accepted);
    let j_fine = fine.report.energy;
    // Nested P1 spaces, g = 0 and φ_low linear: J(U) cannot increase from step to step.
    for w in rows.windows(2) {
        assert!(
            w[1].energy <= w[0].energy + 1e-10,
            "J rose at step {}",
            w[1].step
        );
    }
    let start = rows[0].energy - j_fine;
    let last = rows.last().unwrap();
    assert!(last.vertices <= fine.mesh().n_vertices());
    assert!(
        (last.energy - j_fine).abs() < start / 100.0,
        "J − J_fine: {start:.3e} at the start, {:.3e} with {} vertices",
        last.energy - j_fine,
        last.vertices
    );
}
