//! Tests of assembly and the model's checks.

use super::sampling::mollify;
use super::*;
use crate::mesh::test_square as square;
use crate::mesh::VertexTriangles;
use crate::quadrature::gauss_legendre;

fn data<'a>(h: &'a f64, foundation: Foundation) -> ProblemData<'a> {
    ProblemData {
        tension: 2.0,
        load: &3.0,
        shape: &0.1,
        stiffness: BodyStiffness::Elastic(h),
        foundation,
        sampling: Sampling::Nodal,
    }
}

#[test]
fn matrices_have_the_expected_sums() {
    let m = square(8);
    let h = 5.0;
    let model = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap();
    // Σ_ij L_ij over interior × interior = ∫ h (Σ_i g_i)² ≤ h |Ω|; and L ≥ 0 entrywise.
    let FoundationMatrix::Consistent(l) = &model.l else {
        panic!()
    };
    assert!(l.val.iter().all(|&v| v >= 0.0));
    let ones = vec![1.0; model.n()];
    let total = l.quad_form(&ones);
    assert!(total > 0.0 && total < h);
    // S annihilates constants in the interior rows far from the boundary and is SPD.
    assert!(model.s.quad_form(&ones) > 0.0);
    // Σ D_i = ∫ f Σ g_i = f (|Ω| − boundary layer /3 ...) < f |Ω|.
    let sd: f64 = model.d.iter().sum();
    assert!(sd < 3.0 && sd > 0.0);
    assert!((model.total_load - 3.0).abs() < 1e-13);
    // Lumped l_i = ∫ h g_i = row sums of the full mass matrix = h × patch area / 3.
    let lumped = Model::assemble(&m, &data(&h, Foundation::Lumped)).unwrap();
    let FoundationMatrix::Lumped(d) = &lumped.l else {
        panic!()
    };
    for &v in d {
        assert!((v - h * 6.0 / (2.0 * 64.0) / 3.0).abs() < 1e-14);
    }
}

#[test]
fn bad_data_is_reported() {
    let m = square(4);
    let h = -1.0;
    let e = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap_err();
    assert!(e.to_string().contains("negative"), "{e}");
    let h = f64::NAN;
    let e = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap_err();
    assert!(e.to_string().contains("NaN"), "{e}");
    let h = 1.0;
    let mut d = data(&h, Foundation::Consistent);
    d.tension = 0.0;
    let e = Model::assemble(&m, &d).unwrap_err();
    assert!(e.to_string().contains("tension"), "{e}");
}

#[test]
fn mollification_keeps_constants_and_linear_functions() {
    let m = square(4);
    let adj = VertexTriangles::new(&m);
    let c = crate::field::FnCoefficient(|p: crate::mesh::Point| 2.0 * p[0] - p[1] + 0.5);
    let v = mollify(&m, &adj, &c, 0.3);
    for (k, p) in m.points.iter().enumerate() {
        assert!((v[k] - (2.0 * p[0] - p[1] + 0.5)).abs() < 1e-13);
    }
    let (x, w) = gauss_legendre(8);
    let s: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
    assert!((s - 2.0 / 15.0).abs() < 1e-14);
    assert!(paper_epsilon(&m) >= 0.25f64.sqrt().sqrt() * 2f64.sqrt().sqrt() - 1e-12);
}

use crate::field::Field;
use crate::model::{Foundation, Sampling};

#[test]
fn loads_singular_on_the_boundary_and_rigid_bodies_below_it_are_refused() {
    let mesh = crate::mesh::test_square(4);
    let bind = |f: &str| {
        Field::parse(f)
            .unwrap()
            .bind_to_mesh("membrane.load", &mesh)
            .unwrap()
    };
    let (load, shape, h) = (bind("1/x"), bind("0.1"), bind("10"));
    let mut data = ProblemData {
        tension: 1.0,
        load: &load,
        shape: &shape,
        stiffness: BodyStiffness::Elastic(&h),
        foundation: Foundation::Consistent,
        sampling: Sampling::Nodal,
    };
    let e = assemble_checked(&mesh, &data, &Extensions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("boundary") && e.contains("membrane.load"), "{e}");
    let (one, below) = (bind("1"), bind("x - 0.5"));
    data.load = &one;
    data.shape = &below;
    data.stiffness = BodyStiffness::Rigid;
    let e = assemble_checked(&mesh, &data, &Extensions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("below the fixed boundary"), "{e}");
    data.stiffness = BodyStiffness::Elastic(&h);
    assert!(assemble_checked(&mesh, &data, &Extensions::default()).is_ok());
}
