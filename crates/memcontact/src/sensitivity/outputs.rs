//! The quantities of interest Q, with their derivatives in U (`∂Q/∂U`, for the tangent and
//! adjoint solves) and their explicit derivatives in a parameter (`∂Q/∂p` at fixed U)
//! (docs/theory.md#adjoint).
//!
//! * `energy`: J(U), differentiated by the envelope theorem (no solve, below).
//! * `sensor:NAME`: u at a point, by P1 interpolation (its triangle's barycentric weights;
//!   a corner on the fixed boundary reads the height g there).
//! * `max_deflection`: |u| at the vertex of the largest |u| (the vertex held fixed).
//! * `total_contact_force`: Σ X₁ = −Σ rᵢ over the vertices the obstacle can touch (rᵢ = 0
//!   where the membrane is clear, so the sum is the obstacle's force, linear in U);
//!   `total_contact_force_low` the body below's, Σ rᵢ.
//! * `contact_force:REGION`: Σ ωᵢ X₁ᵢ with ωᵢ the share of vertex i's patch area in the
//!   region (the shares of all regions add up to the total).
//! * `contact_area`: the measure of `{u_h > φ_h}` over the triangles the elastic obstacle
//!   covers, with `u_h − φ_h` linear in each triangle (the P1 level set); differentiable
//!   where the level set crosses triangles transversally. (The area in `summary.json` is
//!   the nodal area of the vertices in contact, a step function of U.)

use super::parameters::{BodyDerivative, DataDerivative};
use super::states::{PieceStates, Side, States};
use crate::case::Sensor;
use crate::discretization::BoundData;
use crate::error::{Error, Result};
use crate::field::nodal::NodalP1;
use crate::mesh::Mesh;
use crate::model::{Foundation, FoundationMatrix, Model};

/// What an output is, resolved against the mesh.
#[derive(Debug, Clone)]
pub enum OutputKind {
    /// J(U).
    Energy,
    /// |u| at the vertex of the largest |u|.
    MaxDeflection,
    /// The obstacle's total contact force.
    TotalForce,
    /// The body below's.
    TotalForceLow,
    /// The P1 level-set area of `{u_h > φ_h}` on the triangles flagged.
    ContactArea(Vec<bool>),
    /// u at a point: its triangle's corners and barycentric weights.
    Sensor([u32; 3], [f64; 3]),
    /// A region's share ωᵢ of the contact forces, per unknown.
    RegionForce(Vec<f64>),
}

/// An output: its name in `sensitivity.csv` and what it is.
#[derive(Debug, Clone)]
pub struct OutputSpec {
    /// `energy`, `sensor:NAME`, `contact_force:REGION`, ...
    pub name: String,
    /// What it is.
    pub kind: OutputKind,
}

/// Where a point is in a mesh: its triangle's vertices and its barycentric weights there
/// (`None` outside the mesh).
pub type Location = Option<([u32; 3], [f64; 3])>;

/// The locations of `points` in `mesh`: each point's triangle and barycentric weights, or
/// `None` outside the mesh.
pub fn locate(mesh: &Mesh, points: &[[f64; 2]]) -> Result<Vec<Location>> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let zero: std::sync::Arc<[f64]> = vec![0.0; mesh.n_vertices()].into();
    let locator = NodalP1::new("sensors", mesh, zero)?;
    Ok(points
        .iter()
        .map(|&p| locator.locate(p).map(|(k, l)| (mesh.triangles[k], l)))
        .collect())
}

/// The sensors `keyed` (each with the key that names it in errors) located on `mesh` with
/// one point locator; the first outside the mesh is an error naming it.
pub fn sensor_outputs(mesh: &Mesh, keyed: &[(String, &Sensor)]) -> Result<Vec<OutputSpec>> {
    let points: Vec<[f64; 2]> = keyed.iter().map(|(_, s)| s.at).collect();
    let found = locate(mesh, &points)?;
    keyed
        .iter()
        .zip(found)
        .map(|((key, s), f)| match f {
            Some((t, w)) => Ok(OutputSpec {
                name: format!("sensor:{}", s.name),
                kind: OutputKind::Sensor(t, w),
            }),
            None => Err(Error::Case {
                file: None,
                line: None,
                key: key.clone(),
                message: format!(
                    "sensor \"{}\" at ({}, {}) is outside the mesh",
                    s.name, s.at[0], s.at[1]
                ),
            }),
        })
        .collect()
}

