//! The derivatives against central finite differences of the outputs (same mesh, same
//! active set, solver at 1e-13), the envelope identities, Taylor remainders, and the disc's
//! closed form (docs/theory.md#sensitivity-checks).

use super::*;
use crate::case::{Case, ParameterKey};
use crate::run::run_request;
use crate::solve::Silent;

/// A test mesh file of `tests/data`.
fn data(name: &str) -> String {
    format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The sensitivity site (`tests/data/sens.msh`): two soils and a rigid plinth in the
/// obstacle above, an elastic body below under a downward spot load, boundary heights on
/// three sides and the top edge free; `foundation` for both bodies.
pub(crate) fn site(foundation: &str) -> String {
    format!(
        r#"
[mesh]
file = "{mesh}"
[membrane]
tension = 1.3
load = "8 + 4*y - 60*exp(-((x - 1.5)^2 + (y - 0.5)^2)/0.03)"
[obstacle]
shape = "0.02 + 0.01*x"
stiffness = {{ soft = 300, stiff = 1000, plinth = "rigid" }}
foundation = "{foundation}"
[lower]
shape = -0.01
stiffness = 200
foundation = "{foundation}"
[boundary]
height = {{ left = "0.004*y", bottom = 0, right = 0.003 }}
free = ["top"]
[solver]
method = "active-set"
tolerance = 1e-13
[[sensor]]
name = "A"
at = [0.3, 0.3]
[[sensor]]
name = "B"
at = [1.5, 0.5]
[[sensor]]
name = "C"
at = [1.2, 0.8]
[[sensor]]
name = "D"
at = [0.45, 0.5]
"#,
        mesh = data("sens.msh")
    )
}

const OUTPUTS: [&str; 8] = [
    "energy",
    "max_deflection",
    "total_contact_force",
    "total_contact_force_low",
    "contact_area",
    "sensors",
    "contact_force:soft",
    "contact_force:stiff",
];

const PARAMETERS: [&str; 9] = [
    "membrane.tension",
    "membrane.load",
    "obstacle.shape",
    "obstacle.stiffness.soft",
    "obstacle.stiffness.stiff",
    "lower.stiffness",
    "lower.shape",
    "boundary.height.right",
    "boundary.height.left",
];

fn request(outputs: &[&str], parameters: &[&str]) -> Request {
    Request {
        outputs: outputs.iter().map(|s| s.to_string()).collect(),
        parameters: parameters.iter().map(|s| s.to_string()).collect(),
        influence: true,
    }
}

/// The outputs' values and the vertex states (both bodies) of a case.
fn values(case: &Case, req: &Request) -> (Sensitivities, Vec<i8>) {
    let run = run_request(case, req, &mut Silent).expect("a run");
    let d = &run.outcome.discretization;
    let u = &run.outcome.report.u;
    let mut st = d.model.states(u);
    st.extend(d.model.lower_states(u));
    (run.sensitivities.expect("accepted"), st)
}

/// `case` with parameter `key` at `value`.
fn moved(case: &Case, key: &ParameterKey, value: f64) -> Case {
    let mut c = case.clone();
    key.apply(&mut c.problem, value).expect("applied");
    c
}

/// Central differences of every output in parameter `p` at the step `h` and at `h/4`, with
/// the same vertex states at every end (the step is quartered until they are); the step.
fn central(case: &Case, req: &Request, key: &ParameterKey, states: &[i8]) -> ([Vec<f64>; 2], f64) {
    let mut h = reference(key) * 1e-4;
    let only_values = Request {
        influence: false,
        parameters: vec![req.parameters[0].clone()],
        ..req.clone()
    };
    'steps: for _ in 0..6 {
        let mut out: [Vec<f64>; 2] = Default::default();
        for (k, step) in [h, 0.25 * h].into_iter().enumerate() {
            let (a, sa) = values(&moved(case, key, key.value + step), &only_values);
            let (b, sb) = values(&moved(case, key, key.value - step), &only_values);
            if sa != states || sb != states {
                h *= 0.25;
                continue 'steps;
            }
            out[k] = a
                .values
                .iter()
                .zip(&b.values)
                .map(|(x, y)| (x - y) / (2.0 * step))
                .collect();
        }
        return (out, h);
    }
    panic!("{}: the vertex states change at every step", key.key);
}

