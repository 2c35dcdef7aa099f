//! Bounded Levenberg-Marquardt on a small least-squares problem
//! `min ½ ‖r(x)‖² + ½ α ‖x − x₀‖²` over a box (docs/theory.md#back-analysis): the exact
//! Jacobian from the caller, a Marquardt-scaled damping updated by the gain ratio
//! (Nielsen's rule), steps limited to a trust radius in the variables (1 at the start: a
//! factor e on a logarithmic variable; doubled after a step the model predicted well,
//! quartered after a rejected one, so that a start far away is not paid for with many
//! rejected forward solves), projected onto the bounds with the variables held at a bound
//! (whose gradient pushes outward) left out of the step. The caller evaluates the model;
//! the optimiser never solves anything itself, so it is tested on plain functions.

use crate::error::Result;

/// The model a fit drives: residuals at x, and their Jacobian at the point last evaluated.
pub trait LeastSquares {
    /// The residuals `r(x)` (weighted: `(Q − m)/σ`). An `Err` ends the fit.
    fn residuals(&mut self, x: &[f64]) -> Result<Vec<f64>>;
    /// The Jacobian `∂r/∂x` at the `x` of the last [`LeastSquares::residuals`] call,
    /// row-major (residuals × variables).
    fn jacobian(&mut self) -> Result<Vec<f64>>;
}

/// The options of [`minimize`].
#[derive(Debug, Clone)]
pub struct Options {
    /// The most accepted iterations.
    pub max_iterations: usize,
    /// Stop when a step moves no variable by more than `tolerance (1 + |x|)`, or the
    /// projected gradient is below `tolerance (1 + cost)`.
    pub tolerance: f64,
    /// The prior's weight α (0: none).
    pub prior: f64,
    /// The initial trust radius: the largest change of a variable in one step (in the
    /// variable's units, ln p for a logarithmic parameter).
    pub radius: f64,
}

/// Why a fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// The last step was below the tolerance.
    Step,
    /// The projected gradient was below the tolerance.
    Gradient,
    /// The residuals vanish (to rounding).
    Residual,
    /// `max_iterations` reached first.
    MaxIterations,
    /// The damping grew without an acceptable step.
    Stalled,
}

impl Stop {
    /// Whether the stop means convergence.
    pub fn converged(self) -> bool {
        matches!(self, Stop::Step | Stop::Gradient | Stop::Residual)
    }

    /// The name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Stop::Step => "step",
            Stop::Gradient => "gradient",
            Stop::Residual => "residual",
            Stop::MaxIterations => "max_iterations",
            Stop::Stalled => "stalled",
        }
    }
}

/// One accepted (or the start) iterate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Iterate {
    /// 0 for the start.
    pub iteration: usize,
    /// The variables.
    pub x: Vec<f64>,
    /// The cost `½ ‖r‖² (+ prior)`.
    pub cost: f64,
    /// The largest change of a variable in the step that led here (0 for the start).
    pub step: f64,
    /// The damping μ of that step.
    pub damping: f64,
    /// Model evaluations so far (trial steps included).
    pub evaluations: usize,
}

/// What [`minimize`] produced.
#[derive(Debug, Clone)]
pub struct Minimum {
    /// The best point.
    pub x: Vec<f64>,
    /// Its residuals.
    pub r: Vec<f64>,
    /// The Jacobian there (row-major).
    pub jacobian: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// The accepted iterates, the start first.
    pub history: Vec<Iterate>,
    /// Why it stopped.
    pub stop: Stop,
}