/// The outputs named in `names` (`sensors` expands to every sensor), resolved on `mesh`.
pub fn resolve(
    names: &[String],
    sensors: &[Sensor],
    mesh: &Mesh,
    model: &Model,
    bound: &BoundData,
) -> Result<Vec<OutputSpec>> {
    let case_error = |message: String| Error::Case {
        file: None,
        line: None,
        key: "sensitivity.outputs".into(),
        message,
    };
    // The sensors asked for, located together (one point locator).
    let mut wanted: Vec<usize> = Vec::new();
    for name in names {
        if name == "sensors" {
            wanted.extend(0..sensors.len());
        } else if let Some(s) = name.strip_prefix("sensor:") {
            let i = sensors
                .iter()
                .position(|x| x.name == s)
                .ok_or_else(|| case_error(format!("no [[sensor]] is named \"{s}\"")))?;
            wanted.push(i);
        }
    }
    let keyed: Vec<(String, &Sensor)> = wanted
        .iter()
        .map(|&i| (format!("sensor.{i}"), &sensors[i]))
        .collect();
    let located = sensor_outputs(mesh, &keyed)?;
    let sensor = |i: usize| -> OutputSpec {
        let k = wanted.iter().position(|&w| w == i).expect("located");
        located[k].clone()
    };
    let mut out: Vec<OutputSpec> = Vec::new();
    for name in names {
        if name == "sensors" {
            for i in 0..sensors.len() {
                let o = sensor(i);
                if !out.iter().any(|x| x.name == o.name) {
                    out.push(o);
                }
            }
            continue;
        }
        if let Some(s) = name.strip_prefix("sensor:") {
            let i = sensors
                .iter()
                .position(|x| x.name == s)
                .expect("found above");
            let o = sensor(i);
            if !out.iter().any(|x| x.name == o.name) {
                out.push(o);
            }
            continue;
        }
        let kind = if let Some(region) = name.strip_prefix("contact_force:") {
            OutputKind::RegionForce(region_weights(mesh, model, region).map_err(case_error)?)
        } else {
            match name.as_str() {
                "energy" => OutputKind::Energy,
                "max_deflection" => OutputKind::MaxDeflection,
                "total_contact_force" => OutputKind::TotalForce,
                "total_contact_force_low" => OutputKind::TotalForceLow,
                "contact_area" => OutputKind::ContactArea(covered_triangles(mesh, bound)),
                _ => return Err(case_error(format!("unknown output \"{name}\""))),
            }
        };
        out.push(OutputSpec {
            name: name.clone(),
            kind,
        });
    }
    Ok(out)
}

/// The triangles the elastic obstacle covers: h > 0 at the centroid, not rigid.
fn covered_triangles(mesh: &Mesh, bound: &BoundData) -> Vec<bool> {
    (0..mesh.n_triangles())
        .map(|k| {
            let region = mesh.regions[k];
            if bound.rigid_regions.contains(&region) {
                return false;
            }
            let Some(h) = &bound.stiffness else {
                return false;
            };
            let c = mesh.corners(k);
            let m = [
                (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                (c[0][1] + c[1][1] + c[2][1]) / 3.0,
            ];
            h.eval(m, region) > 0.0
        })
        .collect()
}

/// The share ωᵢ of each unknown's patch area in the region named `region` (a name or a
/// tag of the mesh).
fn region_weights(
    mesh: &Mesh,
    model: &Model,
    region: &str,
) -> std::result::Result<Vec<f64>, String> {
    let present = mesh.region_tags();
    let mut tags: Vec<u32> = mesh
        .region_names
        .iter()
        .filter(|(t, n)| n.as_str() == region && present.contains(t))
        .map(|(&t, _)| t)
        .collect();
    if tags.is_empty() {
        if let Ok(t) = region.trim().parse::<u32>() {
            if present.contains(&t) {
                tags.push(t);
            }
        }
    }
    if tags.is_empty() {
        let names: Vec<String> = present.iter().map(|&t| mesh.region_name(t)).collect();
        return Err(format!(
            "\"contact_force:{region}\": no region \"{region}\" in the mesh (regions: {})",
            names.join(", ")
        ));
    }
    let nv = mesh.n_vertices();
    let (mut inside, mut all) = (vec![0.0; nv], vec![0.0; nv]);
    for (k, t) in mesh.triangles.iter().enumerate() {
        let a = mesh.area(k) / 3.0;
        let is_in = tags.contains(&mesh.regions[k]);
        for &v in t {
            all[v as usize] += a;
            if is_in {
                inside[v as usize] += a;
            }
        }
    }
    Ok(model
        .dofs
        .vertex
        .iter()
        .map(|&v| {
            let v = v as usize;
            if all[v] > 0.0 {
                inside[v] / all[v]
            } else {
                0.0
            }
        })
        .collect())
}

/// The solution an output is evaluated at.
pub struct At<'a> {
    /// The mesh (solver's numbering).
    pub mesh: &'a Mesh,
    /// The model.
    pub model: &'a Model,
    /// U over the unknowns.
    pub u: &'a [f64],
    /// The states.
    pub states: &'a States,
    /// J(U).
    pub energy: f64,
    /// The obstacle's and the body below's nodal contact forces (as the outputs report).
    pub forces: &'a crate::certificate::ContactForces,
}

