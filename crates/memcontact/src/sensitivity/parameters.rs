//! Parameters bound to the model: for a case key ([`ParameterKey`]), the derivative of the
//! assembled data S, L, D, φₙ, the lifting and the outputs' vertex data in it
//! ([`DataDerivative`]), and from those the partial derivative `∂R/∂p` of the optimality
//! system and the values prescribed on the held vertices (docs/theory.md#tangent).
//!
//! Every datum enters the discrete model linearly, so the derivative data are the model's
//! data assembled with the derivative coefficient of the key: 1 on the region of a region
//! entry (0 on the others), the entry's own expression for a factor, 1 everywhere for a
//! number or an offset of the whole datum ([`crate::model::DerivativeAssembly`]).

use crate::case::{ParameterKey, ParameterKind, ParameterTarget};
use crate::discretization::bind_height;
use crate::error::{Error, Result};
use crate::field::{BoundField, Field, Stiffness};
use crate::model::{DerivativeAssembly, Foundation, FoundationMatrix, Model, VertexValues};
use crate::problem::{Obstacle, Problem};
use std::collections::BTreeMap;

/// The derivative of one body's data (the obstacle's, or the body below's).
#[derive(Debug, Clone, Default)]
pub struct BodyDerivative {
    /// The derivative coefficient of the stiffness and the body's rigid regions: the
    /// energy's `½ p̂ᵀ dL p̂` from the element matrices
    /// ([`crate::model::consistent_foundation_form`]).
    pub stiffness: Option<(BoundField, Vec<u32>)>,
    /// dL (consistent on the pattern of S, or the lumped diagonal). A consistent dL is
    /// assembled only for data prepared for solves ([`DataDerivative::new`]).
    pub dl: Option<FoundationMatrix>,
    /// dh at every vertex (as the model keeps h for its outputs).
    pub dh_vertices: Option<Vec<f64>>,
    /// dφ at every vertex.
    pub dphi_vertices: Option<Vec<f64>>,
    /// dφ at the unknowns.
    pub dphi: Option<Vec<f64>>,
}

/// The derivative of the model's data in one parameter.
#[derive(Debug, Clone)]
pub struct DataDerivative {
    /// The parameter.
    pub key: ParameterKey,
    /// The tension: dS = S / t and d(lift) = lift / t at the model's current tension.
    pub tension: bool,
    /// d(∫ f gᵢ) over the unknowns (the load without the lifting), and d(∫ f).
    pub dload: Option<(Vec<f64>, f64)>,
    /// dG over all vertices, and the lifting of it, `S_fix dG`, at the tension `t0`.
    pub dheights: Option<(Vec<f64>, Vec<f64>, f64)>,
    /// The obstacle.
    pub up: BodyDerivative,
    /// The body below.
    pub low: BodyDerivative,
}

/// The derivative coefficient of a region table's entry `region` (1, or the entry itself
/// for a factor; 0 on the other entries, which keep their keys so that the regions resolve
/// as in the case).
fn entry_table(table: &BTreeMap<String, Field>, region: &str, kind: ParameterKind) -> Field {
    Field::Regions(
        table
            .iter()
            .map(|(k, v)| {
                let d = if k == region {
                    match kind {
                        ParameterKind::Factor => v.clone(),
                        _ => Field::Constant(1.0),
                    }
                } else {
                    Field::Constant(0.0)
                };
                (k.clone(), d)
            })
            .collect(),
    )
}

/// The derivative coefficient of a field (or of its region entry) in the parameter.
fn field_derivative(field: &Field, key: &ParameterKey) -> Field {
    match (&key.region, field) {
        (Some(r), Field::Regions(t)) => entry_table(t, r, key.kind),
        _ => match key.kind {
            ParameterKind::Factor => field.clone(),
            _ => Field::Constant(1.0),
        },
    }
}

