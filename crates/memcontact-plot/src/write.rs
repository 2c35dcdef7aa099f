//! Result sets with their pictures, as `memcontact solve` writes them and the Python
//! module's `write` writes them too: the library's files ([`memcontact::output`]) plus
//! the pictures of the case's `[output]` section, and for a sweep or load cases a
//! directory per step, `sweep.csv` and the force-deflection picture `sweep.png`.
//!
//! The picture options stored in each `summary.json` are the ones the pictures were drawn
//! with (title included), so that `memcontact plot DIR` redraws identical files.

use crate::bodies::{merge, BodyFields};
use crate::{draw_all, line_plot, LinePlot, PlotData, PlotKind, PlotOptions, Series, Units};
use memcontact::mesh::Mesh;
use memcontact::output::{step_label, write_result_set, SweepSet, WriteOptions};
use memcontact::problem::{PictureKind, VtuFormat};
use memcontact::results::NodalFields;
use memcontact::sweep::{StepRow, StepSpec};
use memcontact::{Case, Discretization, Error, Observer, Outcome, Result, Summary};
use std::path::Path;
use std::time::{Duration, Instant};

/// The file name of the force-deflection picture of a sweep.
pub const SWEEP_PICTURE: &str = "sweep.png";

/// What the steps of `case` are, for titles and reports: `sweep of load factor`, or
/// `load cases`.
pub fn steps_kind(case: &Case) -> String {
    match &case.sweep {
        Some(s) => format!("sweep of {}", s.parameter.name().replace('_', " ")),
        None => "load cases".into(),
    }
}

/// The picture options of `case` (its `[output]` and `[units]` keys), titled `label`.
pub fn plot_options(case: &Case, label: &str) -> PlotOptions {
    PlotOptions {
        plots: case
            .output
            .pictures()
            .into_iter()
            .map(|k| match k {
                PictureKind::Deflection => PlotKind::Deflection,
                PictureKind::Pressure => PlotKind::Pressure,
                PictureKind::Liftoff => PlotKind::Liftoff,
                PictureKind::Profile => PlotKind::Profile,
            })
            .collect(),
        allowable_pressure: case.output.allowable_pressure,
        profile: case.output.profile,
        units: Units {
            length: case.units.length.clone(),
            force: case.units.force.clone(),
        },
        title: Some(label.to_string()),
    }
}

/// Solves a case of one step (no `[sweep]`, no `[[load_case]]`): the mesh and assembly,
/// the picture options checked on the mesh ([`check_on_mesh`]) before anything is solved,
/// then the solve. The outcome is returned whatever the solve's status.
pub fn solve_case(case: &Case, observer: &mut dyn Observer) -> Result<Outcome> {
    let discretization = Discretization::new(&case.problem, observer)?;
    check_on_mesh(case, discretization.mesh())?;
    let report = discretization.solve(&case.settings, observer)?;
    Ok(Outcome {
        discretization,
        report,
    })
}

/// Checks the picture options of `case` against the mesh before anything is solved: a
/// given profile line must cross the mesh (else `profile.png` could not be drawn).
pub fn check_on_mesh(case: &Case, mesh: &Mesh) -> Result<()> {
    let Some([a, b]) = case.output.profile else {
        return Ok(());
    };
    if !crate::profile::crosses(&mesh.points, &mesh.triangles, a, b) {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "output.profile".into(),
            message: format!(
                "the line from ({}, {}) to ({}, {}) does not cross the mesh (its bounding \
                 box is {})",
                a[0],
                a[1],
                b[0],
                b[1],
                bbox_text(&mesh.points)
            ),
        });
    }
    Ok(())
}

/// `[x0, x1] × [y0, y1]` of the points.
fn bbox_text(points: &[[f64; 2]]) -> String {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        (x0, x1) = (x0.min(p[0]), x1.max(p[0]));
        (y0, y1) = (y0.min(p[1]), y1.max(p[1]));
    }
    format!("[{x0}, {x1}] × [{y0}, {y1}]")
}

/// The pictures of `options` as the `extra` files of [`memcontact::output::write_files`]:
/// drawn into the directory from the nodal fields on `mesh`; returns their names.
pub fn pictures<'a>(
    mesh: &'a Mesh,
    options: &'a PlotOptions,
) -> impl FnMut(&Path, &NodalFields) -> Result<Vec<String>> + 'a {
    move |dir: &Path, fields: &NodalFields| {
        if options.plots.is_empty() {
            return Ok(Vec::new());
        }
        let upper = BodyFields {
            phi: &fields.phi,
            state: &fields.state,
            pressure: &fields.pressure,
            covered: &fields.covered,
        };
        // With a body below, both bodies' contact is drawn ([`crate::bodies`]).
        let merged = fields.lower.as_ref().map(|l| {
            merge(
                upper,
                BodyFields {
                    phi: &l.phi,
                    state: &l.state,
                    pressure: &l.pressure,
                    covered: &l.covered,
                },
            )
        });
        let shown = match &merged {
            Some(m) => BodyFields {
                phi: &m.phi,
                state: &m.state,
                pressure: &m.pressure,
                covered: &m.covered,
            },
            None => upper,
        };
        let data = PlotData {
            points: &mesh.points,
            triangles: &mesh.triangles,
            u: &fields.u,
            phi: shown.phi,
            state: shown.state,
            pressure: shown.pressure,
            covered: shown.covered,
        };
        let files =
            draw_all(dir, &data, options).map_err(|e| Error::Data(format!("pictures: {e}")))?;
        Ok(files
            .iter()
            .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect())
    }
}

