//! # memcontact
//!
//! Contact between a stretched membrane and an elastic (tensionless Winkler) obstacle,
//! discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model for the
//! contact problem between a membrane and an elastic obstacle", Rend. Lincei 80 (1986).
//!
//! The library owns the run; data flows one way, each layer importing only those below it:
//!
//! ```text
//! case ──► problem ──► discretization ──► model ──► certificate, solve ──► outcome ──► write
//! (TOML,    (pure       (meshes, levels,     (S, L, D,   (2e/2f; every       (fields,    (VTU, CSV,
//!  sweeps,   data,       numbering, data      φₙ, M,      formulation of      totals,     JSON: result
//!  output)   validate)   bound to the mesh)   checks)     the paper)          summary)    sets)
//! ```
//!
//! - [`mod@run`] holds the only places that run: [`run::run`] (a case of one step),
//!   [`run::run_sweep`] (its load steps or load cases in turn), [`run::run_adapt`] (the
//!   adaptive loop: solve, [`estimate`], mark and bisect in [`mesh`], solve again),
//!   [`run::run_sensitivity`] and [`run::run_fit`] (derivatives of outputs in case keys
//!   through the contact, [`sensitivity`], and the back-analysis of parameters from
//!   measured deflections, [`fit`]), and, beside the pipeline,
//!   [`verify::study::run_study`] (a convergence study with the exact solutions of
//!   [`verify::exact`] and the norms of [`verify::norms`]). The command-line tool and the
//!   Python module call these and the writers of [`mod@write`]; they run nothing themselves.
//! - Below the pipeline: [`mesh`] (meshes, generators, refinement, bisection and marking,
//!   renumbering), [`field`]
//!   (the data f, φ, h and their expressions), [`fem`] (P1 elements), [`io`] (Gmsh, VTU,
//!   CSV, JSON, atomic result sets), [`sparse`], [`quadrature`], [`limits`] (memory),
//!   [`parallel`] (the worker pool and the cancellation token), [`error`].

pub mod case;
pub mod certificate;

pub mod discretization;
pub mod error;
pub mod estimate;

pub mod fem;
pub mod field;
pub mod fit;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod model;
pub mod outcome;
pub mod parallel;
pub mod problem;
pub mod quadrature;
pub mod run;
pub mod sensitivity;
pub mod solve;
pub mod sparse;
pub mod verify;
pub mod write;

pub use case::Case;
pub use discretization::Discretization;
pub use error::{Error, Invalid, Result};
pub use outcome::{Outcome, Report, Summary};
pub use parallel::{on_workers, Cancel};
pub use problem::Problem;
pub use run::run;
pub use solve::{Method, Observer, Settings, Status};