/// The size of a parameter: its value, 1 for a factor, 0.01 (a length) for an offset.
fn reference(key: &ParameterKey) -> f64 {
    match key.kind {
        ParameterKind::Value => key.value.abs().max(1e-2),
        ParameterKind::Factor => 1.0,
        ParameterKind::Offset => 1e-2,
    }
}

/// How far a derivative `d` is from a central difference `fd` taken with the step `h` on
/// an output of size `q`: `(relative difference, noise)` where the noise is the
/// differences' rounding (`1e-13 |q| / h`, some hundred ulps of q over the step) relative
/// to the larger of the two. A derivative agrees when the first is at most 1e-6, or the
/// difference is within the noise (`relative ≤ noise`).
fn difference(d: f64, fd: f64, q: f64, h: f64) -> (f64, f64) {
    let size = d.abs().max(fd.abs()).max(f64::MIN_POSITIVE);
    ((d - fd).abs() / size, 1e-13 * q.abs() / h / size)
}

/// Whether a derivative agrees with its difference (see [`difference`]).
fn agrees((rel, noise): (f64, f64)) -> bool {
    rel <= 1e-6 || rel <= noise
}

/// Every output in every parameter kind against central differences, to 1e-6 relative,
/// on the site (two soils, a rigid region, the body below, a free edge, boundary heights)
/// with `foundation`.
fn finite_differences(foundation: &str) {
    let case = Case::from_toml_str(&site(foundation), None).unwrap();
    let req = request(&OUTPUTS, &PARAMETERS);
    let (s, states) = values(&case, &req);
    assert_eq!(
        s.biactive(),
        0,
        "{foundation}: the site has no biactive vertex"
    );
    let np = s.parameters.len();
    let mut worst: f64 = 0.0;
    println!("{foundation}: output, parameter, kind, derivative, central difference, rel. error");
    for (p, key) in s.parameters.iter().enumerate() {
        let ([fd, fd4], h) = central(&case, &req, key, &states);
        for (o, name) in s.outputs.iter().enumerate() {
            let d = s.derivative[o * np + p];
            let q = s.values[o];
            // The better of the two steps: where a vertex's gap is within a step of zero
            // the contact area is C¹ but not C² and the larger step's difference is first
            // order.
            let (r, fd) = [
                (difference(d, fd[o], q, h), fd[o]),
                (difference(d, fd4[o], q, 0.25 * h), fd4[o]),
            ]
            .into_iter()
            .fold(((f64::INFINITY, 0.0), 0.0), |a, b| {
                if b.0 .0 < a.0 .0 {
                    b
                } else {
                    a
                }
            });
            // The worst of the derivatives well above the differences' noise.
            if r.1 < 1e-3 {
                worst = worst.max(r.0);
            }
            println!(
                "  {name:>22} {:>26} {:>6} {d:>14.6e} {fd:>14.6e} {:9.1e}{}",
                key.key,
                key.kind.name(),
                r.0,
                if r.1 >= 1e-3 {
                    " (near the differences' noise)"
                } else {
                    ""
                }
            );
            assert!(
                agrees(r),
                "{foundation}: d {name} / d {}: {d:e} against {fd:e} (relative {:e}, noise {:e})",
                key.key,
                r.0,
                r.1
            );
        }
    }
    println!("{foundation}: worst relative difference above the noise {worst:.1e}");
}

#[test]
fn every_output_in_every_parameter_kind_consistent() {
    finite_differences("consistent");
}

#[test]
fn every_output_in_every_parameter_kind_lumped() {
    finite_differences("lumped");
}

/// The solution of a case, its states, and the derivative data of `parameters`.
struct Solved {
    discretization: crate::discretization::Discretization,
    report: crate::outcome::Report,
    prepared: Prepared,
}