/// Writes the result set of `outcome` into `target` atomically: the library's files, the
/// pictures of `plots`, and `summary.json` recording `plots` (so they can be redrawn).
/// `options.plot_options` is replaced by `plots`. Returns the summary written.
pub fn write_result(
    target: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    plots: &PlotOptions,
) -> Result<Summary> {
    let options = WriteOptions {
        plot_options: serde_json::to_value(plots).ok(),
        ..options.clone()
    };
    let mesh = outcome.mesh();
    let mut draw = pictures(&mesh, plots);
    write_result_set(target, outcome, case, &options, &mut draw)
}

/// A sweep's (or load cases') result set being written: a directory per step with its
/// files and pictures (titled with the step's label), then `sweep.csv` and `sweep.png`.
/// Nothing is in place until [`SweepWriter::finish`]; dropping the writer leaves the
/// target as it was.
#[derive(Debug)]
pub struct SweepWriter {
    set: SweepSet,
    label: String,
    vtu: VtuFormat,
    plots: PlotOptions,
    what: String,
}

impl SweepWriter {
    /// Starts the set in `target` for the steps of `case`, labelled `label`; `pictures`
    /// false draws no picture (neither the maps nor `sweep.png`).
    pub fn begin(
        target: &Path,
        force: bool,
        case: &Case,
        label: &str,
        vtu: VtuFormat,
        pictures: bool,
    ) -> Result<SweepWriter> {
        let mut plots = plot_options(case, label);
        if !pictures {
            plots.plots.clear();
        }
        Ok(SweepWriter {
            set: SweepSet::begin(target, force)?,
            label: label.to_string(),
            vtu,
            plots,
            what: steps_kind(case),
        })
    }

    /// Step directories written so far.
    pub fn steps_written(&self) -> usize {
        self.set.steps_written()
    }

    /// Writes the files and pictures of `step`, solved as `outcome` in `seconds`.
    /// Returns the step's summary.
    pub fn write_step(
        &mut self,
        case: &Case,
        step: &StepSpec,
        outcome: &Outcome,
        seconds: f64,
    ) -> Result<Summary> {
        let label = step_label(&self.label, step);
        let plots = PlotOptions {
            title: Some(label.clone()),
            ..self.plots.clone()
        };
        let now = Instant::now();
        let options = WriteOptions {
            label,
            vtu: self.vtu,
            csv: case.output.writes_csv(),
            force: false,
            started: now
                .checked_sub(Duration::from_secs_f64(seconds.max(0.0)))
                .unwrap_or(now),
            plot_options: serde_json::to_value(&plots).ok(),
            // The set's own run id (SweepSet::write_step).
            run_id: None,
        };
        let mesh = outcome.mesh();
        let mut draw = pictures(&mesh, &plots);
        self.set
            .write_step(step, outcome, case, &options, &mut draw)
    }

    /// Writes `sweep.csv` of `rows` and `sweep.png` (the total contact force against the
    /// largest deflection; not when no picture is drawn, `plots = []`), and moves the set
    /// into place.
    pub fn finish(self, rows: &[StepRow]) -> Result<()> {
        let title = format!("Force-deflection ({}): {}", self.what, self.label);
        let draw = !self.plots.plots.is_empty();
        let units = self.plots.units.clone();
        self.set.commit(rows, &mut |dir, rows| {
            if draw {
                sweep_picture(&dir.join(SWEEP_PICTURE), &title, &units, rows)?;
            }
            Ok(())
        })
    }
}

/// Draws the force-deflection curve of a sweep: the total contact force of each step
/// against its largest deflection, in step order.
pub fn sweep_picture(path: &Path, title: &str, units: &Units, rows: &[StepRow]) -> Result<()> {
    line_plot(
        path,
        &LinePlot {
            title: title.to_string(),
            x_label: format!("max deflection{}", units.length_suffix()),
            y_label: format!("total contact force{}", units.force_suffix()),
            series: vec![Series {
                name: "total contact force".into(),
                points: rows
                    .iter()
                    .map(|r| (r.max_deflection, r.total_contact_force))
                    .collect(),
            }],
        },
    )
}