/// The derivative coefficient of a stiffness in the parameter, as a field (rigid entries
/// 0; the rigid regions are masked by the assembly anyway).
fn stiffness_derivative(s: &Stiffness, key: &ParameterKey) -> Field {
    match s {
        Stiffness::Elastic(f) => field_derivative(f, key),
        Stiffness::Rigid => Field::Constant(0.0),
        Stiffness::Mixed(t) => {
            let elastic: BTreeMap<String, Field> = t
                .iter()
                .map(|(k, v)| {
                    let f = match v {
                        Stiffness::Elastic(f) => f.clone(),
                        _ => Field::Constant(0.0),
                    };
                    (k.clone(), f)
                })
                .collect();
            match &key.region {
                Some(r) => entry_table(&elastic, r, key.kind),
                None => match key.kind {
                    ParameterKind::Factor => Field::Regions(elastic),
                    _ => Field::Constant(1.0),
                },
            }
        }
    }
}

impl DataDerivative {
    /// The derivative data of `key` for `model`, assembled by `asm` (on the solved mesh, in
    /// the solver's numbering) with the model's own kernels. With `for_solves` false, only
    /// what the energy's envelope derivative reads: a consistent dL and dh at the vertices
    /// (for linear solves, other outputs and moved models) are left out, the costly part on
    /// a large mesh.
    pub fn new(
        problem: &Problem,
        key: &ParameterKey,
        asm: &DerivativeAssembly,
        model: &Model,
        for_solves: bool,
    ) -> Result<DataDerivative> {
        let mesh = asm.mesh;
        let mut d = DataDerivative {
            key: key.clone(),
            tension: false,
            dload: None,
            dheights: None,
            up: BodyDerivative::default(),
            low: BodyDerivative::default(),
        };
        let name = |what: &str| format!("the derivative of {} in {}", what, key.key);
        let body = |obstacle: &Obstacle,
                    shape: bool,
                    section: &str,
                    foundation: Foundation,
                    epsilon: Option<f64>|
         -> Result<BodyDerivative> {
            let mut b = BodyDerivative::default();
            if shape {
                let f = field_derivative(&obstacle.shape, key);
                let bound = f.bind_to_mesh(&name(&format!("{section}.shape")), mesh)?;
                let at_vertices = asm.surface(&bound, epsilon);
                b.dphi = Some(model.dofs.to_unknowns(&at_vertices));
                b.dphi_vertices = Some(at_vertices);
            } else {
                let bound = obstacle
                    .stiffness
                    .bind_to_mesh(&format!("{section}.stiffness"), mesh)?;
                let f = stiffness_derivative(&obstacle.stiffness, key);
                let c = f.bind_to_mesh(&name(&format!("{section}.stiffness")), mesh)?;
                if for_solves || foundation == Foundation::Lumped {
                    b.dl = Some(asm.foundation(&c, &bound.rigid_tags, foundation));
                }
                if for_solves {
                    b.dh_vertices = Some(asm.vertex_stiffness(&c, &bound.rigid_tags));
                }
                b.stiffness = Some((c, bound.rigid_tags));
            }
            Ok(b)
        };
        match key.target {
            ParameterTarget::Tension => d.tension = true,
            ParameterTarget::Load => {
                let f = field_derivative(&problem.membrane.load, key);
                let c = f.bind_to_mesh(&name("membrane.load"), mesh)?;
                d.dload = Some(asm.load(&c));
            }
            ParameterTarget::Shape | ParameterTarget::Stiffness => {
                d.up = body(
                    &problem.obstacle,
                    key.target == ParameterTarget::Shape,
                    "obstacle",
                    model.foundation,
                    model.epsilon,
                )?;
            }
            ParameterTarget::LowerShape | ParameterTarget::LowerStiffness => {
                let (Some(low), Some(lm)) = (&problem.lower, &model.lower) else {
                    return Err(Error::Data(format!("{}: the case has no [lower]", key.key)));
                };
                d.low = body(
                    low,
                    key.target == ParameterTarget::LowerShape,
                    "lower",
                    lm.foundation,
                    lm.epsilon,
                )?;
            }
            ParameterTarget::Height => {
                let mut boundary = problem.boundary.clone();
                boundary.height = field_derivative(&problem.boundary.height, key);
                let c = bind_height(&boundary, mesh)?;
                let g = asm.heights(&c, &boundary.free)?;
                let lift = asm.lift(model.tension, &g);
                d.dheights = Some((g, lift, model.tension));
            }
        }
        Ok(d)
    }