impl At<'_> {
    /// u at vertex `v`: U there, or the fixed height g.
    fn u_at(&self, v: usize) -> f64 {
        match self.model.dofs.of(v) {
            Some(i) => self.u[i as usize],
            None => self.model.boundary_values.get(v).copied().unwrap_or(0.0),
        }
    }

    /// The vertex of the largest |u| (the first, in the solver's numbering, of equals) and
    /// the sign of u there.
    fn max_vertex(&self) -> (usize, f64) {
        let mut best = (0usize, -1.0f64);
        for v in 0..self.mesh.n_vertices() {
            let a = self.u_at(v).abs();
            if a > best.1 {
                best = (v, a);
            }
        }
        (best.0, self.u_at(best.0).signum())
    }

    /// The unknowns in the sum of a body's total force: those it can touch, not in contact
    /// with the other body.
    fn force_set(&self, side: Side) -> Vec<bool> {
        let m = self.model;
        (0..m.n())
            .map(|i| {
                let up = m.can_touch[i];
                let low = m.lower.as_ref().is_some_and(|b| b.can_touch[i]);
                let up_contact =
                    up && (self.u[i] >= m.phi[i] || self.states.held[i] == Some(Side::Upper));
                let low_contact = m.lower.as_ref().is_some_and(|b| {
                    b.can_touch[i]
                        && (self.u[i] <= b.phi[i] || self.states.held[i] == Some(Side::Lower))
                });
                match side {
                    Side::Upper => up && !low_contact,
                    Side::Lower => low && !up_contact,
                }
            })
            .collect()
    }

    /// The gap `e = u − φ` of the obstacle at every vertex.
    fn gaps(&self) -> Vec<f64> {
        let phi = self.model.phi_vertices();
        (0..self.mesh.n_vertices())
            .map(|v| self.u_at(v) - phi[v])
            .collect()
    }

    /// The value of output `o`.
    pub fn value(&self, o: &OutputSpec) -> f64 {
        match &o.kind {
            OutputKind::Energy => self.energy,
            OutputKind::MaxDeflection => self.max_vertex().1 * self.u_at(self.max_vertex().0),
            OutputKind::TotalForce => self.forces.up.iter().sum(),
            OutputKind::TotalForceLow => self.forces.low.iter().sum(),
            OutputKind::ContactArea(covered) => {
                let e = self.gaps();
                (0..self.mesh.n_triangles())
                    .filter(|&k| covered[k])
                    .map(|k| {
                        let t = self.mesh.triangles[k];
                        level_set_area(self.mesh.area(k), t.map(|v| e[v as usize])).0
                    })
                    .sum()
            }
            OutputKind::Sensor(t, w) => (0..3).map(|a| w[a] * self.u_at(t[a] as usize)).sum(),
            OutputKind::RegionForce(w) => self.forces.up.iter().zip(w).map(|(x, w)| x * w).sum(),
        }
    }

    /// `∂Q/∂U` over the unknowns (`None` for the energy, differentiated by the envelope
    /// theorem).
    pub fn gradient(&self, o: &OutputSpec) -> Option<Vec<f64>> {
        let n = self.model.n();
        let mut g = vec![0.0; n];
        let s = &self.model.s;
        let add_vertex = |g: &mut [f64], v: usize, w: f64| {
            if let Some(i) = self.model.dofs.of(v) {
                g[i as usize] += w;
            }
        };
        match &o.kind {
            OutputKind::Energy => return None,
            OutputKind::MaxDeflection => {
                let (v, sign) = self.max_vertex();
                add_vertex(&mut g, v, sign);
            }
            OutputKind::Sensor(t, w) => {
                for a in 0..3 {
                    add_vertex(&mut g, t[a] as usize, w[a]);
                }
            }
            OutputKind::TotalForce | OutputKind::TotalForceLow | OutputKind::RegionForce(_) => {
                // Q = c Σ ωᵢ rᵢ over the set: ∂Q/∂U = c Sᵀ (ω 1_set) = c S (ω 1_set).
                let (set, c, w) = self.force_weights(o);
                let x: Vec<f64> = (0..n)
                    .map(|i| if set[i] { c * w[i] } else { 0.0 })
                    .collect();
                g = s.mul(&x);
            }
            OutputKind::ContactArea(covered) => {
                let e = self.gaps();
                for k in (0..self.mesh.n_triangles()).filter(|&k| covered[k]) {
                    let t = self.mesh.triangles[k];
                    let (_, d) = level_set_area(self.mesh.area(k), t.map(|v| e[v as usize]));
                    for a in 0..3 {
                        add_vertex(&mut g, t[a] as usize, d[a]);
                    }
                }
            }
        }
        Some(g)
    }

    /// The set, sign and weights of a force output: `Q = c Σ_set ωᵢ rᵢ`.
    fn force_weights(&self, o: &OutputSpec) -> (Vec<bool>, f64, Vec<f64>) {
        let n = self.model.n();
        match &o.kind {
            OutputKind::TotalForce => (self.force_set(Side::Upper), -1.0, vec![1.0; n]),
            OutputKind::TotalForceLow => (self.force_set(Side::Lower), 1.0, vec![1.0; n]),
            OutputKind::RegionForce(w) => (self.force_set(Side::Upper), -1.0, w.clone()),
            _ => unreachable!("a force output"),
        }
    }

    /// `∂r/∂p` over the unknowns (`r = SU − D`, the lifting included):
    /// `ds (SU + lift) − dD_f + d(lift)` with `ds = 1/t` for the tension.
    pub fn dr(&self, d: &DataDerivative) -> Vec<f64> {
        let m = self.model;
        let n = m.n();
        let mut out = vec![0.0; n];
        if d.tension {
            let su = m.s.mul(self.u);
            let k = match d.key.kind {
                crate::case::ParameterKind::Factor => 1.0,
                _ => 1.0 / m.tension,
            };
            for i in 0..n {
                out[i] = k * (su[i] + m.lift.get(i).copied().unwrap_or(0.0));
            }
        }
        if let Some((dd, _)) = &d.dload {
            for i in 0..n {
                out[i] -= dd[i];
            }
        }
        if let Some((_, dlift, t0)) = &d.dheights {
            let k = m.tension / t0;
            for i in 0..n {
                out[i] += k * dlift[i];
            }
        }
        out
    }

    /// `∂Q/∂p` at fixed U (for the energy: `dJ/dp` itself, by the envelope theorem), with
    /// `dr = ∂r/∂p` ([`At::dr`]).
    pub fn partial(&self, o: &OutputSpec, d: &DataDerivative, dr: &[f64]) -> f64 {
        let dg = |v: usize| -> f64 {
            match (&d.dheights, self.model.dofs.of(v)) {
                (Some((g, _, _)), None) => g[v],
                _ => 0.0,
            }
        };
        match &o.kind {
            OutputKind::Energy => self.envelope(d, dr),
            OutputKind::MaxDeflection => {
                let (v, sign) = self.max_vertex();
                sign * dg(v)
            }
            OutputKind::Sensor(t, w) => (0..3).map(|a| w[a] * dg(t[a] as usize)).sum(),
            OutputKind::TotalForce | OutputKind::TotalForceLow | OutputKind::RegionForce(_) => {
                let (set, c, w) = self.force_weights(o);
                (0..self.model.n())
                    .filter(|&i| set[i])
                    .map(|i| c * w[i] * dr[i])
                    .sum()
            }
            OutputKind::ContactArea(covered) => {
                let e = self.gaps();
                let dphi = d.up.dphi_vertices.as_deref();
                let mut sum = 0.0;
                for k in (0..self.mesh.n_triangles()).filter(|&k| covered[k]) {
                    let t = self.mesh.triangles[k];
                    let (_, da) = level_set_area(self.mesh.area(k), t.map(|v| e[v as usize]));
                    for a in 0..3 {
                        let v = t[a] as usize;
                        let de = dg(v) - dphi.map_or(0.0, |x| x[v]);
                        sum += da[a] * de;
                    }
                }
                sum
            }
        }
    }

    /// dJ/dp by the envelope theorem: J is the minimum over V, so its derivative is the
    /// partial derivative at U,
    /// `½ ds UᵀSU + ds Uᵀlift − Uᵀ(dD_f − d lift) + ½ p̂ᵀ dL p̂ + ½ q̂ᵀ dL_low q̂`
    /// `− X₁ᵀdφ + X_lowᵀ dφ_low`
    /// (ds = 1/t for the tension; X the nodal contact forces, so that a vertex held on a
    /// surface contributes its force times the surface's motion). No solve
    /// (docs/theory.md#envelope).
    pub fn envelope(&self, d: &DataDerivative, dr: &[f64]) -> f64 {
        let m = self.model;
        let u = self.u;
        // ½ ds UᵀSU + ds Uᵀlift − Uᵀ(dD − dlift) = Uᵀ dr − ½ ds UᵀSU.
        let mut j = crate::sparse::dot(u, dr);
        if d.tension {
            let k = match d.key.kind {
                crate::case::ParameterKind::Factor => 1.0,
                _ => 1.0 / m.tension,
            };
            j -= 0.5 * k * m.s.quad_form(u);
        }
        if d.up.stiffness.is_some() {
            let p = self.states.p_hat(m, u);
            j += 0.5 * self.dl_form(&d.up, m.foundation, &p);
        }
        if let Some(dphi) = &d.up.dphi {
            j -= crate::sparse::dot(&self.forces.up, dphi);
        }
        if let (Some(_), Some(low)) = (&d.low.stiffness, &m.lower) {
            let q = self.states.q_hat(m, u);
            j += 0.5 * self.dl_form(&d.low, low.foundation, &q);
        }
        if let (Some(dphi), false) = (&d.low.dphi, self.forces.low.is_empty()) {
            j += crate::sparse::dot(&self.forces.low, dphi);
        }
        j
    }

    /// `xᵀ dL x` for a body's derivative `b` on a body with `foundation`: from the element
    /// matrices where it is consistent (dL need not be assembled), else from dL.
    fn dl_form(&self, b: &BodyDerivative, foundation: Foundation, x: &[f64]) -> f64 {
        match (&b.stiffness, foundation, &b.dl) {
            (Some((c, rigid)), Foundation::Consistent, _) => {
                crate::model::consistent_foundation_form(self.mesh, &self.model.dofs, c, rigid, x)
            }
            (_, _, Some(dl)) => quad(dl, x),
            _ => 0.0,
        }
    }

    /// `∂R/∂p` on the free unknowns of the piece `ps` (zero on the held ones), with
    /// `dr = ∂r/∂p`: `dr + E_P (dL p̂ − L E_P dφ) − E_Q (dL_low q̂ + L_low E_Q dφ_low)`.
    pub fn residual_derivative(
        &self,
        ps: &PieceStates,
        d: &DataDerivative,
        dr: &[f64],
    ) -> Vec<f64> {
        let m = self.model;
        let n = m.n();
        let mut out = dr.to_vec();
        let p = pen_values(ps, &ps.pen_up, |i| self.u[i] - m.phi[i]);
        if let Some(dl) = &d.up.dl {
            let y = super::states::restricted_mul(dl, &ps.pen_up, &p);
            for i in 0..n {
                out[i] += y[i];
            }
        }
        if let Some(dphi) = &d.up.dphi {
            let y = super::states::restricted_mul(&m.l, &ps.pen_up, dphi);
            for i in 0..n {
                out[i] -= y[i];
            }
        }
        if let Some(low) = &m.lower {
            let q = pen_values(ps, &ps.pen_low, |i| low.phi[i] - self.u[i]);
            if let Some(dl) = &d.low.dl {
                let y = super::states::restricted_mul(dl, &ps.pen_low, &q);
                for i in 0..n {
                    out[i] -= y[i];
                }
            }
            if let Some(dphi) = &d.low.dphi {
                let y = super::states::restricted_mul(&low.l, &ps.pen_low, dphi);
                for i in 0..n {
                    out[i] -= y[i];
                }
            }
        }
        for (o, h) in out.iter_mut().zip(&ps.held) {
            if h.is_some() {
                *o = 0.0;
            }
        }
        out
    }

    /// The values prescribed on the held unknowns of `ps`: `δUᵢ = dφᵢ` (or `dφ_low,ᵢ`),
    /// zero elsewhere.
    pub fn prescribed(&self, ps: &PieceStates, d: &DataDerivative) -> Vec<f64> {
        let n = self.model.n();
        (0..n)
            .map(|i| match ps.held[i] {
                Some(Side::Upper) => d.up.dphi.as_ref().map_or(0.0, |x| x[i]),
                Some(Side::Lower) => d.low.dphi.as_ref().map_or(0.0, |x| x[i]),
                None => 0.0,
            })
            .collect()
    }
}

