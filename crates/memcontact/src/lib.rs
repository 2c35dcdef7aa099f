//! # memcontact
//!
//! Contact between a stretched membrane and an elastic (tensionless Winkler) obstacle,
//! discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model for the
//! contact problem between a membrane and an elastic obstacle", Rend. Lincei 80 (1986).
//!
//! Data flows one way: [`field`] data and a [`mesh::Mesh`] build a [`model::Model`]
//! (S, L, D, φₙ of the paper's §2), a [`solve`] method returns a [`solve::Solution`],
//! and [`results`] derives the physical fields that the [`io`] writers store.

pub mod certificate;

pub mod convergence;
pub mod error;
pub mod errors;
pub mod exact;
pub mod fem;
pub mod field;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod model;
pub mod outcome;
pub mod output;
pub mod parallel;
pub mod problem;
pub mod quadrature;
pub mod results;
pub mod run;
pub mod solve;
pub mod sparse;
pub mod summary;
pub mod sweep;

pub use error::{Error, Invalid, Result};
pub use parallel::on_workers;
pub use problem::{Case, Problem};
pub use run::{run, Discretization, Outcome, Report};
pub use solve::{Method, Observer, Settings, Status};
pub use summary::Summary;
