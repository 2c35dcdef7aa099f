//! `memcontact example`: ready-to-run case files, embedded in the binary.

use anyhow::{bail, Context, Result};
use std::path::Path;

/// An example: name, one-line description, and its files (name, contents).
struct Example {
    name: &'static str,
    about: &'static str,
    files: &'static [(&'static str, &'static str)],
}

const EXAMPLES: &[Example] = &[
    Example {
        name: "disk",
        about: "the axisymmetric disc on a flat elastic foundation (exact solution known: Bessel functions)",
        files: &[("disk.toml", include_str!("../../../examples/disk.toml"))],
    },
    Example {
        name: "roof",
        about: "a roof membrane with a skylight opening over an irregular foam cushion (polygon with a hole, two soils)",
        files: &[("roof.toml", include_str!("../../../examples/roof.toml"))],
    },
    Example {
        name: "bench-square",
        about: "the standard benchmark on the unit square (N × N structured mesh)",
        files: &[(
            "bench-square.toml",
            include_str!("../../../examples/bench-square.toml"),
        )],
    },
    Example {
        name: "rigid-square",
        about: "the classical rigid obstacle problem u ≤ φ on the unit square",
        files: &[(
            "rigid-square.toml",
            include_str!("../../../examples/rigid-square.toml"),
        )],
    },
    Example {
        name: "disk-rigid",
        about: "the disc on a rigid obstacle (the classical obstacle problem; exact solution known)",
        files: &[("disk-rigid.toml", include_str!("../../../examples/disk-rigid.toml"))],
    },
    Example {
        name: "disk-step",
        about: "a disc over a step-shaped obstacle (discontinuous φ): nodal vs mollified sampling",
        files: &[("disk-step.toml", include_str!("../../../examples/disk-step.toml"))],
    },
    Example {
        name: "manufactured-square",
        about: "a manufactured solution on the square (varying h and φ) for convergence studies",
        files: &[(
            "manufactured-square.toml",
            include_str!("../../../examples/manufactured-square.toml"),
        )],
    },
    Example {
        name: "roof-frame",
        about: "a roof membrane on a frame of varying height, under snow, sagging onto insulation below it",
        files: &[("roof-frame.toml", include_str!("../../../examples/roof-frame.toml"))],
    },
    Example {
        name: "geomembrane",
        about: "a geomembrane liner between the subsoil below and a cover layer above (two bodies)",
        files: &[(
            "geomembrane.toml",
            include_str!("../../../examples/geomembrane.toml"),
        )],
    },
    Example {
        name: "plinth",
        about: "a cover resting on a foam bed interrupted by a rigid plinth (a body rigid in one region)",
        files: &[("plinth.toml", include_str!("../../../examples/plinth.toml"))],
    },
    Example {
        name: "petsc-ex9",
        about: "PETSc SNES ex9, the rigid obstacle benchmark with boundary data (exact solution known)",
        files: &[
            ("petsc-ex9.toml", include_str!("../../../examples/petsc-ex9.toml")),
            (
                "petsc-ex9-lower.toml",
                include_str!("../../../examples/petsc-ex9-lower.toml"),
            ),
        ],
    },
    Example {
        name: "mfem-ex36",
        about: "MFEM ex36, the obstacle benchmark on the unit disc (exact solution known)",
        files: &[("mfem-ex36.toml", include_str!("../../../examples/mfem-ex36.toml"))],
    },
    Example {
        name: "manufactured-free-edge",
        about: "a manufactured solution with boundary heights, a free edge and two elastic bodies",
        files: &[(
            "manufactured-free-edge.toml",
            include_str!("../../../examples/manufactured-free-edge.toml"),
        )],
    },
    Example {
        name: "gmsh-disk",
        about: "a Gmsh mesh with two physical surfaces (foam, soil) of different stiffness",
        files: &[
            ("gmsh-disk.toml", include_str!("../../../examples/gmsh-disk.toml")),
            ("disk.msh", include_str!("../../../examples/disk.msh")),
        ],
    },
    Example {
        name: "roof-corner",
        about: "an L-shaped roof pushed up against a foam cushion, refined adaptively ([adapt])",
        files: &[("roof-corner.toml", include_str!("../../../examples/roof-corner.toml"))],
    },
    Example {
        name: "liner-slope",
        about: "a geomembrane liner on a slope, meshed in Gmsh: heights per physical curve, a free crest, soils above and below",
        files: &[
            ("liner-slope.toml", include_str!("../../../examples/liner-slope.toml")),
            ("liner-slope.msh", include_str!("../../../examples/liner-slope.msh")),
            ("liner-slope.geo", include_str!("../../../examples/liner-slope.geo")),
        ],
    },
    Example {
        name: "soils",
        about: "three soils under a slab fitted to 18 settlement plates ([fit]), with the plates' sensitivities ([sensitivity])",
        files: &[("soils.toml", include_str!("../../../examples/soils.toml"))],
    },
];

/// Lists the examples, or writes example `name` into `dir`.
pub fn run(name: Option<&str>, dir: &Path, force: bool) -> Result<()> {
    let Some(name) = name else {
        println!("examples (write one with `memcontact example NAME [--dir DIR]`):");
        for e in EXAMPLES {
            println!("  {:<14} {}", e.name, e.about);
        }
        return Ok(());
    };
    let Some(example) = EXAMPLES.iter().find(|e| e.name == name) else {
        let names: Vec<&str> = EXAMPLES.iter().map(|e| e.name).collect();
        bail!(
            "no example named \"{name}\" (examples: {})",
            names.join(", ")
        );
    };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory {}", dir.display()))?;
    for (file, text) in example.files {
        let path = dir.join(file);
        if path.exists() && !force {
            bail!("{} exists (use --force to overwrite)", path.display());
        }
        memcontact::io::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        println!("wrote {}", path.display());
    }
    println!(
        "run it with: memcontact solve {} -o out",
        dir.join(example.files[0].0).display()
    );
    Ok(())
}