/// The penetration of the flagged unknowns (0 on the others and on held ones).
fn pen_values(ps: &PieceStates, on: &[bool], f: impl Fn(usize) -> f64) -> Vec<f64> {
    (0..on.len())
        .map(|i| {
            if on[i] && ps.held[i].is_none() {
                f(i)
            } else {
                0.0
            }
        })
        .collect()
}

/// `xᵀ L x`.
fn quad(l: &FoundationMatrix, x: &[f64]) -> f64 {
    match l {
        FoundationMatrix::Consistent(a) => a.quad_form(x),
        FoundationMatrix::Lumped(d) => d.iter().zip(x).map(|(d, x)| d * x * x).sum(),
        FoundationMatrix::Rigid => 0.0,
    }
}

/// The area of `{e_h > 0}` in a triangle of area `area` with corner values `e` (e_h
/// linear), and its derivatives in the three values. A zero value counts as not positive
/// (the area is continuous there, and differentiable while the other two corners differ
/// in sign).
pub fn level_set_area(area: f64, e: [f64; 3]) -> (f64, [f64; 3]) {
    let pos: Vec<usize> = (0..3).filter(|&a| e[a] > 0.0).collect();
    match pos.len() {
        0 => (0.0, [0.0; 3]),
        3 => (area, [0.0; 3]),
        1 => corner(area, e, pos[0], 1.0),
        _ => {
            let neg = (0..3).find(|a| !pos.contains(a)).expect("one corner");
            let (a, d) = corner(area, e, neg, -1.0);
            (area - a, d)
        }
    }
}

/// The area of the corner region at corner `c` where e has the sign of e[c] (`sign` = 1
/// for a lone positive corner, −1 for a lone non-positive one): `|T| e_c² / ((e_c − e_a)(e_c
/// − e_b))`, and its derivatives times `sign` (the derivatives of the positive area).
fn corner(area: f64, e: [f64; 3], c: usize, sign: f64) -> (f64, [f64; 3]) {
    let (a, b) = ((c + 1) % 3, (c + 2) % 3);
    let (ec, ea, eb) = (e[c], e[a], e[b]);
    let (da, db) = (ec - ea, ec - eb);
    if da == 0.0 || db == 0.0 {
        // A lone corner equal to another: the corner region is empty.
        return (0.0, [0.0; 3]);
    }
    let value = area * ec * ec / (da * db);
    let mut d = [0.0; 3];
    d[c] = area * (2.0 * ec * da * db - ec * ec * (da + db)) / (da * da * db * db);
    d[a] = area * ec * ec / (da * da * db);
    d[b] = area * ec * ec / (da * db * db);
    (value, d.map(|x| sign * x))
}
