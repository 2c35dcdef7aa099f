//! Sensitivities through the contact (docs/theory.md#sensitivities): exact derivatives of
//! the discrete problem actually solved (same foundation, sampling, lifting), in case keys.
//!
//! Write the optimality system as `R(U, p) = 0` with
//! `R = SU − D + E_P L (U − φ)⁺ − E_Q L_low (φ_low − U)⁺` on the free unknowns (P, Q the
//! vertices penetrating the obstacle and the body below) and `Uᵢ = φᵢ` (or `φ_low,ᵢ`) on
//! the held ones. Off the biactive set the solution map p ↦ U is smooth and
//!
//! * **tangent**: `K δU = −∂ₚR − K_{F,H} δφ_H` on the free unknowns, `δU_H = δφ_H`, with the
//!   Jacobian `K = S + E_P L E_P + E_Q L_low E_Q`;
//! * **adjoint**: `K λ = (∂Q/∂U)_F`, then `dQ/dp = ∂ₚQ − λᵀ∂ₚR + (∂Q/∂U − Kλ)_Hᵀ δφ_H`: one
//!   solve per output gives its derivative in every parameter, and its influence map in
//!   the stiffness at every vertex;
//! * **energy**: no solve, by the envelope theorem.
//!
//! At biactive vertices both one-sided derivatives come from a small complementarity
//! problem on them (docs/theory.md#biactive). The parameters and the outputs are bound to
//! the model once ([`Prepared`]), so that a fit evaluates them at every iterate without
//! assembling again.

pub(crate) mod influence;
pub(crate) mod lcp;
pub(crate) mod linear;
pub(crate) mod outputs;
pub(crate) mod parameters;
pub(crate) mod states;
#[cfg(test)]
mod tests;

use crate::case::{ParameterKey, ParameterKind, Sensor};
use crate::certificate::Certificate;
use crate::discretization::BoundData;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::model::{FoundationMatrix, Model};
use crate::problem::Problem;
pub use linear::SolveRecord;
use outputs::{At, OutputKind, OutputSpec};
use parameters::DataDerivative;
use states::{Piece, States};
use std::time::Instant;

/// What to differentiate: output names, parameter keys, and whether to make the influence
/// maps (see [`crate::case::SensitivitySpec`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// Output names (`energy`, `sensors`, `sensor:NAME`, `contact_force:REGION`, ...).
    pub outputs: Vec<String>,
    /// Case keys.
    pub parameters: Vec<String>,
    /// The influence maps of the energy and of every sensor output.
    pub influence: bool,
}

impl Request {
    /// The request of a case's `[sensitivity]`.
    pub fn of(spec: &crate::case::SensitivitySpec) -> Request {
        Request {
            outputs: spec.outputs.clone(),
            parameters: spec.parameters.clone(),
            influence: spec.influence.unwrap_or(true),
        }
    }
}

/// How the derivatives were computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// One adjoint solve per output (besides the energy).
    Adjoint,
    /// One tangent solve per parameter.
    Tangent,
    /// Biactive vertices: both one-sided derivatives per parameter, by tangent solves on
    /// the pieces of the complementarity problem.
    OneSided,
}

impl Mode {
    /// The name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Adjoint => "adjoint",
            Mode::Tangent => "tangent",
            Mode::OneSided => "one_sided",
        }
    }
}

/// The derivatives of a run: every output in every parameter, in owned arrays (row-major,
/// outputs × parameters) with their names, ready for a table, a fit or NumPy.
#[derive(Debug, Clone)]
pub struct Sensitivities {
    /// Output names (`energy`, `sensor:NAME`, ...).
    pub outputs: Vec<String>,
    /// The outputs' values Q.
    pub values: Vec<f64>,
    /// The parameters (key, kind, value in the case).
    pub parameters: Vec<ParameterKey>,
    /// dQ/dp, row-major (`derivative[o * parameters.len() + p]`): the mean of the one-sided
    /// derivatives where they differ.
    pub derivative: Vec<f64>,
    /// The derivative in the direction +δp (equal to `derivative` where it is smooth).
    pub derivative_plus: Vec<f64>,
    /// Minus the derivative in the direction −δp.
    pub derivative_minus: Vec<f64>,
    /// Where the one-sided derivatives differ (biactive vertices reach the output).
    pub nonsmooth: Vec<bool>,
    /// The biactive vertices, in the user's numbering.
    pub biactive_vertices: Vec<u32>,
    /// Influence maps over the vertices (user's numbering): `dJ_dh`, `dsensor_NAME_dh`
    /// (and `_low` for the body below).
    pub influence: Vec<(String, Vec<f64>)>,
    /// Every linear solve, with its residual.
    pub solves: Vec<SolveRecord>,
    /// How the derivatives were computed.
    pub mode: Mode,
    /// The force accuracy the index sets were judged with.
    pub force_tolerance: f64,
    /// Wall-clock seconds of the whole analysis.
    pub seconds: f64,
    /// The tangents δU = dU/dp over the unknowns (solver's numbering), one per parameter,
    /// when [`Prepared::keep_tangents`] asked for them and they were computed (tangent
    /// mode; one-sided: the mean of the two); empty otherwise. A fit predicts the next
    /// iterate's solution with them.
    pub(crate) tangents: Vec<Vec<f64>>,
}