fn solved(case: &Case, req: &Request) -> Solved {
    let run = run_request(case, req, &mut Silent).expect("a run");
    let d = run.outcome.discretization;
    let prepared =
        Prepared::new(&case.problem, &case.sensors, req, d.mesh(), &d.model).expect("prepared");
    Solved {
        discretization: d,
        report: run.outcome.report,
        prepared,
    }
}

/// The envelope identities: dJ/dp by the envelope theorem (no solve) equals the chain rule
/// through the tangent solve, `∂ₚJ + ∇J·δU` with ∇J from the solution itself, to 1e-10.
fn envelope(foundation: &str) {
    let case = Case::from_toml_str(&site(foundation), None).unwrap();
    // With an output besides the energy, the derivative data are those of the solves
    // (dL assembled), which the chain rule below reads.
    let req = request(&["energy", "total_contact_force"], &PARAMETERS);
    let s = solved(&case, &req);
    let model = &s.discretization.model;
    let u = &s.report.u;
    let states = States::classify(model, u, &s.report.certificate);
    let forces = crate::certificate::contact_forces(model, u);
    let at = At {
        mesh: s.discretization.mesh(),
        model,
        u,
        states: &states,
        energy: s.report.energy,
        forces: &forces,
    };
    let n = model.n();
    let p = states.p_hat(model, u);
    let q = states.q_hat(model, u);
    // ∇J of the piece at U: r + E_P L p̂ − E_Q L_low q̂ (r alone on held rows).
    let lp = states::restricted_mul(&model.l, &states.pen_up, &p);
    let lq = match &model.lower {
        Some(low) => states::restricted_mul(&low.l, &states.pen_low, &q),
        None => vec![0.0; n],
    };
    let grad: Vec<f64> = (0..n).map(|i| states.r[i] + lp[i] - lq[i]).collect();
    println!("{foundation}: parameter, dJ/dp (envelope), chain rule, relative difference");
    // Prepared for the energy alone (with its influence map): no consistent dL is
    // assembled, the envelope reads the element matrices; the same derivatives.
    let lean = Prepared::new(
        &case.problem,
        &case.sensors,
        &request(&["energy"], &PARAMETERS),
        s.discretization.mesh(),
        model,
    )
    .unwrap();
    for (d, e) in s.prepared.parameters.iter().zip(&lean.parameters) {
        let dr = at.dr(d);
        let env = at.envelope(d, &dr);
        if foundation == "consistent" {
            assert!(e.up.dl.is_none() && e.low.dl.is_none());
        }
        let lean_env = at.envelope(e, &at.dr(e));
        assert!(
            (lean_env - env).abs() <= 1e-13 * env.abs().max(1e-12),
            "{}: {lean_env:e} against {env:e}",
            d.key.key
        );
        let (du, _) = lcp::directional(&at, &states, None, 1e-12, d, &dr, 1.0).unwrap();
        // ∂ₚJ of the piece at fixed U.
        let mut partial = crate::sparse::dot(u, &dr);
        if d.tension {
            partial -= 0.5 / model.tension * model.s.quad_form(u);
        }
        if let Some(dl) = &d.up.dl {
            partial += 0.5 * outputs_quad(dl, &p);
        }
        if let Some(dphi) = &d.up.dphi {
            partial -= crate::sparse::dot(&lp, dphi);
        }
        if let Some(dl) = &d.low.dl {
            partial += 0.5 * outputs_quad(dl, &q);
        }
        if let Some(dphi) = &d.low.dphi {
            partial += crate::sparse::dot(&lq, dphi);
        }
        let chain = partial + crate::sparse::dot(&grad, &du);
        let scale = env
            .abs()
            .max(chain.abs())
            .max(1e-12 * s.report.energy.abs() / reference(&d.key));
        let rel = (env - chain).abs() / scale;
        println!("  {:>26} {env:>16.9e} {chain:>16.9e} {rel:9.1e}", d.key.key);
        assert!(
            rel <= 1e-10,
            "{foundation} {}: {env:e} against {chain:e}",
            d.key.key
        );
    }
}

