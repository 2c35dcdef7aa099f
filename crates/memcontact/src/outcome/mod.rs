//! The outcome of a solve: the report (status, method, certificate, iterate), the physical
//! fields and totals in the user's numbering, `summary.json`'s values, and the checks they
//! pass before anything is written.

pub(crate) mod checks;
pub mod fields;
mod report;
mod sensitivity;
mod solved;
pub mod summary;
pub mod sweep;
mod system;

pub use fields::{LowerFields, LowerTotals, NodalFields, Totals};
pub use report::Report;
pub use sensitivity::SensitivityTotals;
pub use solved::Outcome;
pub use summary::{FileRecord, Summary};
pub use sweep::StepRow;
pub use system::{SparseRows, System, SystemBody};