impl Sensitivities {
    /// dQ/dp for output `o` and parameter `p`.
    pub fn get(&self, o: usize, p: usize) -> f64 {
        self.derivative[o * self.parameters.len() + p]
    }

    /// The elasticity `(p/Q) dQ/dp` (NaN for an offset, p = 0 or Q = 0): p is the value
    /// of a number, 1 for a factor.
    pub fn elasticity(&self, o: usize, p: usize) -> f64 {
        let key = &self.parameters[p];
        let pv = match key.kind {
            ParameterKind::Value => key.value,
            ParameterKind::Factor => 1.0,
            ParameterKind::Offset => return f64::NAN,
        };
        let q = self.values[o];
        if pv == 0.0 || q == 0.0 {
            f64::NAN
        } else {
            pv / q * self.get(o, p)
        }
    }

    /// The number of biactive vertices.
    pub fn biactive(&self) -> usize {
        self.biactive_vertices.len()
    }
}

/// Parameters and outputs bound to a model: the derivative data of every parameter and
/// the outputs located on the mesh (built once; evaluated at any solution of the same
/// mesh).
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The parameters' derivative data.
    pub(crate) parameters: Vec<DataDerivative>,
    /// The outputs.
    pub(crate) outputs: Vec<OutputSpec>,
    /// The influence maps wanted.
    pub(crate) influence: bool,
    /// Keep the tangents δU in [`Sensitivities::tangents`] (and compute them by tangent
    /// solves even where adjoint solves would be fewer).
    pub(crate) keep_tangents: bool,
    /// The relative residual the iterative linear solves are driven to (default
    /// [`linear::ITERATIVE_TOLERANCE`]; factorised solves are exact to rounding).
    pub(crate) linear_tolerance: f64,
    /// The rigid regions of the obstacle and of the body below (masked in the maps).
    rigid: (Vec<u32>, Vec<u32>),
    /// The sensors' names by output.
    sensor_names: Vec<Option<String>>,
    /// The multigrid levels of the linear solves, built on first use and kept for the
    /// next solutions of the same mesh (a fit's iterates): `None` inside when the systems
    /// are factorised.
    levels: std::sync::OnceLock<Option<std::sync::Arc<crate::solve::multigrid::Levels>>>,
}

impl Prepared {
    /// Binds `request` to the discretised `problem` (the mesh in the solver's numbering).
    pub fn new(
        problem: &Problem,
        sensors: &[Sensor],
        request: &Request,
        mesh: &Mesh,
        model: &Model,
    ) -> Result<Prepared> {
        let bound = BoundData::new(problem, mesh)?;
        let mut parameters = Vec::with_capacity(request.parameters.len());
        // The energy alone (envelope derivatives; its influence map reads p̂ alone) needs no
        // assembled dL.
        let for_solves = request.outputs.iter().any(|o| o != "energy");
        let asm = crate::model::DerivativeAssembly::new(mesh, &model.dofs, &model.s.pattern);
        for key in &request.parameters {
            let k = ParameterKey::parse(problem, key).map_err(|m| crate::error::Error::Case {
                file: None,
                line: None,
                key: "sensitivity.parameters".into(),
                message: m,
            })?;
            parameters.push(DataDerivative::new(problem, &k, &asm, model, for_solves)?);
        }
        let outputs = outputs::resolve(&request.outputs, sensors, mesh, model, &bound)?;
        let sensor_names = outputs
            .iter()
            .map(|o| o.name.strip_prefix("sensor:").map(str::to_string))
            .collect();
        Ok(Prepared {
            parameters,
            outputs,
            influence: request.influence,
            rigid: (
                bound.rigid_regions.clone(),
                bound
                    .lower
                    .as_ref()
                    .map(|l| l.rigid_regions.clone())
                    .unwrap_or_default(),
            ),
            sensor_names,
            keep_tangents: false,
            linear_tolerance: linear::ITERATIVE_TOLERANCE,
            levels: std::sync::OnceLock::new(),
        })
    }