fn outputs_quad(l: &crate::model::FoundationMatrix, x: &[f64]) -> f64 {
    match l {
        crate::model::FoundationMatrix::Consistent(a) => a.quad_form(x),
        crate::model::FoundationMatrix::Lumped(d) => d.iter().zip(x).map(|(d, x)| d * x * x).sum(),
        crate::model::FoundationMatrix::Rigid => 0.0,
    }
}

#[test]
fn envelope_identities_consistent() {
    envelope("consistent");
}

#[test]
fn envelope_identities_lumped() {
    envelope("lumped");
}

/// Taylor remainders `|Q(p + ε) − Q(p) − ε dQ/dp|` fall like ε² while the vertex states
/// stay (rates printed and checked above 1.8).
#[test]
fn taylor_remainders_fall_at_rate_two() {
    let case = Case::from_toml_str(&site("consistent"), None).unwrap();
    let outputs = [
        "energy",
        "sensor:B",
        "total_contact_force",
        "contact_force:stiff",
    ];
    let params = [
        "obstacle.stiffness.stiff",
        "membrane.tension",
        "lower.shape",
    ];
    let req = request(&outputs, &params);
    let (s, states) = values(&case, &req);
    let only = Request {
        influence: false,
        ..req.clone()
    };
    for (p, key) in s.parameters.iter().enumerate() {
        let eps: Vec<f64> = (0..4)
            .map(|k| 2e-3 * reference(key) / f64::powi(2.0, k))
            .collect();
        let mut rem = vec![vec![0.0; eps.len()]; outputs.len()];
        for (k, &e) in eps.iter().enumerate() {
            let (a, sa) = values(&moved(&case, key, key.value + e), &only);
            assert_eq!(sa, states, "{}: the states change at ε = {e:e}", key.key);
            for (o, r) in rem.iter_mut().enumerate() {
                r[k] = (a.values[o] - s.values[o] - e * s.get(o, p)).abs();
            }
        }
        for (o, name) in outputs.iter().enumerate() {
            let rates: Vec<f64> = rem[o].windows(2).map(|w| (w[0] / w[1]).log2()).collect();
            println!(
                "  {name:>20} in {:>26}: remainders {:.2e} .. {:.2e}, rates {rates:.3?}",
                key.key, rem[o][0], rem[o][3]
            );
            // A remainder at rounding level has no rate to show.
            if rem[o][0] > 1e-13 * s.values[o].abs() {
                assert!(
                    rates.iter().all(|&r| r > 1.8 && r < 2.2),
                    "{name} in {}: {rates:?}",
                    key.key
                );
            }
        }
    }
}

