//! The one list of a case file's sections and keys: what `memcontact solve --help` prints,
//! what the documentation's case-file pages are tested against, and what the parser is
//! tested against (every key it accepts is listed here, and only those).

/// A section of the case file.
#[derive(Debug, Clone, Copy)]
pub struct SectionDoc {
    /// The section's name (`mesh`, `load_case`, ...).
    pub name: &'static str,
    /// Whether the section is an array of tables (`[[load_case]]`).
    pub array: bool,
    /// What it is for, in a few words.
    pub summary: &'static str,
    /// Its keys, in the order the documentation lists them.
    pub keys: &'static [KeyDoc],
}

/// A key of a section.
#[derive(Debug, Clone, Copy)]
pub struct KeyDoc {
    /// The key.
    pub name: &'static str,
    /// Its value: a form, a default (`= 0`), or the values it takes.
    pub value: &'static str,
    /// What it means, in one line.
    pub meaning: &'static str,
}

impl SectionDoc {
    /// The section's heading as a case file writes it: `[mesh]` or `[[load_case]]`.
    pub fn heading(&self) -> String {
        if self.array {
            format!("[[{}]]", self.name)
        } else {
            format!("[{}]", self.name)
        }
    }
}

const fn key(name: &'static str, value: &'static str, meaning: &'static str) -> KeyDoc {
    KeyDoc {
        name,
        value,
        meaning,
    }
}

