//! # memcontact-plot
//!
//! Pictures of a solved membrane contact problem (the discrete model of Maceri & Maceri,
//! 1986), as PNG files readable in a report:
//!
//! * `deflection.png`: the deflection u as a smooth colour map with labelled contour lines,
//!   the contact zone outlined and hatched (penetrating and touching vertices told apart);
//! * `pressure.png`: the contact pressure h(u − φ)⁺ (for a rigid obstacle the nodal contact
//!   force per nodal area), or the ratio pressure / allowable with the area above 1
//!   outlined;
//! * `liftoff.png`: where the membrane is clear of the body over the area the body covers,
//!   with the gap φ − u there;
//! * `profile.png`: u and φ along a line against arc length, contact stretches shaded.
//!
//! Maps are rasterised here (every pixel centre interpolates the nodal field in the
//! triangle that covers it, see [`raster`]), in parallel and deterministically, so that a
//! mesh of a million vertices is drawn in a fraction of a second. Also here: the log-log
//! convergence plot and an x-y line plot (e.g. a force-deflection curve), and a reader for
//! the VTU files the library writes, so that pictures can be redrawn from a result
//! directory ([`result`]), and the writers of result sets with their pictures, single
//! solves and sweeps alike ([`write`]).
//!
//! The crate prints nothing: errors are returned, notes are handed back to the caller.

pub mod axes;
pub mod bodies;
pub mod canvas;
pub mod colormap;
pub mod fit_plot;
pub mod lines;
pub mod loglog;
mod maps;
pub mod profile;
pub mod raster;
pub mod result;
pub mod text;
pub mod ticks;
pub mod vtu;
pub mod write;

pub use axes::{hatch_color, HATCH_SPACING};
pub use canvas::{Canvas, PixelRect};
pub use fit_plot::{fit_plot, FIT_PICTURE};
pub use lines::{line_plot, LinePlot, Series};
pub use loglog::loglog_plot;
pub use maps::{
    field_plot, mesh_plot, MapLayout, Picture, CONTACT, NOT_COVERED, OUTLINE, PRESSURE_OUTLINE,
};
pub use raster::MapTransform;

use memcontact::{Error, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Width of the map pictures (deflection, pressure, lift-off), pixels.
pub const MAP_WIDTH: u32 = 1300;
/// Height of the map pictures, pixels.
pub const MAP_HEIGHT: u32 = 950;
/// Width of the profile picture, pixels.
pub const PROFILE_WIDTH: u32 = 1300;
/// Height of the profile picture, pixels.
pub const PROFILE_HEIGHT: u32 = 700;

/// One of the pictures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlotKind {
    /// `deflection.png`.
    Deflection,
    /// `pressure.png`.
    Pressure,
    /// `liftoff.png`.
    Liftoff,
    /// `profile.png`.
    Profile,
}

impl PlotKind {
    /// All four, in the order they are drawn.
    pub const ALL: [PlotKind; 4] = [
        PlotKind::Deflection,
        PlotKind::Pressure,
        PlotKind::Liftoff,
        PlotKind::Profile,
    ];

    /// The name in case files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PlotKind::Deflection => "deflection",
            PlotKind::Pressure => "pressure",
            PlotKind::Liftoff => "liftoff",
            PlotKind::Profile => "profile",
        }
    }

    /// The file name, `<name>.png`.
    pub fn file_name(self) -> String {
        format!("{}.png", self.name())
    }
}

impl std::str::FromStr for PlotKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<PlotKind> {
        PlotKind::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| {
                Error::Data(format!(
                    "unknown plot \"{s}\": expected deflection, pressure, liftoff or profile"
                ))
            })
    }
}

/// Units of the case, for axis and colour-bar labels ("m", "kN"); `None` leaves them out.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Units {
    /// Length unit (of x, y, u, φ).
    pub length: Option<String>,
    /// Force unit (pressure is force per length²).
    pub force: Option<String>,
}

impl Units {
    /// `" [m]"`, or nothing without a length unit.
    pub fn length_suffix(&self) -> String {
        match &self.length {
            Some(l) if !l.trim().is_empty() => format!(" [{}]", l.trim()),
            _ => String::new(),
        }
    }

    /// `" [kN/m²]"`, or nothing unless both units are known.
    pub fn pressure_suffix(&self) -> String {
        match (&self.length, &self.force) {
            (Some(l), Some(f)) if !l.trim().is_empty() && !f.trim().is_empty() => {
                format!(" [{}/{}²]", f.trim(), l.trim())
            }
            _ => String::new(),
        }
    }

    /// `" [kN]"`, or nothing without a force unit.
    pub fn force_suffix(&self) -> String {
        match &self.force {
            Some(f) if !f.trim().is_empty() => format!(" [{}]", f.trim()),
            _ => String::new(),
        }
    }
}

fn default_plots() -> Vec<PlotKind> {
    PlotKind::ALL.to_vec()
}

/// What to draw and how (the `[output]` keys of a case; serialised into `summary.json` so
/// that `memcontact plot` redraws the same pictures).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlotOptions {
    /// The pictures to draw (default: all four; empty: none).
    pub plots: Vec<PlotKind>,
    /// The allowable contact pressure: with it, `pressure.png` maps pressure / allowable
    /// and outlines the area above 1.
    pub allowable_pressure: Option<f64>,
    /// The profile line `[[x0, y0], [x1, y1]]` (default: horizontally through the middle of
    /// the mesh's bounding box).
    pub profile: Option<[[f64; 2]; 2]>,
    /// Units for the labels.
    pub units: Units,
    /// The case's name, shown in every title.
    pub title: Option<String>,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            plots: default_plots(),
            allowable_pressure: None,
            profile: None,
            units: Units::default(),
            title: None,
        }
    }
}