/// A rigid obstacle that the free membrane just touches at one vertex (φ = max u₀ there):
/// the vertex is biactive (zero contact force), and the one-sided derivatives in φ are
/// those of one-sided differences: raising the obstacle frees the membrane (0), lowering it
/// pushes the vertex down with it.
#[test]
fn a_biactive_vertex_gives_both_one_sided_derivatives() {
    for stiffness in ["\"rigid\"", "400"] {
        let base = |phi: f64, h: &str| {
            format!(
                r#"
[mesh]
generator = "rectangle"
nx = 8
[membrane]
tension = 1
load = 8
[obstacle]
shape = {phi:e}
stiffness = {h}
foundation = "lumped"
[solver]
method = "active-set"
tolerance = 1e-13
[[sensor]]
name = "mid"
at = [0.5, 0.5]
[[sensor]]
name = "side"
at = [0.25, 0.5]
"#
            )
        };
        let req = request(
            &["sensors", "energy", "total_contact_force"],
            &["obstacle.shape"],
        );
        // The free membrane's deflection at the centre.
        let free = Case::from_toml_str(&base(10.0, "0"), None).unwrap();
        let (f, _) = values(&free, &req);
        let top = f.values[0];
        let case = Case::from_toml_str(&base(top, stiffness), None).unwrap();
        let (s, _) = values(&case, &req);
        assert!(s.biactive() >= 1, "{stiffness}: {} biactive", s.biactive());
        assert_eq!(s.mode, Mode::OneSided);
        let key = &s.parameters[0];
        let at = |c: f64| values(&moved(&case, key, c), &req).0.values;
        // One-sided differences, Richardson-extrapolated (the response is piecewise
        // quadratic in φ: the extrapolation removes the O(h) term).
        let h = 1e-6 * top;
        let (u1, u2, d1, d2) = (
            at(top + h),
            at(top + 0.5 * h),
            at(top - h),
            at(top - 0.5 * h),
        );
        for o in 0..s.outputs.len() {
            let q = s.values[o];
            let right = 2.0 * (u2[o] - q) / (0.5 * h) - (u1[o] - q) / h;
            let left = 2.0 * (q - d2[o]) / (0.5 * h) - (q - d1[o]) / h;
            let (plus, minus) = (s.derivative_plus[o], s.derivative_minus[o]);
            println!(
                "  {stiffness:>8} {:>20}: plus {plus:.9e} (right difference {right:.9e}), minus {minus:.9e} (left {left:.9e}), derivative {:.6e}, flagged {}",
                s.outputs[o], s.derivative[o], s.nonsmooth[o]
            );
            let close = |a: f64, b: f64| agrees(difference(a, b, q, 0.5 * h));
            assert!(
                close(plus, right),
                "{}: plus {plus:e} right {right:e}",
                s.outputs[o]
            );
            assert!(
                close(minus, left),
                "{}: minus {minus:e} left {left:e}",
                s.outputs[o]
            );
            assert!(
                (s.derivative[o] - 0.5 * (plus + minus)).abs()
                    <= 1e-15 * plus.abs().max(minus.abs())
            );
        }
        // The centre's deflection follows the obstacle down, not up.
        assert!(s.nonsmooth[0] && s.derivative_plus[0].abs() < 1e-9 && s.derivative_minus[0] > 0.1);
    }
}

/// The axisymmetric disc (t = f = R = 1, φ = 0.1, h = 100): dJ/dh and du(0)/dh converge
/// under refinement to the values of the Bessel solution differentiated in h.
#[test]
fn disc_derivatives_converge_to_the_bessel_solution() {
    let exact =
        crate::verify::exact::DiskSolution::new([0.0, 0.0], 1.0, 1.0, 1.0, Some(100.0), 0.1)
            .unwrap();
    let (dj, du0) = exact.h_derivatives().unwrap();
    // The derivative of the closed form's u(0) by Richardson-extrapolated differences.
    let u0 = |h: f64| {
        crate::verify::exact::DiskSolution::new([0.0, 0.0], 1.0, 1.0, 1.0, Some(h), 0.1)
            .unwrap()
            .radial(0.0)[0]
    };
    let fd = |d: f64| (u0(100.0 + d) - u0(100.0 - d)) / (2.0 * d);
    let richardson = (4.0 * fd(0.05) - fd(0.1)) / 3.0;
    println!("exact: dJ/dh = {dj:.12e}, du(0)/dh = {du0:.12e} (differences of the closed form {richardson:.12e})");
    assert!((richardson - du0).abs() <= 1e-8 * du0.abs());
    // The values derived independently of this code (the same closed form, in extended
    // precision).
    #[allow(clippy::excessive_precision)] // the digits as derived
    const DJ_DH: f64 = 3.00389749175527651e-5;
    #[allow(clippy::excessive_precision)]
    const DU0_DH: f64 = -9.447197135043153254e-5;
    assert!(
        (dj - DJ_DH).abs() <= 1e-10 * DJ_DH.abs(),
        "{dj:e} against {DJ_DH:e}"
    );
    assert!(
        (du0 - DU0_DH).abs() <= 1e-10 * DU0_DH.abs(),
        "{du0:e} against {DU0_DH:e}"
    );
    let mut errors = Vec::new();
    for refine in 0..4 {
        let text = format!(
            r#"
[mesh]
generator = "disk"
radius = 1
size = 0.2
refine = {refine}
[membrane]
tension = 1
load = 1
[obstacle]
shape = 0.1
stiffness = 100
[solver]
method = "active-set"
tolerance = 1e-12
[[sensor]]
name = "centre"
at = [0, 0]
"#
        );
        let case = Case::from_toml_str(&text, None).unwrap();
        let req = request(&["energy", "sensor:centre"], &["obstacle.stiffness"]);
        let run = run_request(&case, &req, &mut Silent).unwrap();
        let s = run.sensitivities.unwrap();
        let n = run.outcome.discretization.mesh().n_vertices();
        let (ej, eu) = (
            (s.get(0, 0) - dj).abs() / dj.abs(),
            (s.get(1, 0) - du0).abs() / du0.abs(),
        );
        println!(
            "  refine {refine}: {n:>6} vertices, dJ/dh {:.10e} (rel. error {ej:.2e}), du(0)/dh {:.10e} (rel. error {eu:.2e})",
            s.get(0, 0),
            s.get(1, 0)
        );
        errors.push((ej, eu));
    }
    for w in errors.windows(2) {
        assert!(w[1].0 < 0.5 * w[0].0 && w[1].1 < 0.5 * w[0].1, "{errors:?}");
    }
}

