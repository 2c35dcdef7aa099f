//! A result directory read back for redrawing: `solution.vtu` (point fields u, phi, state,
//! pressure, and `covered` when present; with a body below, `phi_low`, `state_low`,
//! `pressure_low` and `covered_low`) and `summary.json` (the case's name and the plot
//! options used when it was solved), so that `memcontact plot DIR` draws the same
//! pictures without solving again.

use crate::error::{Error, Result};
use crate::io::vtu::read_vtu;
use memcontact_plot::{BodyData, PlotData, PlotOptions};
use std::path::Path;

/// The fields of a result, owned.
#[derive(Debug, Clone, Default)]
pub struct ResultData {
    /// Vertex coordinates.
    pub points: Vec<[f64; 2]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Deflection.
    pub u: Vec<f64>,
    /// Obstacle surface.
    pub phi: Vec<f64>,
    /// −1 clear, 0 touching, 1 penetrating.
    pub state: Vec<i8>,
    /// Contact pressure.
    pub pressure: Vec<f64>,
    /// Where the body can touch.
    pub covered: Vec<bool>,
    /// The body below's fields, when there is one.
    pub lower: Option<LowerData>,
}

/// The fields of the body below, owned.
#[derive(Debug, Clone, Default)]
pub struct LowerData {
    /// Its surface φ_low.
    pub phi: Vec<f64>,
    /// −1 clear (u > φ_low), 0 touching, 1 sunk in (u < φ_low).
    pub state: Vec<i8>,
    /// Its contact pressure.
    pub pressure: Vec<f64>,
    /// Where it lies under the membrane.
    pub covered: Vec<bool>,
}

impl ResultData {
    /// The borrowed view the drawing functions take.
    pub fn view(&self) -> PlotData<'_> {
        PlotData {
            points: &self.points,
            triangles: &self.triangles,
            u: &self.u,
            phi: &self.phi,
            state: &self.state,
            pressure: &self.pressure,
            covered: &self.covered,
            lower: self.lower.as_ref().map(|l| BodyData {
                phi: &l.phi,
                state: &l.state,
                pressure: &l.pressure,
                covered: &l.covered,
            }),
            numbering: None,
        }
    }
}

/// A result directory, read.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The fields.
    pub data: ResultData,
    /// The plot options stored at solve time (or defaults), titled with the case's name.
    pub options: PlotOptions,
    /// What had to be assumed (missing optional fields or keys), for the caller to show.
    pub notes: Vec<String>,
}

/// Reads `dir/solution.vtu` and `dir/summary.json`.
pub fn load(dir: &Path) -> Result<Loaded> {
    let vtu_path = dir.join("solution.vtu");
    let mesh = read_vtu(&vtu_path)?;
    let file_err = |message: String| Error::File {
        path: vtu_path.clone(),
        message,
    };
    let field = |name: &str| -> Result<Vec<f64>> {
        mesh.point_array(name)
            .map(|a| a.values.clone())
            .ok_or_else(|| {
                file_err(format!(
                    "no point field `{name}` (is this a memcontact result?)"
                ))
            })
    };
    let mut notes = Vec::new();
    let u = field("u")?;
    let phi = field("phi")?;
    let pressure = field("pressure")?;
    let states = |name: &str, values: &[f64]| -> Result<Vec<i8>> {
        values
            .iter()
            .enumerate()
            .map(|(i, &s)| match s {
                -1.0 => Ok(-1),
                0.0 => Ok(0),
                1.0 => Ok(1),
                _ => Err(file_err(format!(
                    "point field `{name}` is {s} at vertex {i} (expected -1, 0 or 1)"
                ))),
            })
            .collect()
    };
    let state = states("state", &field("state")?)?;
    let covered: Vec<bool> = match mesh.point_array("covered") {
        Some(a) => a.values.iter().map(|&c| c != 0.0).collect(),
        None => {
            notes.push(
                "solution.vtu has no `covered` field: the body is taken to cover every vertex \
                 where φ is finite"
                    .into(),
            );
            phi.iter().map(|p| p.is_finite()).collect()
        }
    };
    // A body below: its four fields, all or none.
    let lower_names = ["phi_low", "state_low", "pressure_low", "covered_low"];
    let present: Vec<&str> = lower_names
        .into_iter()
        .filter(|n| mesh.point_array(n).is_some())
        .collect();
    let lower = match present.len() {
        0 => None,
        4 => Some(LowerData {
            phi: field("phi_low")?,
            state: states("state_low", &field("state_low")?)?,
            pressure: field("pressure_low")?,
            covered: field("covered_low")?.iter().map(|&c| c != 0.0).collect(),
        }),
        _ => {
            return Err(file_err(format!(
                "has the body below's point fields {} but not all of {}",
                present.join(", "),
                lower_names.join(", ")
            )))
        }
    };
    let summary_path = dir.join("summary.json");
    let mut options = PlotOptions::default();
    let mut case = None;
    match std::fs::read_to_string(&summary_path) {
        Ok(text) => {
            let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::File {
                path: summary_path.clone(),
                message: format!("not valid JSON: {e}"),
            })?;
            case = json
                .get("case")
                .and_then(|c| c.as_str())
                .map(str::to_string);
            // The pictures must be drawn from this run's solution.vtu: a directory mixing
            // the files of two runs is refused.
            if let Some(record) = json.pointer("/files/solution.vtu") {
                let actual = super::file_record(&vtu_path)?;
                if record.get("xxh3").and_then(|h| h.as_str()) != Some(actual.xxh3.as_str()) {
                    return Err(file_err(format!(
                        "is not the solution.vtu that summary.json lists (run {}): the \
                         directory mixes the files of two runs; solve the case again",
                        json.get("run_id").and_then(|r| r.as_str()).unwrap_or("?")
                    )));
                }
            }
            match json.get("plot_options") {
                Some(o) => {
                    options = serde_json::from_value(o.clone()).map_err(|e| Error::File {
                        path: summary_path.clone(),
                        message: format!("plot_options: {e}"),
                    })?;
                }
                None => notes.push("summary.json has no plot_options: default plot options".into()),
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            notes.push("no summary.json: default plot options, no case name".into())
        }
        Err(source) => {
            return Err(Error::Io {
                path: summary_path,
                source,
            })
        }
    }
    if options.title.is_none() {
        options.title = case;
    }
    let data = ResultData {
        points: mesh.points,
        triangles: mesh.triangles,
        u,
        phi,
        state,
        pressure,
        covered,
        lower,
    };
    data.view().validate()?;
    options.validate()?;
    Ok(Loaded {
        data,
        options,
        notes,
    })
}
