//! # memcontact
//!
//! Contact between a stretched membrane and an elastic (tensionless Winkler) obstacle,
//! discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model for the
//! contact problem between a membrane and an elastic obstacle", Rend. Lincei 80 (1986),
//! with every formulation of the paper as a solver and every answer certified by the
//! residuals of its Kuhn-Tucker conditions (Problems 2e and 2f). The documentation site
//! (`docs/` in the repository) explains the case file, the outputs and the theory.
//!
//! A case solved in a few lines (the case file's TOML, or [`Case`]'s fields from Rust):
//!
//! ```
//! use memcontact::{run, Case, Silent};
//!
//! let case = Case::from_toml_str(
//!     r#"
//!     [mesh]
//!     generator = "disk"
//!     size = 0.1
//!     [membrane]
//!     tension = 1.0
//!     load = 8.0
//!     [obstacle]
//!     shape = 1.0
//!     stiffness = 100.0
//!     "#,
//!     None,
//! )?;
//! let outcome = run(&case, &mut Silent)?;
//! assert!(outcome.report.accepted && outcome.report.certificate.kkt() <= 1e-10);
//! let (fields, totals) = outcome.fields();
//! assert!(fields.u.iter().any(|&u| u > 1.0) && totals.contact_area > 0.5);
//! # Ok::<(), memcontact::Error>(())
//! ```
//!
//! The library owns the run; data flows one way, each layer importing only those below it:
//!
//! ```text
//! case ──► problem ──► discretization ──► model ──► solve ──► outcome ──► write
//! (TOML,    (pure       (meshes, levels,     (S, L, D,   (every         (fields,    (VTU, CSV,
//!  sweeps,   data,       numbering, data      φₙ, M)      formulation,   totals,     JSON, PNG:
//!  output)   validate)   bound to the mesh)               certified)     summary)    result sets)
//! ```
//!
//! - [`mod@run`] holds the entry points, one per kind of run: [`run::run`] (a case of one
//!   step), [`run::run_to_files`] (the same, written as `memcontact solve` writes it),
//!   [`run::run_sweep`] (load steps or load cases in turn), [`run::run_adapt`] (the
//!   adaptive loop of [`adapt`]), [`run::run_study`] (a convergence study, with the exact
//!   solutions and norms of [`verify`]), [`run::run_sensitivity`] (derivatives of a case's
//!   outputs in its parameters, through the contact, with [`sensitivity`]),
//!   [`run::run_fit`] (parameters fitted to measured deflections, with [`fit`]) and
//!   [`run::check`] (everything a run would refuse, without solving). The command-line
//!   tool and the Python module call these and the writers of [`mod@write`]; they run
//!   nothing themselves.
//! - The data: [`case`] (the case file), [`problem`], [`field`] (numbers, expressions,
//!   region tables), [`mesh`] (meshes, generators, uniform refinement), [`io`] (Gmsh and
//!   VTU files).
//! - The results: [`outcome`] (the report, fields and totals, `summary.json`),
//!   [`discretization`] (the mesh levels and the assembled model of a run), [`solve`] (the
//!   methods, their settings and statuses), [`error`], [`limits`] (memory),
//!   [`parallel`] (the worker pool and the cancellation token).

#![warn(missing_docs)]

pub mod adapt;
pub mod case;
pub(crate) mod certificate;
pub mod discretization;
pub mod error;
pub(crate) mod fem;
pub mod field;
pub mod fit;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod model;
pub mod outcome;
pub mod parallel;
pub mod problem;
pub(crate) mod quadrature;
pub mod run;
pub mod sensitivity;
pub mod solve;
pub(crate) mod sparse;
pub mod verify;
pub mod write;

/// The building blocks the benchmark harness times one by one (assembly kernels, the
/// multigrid solver's options and kernel timings): not a stable API, behind the `bench`
/// feature.
#[cfg(feature = "bench")]
pub mod bench;

pub use case::Case;
pub use discretization::Discretization;
pub use error::{Error, Invalid, Result};
pub use outcome::{Outcome, Report, Summary};
pub use parallel::{on_workers, Cancel};
pub use problem::Problem;
pub use run::run;
pub use solve::{Method, Observer, Settings, Silent, Status};
