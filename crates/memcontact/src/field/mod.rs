//! Scalar problem data of the physical problem (docs/theory.md#physics): the load `f`, the
//! obstacle surface `φ` and the foundation stiffness `h` (with the rigid limit `h → ∞`).
//!
//! A [`Field`] is what a case file says: a number, an [`Expr`] of `x, y`, or a table of
//! values per named mesh region. [`Field::bind`] resolves it against a mesh's regions once
//! and gives a [`BoundField`] that assembly evaluates at quadrature points (and asks
//! whether it is constant on a region, to skip quadrature). [`check_values`] validates
//! sampled values (`h ≥ 0`, no NaN, ...) and says where a bad value sits.

mod bind;
mod coefficient;
pub(crate) mod expr;
pub(crate) mod nodal;
mod serde;
#[cfg(test)]
mod tests;
mod value;

pub use bind::{BoundField, BoundStiffness};
pub use coefficient::{Coefficient, FnCoefficient};
pub use expr::Expr;
pub use value::{check_value, check_values, Field, Rule, Stiffness, DEFAULT_KEY};
