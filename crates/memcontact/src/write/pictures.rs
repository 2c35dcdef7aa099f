//! Result sets with their pictures, as `memcontact solve` and the Python module's `write`
//! write them: the files of [`super::write_result_set`] plus the pictures of the case's
//! `[output]` section (drawn by the picture crate, `memcontact_plot`, and written here),
//! and for a sweep or load cases a directory per step, `sweep.csv` and the
//! force-deflection picture `sweep.png`.
//!
//! The picture options stored in each `summary.json` are the ones the pictures were drawn
//! with (title included), so that `memcontact plot DIR` redraws identical files.

use super::{step_label, write_result_set, SweepSet, WriteOptions};
use crate::case::StepSpec;
use crate::case::{Case, PictureKind, VtuFormat};
use crate::error::{Error, Result};
use crate::mesh::reorder::Reordering;
use crate::mesh::Mesh;
use crate::outcome::fields::NodalFields;
use crate::outcome::{Outcome, StepRow, Summary};
use crate::verify::convergence::LevelResult;
use crate::verify::study::{StudyOutcome, StudyResult};
use memcontact_plot::{
    render, render_line_plot, BodyData, Canvas, LinePlot, PlotData, PlotKind, PlotOptions, Series,
    Units, UserNumbering,
};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
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

/// Writes a picture as a PNG file, atomically.
pub fn write_png(path: &Path, canvas: &Canvas) -> Result<()> {
    let png = canvas.encode_png()?;
    crate::io::write_atomic(path, |w| w.write_all(&png)).map(|_| ())
}

/// Draws the pictures `options.plots` into `dir` (`deflection.png`, `pressure.png`,
/// `liftoff.png`, `profile.png`), each written atomically; returns the files written.
pub fn draw_all(dir: &Path, data: &PlotData, options: &PlotOptions) -> Result<Vec<PathBuf>> {
    in_local_order(data, |data| {
        let pictures = render(data, options)?;
        pictures
            .par_iter()
            .map(|p| {
                let path = dir.join(p.kind.file_name());
                write_png(&path, &p.canvas)?;
                Ok(path)
            })
            .collect()
    })
}

/// Calls `draw` with `data` renumbered for locality when its numbering is scattered (a
/// mesh generator's: the renumbering of the solver, vertices along the Hilbert curve),
/// with the user's numbering attached so that the pictures are the same (see
/// [`UserNumbering`]) and drawn several times faster; with `data` itself when its order
/// is already local or it is renumbered already. Invalid data are refused before
/// anything is moved.
fn in_local_order<T>(data: &PlotData, draw: impl FnOnce(&PlotData) -> Result<T>) -> Result<T> {
    use crate::mesh::reorder::{locality_order, scattered};
    if data.numbering.is_some() || !scattered(data.points.len(), data.triangles) {
        return draw(data);
    }
    data.validate()?;
    let Some(order) = locality_order(data.points, data.triangles) else {
        return draw(data);
    };
    let v = &order.vertices;
    let triangles: Vec<[u32; 3]> = order
        .triangles
        .old_of_new
        .par_iter()
        .with_min_len(8192)
        .map(|&k| data.triangles[k as usize].map(|x| v.new_of_old[x as usize]))
        .collect();
    let (points, u, phi) = (v.to_new(data.points), v.to_new(data.u), v.to_new(data.phi));
    let (state, pressure, covered) = (
        v.to_new(data.state),
        v.to_new(data.pressure),
        v.to_new(data.covered),
    );
    let lower = data.lower.map(|l| {
        (
            v.to_new(l.phi),
            v.to_new(l.state),
            v.to_new(l.pressure),
            v.to_new(l.covered),
        )
    });
    draw(&PlotData {
        points: &points,
        triangles: &triangles,
        u: &u,
        phi: &phi,
        state: &state,
        pressure: &pressure,
        covered: &covered,
        lower: lower.as_ref().map(|l| BodyData {
            phi: &l.0,
            state: &l.1,
            pressure: &l.2,
            covered: &l.3,
        }),
        numbering: Some(user_numbering(&order)),
    })
}

