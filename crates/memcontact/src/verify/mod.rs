//! Verification beside the pipeline: exact solutions (docs/theory.md#verification,
//! docs/theory.md#obstacle-benchmarks), the error norms of a P1 function against them,
//! convergence studies over refined meshes, and the study of a case (its `[exact]` section,
//! the comparisons, the rigid limit).

pub mod convergence;
pub mod exact;
pub(crate) mod exact_case;
pub mod norms;
pub mod study;
