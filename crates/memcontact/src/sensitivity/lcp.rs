//! One-sided derivatives at biactive vertices (docs/theory.md#biactive; Mignot 1976,
//! and for the Winkler term Christof, Clason, Meyer & Walther 2018). Where a vertex lies on
//! a body's surface with its contact force at an end of its range, the solution map is
//! only directionally differentiable: the derivative δU in a direction δp solves the
//! tangent system with, at each biactive vertex, a complementarity condition instead of an
//! equation. Such a vertex may follow the surface (held, `δUᵢ = δφᵢ`, its force change
//! keeping the right sign), leave it (clear, the gap opening) or, for an elastic body whose
//! force is at the top of its range, sink in (its foundation acting). That small linear
//! complementarity problem on the biactive set B is solved by a primal-dual active-set
//! iteration on the pieces of B (each step one tangent solve on the piece, then the pieces
//! whose sign condition fails switch); K is positive definite and the problem is convex, so
//! the iteration ends, in a few steps, with the directional derivative.

use super::linear::{Jacobian, SolveRecord};
use super::outputs::At;
use super::parameters::DataDerivative;
use super::states::{Piece, Side, States};
use crate::error::{Error, Result};
use crate::solve::multigrid::Levels;

/// The directional derivative `δU` of the solution in the direction `sign · δp` of the
/// parameter `d` (`dr` its `∂r/∂p`; iterative solves to the relative residual
/// `tolerance`), with the solves it took.
pub fn directional(
    at: &At,
    states: &States,
    levels: Option<&Levels>,
    tolerance: f64,
    d: &DataDerivative,
    dr: &[f64],
    sign: f64,
) -> Result<(Vec<f64>, Vec<SolveRecord>)> {
    let model = at.model;
    let n = model.n();
    let nb = states.biactive.len();
    let mut pieces = vec![Piece::Held; nb];
    let mut seen: Vec<Vec<Piece>> = Vec::new();
    let mut records = Vec::new();
    let label = format!(
        "tangent{}:{}",
        if sign > 0.0 { "+" } else { "-" },
        d.key.key
    );
    let max_steps = 4 * nb + 10;
    for _ in 0..max_steps {
        let ps = states.piece(&pieces);
        let mut jac = Jacobian::new(model, &ps, levels, tolerance)?;
        let dres = at.residual_derivative(&ps, d, dr);
        let b: Vec<f64> = at.prescribed(&ps, d).iter().map(|x| sign * x).collect();
        let sb = model.s.mul(&b);
        let rhs: Vec<f64> = (0..n)
            .map(|i| {
                if ps.held[i].is_some() {
                    0.0
                } else {
                    -sign * dres[i] - sb[i]
                }
            })
            .collect();
        let (x, rec) = jac.solve(&rhs, &label)?;
        records.push(rec);
        let du: Vec<f64> = (0..n).map(|i| x[i] + b[i]).collect();
        // The sign conditions of the biactive vertices at this piece.
        let mut dr_total = model.s.mul(&du);
        for i in 0..n {
            dr_total[i] += sign * dr[i];
        }
        let scale_u = crate::sparse::norm_inf(&du).max(crate::sparse::norm_inf(&b));
        let scale_f = crate::sparse::norm_inf(&dr_total)
            .max(crate::sparse::norm_inf(&sb))
            .max(f64::MIN_POSITIVE);
        let tol_u = 1e-9 * scale_u.max(f64::MIN_POSITIVE);
        let tol_f = 1e-9 * scale_f;
        let dphi_up = |i: usize| sign * d.up.dphi.as_ref().map_or(0.0, |x| x[i]);
        let dphi_low = |i: usize| sign * d.low.dphi.as_ref().map_or(0.0, |x| x[i]);
        // ŵ on the penetrating vertices of the piece, and the base p̂, q̂ of dL p̂.
        let w_up: Vec<f64> = (0..n)
            .map(|i| {
                if ps.pen_up[i] && ps.held[i].is_none() {
                    du[i] - dphi_up(i)
                } else {
                    0.0
                }
            })
            .collect();
        let p_hat = states.p_hat(model, at.u);
        let (w_low, q_hat) = match &model.lower {
            Some(_) => (
                (0..n)
                    .map(|i| {
                        if ps.pen_low[i] && ps.held[i].is_none() {
                            dphi_low(i) - du[i]
                        } else {
                            0.0
                        }
                    })
                    .collect::<Vec<f64>>(),
                states.q_hat(model, at.u),
            ),
            None => (Vec::new(), Vec::new()),
        };
        let mut next = pieces.clone();
        for (k, bv) in states.biactive.iter().enumerate() {
            let i = bv.i;
            next[k] = match (bv.side, pieces[k]) {
                (Side::Upper, Piece::Held) => {
                    let da = -dr_total[i];
                    let dlp = model.l.row_dot(i, &w_up)
                        + sign * d.up.dl.as_ref().map_or(0.0, |l| l.row_dot(i, &p_hat));
                    let db = dr_total[i] + dlp;
                    if bv.may_leave && da < -tol_f {
                        Piece::Clear
                    } else if bv.may_sink && db < -tol_f {
                        Piece::Sunk
                    } else {
                        Piece::Held
                    }
                }
                (Side::Upper, Piece::Clear) if du[i] - dphi_up(i) > tol_u => Piece::Held,
                (Side::Upper, Piece::Sunk) if du[i] - dphi_up(i) < -tol_u => Piece::Held,
                (Side::Lower, Piece::Held) => {
                    let low = model.lower.as_ref().expect("a body below");
                    let da = dr_total[i];
                    let dlq = low.l.row_dot(i, &w_low)
                        + sign * d.low.dl.as_ref().map_or(0.0, |l| l.row_dot(i, &q_hat));
                    let db = dlq - dr_total[i];
                    if bv.may_leave && da < -tol_f {
                        Piece::Clear
                    } else if bv.may_sink && db < -tol_f {
                        Piece::Sunk
                    } else {
                        Piece::Held
                    }
                }
                (Side::Lower, Piece::Clear) if du[i] - dphi_low(i) < -tol_u => Piece::Held,
                (Side::Lower, Piece::Sunk) if du[i] - dphi_low(i) > tol_u => Piece::Held,
                (_, p) => p,
            };
        }
        if next == pieces {
            return Ok((du, records));
        }
        seen.push(pieces.clone());
        if seen.contains(&next) {
            // A cycle: change one piece at a time.
            let k = (0..nb).find(|&k| next[k] != pieces[k]).expect("a change");
            pieces[k] = next[k];
        } else {
            pieces = next;
        }
    }
    Err(Error::Solver {
        solver: "sensitivity".into(),
        message: format!(
            "the one-sided derivative in {} ({}) did not settle the pieces of its {nb} \
             biactive vertices in {max_steps} steps",
            d.key.key,
            if sign > 0.0 { "+" } else { "-" }
        ),
    })
}
