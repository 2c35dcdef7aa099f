//! Verification beside the pipeline: exact solutions (SPEC §4 and §5), the error norms of a
//! P1 function against them, and convergence studies over refined meshes.

pub mod convergence;
pub mod exact;
pub mod norms;