/// A deterministic standard normal sequence (a linear congruential generator and the
/// Box-Muller transform), for the noisy fit.
fn normals(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed;
    let mut uniform = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (a, b) = (uniform(), uniform());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        })
        .collect()
}

/// A fit case on `mesh_case` (a case text without sensors and fit) with sensors at
/// `points` measuring the deflections of the true parameters `truth` (times `1 + noise_k`
/// with σ = the noise level times |u|, when `noise` > 0), started at `start`.
fn synthetic_fit(
    mesh_case: &str,
    points: &[[f64; 2]],
    truth: &[(&str, f64)],
    start: &[(&str, f64)],
    noise: f64,
    extra: &str,
) -> Case {
    let names: Vec<String> = (0..points.len()).map(|i| format!("S{i}")).collect();
    let sensors: String = points
        .iter()
        .zip(&names)
        .map(|(p, n)| format!("[[sensor]]\nname = \"{n}\"\nat = [{}, {}]\n", p[0], p[1]))
        .collect();
    let mut case = Case::from_toml_str(&format!("{mesh_case}{sensors}"), None).unwrap();
    for (k, v) in truth {
        ParameterKey::parse(&case.problem, k)
            .unwrap()
            .apply(&mut case.problem, *v)
            .unwrap();
    }
    let req = request(&["sensors"], &["membrane.tension"]);
    let (s, _) = values(&case, &req);
    let z = normals(7, points.len());
    for (i, sensor) in case.sensors.iter_mut().enumerate() {
        let u = s.values[i];
        sensor.measured = Some(u * (1.0 + noise * z[i]));
        if noise > 0.0 {
            sensor.sigma = Some(noise * u.abs());
        }
    }
    for (k, v) in start {
        ParameterKey::parse(&case.problem, k)
            .unwrap()
            .apply(&mut case.problem, *v)
            .unwrap();
    }
    let bounds: String = start
        .iter()
        .map(|(k, _)| format!("\"{k}\" = [1, 1e6]\n"))
        .collect();
    let text = format!(
        "{}[fit]\n{extra}\n[fit.parameters]\n{bounds}",
        case.to_toml_string().unwrap()
    );
    Case::from_toml_str(&text, None).unwrap()
}

/// A grid of points inside `[x0, x1] × [y0, y1]`.
fn grid(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Vec<[f64; 2]> {
    let mut p = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            p.push([
                x[0] + (x[1] - x[0]) * (i as f64 + 0.5) / nx as f64,
                y[0] + (y[1] - y[0]) * (j as f64 + 0.5) / ny as f64,
            ]);
        }
    }
    p
}

