//! Long help texts: the case-file keys with their units and defaults.

/// The case-file reference printed by `memcontact solve --help` and `check --help`.
pub const CASE_KEYS: &str = "\
CASE FILE (TOML; paths relative to the case file; unknown keys are errors)

[mesh]        file = \"mesh.msh\"          Gmsh MSH 2.2/4.1, ASCII or binary; or instead
              generator = \"rectangle\"    x0, y0, x1, y1 (0, 0, 1, 1), nx (16), ny (nx),
                                         diagonal = right | left | alternate | crossed (right)
              generator = \"disk\"         center ([0, 0]), radius (1), size (radius/8)
              generator = \"polygon\"      outer = [[x, y], ...], holes = [[[x, y], ...]],
                                         regions = [{ name, polygon }], size, min_angle (25°)
              refine = 0                 uniform refinements (levels kept for multigrid)
[membrane]    tension = t > 0            force/length
              load = f                   force/area: number, expression in x, y, or region table
[obstacle]    shape = φ                  length: number, expression or region table
              stiffness = h ≥ 0          force/length³, or \"rigid\" (u ≤ φ)
              foundation = consistent    or lumped (l_i = ∫ h g_i)
              sampling = nodal           or mollified (φ_n = r_n(J_ε * φ)); epsilon = ε (paper's ε_n)
[solver]      method = auto              linear | active-set | qp | coordinate | multigrid
              tolerance = 1e-10          on the scaled KKT residual (2e, 2f), below 1e-2
              max_iterations             per method by default
              accept_rounding_floor = true   accept an answer at the rounding floor of
                                         double precision above the tolerance (reported)
[output]      vtu = binary               or ascii | compressed
              csv = true                 false: no nodes.csv (solution.vtu has the fields)
              plots = [\"deflection\", \"pressure\", \"liftoff\", \"profile\"]  (default all; [] none)
              allowable_pressure = p     force/area: pressure.png maps pressure / p
              profile = [[x0, y0], [x1, y1]]  the line of profile.png (default: mid-height)
[units]       length = \"m\", force = \"kN\"   names for the labels of the pictures
[sweep]       parameter = \"load_factor\"  or stiffness_factor | tension | obstacle_offset (+ φ)
              values = [v, ...]          or from = a, to = b, steps = n (evenly, both ends)
                                         one solve per value, each from the previous answer
[[load_case]] name = \"...\"               one entry per combination (its output directory)
              load, load_factor (1),     override the base case's data
              shape, stiffness
[[sensor]]    name = \"A\", at = [x, y]     u there (P1); measured = u_m, sigma = σ (1) for [fit]
[sensitivity] outputs = [\"energy\"]         max_deflection, total_contact_force(_low), contact_area,
                                         sensors, sensor:NAME, contact_force:REGION
              parameters = [\"key\", ...]    membrane.tension, membrane.load, obstacle.shape,
                                         obstacle.stiffness(.REGION), lower.*, boundary.height
              influence = true           dJ_dh, dsensor_NAME_dh in solution.vtu; writes
                                         sensitivity.csv (output,parameter,value,derivative,...)
[fit]         parameters = { \"key\" = [min, max] }  start: the case's value; ln p if min > 0
              measurements = \"points.csv\"  name,x,y,u[,sigma] (default: sensors' measured)
              max_iterations = 30, tolerance = 1e-8, prior = α   writes fit.json, fit.csv, fit.png

Units: any consistent system (e.g. m, kN: t in kN/m, f in kN/m², h in kN/m³).
Expressions: x, y, r, pi, e; + - * / ^; < <= > >= == != && || !; sin cos tan asin acos atan
atan2 sinh cosh tanh exp ln log log10 sqrt abs min max pow floor ceil round sign hypot step
if(c, a, b).";
