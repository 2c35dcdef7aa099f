//! [`Case`]: the sections of a case file as one value, read from TOML or JSON, validated
//! once.

use super::adapt::AdaptSpec;
use super::exact::ExactSpec;
use super::output::{OutputOptions, Units};
use super::overrides::{apply_overrides, key_span, line_of, plain_types, strip_json_position};
use super::sensitivity::{FitSpec, SensitivitySpec, Sensor};
use super::sweep::{step_list, validate_steps, LoadCase, StepSpec, SweepSpec};
use crate::error::{Error, Invalid, Result};
use crate::problem::{Boundary, Membrane, MeshSpec, Obstacle, Problem};
use crate::solve::Settings;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A whole case: the problem, how to solve it, what to write, and (optionally) its exact
/// solution. The TOML case file has the sections `[mesh]`, `[membrane]`, `[obstacle]`,
/// `[solver]`, `[output]` and `[exact]`, and, beyond the paper's frame, `[boundary]` (heights
/// and free edges) and `[lower]` (a body below).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "CaseFile", into = "CaseFile")]
pub struct Case {
    /// The mesh and the data of the paper's Problem 1.
    pub problem: Problem,
    /// `[solver]`.
    pub settings: Settings,
    /// `[output]`.
    pub output: OutputOptions,
    /// `[exact]`: the closed-form solution this case has, for convergence studies.
    pub exact: Option<ExactSpec>,
    /// `[units]`: the names of the case's units, for labels.
    pub units: Units,
    /// `[sweep]`: one parameter varied over a list of values.
    pub sweep: Option<SweepSpec>,
    /// `[[load_case]]`: named combinations overriding the case's data.
    pub load_cases: Vec<LoadCase>,
    /// `[adapt]`: adaptive refinement of the mesh.
    pub adapt: Option<AdaptSpec>,
    /// `[[sensor]]`: points where the deflection is read (and measured).
    pub sensors: Vec<Sensor>,
    /// `[sensitivity]`: derivatives of outputs in case keys.
    pub sensitivity: Option<SensitivitySpec>,
    /// `[fit]`: case keys fitted to measured deflections.
    pub fit: Option<FitSpec>,
}

/// The serde shape of [`Case`]: one field per section.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    mesh: MeshSpec,
    membrane: Membrane,
    obstacle: Obstacle,
    #[serde(default, skip_serializing_if = "Boundary::is_default")]
    boundary: Boundary,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lower: Option<Obstacle>,
    #[serde(default)]
    solver: Settings,
    #[serde(default)]
    output: OutputOptions,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exact: Option<ExactSpec>,
    #[serde(default)]
    units: Units,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sweep: Option<SweepSpec>,
    #[serde(default, rename = "load_case", skip_serializing_if = "Vec::is_empty")]
    load_cases: Vec<LoadCase>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    adapt: Option<AdaptSpec>,
    #[serde(default, rename = "sensor", skip_serializing_if = "Vec::is_empty")]
    sensors: Vec<Sensor>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sensitivity: Option<SensitivitySpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fit: Option<FitSpec>,
}

impl From<CaseFile> for Case {
    fn from(c: CaseFile) -> Case {
        Case {
            problem: Problem {
                mesh: c.mesh,
                membrane: c.membrane,
                obstacle: c.obstacle,
                boundary: c.boundary,
                lower: c.lower,
            },
            settings: c.solver,
            output: c.output,
            exact: c.exact,
            units: c.units,
            sweep: c.sweep,
            load_cases: c.load_cases,
            adapt: c.adapt,
            sensors: c.sensors,
            sensitivity: c.sensitivity,
            fit: c.fit,
        }
    }
}

impl From<Case> for CaseFile {
    fn from(c: Case) -> CaseFile {
        CaseFile {
            mesh: c.problem.mesh,
            membrane: c.problem.membrane,
            obstacle: c.problem.obstacle,
            boundary: c.problem.boundary,
            lower: c.problem.lower,
            solver: c.settings,
            output: c.output,
            exact: c.exact,
            units: c.units,
            sweep: c.sweep,
            load_cases: c.load_cases,
            adapt: c.adapt,
            sensors: c.sensors,
            sensitivity: c.sensitivity,
            fit: c.fit,
        }
    }
}