/// Every section of the case file, in the order of the documentation.
#[rustfmt::skip]
pub const SECTIONS: &[SectionDoc] = &[
    SectionDoc {
        name: "mesh",
        array: false,
        summary: "the triangulation: a Gmsh file or a generator, and uniform refinements",
        keys: &[
            key("file", "= \"mesh.msh\"", "Gmsh MSH 2.2/4.1 (physical surfaces, curves: regions)"),
            key("generator", "= rectangle | disk | polygon", "a generated mesh instead of a file"),
            key("x0", "= 0", "rectangle: lower-left corner x"),
            key("y0", "= 0", "rectangle: lower-left corner y"),
            key("x1", "= 1", "rectangle: upper-right corner x"),
            key("y1", "= 1", "rectangle: upper-right corner y"),
            key("nx", "= 16", "rectangle: cells along x"),
            key("ny", "= nx", "rectangle: cells along y"),
            key("diagonal", "= right", "rectangle: right | left | alternate | crossed"),
            key("center", "= [0, 0]", "disk: centre"),
            key("radius", "= 1", "disk: radius"),
            key("size", "= radius/8", "disk, polygon: target element size (length)"),
            key("outer", "= [[x, y], ...]", "polygon: the outer boundary"),
            key("holes", "= [[[x, y], ...], ...]", "polygon: holes"),
            key("regions", "= [{ name, polygon }]", "polygon: named sub-polygons (region-table keys)"),
            key("min_angle", "= 25", "polygon: smallest angle, degrees (at most 30)"),
            key("refine", "= 0", "uniform refinements (the levels are kept for multigrid)"),
            key("given", "= \"...\"", "written by programs: a mesh given as data, described"),
        ],
    },
    SectionDoc {
        name: "membrane",
        array: false,
        summary: "the membrane: tension and load",
        keys: &[
            key("tension", "= t > 0", "force/length"),
            key("load", "= f", "force/area: number, expression in x, y, region table"),
        ],
    },
    SectionDoc {
        name: "obstacle",
        array: false,
        summary: "the elastic body above the membrane",
        keys: &[
            key("shape", "= φ", "length: number, expression or region table"),
            key("stiffness", "= h ≥ 0", "force/length³, region table, or \"rigid\" (u ≤ φ)"),
            key("foundation", "= consistent", "or lumped (l_i = ∫ h g_i)"),
            key("sampling", "= nodal", "or mollified (φ_n = r_n(J_ε * φ))"),
            key("epsilon", "= ε_n", "mollifier radius (default: the paper's ε_n)"),
        ],
    },
    SectionDoc {
        name: "lower",
        array: false,
        summary: "a second body below the membrane (pushes up where u < φ_low)",
        keys: &[
            key("shape", "= φ_low", "length: number, expression or region table"),
            key("stiffness", "= h_low ≥ 0", "force/length³, or \"rigid\" (u ≥ φ_low)"),
            key("foundation", "= consistent", "or lumped"),
            key("sampling", "= nodal", "or mollified"),
            key("epsilon", "= ε_n", "mollifier radius for mollified sampling"),
        ],
    },
    SectionDoc {
        name: "boundary",
        array: false,
        summary: "heights of the held boundary and free edges",
        keys: &[
            key("height", "= 0", "g: number, expression, table per boundary region"),
            key("free", "= [\"name\", ...]", "boundary regions left free (t ∂u/∂n = 0)"),
        ],
    },
    SectionDoc {
        name: "solver",
        array: false,
        summary: "the method and its tolerance",
        keys: &[
            key("method", "= auto", "linear | active-set | qp | coordinate | multigrid"),
            key("tolerance", "= 1e-10", "on the scaled KKT residual (2e, 2f), below 1e-2"),
            key("max_iterations", "", "iteration limit (per method by default)"),
            key("accept_rounding_floor", "= true", "accept an answer at double precision's floor"),
            key("hierarchy", "= auto", "multigrid levels: geometric | algebraic"),
        ],
    },
    SectionDoc {
        name: "output",
        array: false,
        summary: "the files and pictures written",
        keys: &[
            key("vtu", "= binary", "or ascii | compressed"),
            key("csv", "= true", "false: no nodes.csv (solution.vtu has the fields)"),
            key("plots", "= [deflection, pressure, liftoff, profile]", "the pictures ([] none)"),
            key("plot", "= true", "false: no pictures"),
            key("allowable_pressure", "= p", "force/area: pressure.png maps pressure / p"),
            key("profile", "= [[x0, y0], [x1, y1]]", "the line of profile.png (default: mid-height)"),
            key("keep_steps", "= false", "with [adapt]: every step's files in step-NNN/"),
        ],
    },
    SectionDoc {
        name: "units",
        array: false,
        summary: "names of the units, for labels",
        keys: &[
            key("length", "= \"m\"", "the unit of x, y, u, φ"),
            key("force", "= \"kN\"", "the unit of forces"),
        ],
    },
    SectionDoc {
        name: "sweep",
        array: false,
        summary: "one parameter over a list of values, each step from the previous answer",
        keys: &[
            key("parameter", "= load_factor", "or stiffness_factor | tension | obstacle_offset"),
            key("values", "= [v, ...]", "the values, in order"),
            key("from", "= a", "first value (with to, steps)"),
            key("to", "= b", "last value"),
            key("steps", "= n", "n ≥ 2 evenly spaced values, both ends included"),
        ],
    },
    SectionDoc {
        name: "load_case",
        array: true,
        summary: "named load combinations, each solved in turn",
        keys: &[
            key("name", "= \"...\"", "the combination's name and output directory"),
            key("load", "= f", "this combination's load (default: the base case's)"),
            key("load_factor", "= 1", "a factor on the load"),
            key("shape", "= φ", "this combination's obstacle surface"),
            key("stiffness", "= h", "this combination's stiffness (or \"rigid\")"),
        ],
    },
    SectionDoc {
        name: "adapt",
        array: false,
        summary: "adaptive refinement: solve, estimate, mark, bisect, solve again",
        keys: &[
            key("max_vertices", "= n", "stop before a mesh with more vertices"),
            key("steps", "= 20", "the most steps solved (step 0: the start mesh)"),
            key("theta", "= 0.5", "Dörfler's fraction θ in (0, 1]"),
            key("free_boundary_rings", "= 1", "rings of the free boundary refined too (0: none)"),
            key("tolerance", "= η", "stop once the estimator is at most this"),
        ],
    },
    SectionDoc {
        name: "sensor",
        array: true,
        summary: "points where the deflection is read (and, for a fit, measured)",
        keys: &[
            key("name", "= \"...\"", "letters, digits, _ - .: the output sensor:NAME"),
            key("at", "= [x, y]", "inside the mesh: u there by P1 interpolation"),
            key("measured", "= u_m", "length: the measured deflection there, for [fit]"),
            key("sigma", "= 1", "length: the measurement's standard deviation σ > 0"),
        ],
    },
    SectionDoc {
        name: "sensitivity",
        array: false,
        summary: "derivatives of outputs in case keys (sensitivity.csv, influence maps)",
        keys: &[
            key("outputs", "= [\"energy\"]", "max_deflection, total_contact_force, sensors, ..."),
            key("parameters", "= [\"key\", ...]", "case keys (membrane.tension, obstacle.stiffness.soil)"),
            key("influence", "= true", "dJ_dh, dsensor_NAME_dh in solution.vtu"),
        ],
    },
    SectionDoc {
        name: "fit",
        array: false,
        summary: "case keys fitted to measured deflections (fit.json, fit.csv, fit.png)",
        keys: &[
            key("parameters", "= { \"key\" = [min, max] }", "the keys fitted, in bounds (start: the case's)"),
            key("measurements", "= \"points.csv\"", "name,x,y,u[,sigma] (default: sensors' measured)"),
            key("max_iterations", "= 30", "Levenberg-Marquardt iterations"),
            key("tolerance", "= 1e-8", "on the step (in ln p) and the gradient"),
            key("prior", "= α", "weight of a pull toward the start, ½ α ‖ln p − ln p₀‖²"),
        ],
    },
    SectionDoc {
        name: "exact",
        array: false,
        summary: "the closed-form solution, for convergence studies",
        keys: &[
            key("kind", "= disk", "or manufactured | petsc-ex9 | mfem-ex36"),
            key("domain", "= rectangle", "manufactured: rectangle | disk"),
            key("amplitude", "= A", "manufactured: the scale of u"),
            key("form", "= vanishing", "manufactured: vanishing | cosine (rectangle)"),
            key("body", "= obstacle", "petsc-ex9, mfem-ex36: obstacle | lower"),
        ],
    },
];