impl PlotOptions {
    /// Checks the values: a finite allowable pressure > 0, a profile of two distinct finite
    /// points, no picture asked for twice.
    pub fn validate(&self) -> Result<()> {
        if let Some(a) = self.allowable_pressure {
            if !(a.is_finite() && a > 0.0) {
                return Err(Error::Data(format!(
                    "allowable_pressure must be a finite number > 0, got {a}"
                )));
            }
        }
        if let Some([p, q]) = self.profile {
            if !p.iter().chain(&q).all(|v| v.is_finite()) || p == q {
                return Err(Error::Data(format!(
                    "profile must be two distinct points [[x0, y0], [x1, y1]] with finite \
                     coordinates, got {:?}",
                    [p, q]
                )));
            }
        }
        for (i, k) in self.plots.iter().enumerate() {
            if self.plots[..i].contains(k) {
                return Err(Error::Data(format!("plots lists \"{}\" twice", k.name())));
            }
        }
        Ok(())
    }
}

/// The result fields to draw, borrowed (one value per mesh vertex).
#[derive(Debug, Clone, Copy)]
pub struct PlotData<'a> {
    /// Vertex coordinates.
    pub points: &'a [[f64; 2]],
    /// Triangles (three vertex indices).
    pub triangles: &'a [[u32; 3]],
    /// Deflection u.
    pub u: &'a [f64],
    /// Obstacle surface φ (sampled at the vertices).
    pub phi: &'a [f64],
    /// Vertex state: −1 clear, 0 touching (u = φ), 1 penetrating (u > φ).
    pub state: &'a [i8],
    /// Contact pressure h(u − φ)⁺, or for a rigid obstacle the nodal contact force per
    /// nodal area.
    pub pressure: &'a [f64],
    /// Where the body can touch the membrane (the set M of the paper's problem 2b).
    pub covered: &'a [bool],
}

impl PlotData<'_> {
    /// Checks lengths, indices, states and finiteness, naming what is wrong.
    pub fn validate(&self) -> Result<()> {
        let n = self.points.len();
        if n == 0 || self.triangles.is_empty() {
            return Err(Error::Data("plot: the mesh has no triangle to draw".into()));
        }
        for (name, len) in [
            ("u", self.u.len()),
            ("phi", self.phi.len()),
            ("state", self.state.len()),
            ("pressure", self.pressure.len()),
            ("covered", self.covered.len()),
        ] {
            if len != n {
                return Err(Error::Data(format!(
                    "plot: field `{name}` has {len} values, the mesh has {n} vertices"
                )));
            }
        }
        if let Some((k, t)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(Error::Data(format!(
                "plot: triangle {k} {t:?} refers to a vertex beyond the {n} vertices"
            )));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::Data(format!(
                "plot: vertex {i} has a non-finite coordinate"
            )));
        }
        if let Some(i) = self.state.iter().position(|s| !(-1..=1).contains(s)) {
            return Err(Error::Data(format!(
                "plot: vertex {i} has state {} (expected -1, 0 or 1)",
                self.state[i]
            )));
        }
        if let Some(i) = self.u.iter().position(|v| !v.is_finite()) {
            return Err(Error::Data(format!("plot: u is not finite at vertex {i}")));
        }
        Ok(())
    }

    /// The bounding box `[xmin, xmax, ymin, ymax]` of the triangles' vertices.
    pub fn bbox(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in self.points {
            b = [
                b[0].min(p[0]),
                b[1].max(p[0]),
                b[2].min(p[1]),
                b[3].max(p[1]),
            ];
        }
        if b[1].partial_cmp(&b[0]) != Some(std::cmp::Ordering::Greater) {
            b[0] -= 0.5;
            b[1] += 0.5;
        }
        if b[3].partial_cmp(&b[2]) != Some(std::cmp::Ordering::Greater) {
            b[2] -= 0.5;
            b[3] += 0.5;
        }
        b
    }
}

/// Draws the pictures `options.plots` in memory, in that order.
pub fn render(data: &PlotData, options: &PlotOptions) -> Result<Vec<Picture>> {
    data.validate()?;
    options.validate()?;
    let maps = options.plots.iter().any(|k| *k != PlotKind::Profile);
    let layout = maps.then(|| MapLayout::new(data));
    options
        .plots
        .par_iter()
        .map(|&kind| match kind {
            PlotKind::Profile => profile::render(data, options),
            k => maps::render(k, layout.as_ref().expect("map layout"), data, options),
        })
        .collect()
}

/// Draws one picture in memory on a layout made once by [`MapLayout::new`] (maps share it;
/// the profile does not use it): for callers that time or reuse the pieces.
pub fn render_kind(
    kind: PlotKind,
    layout: &MapLayout,
    data: &PlotData,
    options: &PlotOptions,
) -> Result<Picture> {
    data.validate()?;
    options.validate()?;
    match kind {
        PlotKind::Profile => profile::render(data, options),
        k => maps::render(k, layout, data, options),
    }
}

/// Draws the pictures `options.plots` into `dir` (`deflection.png`, `pressure.png`,
/// `liftoff.png`, `profile.png`), each written atomically; returns the files written.
pub fn draw_all(dir: &Path, data: &PlotData, options: &PlotOptions) -> Result<Vec<PathBuf>> {
    let pictures = render(data, options)?;
    pictures
        .par_iter()
        .map(|p| {
            let path = dir.join(p.kind.file_name());
            p.canvas.write_png(&path)?;
            Ok(path)
        })
        .collect()
}