/// With 1 % noise on 24 sensors the fitted stiffnesses lie within three reported standard
/// errors of the true ones.
#[test]
fn a_noisy_fit_lies_within_three_standard_errors() {
    let base = site("consistent");
    let base = &base[..base.find("[[sensor]]").unwrap()];
    let truth = [
        ("lower.stiffness", 200.0),
        ("obstacle.stiffness.soft", 300.0),
        ("obstacle.stiffness.stiff", 1000.0),
    ];
    let start = [
        ("lower.stiffness", 1000.0),
        ("obstacle.stiffness.soft", 1500.0),
        ("obstacle.stiffness.stiff", 150.0),
    ];
    let points = grid(6, 4, [0.1, 1.9], [0.1, 0.9]);
    let case = synthetic_fit(base, &points, &truth, &start, 0.01, "tolerance = 1e-9");
    let run = crate::run::run_fit(&case, &mut Silent).unwrap();
    let f = &run.fit;
    println!(
        "noisy fit: {} iterations, {} solves, rms {:.3}, stop {}",
        f.iterations,
        f.solves,
        f.rms,
        f.stop.name()
    );
    assert!(f.converged, "{:?}", f.stop);
    for (p, (k, v)) in f.parameters.iter().zip(truth) {
        assert_eq!(p.key, k);
        let z = (p.value - v) / p.std_error;
        println!(
            "  {k:>26}: true {v}, fitted {:.4} ± {:.4} ({z:+.2} standard errors)",
            p.value, p.std_error
        );
        assert!(z.abs() <= 3.0, "{k}: {z}");
    }
    assert!(f.statistics.warning.is_none());
}

/// A fit of three soils' stiffnesses from 25 sensors on a 10⁵-vertex Gmsh mesh
/// (`scripts/make_strips.py --size 0.0045`, path in `MEMCONTACT_FIT_MESH`), started 5 to 8
/// times away: noise-free values recovered to 1e-6 in at most 15 iterations. Heavy: run
/// with `--ignored`.
#[test]
#[ignore]
fn a_fit_of_three_soils_on_a_hundred_thousand_vertices() {
    let Ok(mesh) = std::env::var("MEMCONTACT_FIT_MESH") else {
        eprintln!("set MEMCONTACT_FIT_MESH to a mesh of scripts/make_strips.py");
        return;
    };
    let base = format!(
        r#"
[mesh]
file = "{mesh}"
[membrane]
tension = 1
load = 20
[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = {{ clay = 400, sand = 1000, gravel = 2500 }}
"#
    );
    let truth = [
        ("obstacle.stiffness.clay", 400.0),
        ("obstacle.stiffness.gravel", 2500.0),
        ("obstacle.stiffness.sand", 1000.0),
    ];
    let start = [
        ("obstacle.stiffness.clay", 2400.0),
        ("obstacle.stiffness.gravel", 400.0),
        ("obstacle.stiffness.sand", 6000.0),
    ];
    let points = grid(5, 5, [0.1, 1.9], [0.1, 0.9]);
    let t0 = std::time::Instant::now();
    let case = synthetic_fit(
        &base,
        &points,
        &truth,
        &start,
        0.0,
        "tolerance = 1e-10\nmax_iterations = 15",
    );
    let t_truth = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let run = crate::run::run_fit(&case, &mut Silent).unwrap();
    let f = &run.fit;
    println!(
        "three soils on {} vertices: {} iterations, {} solves, rms {:.3e}, stop {}, {:.2} s (the truth's run {:.2} s)",
        run.outcome.discretization.mesh().n_vertices(),
        f.iterations,
        f.solves,
        f.rms,
        f.stop.name(),
        t0.elapsed().as_secs_f64(),
        t_truth
    );
    for h in &f.history {
        println!(
            "  iteration {:>2}: {:?} rms {:.3e} step {:.2e}",
            h.iteration, h.parameters, h.rms, h.step
        );
    }
    assert!(
        f.converged && f.iterations <= 15,
        "{:?} {}",
        f.stop,
        f.iterations
    );
    for (p, (k, v)) in f.parameters.iter().zip(truth) {
        assert_eq!(p.key, k);
        println!(
            "  {k}: {} (relative error {:.1e})",
            p.value,
            (p.value - v).abs() / v
        );
        assert!(
            (p.value - v).abs() <= 1e-6 * v,
            "{k}: {} against {v}",
            p.value
        );
    }
}
