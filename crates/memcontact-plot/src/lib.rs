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
//! With a body below the membrane ([`PlotData::lower`]), every picture tells the two
//! bodies apart: each body's contact zone outlined (the obstacle's solid, the body
//! below's dashed) and named, on the lift-off map each body's contact and each body's gap
//! in its own colours, in the profile both surfaces and each body's contact stretches.
//!
//! Maps are rasterised here (every pixel centre interpolates the nodal field in the
//! triangle that covers it, see [`raster`]), in parallel and deterministically, so that a
//! mesh of a million vertices is drawn in a fraction of a second. Also here: the log-log
//! convergence plot and an x-y line plot (e.g. a force-deflection curve).
//!
//! The crate only draws: it takes plain arrays (points, triangles, nodal fields) and gives
//! back pictures in memory ([`Canvas`], PNG bytes). It knows nothing of cases, solvers or
//! files; the `memcontact` library writes the pictures into its result sets and redraws
//! them from a result directory. It prints nothing: errors are returned.

pub mod axes;
pub mod canvas;
pub mod colormap;
pub mod fit_plot;
pub mod lines;
pub mod loglog;
mod maps;
pub mod profile;
pub mod raster;
pub mod segment;
pub mod text;

#[cfg(test)]
mod numbering_tests;
pub mod ticks;

pub use axes::{hatch_color, HATCH_SPACING};
pub use canvas::{Canvas, PixelRect};
pub use fit_plot::{render_fit_plot, FitPlot, FitSensor, FIT_HEIGHT, FIT_WIDTH};
pub use lines::{render_line_plot, LinePlot, Series};
pub use loglog::loglog_plot;
pub use maps::{
    field_plot, mesh_plot, MapLayout, Picture, CONTACT, LOWER_CONTACT, LOWER_OUTLINE,
    LOWER_PRESSURE_OUTLINE, NOT_COVERED, OUTLINE, PRESSURE_OUTLINE,
};
pub use raster::MapTransform;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Why a picture could not be drawn: the data or options at fault, named.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// Bad data or options (lengths, indices, non-finite values, an empty plot).
    Data(String),
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Data(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {}

/// The result of drawing.
pub type Result<T> = std::result::Result<T, Error>;

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
    /// The body below the membrane's fields, when there is one (the membrane between two
    /// bodies): then each picture draws each body's contact separately.
    pub lower: Option<BodyData<'a>>,
    /// For data renumbered for locality, the user's numbering of its vertices and
    /// triangles; `None` for data in the user's own numbering. See [`UserNumbering`].
    pub numbering: Option<UserNumbering<'a>>,
}

/// The user's numbers of the vertices and triangles of a [`PlotData`] renumbered for
/// memory locality (vertices along a space-filling curve): `vertices[i]` is the user's
/// number of vertex `i`, `triangles[k]` that of triangle `k` (each a permutation).
///
/// A mesh numbered in a scattered order (a mesh generator's, which a million-vertex
/// mesh's pictures read with a cache miss at every vertex) is drawn several times faster
/// renumbered. Wherever the pictures depend on the numbering, they follow these numbers:
/// an edge's function and a level line's crossing are computed from the end with the
/// lower user number, level lines are listed in the user's triangle order, ties along the
/// profile go to the lower user triangle, overlapping triangles to the higher, and errors
/// name the user's numbers. The pictures are therefore the same as those drawn from the
/// data in the user's numbering, pixel for pixel; only the areas in the lift-off map's
/// legend (shown to four digits) are summed in the data's order, so their last bits
/// may differ.
#[derive(Debug, Clone, Copy)]
pub struct UserNumbering<'a> {
    /// The user's number of every vertex.
    pub vertices: &'a [u32],
    /// The user's number of every triangle.
    pub triangles: &'a [u32],
}

impl UserNumbering<'_> {
    /// The user's number of vertex `v` under `numbering` (`v` itself without one).
    #[inline]
    pub fn vertex(numbering: Option<UserNumbering>, v: u32) -> u32 {
        numbering.map_or(v, |n| n.vertices[v as usize])
    }

    /// The user's number of triangle `t` under `numbering` (`t` itself without one).
    #[inline]
    pub fn triangle(numbering: Option<UserNumbering>, t: u32) -> u32 {
        numbering.map_or(t, |n| n.triangles[t as usize])
    }
}