    /// The multigrid levels of the linear solves, built now when they are not yet (for
    /// `model` on its mesh `hierarchy`); `None` when the systems are factorised.
    pub(crate) fn shared_levels(
        &self,
        model: &Model,
        hierarchy: Option<&crate::mesh::refine::Hierarchy>,
    ) -> Result<Option<std::sync::Arc<crate::solve::multigrid::Levels>>> {
        self.levels(model, hierarchy)?;
        Ok(self.levels.get().cloned().flatten())
    }

    /// The multigrid levels for `model` (built on the first call, see [`Prepared`]).
    fn levels(
        &self,
        model: &Model,
        hierarchy: Option<&crate::mesh::refine::Hierarchy>,
    ) -> Result<Option<&crate::solve::multigrid::Levels>> {
        if self.levels.get().is_none() {
            let built = linear::levels_for(model, hierarchy)?.map(std::sync::Arc::new);
            let _ = self.levels.set(built);
        }
        Ok(self.levels.get().and_then(|l| l.as_deref()))
    }

    /// The outputs' values alone at the solution `u` of `model` on `mesh`.
    pub fn values(
        &self,
        mesh: &Mesh,
        model: &Model,
        u: &[f64],
        certificate: &Certificate,
        energy: f64,
    ) -> Vec<f64> {
        let states = States::classify(model, u, certificate);
        let forces = crate::certificate::contact_forces(model, u);
        let at = At {
            mesh,
            model,
            u,
            states: &states,
            energy,
            forces: &forces,
        };
        self.outputs.iter().map(|o| at.value(o)).collect()
    }

