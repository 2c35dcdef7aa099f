//! Built-in mesh generators: rectangle (structured, with its multigrid hierarchy), disc and
//! polygon with holes and named regions (constrained Delaunay refinement with spade).

mod delaunay;
mod disk;
mod geometry;
mod polygon;
mod rectangle;
mod size;
#[cfg(test)]
mod tests;

pub use disk::{disk, disk_levels};
pub use polygon::{polygon, polygon_levels, PolygonSpec};
pub use rectangle::{rectangle, Diagonal, RectangleSpec, RECTANGLE_SIDES};
pub use size::{DELAUNAY_TRIANGLES, MAX_STRUCTURED_TRIANGLES, MAX_TRIANGLES};