    /// The model with this parameter moved by `delta` (its value, factor or offset): every
    /// datum it enters is linear in it, so the moved model is the model plus `delta` times
    /// the derivative data (and for the tension, S and the lifting scaled). The vertices
    /// that can touch (M) follow the new L.
    pub fn move_model(&self, model: &mut Model, delta: f64) {
        if delta == 0.0 {
            return;
        }
        if self.tension {
            let t = match self.key.kind {
                ParameterKind::Factor => model.tension * (1.0 + delta),
                _ => model.tension + delta,
            };
            model.set_tension(t);
        }
        if let Some((dd, dtotal)) = &self.dload {
            for (d, x) in model.d.iter_mut().zip(dd) {
                *d += delta * x;
            }
            model.total_load += delta * dtotal;
        }
        if let Some((dg, dlift, t0)) = &self.dheights {
            let k = model.tension / t0;
            if model.boundary_values.len() != dg.len() {
                model.boundary_values = vec![0.0; dg.len()];
            }
            for (g, x) in model.boundary_values.iter_mut().zip(dg) {
                *g += delta * x;
            }
            if model.lift.len() != dlift.len() {
                model.lift = vec![0.0; dlift.len()];
            }
            for ((l, d), x) in model.lift.iter_mut().zip(model.d.iter_mut()).zip(dlift) {
                *l += delta * k * x;
                *d -= delta * k * x;
            }
        }
        let upper_rigid = model.rigid.clone();
        move_body(
            &self.up,
            delta,
            &mut model.l,
            &mut model.phi,
            &mut model.phi_fixed,
            &mut model.h_vertices,
        );
        let rigid_l = model.l.is_rigid();
        for (i, c) in model.can_touch.iter_mut().enumerate() {
            *c = rigid_l || model.l.diag(i) > 0.0 || upper_rigid.as_ref().is_some_and(|r| r[i]);
        }
        if let Some(low) = &mut model.lower {
            move_body(
                &self.low,
                delta,
                &mut low.l,
                &mut low.phi,
                &mut low.phi_fixed,
                &mut low.h_vertices,
            );
            let rigid_l = low.l.is_rigid();
            for i in 0..low.can_touch.len() {
                low.can_touch[i] =
                    rigid_l || low.l.diag(i) > 0.0 || low.rigid.as_ref().is_some_and(|r| r[i]);
            }
        }
    }
}

/// One body's data moved by `delta` times its derivative.
fn move_body(
    d: &BodyDerivative,
    delta: f64,
    l: &mut FoundationMatrix,
    phi: &mut [f64],
    phi_fixed: &mut [(u32, f64)],
    h_vertices: &mut VertexValues,
) {
    assert!(
        d.stiffness.is_none() || (d.dl.is_some() && d.dh_vertices.is_some()),
        "derivative data prepared for the energy alone cannot move a model"
    );
    if let Some(dl) = &d.dl {
        match (l, dl) {
            (FoundationMatrix::Consistent(a), FoundationMatrix::Consistent(b)) => {
                for (x, y) in a.val.iter_mut().zip(&b.val) {
                    *x += delta * y;
                }
            }
            (FoundationMatrix::Lumped(a), FoundationMatrix::Lumped(b)) => {
                for (x, y) in a.iter_mut().zip(b) {
                    *x += delta * y;
                }
            }
            _ => {}
        }
    }
    if let Some(dh) = &d.dh_vertices {
        let mut h = h_vertices.to_vec();
        for (x, y) in h.iter_mut().zip(dh) {
            if x.is_finite() {
                *x += delta * y;
            }
        }
        *h_vertices = VertexValues::from_values(h);
    }
    if let (Some(dphi), Some(dv)) = (&d.dphi, &d.dphi_vertices) {
        for (x, y) in phi.iter_mut().zip(dphi) {
            *x += delta * y;
        }
        for (v, x) in phi_fixed.iter_mut() {
            *x += delta * dv[*v as usize];
        }
    }
}
