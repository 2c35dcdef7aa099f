//! Cross-checks of the solvers on small problems: every method must give the same U, with
//! certificates at the tolerance.

use super::*;
use crate::field::FnCoefficient;
use crate::mesh::test_square as square;
use crate::model::testing::model;
use crate::model::Foundation;

fn settings(method: Method) -> Settings {
    Settings {
        method,
        tolerance: 1e-11,
        ..Settings::default()
    }
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    num / crate::sparse::norm_inf(b).max(1e-300)
}

#[test]
fn active_set_and_coordinate_agree_consistent() {
    let m = square(12);
    let h = FnCoefficient(|p: [f64; 2]| 1e4 * (1.0 + 0.2 * p[0] * p[1]));
    let model = model(&m, Some(&h), Foundation::Consistent);
    let a = solve(&model, None, &settings(Method::ActiveSet), &mut Silent).unwrap();
    let c = solve(&model, None, &settings(Method::Coordinate), &mut Silent).unwrap();
    assert!(rel_diff(&a.u, &c.u) < 1e-8, "{}", rel_diff(&a.u, &c.u));
    assert!(a.certificate.kkt() <= 1e-11);
    let states = model.states(&a.u);
    assert!(states.contains(&1) && states.contains(&-1));
    assert!(
        states.contains(&0),
        "a touching vertex is expected in the consistent model"
    );
    // J decreases monotonically.
    for w in a.history.windows(2) {
        assert!(w[1].energy <= w[0].energy + 1e-14 * w[0].energy.abs());
    }
}

#[test]
fn lumped_and_rigid_agree() {
    let m = square(10);
    let lumped = model(&m, Some(&200.0), Foundation::Lumped);
    let a = solve(&lumped, None, &settings(Method::ActiveSet), &mut Silent).unwrap();
    let c = solve(&lumped, None, &settings(Method::Coordinate), &mut Silent).unwrap();
    assert!(rel_diff(&a.u, &c.u) < 1e-8);
    // The lumped foundation gives a measurably different answer from the consistent one.
    let consistent = model(&m, Some(&200.0), Foundation::Consistent);
    let b = solve(&consistent, None, &settings(Method::ActiveSet), &mut Silent).unwrap();
    assert!(rel_diff(&a.u, &b.u) > 1e-4, "{}", rel_diff(&a.u, &b.u));
    let model = model(&m, None, Foundation::Consistent);
    let a = solve(&model, None, &settings(Method::ActiveSet), &mut Silent).unwrap();
    let c = solve(&model, None, &settings(Method::Coordinate), &mut Silent).unwrap();
    assert!(rel_diff(&a.u, &c.u) < 1e-8);
    assert!(a.u.iter().zip(&model.phi).all(|(u, f)| u <= f));
    assert!(model.states(&a.u).contains(&0));
}

#[test]
fn zero_stiffness_is_the_linear_solve() {
    let m = square(8);
    let model = model(&m, Some(&0.0), Foundation::Consistent);
    assert!(model.is_linear());
    let l = solve(&model, None, &settings(Method::Auto), &mut Silent).unwrap();
    assert_eq!(l.method, Method::Linear);
    let a = solve(&model, None, &settings(Method::ActiveSet), &mut Silent).unwrap();
    assert!(rel_diff(&a.u, &l.u) < 1e-12);
    // S U = D.
    assert!(crate::sparse::norm_inf(&model.residual(&l.u)) < 1e-13);
}