/// Minimises `½ ‖r(x)‖² + ½ α ‖x − x₀‖²` over `lo ≤ x ≤ hi` from `x0` (see the module
/// doc). `on_iterate` sees each accepted iterate.
pub fn minimize(
    model: &mut dyn LeastSquares,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    options: &Options,
    on_iterate: &mut dyn FnMut(&Iterate),
) -> Result<Minimum> {
    let n = x0.len();
    let alpha = options.prior;
    let cost_of = |r: &[f64], x: &[f64]| {
        0.5 * r.iter().map(|v| v * v).sum::<f64>()
            + 0.5
                * alpha
                * x.iter()
                    .zip(x0)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
    };
    let mut x = x0.to_vec();
    let mut r = model.residuals(&x)?;
    let mut jac = model.jacobian()?;
    let m = r.len();
    let mut cost = cost_of(&r, &x);
    let mut evaluations = 1;
    let mut mu = -1.0;
    let mut nu = 2.0;
    let mut history = vec![Iterate {
        iteration: 0,
        x: x.clone(),
        cost,
        step: 0.0,
        damping: 0.0,
        evaluations,
    }];
    on_iterate(&history[0]);
    let scale0 = cost.max(f64::MIN_POSITIVE);
    let mut stop = Stop::MaxIterations;
    let mut iteration = 0;
    // Whether the model's last evaluation was at x (a rejected trial moves it away).
    let mut model_at_x = true;
    let mut radius = options.radius;
    'outer: while iteration < options.max_iterations {
        // g = Jᵀr + α(x − x₀), A = JᵀJ + αI.
        let mut g = vec![0.0; n];
        let mut a = vec![0.0; n * n];
        for i in 0..m {
            for j in 0..n {
                g[j] += jac[i * n + j] * r[i];
                for k in 0..n {
                    a[j * n + k] += jac[i * n + j] * jac[i * n + k];
                }
            }
        }
        for j in 0..n {
            g[j] += alpha * (x[j] - x0[j]);
            a[j * n + j] += alpha;
        }
        // Variables at a bound whose gradient pushes outward stay there.
        let free: Vec<bool> = (0..n)
            .map(|j| !((x[j] <= lo[j] && g[j] > 0.0) || (x[j] >= hi[j] && g[j] < 0.0)))
            .collect();
        let pg = (0..n)
            .filter(|&j| free[j])
            .map(|j| g[j].abs())
            .fold(0.0, f64::max);
        if cost <= 1e-28 * scale0.max(1.0) || r.iter().all(|&v| v.abs() <= 1e-15) {
            stop = Stop::Residual;
            break;
        }
        if pg <= options.tolerance * 1e-3 * (1.0 + cost) {
            stop = Stop::Gradient;
            break;
        }
        if radius <= 0.0 {
            radius = options.radius;
        }
        if mu < 0.0 {
            mu = 1e-3 * (0..n).map(|j| a[j * n + j]).fold(0.0, f64::max).max(1e-300);
        }
        loop {
            // (A + μ diag(A)) δ = −g on the free variables.
            let idx: Vec<usize> = (0..n).filter(|&j| free[j]).collect();
            let k = idx.len();
            if k == 0 {
                stop = Stop::Gradient;
                break 'outer;
            }
            let mut sys = vec![0.0; k * k];
            let mut rhs = vec![0.0; k];
            for (p, &j) in idx.iter().enumerate() {
                rhs[p] = -g[j];
                for (q, &l) in idx.iter().enumerate() {
                    sys[p * k + q] = a[j * n + l];
                }
                sys[p * k + p] += mu * a[j * n + j].max(1e-12 * mu.max(1.0));
            }
            let delta_free = match solve_spd(&sys, &rhs) {
                Some(d) => d,
                None => {
                    mu *= nu;
                    nu *= 2.0;
                    if mu > 1e20 {
                        stop = Stop::Stalled;
                        break 'outer;
                    }
                    continue;
                }
            };
            // Within the trust radius.
            let longest = delta_free.iter().map(|v| v.abs()).fold(0.0, f64::max);
            let shrink = if longest > radius {
                radius / longest
            } else {
                1.0
            };
            let mut trial = x.clone();
            for (p, &j) in idx.iter().enumerate() {
                trial[j] = (x[j] + shrink * delta_free[p]).clamp(lo[j], hi[j]);
            }
            let step: Vec<f64> = (0..n).map(|j| trial[j] - x[j]).collect();
            let step_max = step.iter().map(|v| v.abs()).fold(0.0, f64::max);
            if step_max == 0.0 {
                stop = Stop::Step;
                break 'outer;
            }
            // Predicted reduction of the quadratic model along the (projected) step.
            let mut predicted = 0.0;
            for j in 0..n {
                predicted -= g[j] * step[j];
                for l in 0..n {
                    predicted -= 0.5 * step[j] * a[j * n + l] * step[l];
                }
            }
            let r_trial = model.residuals(&trial)?;
            evaluations += 1;
            model_at_x = false;
            let cost_trial = cost_of(&r_trial, &trial);
            let rho = if predicted > 0.0 {
                (cost - cost_trial) / predicted
            } else {
                -1.0
            };
            if cost_trial < cost && rho > 1e-4 {
                x = trial;
                r = r_trial;
                cost = cost_trial;
                jac = model.jacobian()?;
                model_at_x = true;
                iteration += 1;
                mu *= (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if rho > 0.75 {
                    radius = radius.max(2.0 * step_max);
                }
                let it = Iterate {
                    iteration,
                    x: x.clone(),
                    cost,
                    step: step_max,
                    damping: mu,
                    evaluations,
                };
                on_iterate(&it);
                history.push(it);
                let small = (0..n).all(|j| step[j].abs() <= options.tolerance * (1.0 + x[j].abs()));
                if small {
                    stop = Stop::Step;
                    break 'outer;
                }
                continue 'outer;
            }
            // Rejected: more damping, a shorter step.
            mu *= nu;
            nu *= 2.0;
            radius = 0.25 * step_max;
            let size = 1.0 + x.iter().map(|v| v.abs()).fold(0.0, f64::max);
            if step_max <= options.tolerance * size {
                stop = Stop::Step;
                break 'outer;
            }
            if mu > 1e20 {
                stop = Stop::Stalled;
                break 'outer;
            }
        }
    }
    if !model_at_x {
        // The model's last evaluation was a rejected trial: back to the best point.
        r = model.residuals(&x)?;
        jac = model.jacobian()?;
    }
    Ok(Minimum {
        x,
        r,
        jacobian: jac,
        cost,
        history,
        stop,
    })
}

