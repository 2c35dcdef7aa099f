//! Truncated nonsmooth Newton multigrid. (In progress.)

use super::{Observer, Settings, Solution};
use crate::mesh::refine::Hierarchy;
use crate::model::Model;
use crate::{Error, Result};

/// Solves Problem 2b by truncated nonsmooth Newton multigrid.
pub fn solve(
    _model: &Model,
    _hierarchy: &Hierarchy,
    _settings: &Settings,
    _observer: &mut dyn Observer,
) -> Result<Solution> {
    Err(Error::Solver {
        solver: "multigrid".into(),
        message: "not available yet".into(),
    })
}
