//! Tests of the result writers.

use super::*;
use crate::case::Case;

#[test]
fn input_hash_covers_the_case_and_the_whole_mesh_file() {
    let dir = std::env::temp_dir().join(format!("memcontact-hash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Only hashed, never parsed: any bytes will do, over several read blocks.
    let mesh = dir.join("site.msh");
    let bytes: Vec<u8> = (0..3_000_001u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
        .collect();
    std::fs::write(&mesh, &bytes).unwrap();
    let text = "[mesh]\nfile = \"site.msh\"\n[membrane]\ntension = 1.0\nload = 1.0\n\
                [obstacle]\nshape = 0.1\nstiffness = 10.0\n";
    let case = Case::from_toml_str(text, Some(&dir.join("case.toml"))).unwrap();
    // The digest of the case's JSON followed by the file's bytes, all at once.
    let mut whole = serde_json::to_string(&case).unwrap().into_bytes();
    whole.extend_from_slice(&bytes);
    let expected = format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&whole));
    assert_eq!(input_hash(&case), expected);
    // One byte of the mesh changed changes the hash.
    let mut changed = bytes.clone();
    let last = changed.len() - 2;
    changed[last] ^= 1;
    std::fs::write(&mesh, &changed).unwrap();
    assert_ne!(input_hash(&case), expected);
    std::fs::remove_dir_all(&dir).unwrap();
}