/// Solves the small symmetric positive definite system `a x = b` (row-major) by Cholesky;
/// `None` when it is not positive definite.
pub fn solve_spd(a: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * y[k];
        }
        y[i] = s / l[i * n + i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k * n + i] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
    Some(x)
}

/// The eigenvalues (descending) and eigenvectors (columns, row-major) of a small symmetric
/// matrix, by cyclic Jacobi rotations.
pub fn symmetric_eigen(a: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = a.to_vec();
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _ in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-32 * diag.max(f64::MIN_POSITIVE) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| a[j * n + j].total_cmp(&a[i * n + i]));
    let values = order.iter().map(|&i| a[i * n + i]).collect();
    let mut vectors = vec![0.0; n * n];
    for (c, &i) in order.iter().enumerate() {
        for k in 0..n {
            vectors[k * n + c] = v[k * n + i];
        }
    }
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's function as residuals `(10 (y − x²), 1 − x)`.
    struct Rosenbrock {
        at: Vec<f64>,
    }

    impl LeastSquares for Rosenbrock {
        fn residuals(&mut self, x: &[f64]) -> Result<Vec<f64>> {
            self.at = x.to_vec();
            Ok(vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]])
        }
        fn jacobian(&mut self) -> Result<Vec<f64>> {
            let x = &self.at;
            Ok(vec![-20.0 * x[0], 10.0, -1.0, 0.0])
        }
    }

    #[test]
    fn rosenbrock_reaches_its_minimum_and_bounds_hold() {
        let opts = Options {
            max_iterations: 100,
            tolerance: 1e-12,
            prior: 0.0,
            radius: 1.0,
        };
        let mut m = Rosenbrock { at: vec![] };
        let min = minimize(
            &mut m,
            &[-1.2, 1.0],
            &[-5.0, -5.0],
            &[5.0, 5.0],
            &opts,
            &mut |_| {},
        )
        .unwrap();
        assert!(min.stop.converged(), "{:?}", min.stop);
        assert!(
            (min.x[0] - 1.0).abs() < 1e-9 && (min.x[1] - 1.0).abs() < 1e-9,
            "{:?}",
            min.x
        );
        // With x ≤ 0.5 the minimum is on the bound.
        let min = minimize(
            &mut m,
            &[-1.2, 1.0],
            &[-5.0, -5.0],
            &[0.5, 5.0],
            &opts,
            &mut |_| {},
        )
        .unwrap();
        assert!(
            (min.x[0] - 0.5).abs() < 1e-12 && (min.x[1] - 0.25).abs() < 1e-8,
            "{:?}",
            min.x
        );
    }

    #[test]
    fn eigen_and_cholesky_of_small_matrices() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0];
        let (w, v) = symmetric_eigen(&a, 3);
        for c in 0..3 {
            for i in 0..3 {
                let av: f64 = (0..3).map(|k| a[i * 3 + k] * v[k * 3 + c]).sum();
                assert!((av - w[c] * v[i * 3 + c]).abs() < 1e-12);
            }
        }
        assert!(w[0] >= w[1] && w[1] >= w[2]);
        let x = solve_spd(&a, &[1.0, 2.0, 3.0]).unwrap();
        for i in 0..3 {
            let ax: f64 = (0..3).map(|k| a[i * 3 + k] * x[k]).sum();
            assert!((ax - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
        }
    }
}
