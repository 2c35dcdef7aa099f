//! Load sweeps and load combinations. A tensionless foundation cannot be superposed: every
//! load level or combination is its own nonlinear solve. A sweep varies one parameter
//! (`[sweep]`); load cases override the base case's data (`[[load_case]]`). Steps run in
//! turn on one mesh, each warm-started from the previous answer.
//!
//! Here: the steps as data and their validation ([`crate::run::run_sweep`] runs them). A
//! sweep parameter enters the discrete model linearly, so a step scales the assembled
//! base model instead of assembling again: the load factor scales D, the stiffness factor
//! L, the tension S, and the obstacle offset adds to φₙ. A load case with new data
//! assembles once on the same mesh.

use crate::error::{Error, Invalid, Result};
use crate::field::{Field, Stiffness};
use crate::problem::Problem;
use serde::{Deserialize, Serialize};

/// The parameter a `[sweep]` varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepParameter {
    /// Scales the load f.
    LoadFactor,
    /// Scales the stiffness h.
    StiffnessFactor,
    /// The tension t.
    Tension,
    /// Added to the obstacle's surface φ.
    ObstacleOffset,
}

impl SweepParameter {
    /// The name used in case files.
    pub fn name(self) -> &'static str {
        match self {
            SweepParameter::LoadFactor => "load_factor",
            SweepParameter::StiffnessFactor => "stiffness_factor",
            SweepParameter::Tension => "tension",
            SweepParameter::ObstacleOffset => "obstacle_offset",
        }
    }
}

/// `[sweep]`: one parameter over a list of values (`values`, or `from`, `to`, `steps`
/// evenly spaced, both ends included).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// What varies.
    pub parameter: SweepParameter,
    /// The values, in order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<f64>>,
    /// First value (with `to` and `steps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<f64>,
    /// Last value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
    /// Number of values from `from` to `to` (at least 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<usize>,
}

impl SweepSpec {
    /// The values of the sweep.
    pub fn values(&self) -> std::result::Result<Vec<f64>, Invalid> {
        let values = match (&self.values, self.from, self.to, self.steps) {
            (Some(v), None, None, None) => v.clone(),
            // The count is checked before anything is allocated for it.
            (None, Some(_), Some(_), Some(n)) if n > MAX_STEPS => {
                return Err(Invalid::new(
                    "sweep.steps",
                    format!("{n} steps is more than {MAX_STEPS}"),
                ))
            }
            (None, Some(a), Some(b), Some(n)) if n >= 2 => (0..n)
                .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
                .collect(),
            (None, Some(_), Some(_), Some(n)) => {
                return Err(Invalid::new(
                    "sweep.steps",
                    format!("must be at least 2, got {n}"),
                ))
            }
            _ => {
                return Err(Invalid::new(
                    "sweep",
                    "give either `values = [...]` or `from`, `to` and `steps`",
                ))
            }
        };
        if values.is_empty() {
            return Err(Invalid::new("sweep.values", "is empty"));
        }
        if values.len() > MAX_STEPS {
            return Err(Invalid::new(
                "sweep.values",
                format!("{} steps is more than {MAX_STEPS}", values.len()),
            ));
        }
        for v in &values {
            let ok = v.is_finite()
                && match self.parameter {
                    SweepParameter::LoadFactor | SweepParameter::ObstacleOffset => true,
                    SweepParameter::StiffnessFactor => *v >= 0.0,
                    SweepParameter::Tension => *v > 0.0,
                };
            if !ok {
                return Err(Invalid::new(
                    "sweep.values",
                    format!("{v} is not a valid {}", self.parameter.name()),
                ));
            }
        }
        Ok(values)
    }
}

/// The most steps a sweep or a list of load cases may have.
pub const MAX_STEPS: usize = 10_000;

/// `[[load_case]]`: a named combination, overriding the base case's data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadCase {
    /// The name (and the name of its output directory).
    pub name: String,
    /// The load f of this case (default: the base case's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<Field>,
    /// A factor on the load (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_factor: Option<f64>,
    /// The obstacle's surface φ (default: the base case's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<Field>,
    /// The stiffness h (default: the base case's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<Stiffness>,
}

impl LoadCase {
    /// The base problem with this case's data.
    pub fn problem(&self, base: &Problem) -> Problem {
        let mut p = base.clone();
        if let Some(f) = &self.load {
            p.membrane.load = f.clone();
        }
        if let Some(phi) = &self.shape {
            p.obstacle.shape = phi.clone();
        }
        if let Some(h) = &self.stiffness {
            p.obstacle.stiffness = h.clone();
        }
        p
    }