/// The section named `name`, if the case file has one.
pub fn section(name: &str) -> Option<&'static SectionDoc> {
    SECTIONS.iter().find(|s| s.name == name)
}

/// The case-file reference printed by `memcontact solve --help` and `check --help`: every
/// section of [`SECTIONS`] with its keys.
pub fn reference() -> String {
    const HEADING: usize = 15;
    const KEY: usize = 30;
    let mut out = String::from(
        "CASE FILE (TOML; paths relative to the case file; unknown keys are errors)\n\n",
    );
    for s in SECTIONS {
        let mut first = true;
        for k in s.keys {
            let heading = if first { s.heading() } else { String::new() };
            first = false;
            let assignment = if k.value.is_empty() {
                k.name.to_string()
            } else {
                format!("{} {}", k.name, k.value)
            };
            let pad = |text: &str, width: usize| {
                let n = text.chars().count();
                format!("{text}{}", " ".repeat(width.saturating_sub(n).max(1)))
            };
            let head = pad(&heading, HEADING);
            if assignment.chars().count() >= KEY {
                out.push_str(&format!("{head}{assignment}\n"));
                out.push_str(&format!("{}{}\n", " ".repeat(HEADING + KEY), k.meaning));
            } else {
                out.push_str(&format!("{head}{}{}\n", pad(&assignment, KEY), k.meaning));
            }
        }
    }
    out.push_str(
        "\nUnits: any consistent system (e.g. m, kN: t in kN/m, f in kN/m², h in kN/m³).\n\
         Expressions: x, y, r, pi, e; + - * / ^; < <= > >= == != && || !; sin cos tan asin \
         acos atan\natan2 sinh cosh tanh exp ln log log10 sqrt abs min max pow floor ceil \
         round sign hypot step\nif(c, a, b). Region tables: { foam = 50.0, default = \"200 + \
         10*y\" }.\n",
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Case;

    /// A minimal complete case with `extra` appended.
    fn with(extra: &str) -> String {
        format!(
            "[mesh]\ngenerator = \"rectangle\"\nnx = 2\n[membrane]\ntension = 1.0\nload = 1.0\n\
             [obstacle]\nshape = 1.0\nstiffness = 1.0\n{extra}"
        )
    }

    /// The keys the parser accepts in `section`, read from its refusal of an unknown key
    /// (serde lists the expected fields).
    fn accepted(section: &SectionDoc) -> Vec<String> {
        let probe = "zz_not_a_key = 1";
        let text = match section.name {
            "mesh" => format!(
                "[mesh]\n{probe}\n[membrane]\ntension = 1.0\nload = 1.0\n[obstacle]\nshape = 1.0\n\
                 stiffness = 1.0\n"
            ),
            "membrane" | "obstacle" => {
                let base = with("");
                base.replace(
                    &format!("[{}]\n", section.name),
                    &format!("[{}]\n{probe}\n", section.name),
                )
            }
            name if section.array => with(&format!("[[{name}]]\n{probe}\n")),
            name => with(&format!("[{name}]\n{probe}\n")),
        };
        let e = Case::from_toml_str(&text, None).unwrap_err().to_string();
        let list = e
            .split_once("expected")
            .map(|(_, list)| list)
            .unwrap_or_else(|| panic!("[{}]: no list of fields in {e}", section.name));
        list.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    }

    #[test]
    fn every_key_the_parser_accepts_is_listed_and_only_those() {
        for s in SECTIONS {
            if s.name == "exact" {
                continue; // a tagged enum: its keys differ per kind (tested below)
            }
            let mut want = accepted(s);
            want.sort();
            let mut listed: Vec<String> = s.keys.iter().map(|k| k.name.to_string()).collect();
            listed.sort();
            assert_eq!(listed, want, "[{}]", s.name);
        }
    }

    #[test]
    fn every_exact_kind_accepts_its_listed_keys() {
        for (kind, keys) in [
            ("disk", ""),
            (
                "manufactured",
                "domain = \"rectangle\"\namplitude = 1.0\nform = \"vanishing\"\n",
            ),
            ("petsc-ex9", "body = \"obstacle\"\n"),
            ("mfem-ex36", "body = \"lower\"\n"),
        ] {
            let text = with(&format!("[exact]\nkind = \"{kind}\"\n{keys}"));
            Case::from_toml_str(&text, None).unwrap_or_else(|e| panic!("{kind}: {e}"));
        }
        let exact: Vec<&str> = section("exact")
            .unwrap()
            .keys
            .iter()
            .map(|k| k.name)
            .collect();
        assert_eq!(exact, ["kind", "domain", "amplitude", "form", "body"]);
    }

    #[test]
    fn the_reference_names_every_section_and_key() {
        let text = reference();
        for s in SECTIONS {
            assert!(text.contains(&s.heading()), "{}", s.heading());
            for k in s.keys {
                assert!(text.contains(k.name), "{}.{}", s.name, k.name);
            }
        }
        assert!(text.lines().all(|l| l.chars().count() <= 100), "{text}");
    }
}