    /// The derivatives at the solution `u` of `model` on `mesh` (certified by
    /// `certificate`, energy `energy`); `hierarchy`: the mesh levels for multigrid.
    pub fn evaluate(
        &self,
        mesh: &Mesh,
        model: &Model,
        hierarchy: Option<&crate::mesh::refine::Hierarchy>,
        u: &[f64],
        certificate: &Certificate,
        energy: f64,
    ) -> Result<Sensitivities> {
        let t0 = Instant::now();
        let n = model.n();
        let states = States::classify(model, u, certificate);
        let forces = crate::certificate::contact_forces(model, u);
        let at = At {
            mesh,
            model,
            u,
            states: &states,
            energy,
            forces: &forces,
        };
        let no = self.outputs.len();
        let np = self.parameters.len();
        let values: Vec<f64> = self.outputs.iter().map(|o| at.value(o)).collect();
        let drs: Vec<Vec<f64>> = self.parameters.iter().map(|d| at.dr(d)).collect();
        let mut plus = vec![0.0; no * np];
        let mut minus = vec![0.0; no * np];
        let mut solves = Vec::new();
        // The energy: the envelope theorem, no solve.
        for (o, out) in self.outputs.iter().enumerate() {
            if matches!(out.kind, OutputKind::Energy) {
                for (p, d) in self.parameters.iter().enumerate() {
                    let v = at.partial(out, d, &drs[p]);
                    plus[o * np + p] = v;
                    minus[o * np + p] = v;
                }
            }
        }
        let others: Vec<usize> = (0..no)
            .filter(|&o| !matches!(self.outputs[o].kind, OutputKind::Energy))
            .collect();
        let sensors_for_maps: Vec<usize> = if self.influence {
            others
                .iter()
                .copied()
                .filter(|&o| self.sensor_names[o].is_some())
                .collect()
        } else {
            Vec::new()
        };
        let levels = if others.is_empty() || np == 0 {
            None
        } else {
            self.levels(model, hierarchy)?
        };
        let base = states.piece(&vec![Piece::Held; states.biactive.len()]);
        let gradients: Vec<Option<Vec<f64>>> = self
            .outputs
            .iter()
            .map(|o| {
                if matches!(o.kind, OutputKind::Energy) {
                    None
                } else {
                    at.gradient(o)
                }
            })
            .collect();
        let mut adjoints: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut tangents: Vec<Vec<f64>> = Vec::new();
        let mode = if !states.biactive.is_empty() {
            Mode::OneSided
        } else if others.len() <= np && !self.keep_tangents {
            Mode::Adjoint
        } else {
            Mode::Tangent
        };
        if !others.is_empty() && np > 0 {
            let dres: Vec<Vec<f64>> = self
                .parameters
                .iter()
                .zip(&drs)
                .map(|(d, dr)| at.residual_derivative(&base, d, dr))
                .collect();
            let prescribed: Vec<Vec<f64>> = self
                .parameters
                .iter()
                .map(|d| at.prescribed(&base, d))
                .collect();
            match mode {
                Mode::Adjoint | Mode::Tangent => {
                    let mut jac =
                        linear::Jacobian::new(model, &base, levels, self.linear_tolerance)?;
                    if mode == Mode::Adjoint {
                        for &o in &others {
                            let (lambda, rec) = adjoint(
                                &mut jac,
                                model,
                                gradients[o].as_ref().expect("a gradient"),
                                &self.outputs[o].name,
                            )?;
                            solves.push(rec);
                            let g = gradients[o].as_ref().expect("a gradient");
                            let s_lambda = model.s.mul(&lambda);
                            for p in 0..np {
                                let d = &self.parameters[p];
                                let mut v = at.partial(&self.outputs[o], d, &drs[p])
                                    - crate::sparse::dot(&lambda, &dres[p]);
                                for i in 0..n {
                                    if base.held[i].is_some() {
                                        v += (g[i] - s_lambda[i]) * prescribed[p][i];
                                    }
                                }
                                plus[o * np + p] = v;
                                minus[o * np + p] = v;
                            }
                            adjoints.push((o, lambda));
                        }
                    } else {
                        for p in 0..np {
                            let b = &prescribed[p];
                            let sb = model.s.mul(b);
                            let rhs: Vec<f64> = (0..n)
                                .map(|i| {
                                    if base.held[i].is_some() {
                                        0.0
                                    } else {
                                        -dres[p][i] - sb[i]
                                    }
                                })
                                .collect();
                            let label = format!("tangent:{}", self.parameters[p].key.key);
                            let (x, rec) = jac.solve(&rhs, &label)?;
                            solves.push(rec);
                            let du: Vec<f64> = (0..n).map(|i| x[i] + b[i]).collect();
                            for &o in &others {
                                let g = gradients[o].as_ref().expect("a gradient");
                                let v = at.partial(&self.outputs[o], &self.parameters[p], &drs[p])
                                    + crate::sparse::dot(g, &du);
                                plus[o * np + p] = v;
                                minus[o * np + p] = v;
                            }
                            if self.keep_tangents {
                                tangents.push(du);
                            }
                        }
                        for &o in &sensors_for_maps {
                            let (lambda, rec) = adjoint(
                                &mut jac,
                                model,
                                gradients[o].as_ref().expect("a gradient"),
                                &self.outputs[o].name,
                            )?;
                            solves.push(rec);
                            adjoints.push((o, lambda));
                        }
                    }
                }
                Mode::OneSided => {
                    for p in 0..np {
                        let d = &self.parameters[p];
                        let mut mean = vec![0.0; if self.keep_tangents { n } else { 0 }];
                        for (sign, target) in [(1.0, &mut plus), (-1.0, &mut minus)] {
                            let (du, recs) = lcp::directional(
                                &at,
                                &states,
                                levels,
                                self.linear_tolerance,
                                d,
                                &drs[p],
                                sign,
                            )?;
                            solves.extend(recs);
                            for (m, v) in mean.iter_mut().zip(&du) {
                                // δU toward −δp is minus the derivative's left side.
                                *m += 0.5 * sign * v;
                            }
                            for &o in &others {
                                let g = gradients[o].as_ref().expect("a gradient");
                                let v = sign * at.partial(&self.outputs[o], d, &drs[p])
                                    + crate::sparse::dot(g, &du);
                                // derivative_minus is minus the derivative toward −δp.
                                target[o * np + p] = sign * v;
                            }
                        }
                        if self.keep_tangents {
                            tangents.push(mean);
                        }
                    }
                    if !sensors_for_maps.is_empty() {
                        let mut jac =
                            linear::Jacobian::new(model, &base, levels, self.linear_tolerance)?;
                        for &o in &sensors_for_maps {
                            let (lambda, rec) = adjoint(
                                &mut jac,
                                model,
                                gradients[o].as_ref().expect("a gradient"),
                                &self.outputs[o].name,
                            )?;
                            solves.push(rec);
                            adjoints.push((o, lambda));
                        }
                    }
                }
            }
        }
        let derivative: Vec<f64> = plus
            .iter()
            .zip(&minus)
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let nonsmooth: Vec<bool> = plus
            .iter()
            .zip(&minus)
            .map(|(a, b)| (a - b).abs() > 1e-9 * a.abs().max(b.abs()).max(f64::MIN_POSITIVE))
            .collect();
        let influence = if self.influence {
            self.maps(mesh, model, &at, &states, &adjoints)
        } else {
            Vec::new()
        };
        let biactive_vertices: Vec<u32> = {
            let user = |v: u32| {
                mesh.numbering
                    .as_ref()
                    .map_or(v, |r| r.vertices.old_of_new[v as usize])
            };
            states
                .biactive
                .iter()
                .map(|b| user(model.dofs.vertex[b.i]))
                .collect()
        };
        Ok(Sensitivities {
            outputs: self.outputs.iter().map(|o| o.name.clone()).collect(),
            values,
            parameters: self.parameters.iter().map(|d| d.key.clone()).collect(),
            derivative,
            derivative_plus: plus,
            derivative_minus: minus,
            nonsmooth,
            biactive_vertices,
            influence,
            solves,
            mode,
            force_tolerance: states.force_tolerance,
            seconds: t0.elapsed().as_secs_f64(),
            tangents,
        })
    }

