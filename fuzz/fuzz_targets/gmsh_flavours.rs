//! The Gmsh reader past its header: the first byte picks the flavour (2.2 or 4.1, ASCII
//! or binary, either endianness), and the rest is the file after `$EndMeshFormat`, so the
//! fuzzer spends its time in the sections rather than in the header.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let mut file: Vec<u8> = Vec::with_capacity(body.len() + 64);
    let one = 1i32;
    match pick % 6 {
        0 => file.extend_from_slice(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"),
        1 => file.extend_from_slice(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"),
        k => {
            let version: &[u8] = if k % 2 == 0 { b"2.2" } else { b"4.1" };
            let size: &[u8] = if k == 5 { b"4" } else { b"8" };
            file.extend_from_slice(b"$MeshFormat\n");
            file.extend_from_slice(version);
            file.extend_from_slice(b" 1 ");
            file.extend_from_slice(size);
            file.push(b'\n');
            if k >= 4 {
                file.extend_from_slice(&one.to_be_bytes());
            } else {
                file.extend_from_slice(&one.to_le_bytes());
            }
            file.extend_from_slice(b"\n$EndMeshFormat\n");
        }
    }
    file.extend_from_slice(body);
    if let Ok((mesh, _)) = memcontact::io::gmsh::parse_msh(&file) {
        assert!(mesh.n_triangles() > 0);
    }
});
