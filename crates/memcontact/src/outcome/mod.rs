//! The outcome of a solve: the physical fields and totals in the user's numbering, the
//! summary, and the checks they pass before anything is written.

pub mod checks;
