//! `[output]` and `[units]`: which files and pictures a run writes, and the names of the
//! case's units for their labels.

use crate::error::Invalid;
use serde::{Deserialize, Serialize};

/// `[units]`: the names of the length and force units the case's numbers are in (the
/// solver does not convert; pictures label their axes and colour bars with them).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Length (mesh coordinates, u, φ), e.g. `"m"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    /// Force, e.g. `"kN"` (t in force/length, f and pressures in force/length²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<String>,
}

/// `[output]`: what `solve` writes besides `solution.vtu`, `nodes.csv` and `summary.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputOptions {
    /// The encoding of `solution.vtu`.
    #[serde(default)]
    pub vtu: VtuFormat,
    /// `false`: no `nodes.csv` (the node table of a large mesh takes gigabytes); default
    /// `true`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub csv: Option<bool>,
    /// The pictures to draw (default: all four; `[]`: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plots: Option<Vec<PictureKind>>,
    /// `false`: no pictures (the same as `plots = []`); `true`: the default pictures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plot: Option<bool>,
    /// The allowable contact pressure (force/length²): `pressure.png` then maps
    /// pressure / allowable and outlines the area above 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub allowable_pressure: Option<f64>,
    /// The line of `profile.png`, `[[x0, y0], [x1, y1]]` (default: horizontally through
    /// the middle of the domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<[[f64; 2]; 2]>,
    /// With `[adapt]`: also write each step's result set, in `step-K/`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_steps: bool,
}

/// A picture `solve` can draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PictureKind {
    /// `deflection.png`: u with contours and the contact zone.
    Deflection,
    /// `pressure.png`: the contact pressure (or its ratio to the allowable).
    Pressure,
    /// `liftoff.png`: where the membrane is clear of the body it could touch.
    Liftoff,
    /// `profile.png`: u and φ along a line.
    Profile,
}

impl PictureKind {
    /// All four, in order.
    pub const ALL: [PictureKind; 4] = [
        PictureKind::Deflection,
        PictureKind::Pressure,
        PictureKind::Liftoff,
        PictureKind::Profile,
    ];

    /// The name in case files (and the file name without `.png`).
    pub fn name(self) -> &'static str {
        match self {
            PictureKind::Deflection => "deflection",
            PictureKind::Pressure => "pressure",
            PictureKind::Liftoff => "liftoff",
            PictureKind::Profile => "profile",
        }
    }
}

impl OutputOptions {
    /// Whether `nodes.csv` is written (`[output] csv`, default true).
    pub fn writes_csv(&self) -> bool {
        self.csv.unwrap_or(true)
    }

    /// The pictures to draw.
    pub fn pictures(&self) -> Vec<PictureKind> {
        match (&self.plots, self.plot) {
            (Some(p), _) => p.clone(),
            (None, Some(false)) => Vec::new(),
            (None, _) => PictureKind::ALL.to_vec(),
        }
    }

    pub(crate) fn validate(&self) -> std::result::Result<(), Invalid> {
        if let (Some(p), Some(false)) = (&self.plots, self.plot) {
            if !p.is_empty() {
                return Err(Invalid::new(
                    "output.plot",
                    "plot = false contradicts the pictures listed in output.plots",
                ));
            }
        }
        if let Some(p) = &self.plots {
            for (i, k) in p.iter().enumerate() {
                if p[..i].contains(k) {
                    return Err(Invalid::new(
                        "output.plots",
                        format!("\"{}\" is listed twice", k.name()),
                    ));
                }
            }
        }
        if let Some(a) = self.allowable_pressure {
            if !(a.is_finite() && a > 0.0) {
                return Err(Invalid::new(
                    "output.allowable_pressure",
                    format!("must be a finite number > 0, got {a}"),
                ));
            }
        }
        if let Some([p, q]) = self.profile {
            if !p.iter().chain(&q).all(|v| v.is_finite()) || p == q {
                return Err(Invalid::new(
                    "output.profile",
                    format!("must be two distinct finite points, got {p:?}, {q:?}"),
                ));
            }
        }
        Ok(())
    }
}

/// The encoding of `solution.vtu`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VtuFormat {
    /// Raw appended binary (fast, compact).
    #[default]
    Binary,
    /// Text.
    Ascii,
    /// Raw appended binary compressed with zlib in blocks, as ParaView reads it (smaller,
    /// slower to write).
    Compressed,
}
