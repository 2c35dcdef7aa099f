//! The index sets of the certified solution (docs/theory.md#sensitivities): penetrating
//! (P: the body's foundation acts, its L enters the Jacobian), clear (C), held (strongly
//! active: on a body's surface with a contact force strictly inside its range, so the
//! vertex follows the surface, `δUᵢ = δφᵢ`, eliminated as Dirichlet data) and biactive (B:
//! on the surface with a force at an end of its range, to the certificate's accuracy; the
//! solution map is only directionally differentiable there).
//!
//! At a vertex on the obstacle's surface (`Uᵢ = φᵢ`) optimality says
//! `0 ≤ −rᵢ ≤ (Lp)ᵢ` (2f, `r = SU − D`; rigid: `0 ≤ −rᵢ`): the two margins are
//! `a = −rᵢ` (the force that keeps the vertex from leaving) and `b = rᵢ + (Lp)ᵢ` (from
//! sinking in). Both above the certificate's accuracy: held. The consistent L gives such
//! vertices a range `(Lp)ᵢ > 0` from their penetrating neighbours; the lumped one none, so
//! there a vertex exactly on φ is biactive. The body below is the mirror image
//! (`0 ≤ rᵢ ≤ (L_low q)ᵢ`).

use crate::certificate::Certificate;
use crate::model::{FoundationMatrix, Model};

/// Which body a vertex is held on or biactive at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The obstacle (above).
    Upper,
    /// The body below.
    Lower,
}

/// A biactive vertex: the body, and which way it may go at first order (leave the surface,
/// or sink into an elastic body).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biactive {
    /// The unknown.
    pub i: usize,
    /// The body.
    pub side: Side,
    /// It may leave the surface (its contact force is zero to accuracy).
    pub may_leave: bool,
    /// It may sink into the body (elastic, its force at the top of its range).
    pub may_sink: bool,
}

/// The piece of a biactive vertex in a directional derivative.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Piece {
    /// On the surface, following it.
    Held,
    /// Clear of the body.
    Clear,
    /// Sunk into the (elastic) body.
    Sunk,
}

/// The states of the unknowns at the certified solution.
#[derive(Debug, Clone)]
pub struct States {
    /// Penetrating the obstacle (elastic there), its foundation acting.
    pub pen_up: Vec<bool>,
    /// Penetrating the body below (elastic there).
    pub pen_low: Vec<bool>,
    /// Held on a body's surface.
    pub held: Vec<Option<Side>>,
    /// The biactive vertices.
    pub biactive: Vec<Biactive>,
    /// The force accuracy the margins were judged with.
    pub force_tolerance: f64,
    /// The unknowns' residual `r = SU − D`.
    pub r: Vec<f64>,
    /// `(Lp)ᵢ` of the obstacle over every unknown (`p = (U − φ)⁺` on M).
    pub lp: Vec<f64>,
    /// `(L_low q)ᵢ` of the body below (empty without one).
    pub lq: Vec<f64>,
}

/// How many times the certificate's force accuracy a margin must exceed to be strict.
const MARGIN_FACTOR: f64 = 10.0;

impl States {
    /// Classifies the unknowns at `u`, certified by `certificate` (its residual and rounding
    /// floor set the accuracy of forces, and through the Jacobian's diagonal that of gaps).
    pub fn classify(model: &Model, u: &[f64], certificate: &Certificate) -> States {
        let n = model.n();
        let r = model.residual(u);
        let p = model.penetration(u);
        let mut lp = vec![0.0; n];
        model.l.mul_into(&p, &mut lp);
        let lq = match &model.lower {
            Some(low) => {
                let q = low.penetration(u);
                let mut lq = vec![0.0; n];
                low.l.mul_into(&q, &mut lq);
                lq
            }
            None => Vec::new(),
        };
        let accuracy = certificate.kkt().max(certificate.rounding_floor).max(1e-15);
        let eps_f = MARGIN_FACTOR * accuracy * certificate.force_scale;
        let mut st = States {
            pen_up: vec![false; n],
            pen_low: vec![false; n],
            held: vec![None; n],
            biactive: Vec::new(),
            force_tolerance: eps_f,
            r,
            lp,
            lq,
        };
        for (i, &ui) in u.iter().enumerate().take(n) {
            let kii = model.s.get(i, i)
                + if model.can_touch[i] {
                    model.l.diag(i)
                } else {
                    0.0
                }
                + model
                    .lower
                    .as_ref()
                    .map_or(0.0, |b| if b.can_touch[i] { b.l.diag(i) } else { 0.0 });
            let eps_u = eps_f / kii.max(f64::MIN_POSITIVE);
            // The body below first: its force enters the obstacle's balance.
            let mut low_force = 0.0;
            if let Some(low) = model.lower.as_ref().filter(|b| b.can_touch[i]) {
                let gap = low.phi[i] - ui;
                let rigid = low.rigid_at(i);
                if gap.abs() <= eps_u || (rigid && gap >= 0.0) {
                    let a = st.r[i];
                    let b = if rigid {
                        f64::INFINITY
                    } else {
                        st.lq[i] - st.r[i]
                    };
                    st.touch(i, Side::Lower, a, b, eps_f, rigid);
                } else if gap > 0.0 && !rigid {
                    st.pen_low[i] = true;
                    low_force = st.lq[i];
                }
            }
            if model.can_touch[i] {
                let gap = ui - model.phi[i];
                let rigid = model.rigid_at(i);
                if gap.abs() <= eps_u || (rigid && gap >= 0.0) {
                    if st.held[i].is_some() || st.biactive.last().is_some_and(|b| b.i == i) {
                        // Squeezed between the two bodies: biactive whatever the forces.
                        st.held[i] = None;
                        if st.biactive.last().is_none_or(|b| b.i != i) {
                            st.biactive.push(Biactive {
                                i,
                                side: Side::Upper,
                                may_leave: true,
                                may_sink: false,
                            });
                        }
                        continue;
                    }
                    let a = -st.r[i] + low_force;
                    let b = if rigid {
                        f64::INFINITY
                    } else {
                        st.r[i] - low_force + st.lp[i]
                    };
                    st.touch(i, Side::Upper, a, b, eps_f, rigid);
                } else if gap > 0.0 && !rigid {
                    st.pen_up[i] = true;
                }
            }
        }
        st
    }

