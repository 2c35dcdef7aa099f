//! Problem 2c by the Clarabel interior-point solver. (In progress.)

use super::{Settings, Solution};
use crate::model::Model;
use crate::{Error, Result};

/// Solves Problem 2c with Clarabel.
pub fn solve(_model: &Model, _settings: &Settings) -> Result<Solution> {
    Err(Error::Solver {
        solver: "qp".into(),
        message: "not available yet".into(),
    })
}
