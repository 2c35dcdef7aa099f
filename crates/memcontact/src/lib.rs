//! # memcontact
//!
//! Contact between a stretched membrane and an elastic (tensionless Winkler) obstacle,
//! discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model for the
//! contact problem between a membrane and an elastic obstacle", Rend. Lincei 80 (1986).

pub mod case;
pub mod certificate;

pub mod discretization;
pub mod error;

pub mod fem;
pub mod field;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod model;
pub mod outcome;
pub mod parallel;
pub mod problem;
pub mod quadrature;
pub mod run;
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
