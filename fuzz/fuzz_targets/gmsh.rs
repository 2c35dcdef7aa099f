//! The Gmsh reader on arbitrary bytes (MSH 2.2 and 4.1, ASCII and binary, seeded with
//! all four): a mesh that passes the mesh checks, or a message; never a panic, a hang or
//! an allocation the file's size does not justify.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok((mesh, _warnings)) = memcontact::io::gmsh::parse_msh(data) {
        assert!(mesh.n_triangles() > 0);
        let _ = mesh.quality();
    }
});
