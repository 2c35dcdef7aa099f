//! The paper's formulations agree (docs/theory.md#formulations-agree): on square and disc
//! meshes, with constant and varying data, touching vertices, a rigid obstacle and a
//! partial foundation, the solutions of 2f (active set), 2c (QP, Clarabel) and 2b
//! (coordinate descent) coincide, and every answer satisfies the 2e and 2f certificates.

use memcontact::field::{Coefficient, FnCoefficient};
use memcontact::io::gmsh::read_msh;
use memcontact::mesh::generate::{disk, rectangle, Diagonal, RectangleSpec};
use memcontact::mesh::Mesh;
use memcontact::model::{BodyStiffness, Foundation, Model, ProblemData, Sampling};
use memcontact::solve::{solve, Method, Settings, Silent, Solution};
use std::path::Path;

fn square(n: usize, diagonal: Diagonal) -> Mesh {
    rectangle(&RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: n,
        ny: n,
        diagonal,
    })
    .unwrap()
    .finest()
    .clone()
}

fn run(model: &Model, method: Method) -> Solution {
    let s = Settings {
        method,
        tolerance: 1e-11,
        ..Settings::default()
    };
    solve(model, None, &s, &mut Silent).unwrap_or_else(|e| panic!("{}: {e}", method.name()))
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// Solves with the three formulations and checks agreement and certificates; returns the
/// active-set solution.
fn all_agree(name: &str, model: &Model) -> Solution {
    let a = run(model, Method::ActiveSet);
    let q = run(model, Method::Qp);
    let c = run(model, Method::Coordinate);
    for (m, s) in [("active-set", &a), ("qp", &q), ("coordinate", &c)] {
        let cert = model.certificate(&s.u);
        assert!(
            cert.residual_2f <= 1e-9,
            "{name} {m}: 2f {}",
            cert.residual_2f
        );
        assert!(
            cert.residual_2e <= 1e-9,
            "{name} {m}: 2e {}",
            cert.residual_2e
        );
        // J(U) is the minimum: no solver's energy is below another's by more than rounding.
        assert!(
            (s.energy - a.energy).abs() <= 1e-9 * a.energy.abs(),
            "{name} {m}"
        );
    }
    assert!(
        rel_diff(&q.u, &a.u) <= 1e-8,
        "{name}: qp vs active-set {}",
        rel_diff(&q.u, &a.u)
    );
    assert!(
        rel_diff(&c.u, &a.u) <= 1e-8,
        "{name}: coordinate vs active-set {}",
        rel_diff(&c.u, &a.u)
    );
    // The QP's own multipliers satisfy 2e's first equation S U − D + X̂₁ = 0.
    let x = q.multipliers.as_ref().expect("the QP returns multipliers");
    let r = model.residual(&q.u);
    let scale = model.force_scale();
    for (i, ((ri, x1), x2)) in r.iter().zip(&x.x1).zip(&x.x2).enumerate() {
        assert!((ri + x1).abs() <= 1e-8 * scale, "{name}: 2e row {i}");
        assert!(*x1 >= -1e-9 * scale && *x2 >= -1e-9 * scale);
    }
    a
}

fn model(mesh: &Mesh, phi: &dyn Coefficient, h: Option<&dyn Coefficient>, f: Foundation) -> Model {
    Model::assemble(
        mesh,
        &ProblemData {
            tension: 1.5,
            load: &8.0,
            shape: phi,
            stiffness: h.map_or(BodyStiffness::Rigid, BodyStiffness::Elastic),
            foundation: f,
            sampling: Sampling::Nodal,
        },
    )
    .unwrap()
}

#[test]
fn square_constant_data() {
    let m = square(12, Diagonal::Right);
    let model = model(&m, &0.1, Some(&300.0), Foundation::Consistent);
    let a = all_agree("square constant", &model);
    let st = model.states(&a.u);
    assert!(st.contains(&1) && st.contains(&-1));
}

#[test]
fn square_touching_vertex() {
    // A stiff foundation: some vertices end exactly at U = φ (the kink of J₂).
    let m = square(12, Diagonal::Right);
    let phi = FnCoefficient(|p: [f64; 2]| 0.12 + 0.05 * (6.0 * p[0]).sin() * p[1]);
    let model = model(&m, &phi, Some(&1e4), Foundation::Consistent);
    let a = all_agree("touching", &model);
    let touching = model.states(&a.u).iter().filter(|&&s| s == 0).count();
    assert!(touching > 0, "expected a touching vertex");
}

#[test]
fn disc_varying_data() {
    let m = disk([0.0, 0.0], 1.0, 0.15).unwrap();
    let phi = FnCoefficient(|p: [f64; 2]| 0.8 + 0.2 * p[0] - 0.1 * p[1] * p[1]);
    let h = FnCoefficient(|p: [f64; 2]| 50.0 + 200.0 * (p[0] * p[0] + p[1] * p[1]));
    let model = model(&m, &phi, Some(&h), Foundation::Consistent);
    all_agree("disc varying", &model);
}

#[test]
fn disc_rigid() {
    let m = disk([0.0, 0.0], 1.0, 0.15).unwrap();
    let phi = FnCoefficient(|p: [f64; 2]| 0.9 + 0.1 * p[0]);
    let model = model(&m, &phi, None, Foundation::Consistent);
    let a = all_agree("disc rigid", &model);
    assert!(a.u.iter().zip(&model.phi).all(|(u, f)| u <= f));
    assert!(model.states(&a.u).contains(&0));
}

#[test]
fn square_lumped_and_partial_foundation() {
    let m = square(10, Diagonal::Left);
    let phi = FnCoefficient(|p: [f64; 2]| 0.1 + 0.05 * p[0]);
    // h = 0 on the left half: M is a strict subset of the unknowns.
    let h = FnCoefficient(|p: [f64; 2]| if p[0] < 0.5 { 0.0 } else { 400.0 });
    let lumped = model(&m, &phi, Some(&h), Foundation::Lumped);
    let consistent = model(&m, &phi, Some(&h), Foundation::Consistent);
    assert!(consistent.can_touch.iter().any(|c| !c) && consistent.can_touch.iter().any(|&c| c));
    let a = all_agree("lumped partial", &lumped);
    let b = all_agree("consistent partial", &consistent);
    // The lumped variant is a different discrete model: measurably different answers.
    assert!(rel_diff(&a.u, &b.u) > 1e-4, "{}", rel_diff(&a.u, &b.u));
}

#[test]
fn zero_stiffness_equals_the_linear_solve() {
    let m = square(10, Diagonal::Alternate);
    let model = model(&m, &0.1, Some(&0.0), Foundation::Consistent);
    let l = run(&model, Method::Linear);
    for method in [Method::ActiveSet, Method::Qp, Method::Coordinate] {
        let s = run(&model, method);
        assert!(rel_diff(&s.u, &l.u) <= 1e-9, "{}", method.name());
    }
    // The linear solution satisfies S U = D.
    let r = model.residual(&l.u);
    assert!(r.iter().all(|v| v.abs() <= 1e-12 * model.force_scale()));
}

#[test]
fn msh_22_and_41_give_the_same_solution() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut energies = Vec::new();
    let mut maxima = Vec::new();
    for f in [
        "disk_v22_ascii.msh",
        "disk_v41_ascii.msh",
        "disk_v22_binary.msh",
        "disk_v41_binary.msh",
    ] {
        let (mesh, _) = read_msh(&data.join(f)).unwrap();
        let phi = FnCoefficient(|p: [f64; 2]| 0.8 - 0.2 * (p[0] * p[0] + p[1] * p[1]));
        let model = model(&mesh, &phi, Some(&200.0), Foundation::Consistent);
        let s = run(&model, Method::ActiveSet);
        energies.push(s.energy);
        maxima.push(s.u.iter().cloned().fold(f64::MIN, f64::max));
    }
    for k in 1..energies.len() {
        assert!((energies[k] - energies[0]).abs() <= 1e-12 * energies[0].abs());
        assert!((maxima[k] - maxima[0]).abs() <= 1e-12 * maxima[0].abs());
    }
}
