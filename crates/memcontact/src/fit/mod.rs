//! Back-analysis (docs/theory.md#back-analysis): case parameters fitted to measured
//! deflections by minimising `½ Σₖ ((Qₖ(p) − mₖ)/σₖ)² (+ ½ α ‖ln p − ln p₀‖²)` over
//! bounds, in `q = ln p` for positive parameters, with the exact Jacobian of the sensors'
//! deflections from tangent solves ([`crate::sensitivity`]). Here: the optimiser (bounded
//! Levenberg-Marquardt), the measurements file ([`parse_measurements`]) and the
//! statistics of the answer ([`Statistics`]: covariance `σ̂² (JᵀWJ)⁻¹`, standard errors,
//! correlations, the singular values of the scaled Jacobian and the identifiability
//! warning). [`crate::run::run_fit`] runs the fit.

pub(crate) mod measurements;
pub(crate) mod optimizer;

pub use measurements::{parse_measurements, read_measurements};
pub use optimizer::Stop;

/// A condition number of the scaled Jacobian above this means the measurements cannot tell
/// the parameters apart.
pub const CONDITION_LIMIT: f64 = 1e6;

/// A correlation above this (in absolute value) means the same.
pub const CORRELATION_LIMIT: f64 = 0.99;

/// The statistics of a least-squares answer.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Statistics {
    /// The covariance of the fitted variables (ln p for positive parameters), row-major.
    pub covariance: Vec<f64>,
    /// The standard errors of the parameters themselves (`p σ_{ln p}` for a logarithmic
    /// one).
    pub std_errors: Vec<f64>,
    /// The correlation matrix, row-major.
    pub correlation: Vec<f64>,
    /// The singular values of the weighted Jacobian with the parameters scaled (`W^½ J D_p`),
    /// largest first.
    pub singular_values: Vec<f64>,
    /// Their ratio, largest over smallest.
    pub condition_number: f64,
    /// σ̂²: 1 when every measurement has its σ, else the reduced chi-square.
    pub variance_factor: f64,
    /// Why the parameters are not identifiable from the measurements, when they are not.
    pub warning: Option<String>,
}

