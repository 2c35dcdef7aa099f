//! The case-file parser: TOML text → `Case` (serde, every section's validation). An
//! accepted case round-trips through its TOML text; building it is left to the mesh
//! targets (a case may ask for any mesh size).
#![no_main]

use libfuzzer_sys::fuzz_target;
use memcontact::Case;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(case) = Case::from_toml_str(text, None) else {
        return;
    };
    let written = case
        .to_toml_string()
        .expect("an accepted case can be written");
    let again = Case::from_toml_str(&written, None).expect("a written case reads back");
    assert_eq!(
        again.to_toml_string().unwrap(),
        written,
        "the case changed on its way through TOML"
    );
    let json = serde_json::to_string(&case).expect("an accepted case is JSON");
    Case::from_json_str(&json).expect("a case's JSON reads back");
});
