//! Adaptive refinement (docs/theory.md#adaptivity; the guide: docs/adaptivity.md). The
//! loop: solve → estimate → mark → refine → solve, from the case's mesh, until the
//! estimator meets `[adapt] tolerance`, the steps run out, or the next mesh would have more
//! than `max_vertices` vertices.
//!
//! - **Estimate**: the residual indicators (elastic bodies,
//!   rigid ones and rigid regions, a body below, free edges).
//! - **Mark**: Dörfler's bulk criterion on η_T² with fraction θ, together with the
//!   triangles on the free boundary (those holding both contact and non-contact vertices,
//!   of either body) and `free_boundary_rings` rings of neighbours, at most as many of
//!   these as the Dörfler set holds (the largest first): the free boundary is refined as
//!   fast as the bulk and no faster, so its strip never takes over the vertex budget and
//!   the energy error keeps the rate of Dörfler marking.
//! - **Refine**: newest-vertex bisection of the mesh in the
//!   user's numbering (the start mesh labelled by its longest edges once): conforming,
//!   nested and shape-regular, regions and boundary regions carried, new vertices on the
//!   circle of a disc. Every mesh of the loop stays a level of the hierarchy, so
//!   multigrid runs on the nested meshes (the start mesh's own levels below them).
//! - **Solve**: each step starts from the previous answer interpolated onto the new mesh;
//!   data given per vertex are interpolated (P1) onto the new vertices, and the run says
//!   so ([`AdaptRun::interpolated`]).
//!
//! Its public parts: [`run_adapt`] (the loop; the estimator, the marking and the bisection
//! are internal modules of this one), [`AdaptRun`] (its answer), [`AdaptRow`] (a step's row
//! of `adapt.csv`) and the result set of the loop ([`AdaptSet`]). The case's `[adapt]`
//! section is [`crate::case::AdaptSpec`].

pub(crate) mod bisect;
pub(crate) mod estimate;
pub(crate) mod mark;
mod row;
mod run;
mod write;

pub use row::AdaptRow;
pub use run::{check_adapt_on_mesh, run_adapt, AdaptRun, AdaptStop, OnStep};
pub use write::{write_adapt_csv, AdaptHistory, AdaptSet, ADAPT_CSV};
