//! The flags of `memcontact solve` that its runs (one case, a sweep, an adaptive loop)
//! share.

use crate::progress::Verbosity;
use std::path::Path;

/// How `memcontact solve` writes its results.
pub struct SolveFlags<'a> {
    /// The output directory.
    pub out: &'a Path,
    /// `--set` overrides.
    pub sets: &'a [String],
    /// How much progress to show.
    pub verbosity: Verbosity,
    /// Replace an output directory holding other files.
    pub force: bool,
    /// Write the result files of a solve that did not converge (marked in summary.json).
    pub write_unconverged: bool,
}
