//! Real solved cases for the picture tests: the example cases of the repository, written
//! as case files and solved by the library's run, their fields in the user's numbering.

#![allow(dead_code)]

use memcontact::solve::Silent;
use memcontact::write::{LowerData, ResultData};
use memcontact::Case;
use std::path::{Path, PathBuf};

/// A solved case.
pub struct Solved {
    /// Its name (as the examples are called).
    pub name: &'static str,
    /// The fields.
    pub data: ResultData,
    /// The mesh's region tags, per triangle.
    pub regions: Vec<u32>,
}

/// Solves the case `toml` (a case file's text; relative paths are relative to
/// `examples/`) with the default settings.
pub fn solve_case(name: &'static str, toml: &str) -> Solved {
    let case = Case::from_toml_str(toml, Some(&examples().join("case.toml"))).unwrap();
    let outcome = memcontact::run::run(&case, &mut Silent).unwrap();
    assert!(
        outcome.report.accepted,
        "{name}: {:?}",
        outcome.report.status
    );
    let mesh = outcome.mesh().into_owned();
    let (fields, _) = outcome.fields();
    let fields = fields.into_owned();
    Solved {
        name,
        data: ResultData {
            points: mesh.points,
            triangles: mesh.triangles,
            u: fields.u,
            phi: fields.phi,
            state: fields.state,
            pressure: fields.pressure,
            covered: fields.covered,
            lower: fields.lower.map(|l| LowerData {
                phi: l.phi,
                state: l.state,
                pressure: l.pressure,
                covered: l.covered,
            }),
        },
        regions: mesh.regions,
    }
}

/// `examples/disk.toml`: the elastic disc.
pub fn disk() -> Solved {
    solve_case(
        "disk",
        r#"
[mesh]
generator = "disk"
size = 0.1
[membrane]
tension = 1.0
load = 8.0
[obstacle]
shape = 1.0
stiffness = 100.0
"#,
    )
}

/// `examples/disk-step.toml`: the disc on a stepped obstacle.
pub fn disk_step() -> Solved {
    solve_case(
        "disk-step",
        r#"
[mesh]
generator = "disk"
size = 0.1
[membrane]
tension = 1.0
load = 8.0
[obstacle]
shape = "if(x > 0.1, 0.9, 1.1)"
stiffness = 100.0
"#,
    )
}

/// `examples/rigid-square.toml`: the classical obstacle problem (every contact vertex
/// touches).
pub fn rigid_square() -> Solved {
    solve_case(
        "rigid-square",
        r#"
[mesh]
generator = "rectangle"
nx = 64
[membrane]
tension = 1.0
load = 20.0
[obstacle]
shape = "0.3 + 0.2*x*y"
stiffness = "rigid"
"#,
    )
}

/// `examples/roof.toml`: a roof membrane with a skylight opening on a foam cushion with a
/// stiffer block (units m, kN).
pub fn roof() -> Solved {
    solve_case(
        "roof",
        r#"
[mesh]
generator = "polygon"
outer = [[0.0, 0.0], [12.0, 0.0], [12.0, 8.0], [0.0, 8.0]]
holes = [[[7.0, 3.0], [9.0, 3.0], [9.0, 5.0], [7.0, 5.0]]]
regions = [{ name = "block", polygon = [[1.5, 2.5], [5.0, 2.5], [5.0, 5.5], [1.5, 5.5]] }]
size = 0.25
min_angle = 28.0
[membrane]
tension = 6.0
load = "1.2 + 0.3*exp(-((x-3)^2 + (y-4)^2)/4)"
[obstacle]
shape = "0.45 + 0.12*sin(0.9*x)*cos(0.7*y) - 0.1*exp(-((x-9.5)^2 + (y-2)^2)) + 0.01*x"
stiffness = { block = 900.0, default = "250 + 20*y" }
"#,
    )
}

/// `examples/gmsh-disk.toml`: a Gmsh disc with two soils, one of which (foam) is soft,
/// refined once.
pub fn gmsh_disk() -> Solved {
    solve_case(
        "gmsh-disk",
        r#"
[mesh]
file = "disk.msh"
refine = 1
[membrane]
tension = 2.0
load = 10.0
[obstacle]
shape = "0.8 - 0.2*(x*x + y*y)"
stiffness = { foam = 50.0, soil = 400.0 }
"#,
    )
}

/// A partly covered case: the body (h > 0) only under the left half of the square, so
/// that lift-off, contact and "cannot touch" all appear.
pub fn half_covered() -> Solved {
    solve_case(
        "half-covered",
        r#"
[mesh]
generator = "rectangle"
x1 = 2.0
nx = 48
ny = 24
diagonal = "alternate"
[membrane]
tension = 1.0
load = 30.0
[obstacle]
shape = "0.25 + 0.15*sin(3*y)"
stiffness = "if(x < 1.1, 500, 0)"
"#,
    )
}

/// `examples/disk-rigid.toml`: the disc on a rigid flat obstacle.
pub fn disk_rigid() -> Solved {
    solve_case(
        "disk-rigid",
        r#"
[mesh]
generator = "disk"
size = 0.1
[membrane]
tension = 1.0
load = 8.0
[obstacle]
shape = 1.0
stiffness = "rigid"
"#,
    )
}

/// `examples/manufactured-square.toml` (the case's own load): an 8 × 8 mesh, coarse
/// enough that vertex markers are drawn.
pub fn manufactured_square() -> Solved {
    solve_case(
        "manufactured-square",
        r#"
[mesh]
generator = "rectangle"
nx = 8
[membrane]
tension = 1.5
load = 30.0
[obstacle]
shape = "0.55 + 0.3*(x - 0.5)^2 + 0.1*y"
stiffness = "50*(1 + y)"
"#,
    )
}

/// `examples/geomembrane.toml` at a small size (32 × 32): a liner between a cover layer
/// above and the subsoil below, with a stone in the subsoil that squeezes it into the
/// cover, so that it touches the obstacle, the body below, both at once, and neither.
pub const LINER: &str = r#"
[mesh]
generator = "rectangle"
x1 = 20.0
y1 = 20.0
nx = 32
ny = 32
[membrane]
tension = 15.0
load = "1.6*exp(-((x - 6)^2 + (y - 13)^2)/12) - 0.5"
[obstacle]
shape = 0.05
stiffness = 800.0
[lower]
shape = "-0.25*exp(-((x - 13)^2 + (y - 7)^2)/10) + 0.2*exp(-((x - 15)^2 + (y - 15)^2)/3)"
stiffness = 2000.0
foundation = "consistent"
[boundary]
height = 0.0
[units]
length = "m"
force = "kN"
"#;

/// [`LINER`], solved.
pub fn liner() -> Solved {
    solve_case("liner", LINER)
}

/// The repository's `examples/` folder.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Copies `file` into `$MEMCONTACT_KEEP_PLOTS/<prefix>-<file name>` when that variable is
/// set (to look at the pictures).
pub fn keep(file: &Path, prefix: &str) {
    if let Ok(dir) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
        let name = format!("{prefix}-{}", file.file_name().unwrap().to_string_lossy());
        std::fs::copy(file, Path::new(&dir).join(name)).unwrap();
    }
}