/// The fields of the body below the membrane (surface φ_low, reaction pushing up where
/// the membrane sinks into it), borrowed, one value per mesh vertex.
#[derive(Debug, Clone, Copy)]
pub struct BodyData<'a> {
    /// Its surface φ_low (sampled at the vertices).
    pub phi: &'a [f64],
    /// Vertex state: −1 clear (u > φ_low), 0 touching (u = φ_low), 1 sunk in (u < φ_low).
    pub state: &'a [i8],
    /// Its contact pressure (≥ 0, pushing up).
    pub pressure: &'a [f64],
    /// Where it lies under the membrane and can touch it.
    pub covered: &'a [bool],
}

impl PlotData<'_> {
    /// Checks lengths, indices, states and finiteness, naming what is wrong.
    pub fn validate(&self) -> Result<()> {
        let n = self.points.len();
        if n == 0 || self.triangles.is_empty() {
            return Err(Error::Data("plot: the mesh has no triangle to draw".into()));
        }
        let mut lengths = vec![
            ("u", self.u.len()),
            ("phi", self.phi.len()),
            ("state", self.state.len()),
            ("pressure", self.pressure.len()),
            ("covered", self.covered.len()),
        ];
        if let Some(l) = &self.lower {
            lengths.extend([
                ("phi_low", l.phi.len()),
                ("state_low", l.state.len()),
                ("pressure_low", l.pressure.len()),
                ("covered_low", l.covered.len()),
            ]);
        }
        for (name, len) in lengths {
            if len != n {
                return Err(Error::Data(format!(
                    "plot: field `{name}` has {len} values, the mesh has {n} vertices"
                )));
            }
        }
        if let Some(num) = &self.numbering {
            let nt = self.triangles.len();
            let within =
                |a: &[u32], len: usize| a.len() == len && a.iter().all(|&x| (x as usize) < len);
            if !(within(num.vertices, n) && within(num.triangles, nt)) {
                return Err(Error::Data(format!(
                    "plot: the user numbering is not one of the {n} vertices and {nt} triangles"
                )));
            }
        }
        let user = |i: usize| UserNumbering::vertex(self.numbering, i as u32);
        // The first offending vertex or triangle in the user's numbering.
        let first = |len: usize, bad: &dyn Fn(usize) -> bool, number: &dyn Fn(usize) -> u32| {
            (0..len).filter(|&i| bad(i)).min_by_key(|&i| number(i))
        };
        let vertex = |bad: &dyn Fn(usize) -> bool| first(n, bad, &|i| user(i));
        if let Some(k) = first(
            self.triangles.len(),
            &|k| self.triangles[k].iter().any(|&v| v as usize >= n),
            &|k| UserNumbering::triangle(self.numbering, k as u32),
        ) {
            let t = self.triangles[k].map(|v| {
                if (v as usize) < n {
                    user(v as usize)
                } else {
                    v
                }
            });
            return Err(Error::Data(format!(
                "plot: triangle {} {t:?} refers to a vertex beyond the {n} vertices",
                UserNumbering::triangle(self.numbering, k as u32)
            )));
        }
        if let Some(i) = vertex(&|i| {
            let p = self.points[i];
            !(p[0].is_finite() && p[1].is_finite())
        }) {
            return Err(Error::Data(format!(
                "plot: vertex {} has a non-finite coordinate",
                user(i)
            )));
        }
        if let Some(i) = vertex(&|i| !(-1..=1).contains(&self.state[i])) {
            return Err(Error::Data(format!(
                "plot: vertex {} has state {} (expected -1, 0 or 1)",
                user(i),
                self.state[i]
            )));
        }
        if let Some(l) = &self.lower {
            if let Some(i) = vertex(&|i| !(-1..=1).contains(&l.state[i])) {
                return Err(Error::Data(format!(
                    "plot: vertex {} has state_low {} (expected -1, 0 or 1)",
                    user(i),
                    l.state[i]
                )));
            }
        }
        if let Some(i) = vertex(&|i| !self.u[i].is_finite()) {
            return Err(Error::Data(format!(
                "plot: u is not finite at vertex {}",
                user(i)
            )));
        }
        Ok(())
    }

    /// True when vertex `i` is in contact with a body (touching or penetrating either).
    pub fn in_contact(&self, i: usize) -> bool {
        self.state[i] >= 0 || self.lower.is_some_and(|l| l.state[i] >= 0)
    }

    /// True when vertex `i` penetrates a body (u > φ, or u < φ_low).
    pub fn penetrating(&self, i: usize) -> bool {
        self.state[i] == 1 || self.lower.is_some_and(|l| l.state[i] == 1)
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
