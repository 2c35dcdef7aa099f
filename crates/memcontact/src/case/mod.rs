//! The case: what a case file (TOML), a Rust program or a Python dict says, as owned serde
//! values. Everything deserialises into the same [`Case`]; unknown keys and bad values are
//! refused here, before any work, with the key (and, for a file, the file and line).
//!
//! A [`Case`] is a [`crate::problem::Problem`], the solver [`crate::solve::Settings`], the
//! [`OutputOptions`], the [`ExactSpec`] of a closed-form solution for convergence studies,
//! the steps of a load sweep or of load combinations, and the [`Sensor`]s, the
//! [`SensitivitySpec`] and the [`FitSpec`] of a sensitivity run or a fit.

mod adapt;
mod exact;
mod file;
pub mod keys;
mod output;
mod overrides;
pub(crate) mod sensitivity;
mod sweep;
#[cfg(test)]
mod tests;

pub use crate::io::input::CASE_FILE_CAP;
pub use adapt::AdaptSpec;
pub use exact::{BenchmarkBody, ExactSpec, ManufacturedDomain, ManufacturedForm};
pub use file::{read_case_text, steps, Case};
pub use output::{OutputOptions, PictureKind, Units, VtuFormat};
pub use overrides::apply_overrides;
pub use sensitivity::{
    FitParameters, FitSpec, ParameterKey, ParameterKind, ParameterTarget, SensitivitySpec, Sensor,
};
pub use sweep::{
    step_list, validate_steps, LoadCase, StepSpec, SweepParameter, SweepSpec, MAX_STEPS,
};