/// Calls `draw` with the fields of `fields` on `mesh` as the picture crate takes them:
/// with a body below, its fields beside the obstacle's, so that each picture draws each
/// body's contact separately. The one preparation of the data of every picture of a
/// result.
fn with_plot_data<T>(
    mesh: &Mesh,
    fields: &NodalFields,
    draw: impl FnOnce(&PlotData) -> Result<T>,
) -> Result<T> {
    in_local_order(&plot_data(mesh, fields, None), draw)
}

/// Calls `draw` with the fields of the solved `outcome` as the picture crate takes them, in
/// the solver's numbering with the user's attached (see [`outcome_pictures`]).
fn with_outcome_data<T>(outcome: &Outcome, draw: impl FnOnce(&PlotData) -> Result<T>) -> Result<T> {
    let mesh = outcome.discretization.mesh();
    let (fields, _) = outcome.solver_fields();
    let numbering = mesh.numbering.as_deref().map(user_numbering);
    in_local_order(&plot_data(mesh, &fields, numbering), draw)
}

/// The user's numbering of a mesh renumbered by `r`, as the picture crate takes it.
fn user_numbering(r: &Reordering) -> UserNumbering<'_> {
    UserNumbering {
        vertices: &r.vertices.old_of_new,
        triangles: &r.triangles.old_of_new,
    }
}

/// The picture crate's view of `fields` on `mesh`, in the numbering of both, with the
/// user's `numbering` of a renumbered mesh.
fn plot_data<'a>(
    mesh: &'a Mesh,
    fields: &'a NodalFields,
    numbering: Option<UserNumbering<'a>>,
) -> PlotData<'a> {
    PlotData {
        points: &mesh.points,
        triangles: &mesh.triangles,
        u: &fields.u,
        phi: &fields.phi,
        state: &fields.state,
        pressure: &fields.pressure,
        covered: &fields.covered,
        lower: fields.lower.as_ref().map(|l| BodyData {
            phi: &l.phi,
            state: &l.state,
            pressure: &l.pressure,
            covered: &l.covered,
        }),
        numbering,
    }
}

/// [`draw_all`] as the `extra` files of a result set: the names of the files written.
fn draw_named(dir: &Path, data: &PlotData, options: &PlotOptions) -> Result<Vec<String>> {
    let files = draw_all(dir, data, options).map_err(|e| Error::Data(format!("pictures: {e}")))?;
    Ok(files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect())
}

/// The pictures of `options` as the `extra` files of [`super::write_files`]:
/// drawn into the directory from the nodal fields on `mesh`; returns their names.
pub fn pictures<'a>(
    mesh: &'a Mesh,
    options: &'a PlotOptions,
) -> impl FnMut(&Path, &NodalFields) -> Result<Vec<String>> + 'a {
    move |dir: &Path, fields: &NodalFields| {
        if options.plots.is_empty() {
            return Ok(Vec::new());
        }
        with_plot_data(mesh, fields, |data| draw_named(dir, data, options))
    }
}

/// [`pictures`] of the solved `outcome`, as the `extra` files of its result set: drawn from
/// the solver's own arrays (renumbered for locality) with the user's numbering attached,
/// which gives the same files as the fields in the user's numbering, without a copy of
/// them; the fields the result set passes (the user's) are not read.
pub fn outcome_pictures<'a>(
    outcome: &'a Outcome,
    options: &'a PlotOptions,
) -> impl FnMut(&Path, &NodalFields) -> Result<Vec<String>> + 'a {
    move |dir: &Path, _: &NodalFields| {
        if options.plots.is_empty() {
            return Ok(Vec::new());
        }
        with_outcome_data(outcome, |data| draw_named(dir, data, options))
    }
}

