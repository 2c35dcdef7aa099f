//! The discrete model of the paper's §2 (docs/theory.md#discrete-model): the stiffness
//! matrix S, the h-weighted foundation matrix L (consistent, or its lumped variant), the
//! load D, the sampled obstacle φₙ and the set M of vertices that can touch; the energy J
//! of Problem 2b and the certificates of Problems 2e and 2f.

mod assemble;
mod body;
mod boundary;
mod checks;
mod data;
mod derivative;
mod sampling;
mod system;
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests;

pub use body::{Body, FoundationMatrix, VertexValues};
pub use boundary::{fixed_heights, fixed_heights_on};
pub use checks::{
    assemble_checked, assemble_checked_on, check_boundary_data, check_model, OVERFLOW_HINT,
};
pub use data::{
    BodyData, BodyStiffness, BoundaryData, Extensions, Foundation, ProblemData, Sampling,
};
pub(crate) use derivative::{consistent_foundation_form, DerivativeAssembly};
pub use sampling::paper_epsilon;
pub use system::Model;
