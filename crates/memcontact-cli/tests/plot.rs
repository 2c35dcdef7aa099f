//! End-to-end: `memcontact plot DIR` redraws the pictures of a solved case.

mod common;

use common::{examples, run, text, tmp_in};

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &std::path::Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{} is a PNG", path.display());
    let be = |i: usize| u32::from_be_bytes(b[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn plot_redraws_a_result_directory() {
    let dir = tmp_in("plot", "disk");
    let case = examples().join("disk.toml");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let _ = std::fs::remove_file(dir.join("deflection.png"));
    let o = run(&["plot", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    for name in ["deflection", "pressure", "liftoff", "profile"] {
        let f = dir.join(format!("{name}.png"));
        let want = if name == "profile" {
            (
                memcontact_plot::PROFILE_WIDTH,
                memcontact_plot::PROFILE_HEIGHT,
            )
        } else {
            (memcontact_plot::MAP_WIDTH, memcontact_plot::MAP_HEIGHT)
        };
        assert_eq!(png_size(&f), want, "{name}");
    }
    assert!(text(&o).contains("wrote"), "{}", text(&o));
    // --plots chooses; an unknown name is a clear error.
    let first = std::fs::read(dir.join("pressure.png")).unwrap();
    std::fs::remove_file(dir.join("pressure.png")).unwrap();
    std::fs::remove_file(dir.join("profile.png")).unwrap();
    let o = run(&["plot", dir.to_str().unwrap(), "--plots", "pressure"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        std::fs::read(dir.join("pressure.png")).unwrap(),
        first,
        "same picture again"
    );
    assert!(!dir.join("profile.png").exists());
    let o = run(&[
        "plot",
        dir.to_str().unwrap(),
        "--plots",
        "pressure,contours",
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("unknown plot \"contours\""),
        "{}",
        text(&o)
    );
    // Not a result directory: the missing file is named.
    let empty = tmp_in("plot", "empty");
    let o = run(&["plot", empty.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("solution.vtu"), "{}", text(&o));
    // A directory mixing two runs (another run's solution.vtu beside this summary.json)
    // is refused, not redrawn.
    let other = tmp_in("plot", "other");
    let o = run(&[
        "solve",
        examples().join("disk.toml").to_str().unwrap(),
        "-q",
        "-o",
        other.join("r").to_str().unwrap(),
        "--set",
        "membrane.load=9",
        "--set",
        "output.plot=false",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    std::fs::copy(other.join("r/solution.vtu"), dir.join("solution.vtu")).unwrap();
    let o = run(&["plot", dir.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("mixes the files of two runs"),
        "{}",
        text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&empty);
}

/// A membrane between two bodies: `memcontact plot` redraws the pictures `memcontact
/// solve` drew (each body's contact drawn apart, from the body below's fields in
/// `solution.vtu`) byte for byte.
#[test]
fn plot_redraws_two_bodies_byte_for_byte() {
    let dir = tmp_in("plot", "geomembrane");
    let case = examples().join("geomembrane.toml");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "-q",
        "--set",
        "mesh.nx=24",
        "--set",
        "mesh.ny=24",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let names = ["deflection", "pressure", "liftoff", "profile"];
    let solved: Vec<Vec<u8>> = names
        .iter()
        .map(|n| std::fs::read(dir.join(format!("{n}.png"))).unwrap())
        .collect();
    for n in names {
        std::fs::remove_file(dir.join(format!("{n}.png"))).unwrap();
    }
    let o = run(&["plot", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    for (n, want) in names.iter().zip(&solved) {
        let got = std::fs::read(dir.join(format!("{n}.png"))).unwrap();
        assert!(&got == want, "{n}.png redrawn differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