/// The parts of writing the result set of `outcome` with the pictures of `plots`, each
/// alone and one after the other into the existing directory `dir` (the same files as
/// [`write_result`] writes, without `summary.json`): seconds of `solution.vtu`,
/// `nodes.csv` (when the case writes it), the input's hash, the pictures' shared layout,
/// each picture (drawn, encoded and written) and the pictures' records (read back and
/// hashed), each with the processor seconds of all threads the process spent meanwhile
/// (NaN where unknown): `(part, seconds, CPU seconds)`. For the benchmark: where the time
/// of writing goes, and how much of it waits for the disk.
#[cfg(feature = "bench")]
pub fn write_parts_seconds(
    dir: &Path,
    outcome: &Outcome,
    case: &Case,
    plots: &PlotOptions,
) -> Result<Vec<(String, f64, f64)>> {
    use super::result::{file_record, input_hash, write_nodes_csv, write_solution_vtu};
    let (fields, _) = outcome.checked_fields()?;
    let mesh = outcome.mesh();
    let mut parts = Vec::new();
    let mut timed = |name: &str, part: &mut dyn FnMut() -> Result<()>| -> Result<()> {
        let (t, cpu) = (Instant::now(), crate::io::numbers::cpu_seconds());
        part()?;
        let cpu = crate::io::numbers::cpu_seconds() - cpu;
        parts.push((name.to_string(), t.elapsed().as_secs_f64(), cpu));
        Ok(())
    };
    timed("solution.vtu", &mut || {
        write_solution_vtu(dir, &mesh, &fields, case.output.vtu, "0", &[], &[]).map(|_| ())
    })?;
    if case.output.writes_csv() {
        timed("nodes.csv", &mut || {
            write_nodes_csv(dir, &mesh, &fields).map(|_| ())
        })?;
    }
    timed("input hash", &mut || {
        input_hash(case);
        Ok(())
    })?;
    with_outcome_data(outcome, |data| {
        let maps = plots.plots.iter().any(|k| *k != PlotKind::Profile);
        let mut layout = None;
        if maps {
            timed("picture layout", &mut || {
                layout = Some(memcontact_plot::MapLayout::new(data));
                Ok(())
            })?;
        }
        for &kind in &plots.plots {
            timed(&kind.file_name(), &mut || {
                let picture = match &layout {
                    Some(l) if kind != PlotKind::Profile => {
                        memcontact_plot::render_kind(kind, l, data, plots)?
                    }
                    _ => {
                        let one = PlotOptions {
                            plots: vec![kind],
                            ..plots.clone()
                        };
                        render(data, &one)?.pop().expect("one picture")
                    }
                };
                write_png(&dir.join(kind.file_name()), &picture.canvas)
            })?;
        }
        timed("picture records", &mut || {
            for kind in &plots.plots {
                file_record(&dir.join(kind.file_name()))?;
            }
            Ok(())
        })
    })?;
    Ok(parts)
}

/// One picture of the fields of a result on `mesh`, drawn in memory as PNG bytes (the same
/// bytes as the file of a result set drawn with `options`): for a notebook's display.
pub fn render_png(
    mesh: &Mesh,
    fields: &NodalFields,
    options: &PlotOptions,
    kind: PlotKind,
) -> Result<Vec<u8>> {
    let options = PlotOptions {
        plots: vec![kind],
        ..options.clone()
    };
    with_plot_data(mesh, fields, |data| {
        let pictures = render(data, &options)?;
        let picture = pictures
            .first()
            .ok_or_else(|| Error::Data("no picture was drawn".into()))?;
        Ok(picture.canvas.encode_png()?)
    })
}

/// The file name of the mesh picture of an adaptive run.
pub const MESH_PICTURE: &str = "mesh.png";

