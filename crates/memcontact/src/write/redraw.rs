//! A result directory read back for redrawing: `solution.vtu` (point fields u, phi, state,
//! pressure, and `covered` when present) and `summary.json` (the case's name and the plot
//! options used when it was solved), so that `memcontact plot DIR` draws the same
//! pictures without solving again.

use crate::error::{Error, Result};
use crate::io::vtu::read_vtu;
use memcontact_plot::{PlotData, PlotOptions};
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
    let state: Vec<i8> = field("state")?
        .iter()
        .enumerate()
        .map(|(i, &s)| match s {
            -1.0 => Ok(-1),
            0.0 => Ok(0),
            1.0 => Ok(1),
            _ => Err(file_err(format!(
                "point field `state` is {s} at vertex {i} (expected -1, 0 or 1)"
            ))),
        })
        .collect::<Result<_>>()?;
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
    // A body below: its fields are drawn with the obstacle's, as when solving.
    let (phi, state, pressure, covered) = match (
        mesh.point_array("phi_low"),
        mesh.point_array("state_low"),
        mesh.point_array("pressure_low"),
        mesh.point_array("covered_low"),
    ) {
        (Some(p), Some(s), Some(q), Some(c)) => {
            let state_low: Vec<i8> = s.values.iter().map(|&x| x as i8).collect();
            let covered_low: Vec<bool> = c.values.iter().map(|&x| x != 0.0).collect();
            let m = memcontact_plot::bodies::merge(
                memcontact_plot::bodies::BodyFields {
                    phi: &phi,
                    state: &state,
                    pressure: &pressure,
                    covered: &covered,
                },
                memcontact_plot::bodies::BodyFields {
                    phi: &p.values,
                    state: &state_low,
                    pressure: &q.values,
                    covered: &covered_low,
                },
            );
            (m.phi, m.state, m.pressure, m.covered)
        }
        _ => (phi, state, pressure, covered),
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
    };
    data.view().validate()?;
    options.validate()?;
    Ok(Loaded {
        data,
        options,
        notes,
    })
}