impl Case {
    /// A case of `problem` alone: the default `[solver]`, `[output]` and `[units]`, no
    /// steps, no adaptive loop, no exact solution, no sensors, sensitivities or fit.
    pub fn new(problem: Problem) -> Case {
        Case {
            problem,
            settings: Settings::default(),
            output: OutputOptions::default(),
            exact: None,
            units: Units::default(),
            sweep: None,
            load_cases: Vec::new(),
            adapt: None,
            sensors: Vec::new(),
            sensitivity: None,
            fit: None,
        }
    }

    /// Whether the case has steps to solve in turn (a `[sweep]` or `[[load_case]]`
    /// entries): then it is run by [`crate::run::run_sweep`], not [`crate::run::run`].
    pub fn is_sweep(&self) -> bool {
        self.sweep.is_some() || !self.load_cases.is_empty()
    }

    /// Checks the whole case (problem, settings, output, exact solution) without the mesh.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.problem.validate()?;
        self.settings.validate()?;
        self.output.validate()?;
        validate_steps(self.sweep.as_ref(), &self.load_cases, &self.problem)?;
        if let Some(a) = &self.adapt {
            a.validate()?;
            if self.is_sweep() {
                return Err(Invalid::new(
                    "adapt",
                    "a case has either [adapt] or steps ([sweep], [[load_case]]), not both: \
                     the steps of a sweep would each refine their own mesh (solve the steps \
                     on a fixed mesh, or adapt one case at a time)",
                ));
            }
        }
        super::sensitivity::validate_case(self)?;
        if let Some(ExactSpec::Manufactured { amplitude, .. }) = &self.exact {
            if !(amplitude.is_finite() && *amplitude != 0.0) {
                return Err(Invalid::new(
                    "exact.amplitude",
                    format!("must be a finite non-zero number, got {amplitude}"),
                ));
            }
        }
        Ok(())
    }

    /// Parses a case from TOML text. `file` names the text in messages and is the base of
    /// relative mesh paths. Errors carry the key, the file and the line.
    pub fn from_toml_str(text: &str, file: Option<&Path>) -> Result<Case> {
        let located =
            |key: String, message: String, span: Option<std::ops::Range<usize>>| Error::Case {
                file: file.map(Path::to_path_buf),
                line: span.map(|s| line_of(text, s.start)),
                key,
                message,
            };
        let de = toml::Deserializer::parse(text).map_err(|e| {
            located(
                String::new(),
                format!("malformed TOML: {}", e.message().trim()),
                e.span(),
            )
        })?;
        let mut case: Case = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            let key = if key == "." { String::new() } else { key };
            located(key, plain_types(inner.message().trim()), inner.span())
        })?;
        if let Some(base) = file.and_then(Path::parent) {
            case.problem.mesh.resolve(base);
            if let Some(fit) = &mut case.fit {
                fit.resolve(base);
            }
        }
        case.validate().map_err(|inv| {
            let span = key_span(text, &inv.key);
            located(inv.key, inv.message, span)
        })?;
        Ok(case)
    }

    /// Parses a case from JSON text (what the Python module sends).
    pub fn from_json_str(text: &str) -> Result<Case> {
        let mut de = serde_json::Deserializer::from_str(text);
        let case: Case = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            let key = if key == "." { String::new() } else { key };
            let inner = e.into_inner();
            Error::Case {
                file: None,
                line: None,
                key,
                message: plain_types(&strip_json_position(&inner.to_string())),
            }
        })?;
        case.validate().map_err(Invalid::into_error)?;
        Ok(case)
    }

    /// Parses a fragment of a case file (some sections or keys, as the documentation shows
    /// them): the keys and values it gives are checked as in a whole case, on top of the
    /// fewest keys that complete it (a small rectangle mesh, or the generator its `[mesh]`
    /// keys name; tension, load, shape and stiffness 1). Nothing that needs the mesh is
    /// checked. `memcontact check --fragment` calls it.
    pub fn from_fragment_str(text: &str, file: Option<&Path>) -> Result<Case> {
        let table: toml::Table = toml::from_str(text).map_err(|e| Error::Case {
            file: file.map(Path::to_path_buf),
            line: e.span().map(|s| line_of(text, s.start)),
            key: String::new(),
            message: format!("malformed TOML: {}", e.message().trim()),
        })?;
        let section = |name: &str| table.get(name).and_then(toml::Value::as_table);
        let has = |name: &str, key: &str| section(name).is_some_and(|t| t.contains_key(key));
        let mut fill: Vec<String> = Vec::new();
        if !(has("mesh", "file") || has("mesh", "generator") || has("mesh", "given")) {
            let any = |keys: &[&str]| keys.iter().any(|k| has("mesh", k));
            if any(&["outer", "holes", "regions", "min_angle"]) {
                fill.push("mesh.generator=\"polygon\"".into());
                if !has("mesh", "outer") {
                    fill.push("mesh.outer=[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]".into());
                }
                if !has("mesh", "size") {
                    fill.push("mesh.size=0.5".into());
                }
            } else if any(&["center", "radius", "size"]) {
                fill.push("mesh.generator=\"disk\"".into());
            } else {
                fill.push("mesh.generator=\"rectangle\"".into());
                if !has("mesh", "nx") {
                    fill.push("mesh.nx=2".into());
                }
            }
        }
        for (name, key) in [
            ("membrane", "tension"),
            ("membrane", "load"),
            ("obstacle", "shape"),
            ("obstacle", "stiffness"),
        ] {
            if !has(name, key) {
                fill.push(format!("{name}.{key}=1.0"));
            }
        }
        let whole = apply_overrides(text, &fill).map_err(|(key, message)| Error::Case {
            file: file.map(Path::to_path_buf),
            line: None,
            key,
            message,
        })?;
        Case::from_toml_str(&whole, file)
    }

    /// Reads a case file (a regular file of at most [`crate::io::input::CASE_FILE_CAP`] bytes), applies
    /// `key=value` overrides (dotted keys, TOML values; a value that is not TOML is taken
    /// as a string) and parses it; relative paths are relative to the case file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Case> {
        let text = read_case_text(path)?;
        let text = apply_overrides(&text, overrides).map_err(|(key, message)| Error::Case {
            file: Some(path.to_path_buf()),
            line: None,
            key,
            message,
        })?;
        Case::from_toml_str(&text, Some(path))
    }

    /// Reads a fragment of a case file ([`Case::from_fragment_str`]), with overrides as
    /// [`Case::load`] applies them.
    pub fn load_fragment(path: &Path, overrides: &[String]) -> Result<Case> {
        let text = read_case_text(path)?;
        let text = apply_overrides(&text, overrides).map_err(|(key, message)| Error::Case {
            file: Some(path.to_path_buf()),
            line: None,
            key,
            message,
        })?;
        Case::from_fragment_str(&text, Some(path))
    }

    /// The case as TOML text (round-trips through [`Case::from_toml_str`]).
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Data(format!("cannot write the case: {e}")))
    }
}

/// Reads a case file's text: a regular file, at most [`CASE_FILE_CAP`](super::CASE_FILE_CAP)
/// bytes, UTF-8 (errors name the file).
pub fn read_case_text(path: &Path) -> Result<String> {
    let bytes = crate::io::input::read_input(path, crate::io::input::CASE_FILE)?;
    String::from_utf8(bytes).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!(
            "is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })
}

/// The steps of a case: its sweep's values or its load cases (empty for neither).
pub fn steps(case: &Case) -> Result<Vec<StepSpec>> {
    step_list(case.sweep.as_ref(), &case.load_cases)
}