/// The statistics at the answer: `jacobian` is `∂r/∂x` (row-major, `m × n`) of the
/// weighted residuals `r` in the fitted variables x (ln p where `log[j]`), `p` the
/// parameters, `sigmas_given` whether every measurement has its σ, `prior` the weight α,
/// `names` the parameters' keys (for the warning).
pub(crate) fn statistics(
    jacobian: &[f64],
    r: &[f64],
    p: &[f64],
    log: &[bool],
    sigmas_given: bool,
    prior: f64,
    names: &[String],
) -> Statistics {
    let n = p.len();
    let m = r.len();
    let mut a = vec![0.0; n * n];
    for i in 0..m {
        for j in 0..n {
            for k in 0..n {
                a[j * n + k] += jacobian[i * n + j] * jacobian[i * n + k];
            }
        }
    }
    for j in 0..n {
        a[j * n + j] += prior;
    }
    let chi2: f64 = r.iter().map(|v| v * v).sum();
    let variance_factor = if sigmas_given {
        1.0
    } else if m > n {
        chi2 / (m - n) as f64
    } else {
        f64::NAN
    };
    // A⁺ by the eigen-decomposition (directions the data do not see get infinite
    // variance).
    let (w, v) = optimizer::symmetric_eigen(&a, n);
    let top = w.first().copied().unwrap_or(0.0).max(0.0);
    let mut covariance = vec![0.0; n * n];
    for j in 0..n {
        for k in 0..n {
            let mut s = 0.0;
            for c in 0..n {
                s += if w[c] > 1e-14 * top && w[c] > 0.0 {
                    v[j * n + c] * v[k * n + c] / w[c]
                } else if v[j * n + c] != 0.0 && v[k * n + c] != 0.0 {
                    f64::INFINITY
                } else {
                    0.0
                };
            }
            covariance[j * n + k] = variance_factor * s;
        }
    }
    let std_x: Vec<f64> = (0..n)
        .map(|j| covariance[j * n + j].max(0.0).sqrt())
        .collect();
    let std_errors = (0..n)
        .map(|j| if log[j] { p[j] * std_x[j] } else { std_x[j] })
        .collect();
    let correlation: Vec<f64> = (0..n * n)
        .map(|jk| {
            let (j, k) = (jk / n, jk % n);
            if j == k {
                1.0
            } else {
                covariance[jk] / (std_x[j] * std_x[k])
            }
        })
        .collect();
    // Singular values of J D_p: ln p variables are already scaled; others by |p|.
    let scale: Vec<f64> = (0..n)
        .map(|j| if log[j] { 1.0 } else { p[j].abs().max(1e-300) })
        .collect();
    let mut js = vec![0.0; n * n];
    for i in 0..m {
        for j in 0..n {
            for k in 0..n {
                js[j * n + k] += jacobian[i * n + j] * scale[j] * jacobian[i * n + k] * scale[k];
            }
        }
    }
    let (ws, _) = optimizer::symmetric_eigen(&js, n);
    let singular_values: Vec<f64> = ws.iter().map(|&x| x.max(0.0).sqrt()).collect();
    let condition_number = match (singular_values.first(), singular_values.last()) {
        (Some(&hi), Some(&lo)) if lo > 0.0 => hi / lo,
        (Some(_), Some(_)) => f64::INFINITY,
        _ => 1.0,
    };
    let mut worst = (0.0f64, 0, 0);
    for j in 0..n {
        for k in j + 1..n {
            let c = correlation[j * n + k];
            if c.is_nan() || c.abs() > worst.0 {
                worst = (if c.is_nan() { 1.0 } else { c.abs() }, j, k);
            }
        }
    }
    let mut reasons = Vec::new();
    if condition_number.is_nan() || condition_number > CONDITION_LIMIT {
        reasons.push(format!(
            "the scaled Jacobian's condition number is {condition_number:.2e} (above {CONDITION_LIMIT:.0e})"
        ));
    }
    if n > 1 && worst.0 > CORRELATION_LIMIT {
        reasons.push(format!(
            "{} and {} are correlated {:.4}",
            names[worst.1],
            names[worst.2],
            correlation[worst.1 * n + worst.2]
        ));
    }
    let warning = (!reasons.is_empty()).then(|| {
        format!(
            "the parameters are not identifiable from these measurements: {}; place sensors \
             where the parameters act differently, fit fewer parameters, or add a prior",
            reasons.join("; ")
        )
    });
    Statistics {
        covariance,
        std_errors,
        correlation,
        singular_values,
        condition_number,
        variance_factor,
        warning,
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FittedParameter {
    /// The case key.
    pub key: String,
    /// The fitted value.
    pub value: f64,
    /// The start (the case's value).
    pub start: f64,
    /// The bounds.
    pub bounds: [f64; 2],
    /// Fitted in its logarithm.
    pub log: bool,
    /// Its standard error.
    pub std_error: f64,
}

/// One measurement and the fitted model's value there.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fitted {
    /// The sensor's name.
    pub name: String,
    /// Where.
    pub at: [f64; 2],
    /// The measured deflection.
    pub measured: f64,
    /// Its σ (1 when not given).
    pub sigma: f64,
    /// The deflection computed at the fitted parameters.
    pub computed: f64,
}

/// One row of `fit.csv`: an accepted iterate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitIteration {
    /// 0 for the start.
    pub iteration: usize,
    /// The parameters.
    pub parameters: Vec<f64>,
    /// The root-mean-square of the weighted residuals.
    pub rms: f64,
    /// The largest change of a fitted variable (ln p for a logarithmic one) in the step.
    pub step: f64,
    /// The Levenberg-Marquardt damping of the step.
    pub damping: f64,
    /// Forward solves so far.
    pub solves: usize,
}

/// One forward solve of a fit.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitSolve {
    /// The parameters solved at.
    pub parameters: Vec<f64>,
    /// The solver's iterations.
    pub iterations: usize,
    /// Its seconds.
    pub seconds: f64,
    /// Whether its answer was accepted.
    pub accepted: bool,
}

/// The result of a fit (`fit.json`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitResult {
    /// The fitted parameters.
    pub parameters: Vec<FittedParameter>,
    /// The statistics at the answer.
    pub statistics: Statistics,
    /// The root-mean-square of the weighted residuals `(Q − m)/σ`.
    pub rms: f64,
    /// The cost `½ Σ r² (+ prior)`.
    pub cost: f64,
    /// Accepted iterations.
    pub iterations: usize,
    /// Forward solves (trial steps included).
    pub solves: usize,
    /// Whether it converged (`stop` is `step`, `gradient` or `residual`).
    pub converged: bool,
    /// Why it stopped.
    pub stop: Stop,
    /// The measurements and the computed values.
    pub measurements: Vec<Fitted>,
    /// The accepted iterates.
    pub history: Vec<FitIteration>,
    /// Seconds of the fit (mesh, assembly, solves, derivatives and the optimiser).
    pub seconds: f64,
    /// Seconds in forward solves.
    pub seconds_solves: f64,
    /// Seconds in the Jacobians (the tangent solves).
    pub seconds_derivatives: f64,
    /// Every forward solve, in order (trial steps included).
    pub forward_solves: Vec<FitSolve>,
}