    /// Whether the case needs its own assembly (new data, not just a factor).
    pub fn assembles(&self) -> bool {
        self.load.is_some() || self.shape.is_some() || self.stiffness.is_some()
    }

    /// `text` (a key or a message about the base case's data) with the keys of the data
    /// this load case overrides renamed to its own: `membrane.load` → `load_case.N.load`,
    /// `obstacle.shape` → `load_case.N.shape`, `obstacle.stiffness` →
    /// `load_case.N.stiffness`.
    pub(crate) fn rename_keys(&self, index: usize, text: &str) -> String {
        let mut out = text.to_string();
        for (given, base, own) in [
            (self.load.is_some(), "membrane.load", "load"),
            (self.shape.is_some(), "obstacle.shape", "shape"),
            (self.stiffness.is_some(), "obstacle.stiffness", "stiffness"),
        ] {
            if given {
                out = out.replace(base, &format!("load_case.{index}.{own}"));
            }
        }
        out
    }

    /// An error about this load case's problem, naming the load case's keys.
    pub(crate) fn rename_error(&self, index: usize, e: Error) -> Error {
        match e {
            Error::Case {
                file,
                line,
                key,
                message,
            } => Error::Case {
                file,
                line,
                key: self.rename_keys(index, &key),
                message: self.rename_keys(index, &message),
            },
            Error::Data(m) => Error::Data(self.rename_keys(index, &m)),
            other => other,
        }
    }
}

/// Checks the sweep and load cases of a case (its `[sweep]`, its `[[load_case]]` entries
/// and the base problem they modify).
pub fn validate_steps(
    sweep: Option<&SweepSpec>,
    load_cases: &[LoadCase],
    problem: &Problem,
) -> std::result::Result<(), Invalid> {
    if sweep.is_some() && !load_cases.is_empty() {
        return Err(Invalid::new(
            "sweep",
            "a case has either a [sweep] or [[load_case]] entries, not both",
        ));
    }
    if let Some(s) = sweep {
        s.values()?;
    }
    if load_cases.len() > MAX_STEPS {
        return Err(Invalid::new(
            "load_case",
            format!("more than {MAX_STEPS} load cases"),
        ));
    }
    for (i, lc) in load_cases.iter().enumerate() {
        let key = |k: &str| format!("load_case.{i}.{k}");
        let name = lc.name.trim();
        let safe = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | ' '))
            && !name.starts_with('.');
        if !safe {
            return Err(Invalid::new(
                key("name"),
                format!(
                    "\"{}\" cannot name an output directory: use letters, digits, '-', '_', \
                     '.' and spaces",
                    lc.name
                ),
            ));
        }
        if load_cases[..i].iter().any(|o| o.name.trim() == name) {
            return Err(Invalid::new(
                key("name"),
                format!("\"{name}\" is used twice"),
            ));
        }
        if let Some(k) = lc.load_factor {
            if !k.is_finite() {
                return Err(Invalid::new(
                    key("load_factor"),
                    format!("must be finite, got {k}"),
                ));
            }
        }
        let p = lc.problem(problem);
        p.validate()
            .map_err(|e| Invalid::new(lc.rename_keys(i, &e.key), lc.rename_keys(i, &e.message)))?;
    }
    Ok(())
}

/// One step of a sweep or one load case.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSpec {
    /// 0-based index.
    pub index: usize,
    /// The output directory name: `step-000`, … or the load case's name.
    pub name: String,
    /// The swept value (the load factor of a load case).
    pub value: f64,
}

/// The steps of a sweep's values or of load cases (empty for neither).
pub fn step_list(sweep: Option<&SweepSpec>, load_cases: &[LoadCase]) -> Result<Vec<StepSpec>> {
    if let Some(s) = sweep {
        let values = s.values().map_err(Invalid::into_error)?;
        return Ok(values
            .into_iter()
            .enumerate()
            .map(|(index, value)| StepSpec {
                index,
                name: format!("step-{index:03}"),
                value,
            })
            .collect());
    }
    Ok(load_cases
        .iter()
        .enumerate()
        .map(|(index, lc)| StepSpec {
            index,
            name: lc.name.trim().to_string(),
            value: lc.load_factor.unwrap_or(1.0),
        })
        .collect())
}