    /// The influence maps (user's numbering): the energy's (envelope) and each sensor's
    /// (from its adjoint), for each body with an elastic part.
    fn maps(
        &self,
        mesh: &Mesh,
        model: &Model,
        at: &At,
        states: &States,
        adjoints: &[(usize, Vec<f64>)],
    ) -> Vec<(String, Vec<f64>)> {
        let mut out = Vec::new();
        let user = |x: Vec<f64>| mesh.vertex_values_to_user(&x);
        let p = states.p_hat(model, at.u);
        let q = states.q_hat(model, at.u);
        let upper = (!matches!(model.l, FoundationMatrix::Rigid)).then_some(model.foundation);
        let lower = model
            .lower
            .as_ref()
            .filter(|b| !b.l.is_rigid())
            .map(|b| b.foundation);
        let wants_energy = self
            .outputs
            .iter()
            .any(|o| matches!(o.kind, OutputKind::Energy));
        let mut body =
            |suffix: &str, f: crate::model::Foundation, rigid: &[u32], x: &[f64], up: bool| {
                if wants_energy {
                    out.push((
                        format!("dJ_dh{suffix}"),
                        user(influence::vertex_map(mesh, model, f, rigid, x, x, 0.5)),
                    ));
                }
                for (o, lambda) in adjoints {
                    let Some(name) = &self.sensor_names[*o] else {
                        continue;
                    };
                    let on = if up { &states.pen_up } else { &states.pen_low };
                    let l: Vec<f64> = (0..model.n())
                        .map(|i| if on[i] { lambda[i] } else { 0.0 })
                        .collect();
                    let scale = if up { -1.0 } else { 1.0 };
                    out.push((
                        format!("dsensor_{name}_dh{suffix}"),
                        user(influence::vertex_map(mesh, model, f, rigid, &l, x, scale)),
                    ));
                }
            };
        if let Some(f) = upper {
            body("", f, &self.rigid.0, &p, true);
        }
        if let Some(f) = lower {
            body("_low", f, &self.rigid.1, &q, false);
        }
        out
    }
}

/// The adjoint of an output: `K λ = g` on the free unknowns (g zero on the held ones).
fn adjoint(
    jac: &mut linear::Jacobian,
    model: &Model,
    g: &[f64],
    name: &str,
) -> Result<(Vec<f64>, SolveRecord)> {
    let held = jac.held().to_vec();
    let rhs: Vec<f64> = (0..model.n())
        .map(|i| if held[i] { 0.0 } else { g[i] })
        .collect();
    jac.solve(&rhs, &format!("adjoint:{name}"))
}
