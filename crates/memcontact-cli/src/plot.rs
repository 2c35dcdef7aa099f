//! Pictures for the CLI's outputs. The drawing lives in the `memcontact-plot` crate; this
//! module only names what the commands use.

/// A colour map of one nodal field (`deflection.png` until `solve` draws the full set).
pub use memcontact_plot::field_plot;
