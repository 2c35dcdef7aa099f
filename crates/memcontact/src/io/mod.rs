//! Readers and writers: Gmsh meshes in, VTU / CSV / JSON out. Plain functions over library types.

mod atomic;
pub mod csv;
pub mod gmsh;
pub mod json;
pub mod result_set;
pub mod vtu;
pub use atomic::write_atomic;