/// The pictures of an adaptive run's final step (the `extra` files of
/// [`crate::adapt::AdaptSet::finish`]): those of `options`, and, when it draws any,
/// `mesh.png`, the final mesh's edges with the outline of the contact zone (of each
/// body's, with a body below).
pub fn adapt_pictures<'a>(
    mesh: &'a Mesh,
    options: &'a PlotOptions,
) -> impl FnMut(&Path, &NodalFields) -> Result<Vec<String>> + 'a {
    let mut maps = pictures(mesh, options);
    move |dir: &Path, fields: &NodalFields| {
        let mut names = maps(dir, fields)?;
        if options.plots.is_empty() {
            return Ok(names);
        }
        let contact: Vec<bool> = fields.state.iter().map(|&s| s >= 0).collect();
        let contact_low: Option<Vec<bool>> = fields
            .lower
            .as_ref()
            .map(|l| l.state.iter().map(|&s| s >= 0).collect());
        let title = format!("Mesh: {}", options.title.as_deref().unwrap_or(""));
        let picture = memcontact_plot::mesh_plot(
            &mesh.points,
            &mesh.triangles,
            &contact,
            contact_low.as_deref(),
            &title,
            &options.units,
        )?;
        write_png(&dir.join(MESH_PICTURE), &picture)?;
        names.push(MESH_PICTURE.to_string());
        Ok(names)
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
    let mut draw = outcome_pictures(outcome, plots);
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
            force: false,
            started: now
                .checked_sub(Duration::from_secs_f64(seconds.max(0.0)))
                .unwrap_or(now),
            plot_options: serde_json::to_value(&plots).ok(),
            // The set's own run id (SweepSet::write_step).
            run_id: None,
            cell_data: Vec::new(),
            adapt: None,
            unconverged: false,
        };
        let mut draw = outcome_pictures(outcome, &plots);
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
    let picture = render_line_plot(&LinePlot {
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
    })?;
    write_png(path, &picture)
}

/// The pictures of a convergence study, drawn into `dir` (the `pictures` of
/// [`super::write_study`]): `convergence.png` (the L² and H¹ errors of every
/// variant against l_n, reference slopes 1 and 2) or, for the rigid-limit sweep,
/// `h_sweep.png` (the distances to the rigid solution against h, reference slopes −½ and
/// −1). `file_name` (the case file's name) titles them. Returns the names written.
pub fn study_pictures(dir: &Path, outcome: &StudyOutcome, file_name: &str) -> Result<Vec<String>> {
    match &outcome.result {
        StudyResult::Convergence(studies) => {
            let mut series = Vec::new();
            for (v, s) in studies {
                let suffix = if v.name.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", v.name)
                };
                let pts = |f: &dyn Fn(&LevelResult) -> Option<f64>| -> Vec<(f64, f64)> {
                    s.levels
                        .iter()
                        .filter_map(|r| f(r).map(|e| (r.l_n, e)))
                        .collect()
                };
                series.push((
                    format!("L² error{suffix}"),
                    pts(&|r| r.errors.map(|e| e.l2)),
                ));
                series.push((
                    format!("H¹ error{suffix}"),
                    pts(&|r| r.errors.map(|e| e.h1_semi)),
                ));
            }
            let picture = memcontact_plot::loglog_plot(
                &format!("Convergence: {file_name}"),
                "mesh size lₙ",
                if outcome.exact.is_some() {
                    "error against the exact solution"
                } else {
                    "error against the reference solution"
                },
                &series,
                &[1.0, 2.0],
            )?;
            write_png(&dir.join(CONVERGENCE_PICTURE), &picture)?;
            Ok(vec![CONVERGENCE_PICTURE.to_string()])
        }
        StudyResult::RigidLimit {
            sweep,
            exact_distance,
            ..
        } => {
            let mut series = vec![
                (
                    "max nodal |u_h(h) − u_h(∞)|".to_string(),
                    sweep.rows.iter().map(|r| (r.h, r.max_nodal)).collect(),
                ),
                (
                    "H¹ seminorm".to_string(),
                    sweep.rows.iter().map(|r| (r.h, r.h1_semi)).collect(),
                ),
            ];
            if exact_distance.iter().any(Option::is_some) {
                series.push((
                    "exact max |u(h) − u(∞)|".to_string(),
                    sweep
                        .rows
                        .iter()
                        .zip(exact_distance)
                        .filter_map(|(r, c)| c.map(|c| (r.h, c)))
                        .collect(),
                ));
            }
            let picture = memcontact_plot::loglog_plot(
                &format!("Rigid limit: {file_name}"),
                "stiffness h",
                "distance to the rigid solution",
                &series,
                &[-0.5, -1.0],
            )?;
            write_png(&dir.join(H_SWEEP_PICTURE), &picture)?;
            Ok(vec![H_SWEEP_PICTURE.to_string()])
        }
    }
}

/// The file name of a convergence study's picture.
pub const CONVERGENCE_PICTURE: &str = "convergence.png";

/// The file name of a rigid-limit sweep's picture.
pub const H_SWEEP_PICTURE: &str = "h_sweep.png";