    /// A vertex on a body's surface with margins `a` (to leave) and `b` (to sink in).
    fn touch(&mut self, i: usize, side: Side, a: f64, b: f64, eps: f64, rigid: bool) {
        let may_leave = a <= eps;
        let may_sink = !rigid && b <= eps;
        if may_leave || may_sink {
            self.biactive.push(Biactive {
                i,
                side,
                may_leave,
                may_sink,
            });
        } else {
            self.held[i] = Some(side);
        }
    }

    /// The states with every biactive vertex on the piece `pieces[k]`: the held, obstacle-
    /// and lower-penetrating flags of a smooth piece of the solution map.
    pub fn piece(&self, pieces: &[Piece]) -> PieceStates {
        let mut ps = PieceStates {
            held: self.held.clone(),
            pen_up: self.pen_up.clone(),
            pen_low: self.pen_low.clone(),
        };
        for (b, &piece) in self.biactive.iter().zip(pieces) {
            match (piece, b.side) {
                (Piece::Held, s) => ps.held[b.i] = Some(s),
                (Piece::Clear, _) => {}
                (Piece::Sunk, Side::Upper) => ps.pen_up[b.i] = true,
                (Piece::Sunk, Side::Lower) => ps.pen_low[b.i] = true,
            }
        }
        ps
    }

    /// The penetration `p̂ = U − φ` on the penetrating vertices of the obstacle (0
    /// elsewhere): the p of the smooth piece.
    pub fn p_hat(&self, model: &Model, u: &[f64]) -> Vec<f64> {
        (0..model.n())
            .map(|i| {
                if self.pen_up[i] {
                    u[i] - model.phi[i]
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// `q̂ = φ_low − U` on the vertices penetrating the body below (empty without one).
    pub fn q_hat(&self, model: &Model, u: &[f64]) -> Vec<f64> {
        match &model.lower {
            Some(low) => (0..model.n())
                .map(|i| {
                    if self.pen_low[i] {
                        low.phi[i] - u[i]
                    } else {
                        0.0
                    }
                })
                .collect(),
            None => Vec::new(),
        }
    }
}

/// The states of one smooth piece: held vertices (Dirichlet), and the vertices whose
/// foundation acts in the Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub struct PieceStates {
    /// Held on a body's surface.
    pub held: Vec<Option<Side>>,
    /// Penetrating the obstacle.
    pub pen_up: Vec<bool>,
    /// Penetrating the body below.
    pub pen_low: Vec<bool>,
}

impl PieceStates {
    /// The truncated Newton states of this piece, for the Jacobian
    /// ([`crate::solve::newton::NewtonStates`]).
    pub fn newton(&self, model: &Model) -> crate::solve::newton::NewtonStates {
        let mut st = crate::solve::newton::NewtonStates::clear(model);
        for i in 0..model.n() {
            st.truncated[i] = self.held[i].is_some();
            st.penetrating[i] = self.pen_up[i] && self.held[i].is_none();
            if model.lower.is_some() {
                st.penetrating_low[i] = self.pen_low[i] && self.held[i].is_none();
                st.at_lower[i] = self.held[i] == Some(Side::Lower);
            }
        }
        st
    }
}

/// `y = L x` restricted to rows and columns flagged in `on`: `(L x)ᵢ` over `j ∈ on` for
/// `i ∈ on`, 0 elsewhere.
pub fn restricted_mul(l: &FoundationMatrix, on: &[bool], x: &[f64]) -> Vec<f64> {
    let n = on.len();
    let mut y = vec![0.0; n];
    match l {
        FoundationMatrix::Consistent(a) => {
            for i in (0..n).filter(|&i| on[i]) {
                let (cols, vals) = a.row(i);
                y[i] = cols
                    .iter()
                    .zip(vals)
                    .filter(|(&j, _)| on[j as usize])
                    .map(|(&j, &v)| v * x[j as usize])
                    .sum();
            }
        }
        FoundationMatrix::Lumped(d) => {
            for i in (0..n).filter(|&i| on[i]) {
                y[i] = d[i] * x[i];
            }
        }
        FoundationMatrix::Rigid => {}
    }
    y
}
