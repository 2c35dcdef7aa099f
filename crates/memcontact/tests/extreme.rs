//! Extreme data: far and near obstacles, near-rigid soils, tiny loads on stiff soils, a
//! stiff region beside a free one, huge and tiny scales, slivers, a single unknown, and
//! overflowing data. Every method either returns an answer that an independent computation
//! confirms (the free membrane, the rigid limit, a scaled problem, another method) with an
//! accepted certificate, or refuses with a message that names the condition. No iterate
//! passes the certificate unless it solves the problem.

use memcontact::discretization::Discretization;
use memcontact::solve::{Method, Silent, Status};
use memcontact::{Case, Error, Report};

/// The methods every class is tried with (multigrid needs the rectangle's hierarchy;
/// `auto` picks multigrid there; `linear` applies only without contact, see
/// [`linear_refused`]).
const METHODS: [Method; 5] = [
    Method::Auto,
    Method::ActiveSet,
    Method::Multigrid,
    Method::Qp,
    Method::Coordinate,
];

/// `linear` refuses a problem where the body can touch, naming why.
fn linear_refused(what: &str, case: &Case) {
    let e = solve(case, Method::Linear)
        .err()
        .unwrap_or_else(|| panic!("{what}"));
    let m = e.to_string();
    assert!(m.contains("linear") && m.contains("touch"), "{what}: {m}");
}

/// The methods that need no mesh hierarchy.
const ANY_MESH: [Method; 3] = [Method::ActiveSet, Method::Qp, Method::Coordinate];

/// A square case with `n × n` cells and the given `[membrane]` and `[obstacle]` lines.
fn square(n: usize, membrane: &str, obstacle: &str) -> Case {
    let text = format!(
        "[mesh]\ngenerator = \"rectangle\"\nnx = {n}\n[membrane]\n{membrane}\n[obstacle]\n{obstacle}\n"
    );
    Case::from_toml_str(&text, None).unwrap_or_else(|e| panic!("{text}\n{e}"))
}

/// Solves `case` with `method`; `Err` for a refusal before solving.
fn solve(case: &Case, method: Method) -> Result<(Discretization, Report), Error> {
    let mut settings = case.settings.clone();
    settings.method = method;
    let d = Discretization::new(&case.problem, &mut Silent)?;
    let r = d.solve(&settings, &mut Silent)?;
    Ok((d, r))
}

/// Vertex values of U over the mesh (boundary zero).
fn u_of(d: &Discretization, r: &Report) -> Vec<f64> {
    d.model.dofs.to_vertices(&r.u, 0.0)
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The outcome is accepted with its certificate, or refused naming the conditioning.
fn accepted_or_refused(what: &str, r: &Report) -> bool {
    if r.accepted {
        accepted(what, r);
        return true;
    }
    let msg = r.error().unwrap().to_string();
    assert!(
        msg.contains("double precision") && msg.contains("rigid"),
        "{what}: {:?}: {msg}",
        r.status
    );
    false
}

/// The outcome is accepted and its certificate holds.
fn accepted(what: &str, r: &Report) {
    assert!(
        r.accepted,
        "{what}: {:?} with residual {:.3e} (floor {:.1e})",
        r.status,
        r.certificate.kkt(),
        r.certificate.rounding_floor
    );
    assert!(
        r.certificate.kkt() <= r.tolerance.max(8.0 * r.certificate.rounding_floor),
        "{what}: {:?}",
        r.certificate
    );
}

#[test]
fn a_far_obstacle_gives_the_free_membrane() {
    // f = 20 on the unit square with the body 10⁹ above: the answer is the free membrane
    // (max u ≈ 1.469), never u = 0.
    let far = square(16, "tension = 1\nload = 20", "shape = 1e9\nstiffness = 100");
    let free = square(16, "tension = 1\nload = 20", "shape = 1e9\nstiffness = 0");
    let (df, rf) = solve(&free, Method::Linear).unwrap();
    let u_free = u_of(&df, &rf);
    assert!((max_abs(&u_free) - 1.469).abs() < 0.01);
    for m in METHODS {
        let (d, r) = solve(&far, m).unwrap();
        accepted(m.name(), &r);
        assert!(r.iterations > 0, "{}: stopped at the start", m.name());
        let e = max_diff(&u_of(&d, &r), &u_free);
        assert!(e <= 1e-8, "{}: {e:.3e} from the free membrane", m.name());
    }
    linear_refused("far obstacle", &far);
    // The start U = 0 is not a solution, whatever the obstacle's L|φ|.
    let (d, _) = solve(&far, Method::ActiveSet).unwrap();
    assert!(d.model.certificate(&vec![0.0; d.model.n()]).kkt() > 0.1);
}

#[test]
fn a_near_rigid_soil_gives_the_rigid_limit_or_a_refusal() {
    let rigid = square(
        16,
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = \"rigid\"",
    );
    let (dr, rr) = solve(&rigid, Method::ActiveSet).unwrap();
    accepted("rigid", &rr);
    let u_rigid = u_of(&dr, &rr);
    for h in [1e11, 1e13, 1e15] {
        let case = square(
            16,
            "tension = 1\nload = 8",
            &format!("shape = 0.1\nstiffness = {h:e}"),
        );
        linear_refused("near-rigid", &case);
        for m in METHODS {
            let what = format!("h = {h:e}, {}", m.name());
            let (d, r) = solve(&case, m).unwrap_or_else(|e| panic!("{what}: {e}"));
            if accepted_or_refused(&what, &r) {
                // The elastic answer lies within about f/h (plus rounding) of the rigid one.
                let e = max_diff(&u_of(&d, &r), &u_rigid);
                assert!(e <= 1e-6, "{what}: {e:.3e} from the rigid limit");
            } else {
                assert_ne!(r.status, Status::Converged);
            }
        }
    }
}

#[test]
fn a_small_load_on_a_stiff_soil_scales_with_the_load() {
    // With φ = 0 the problem is positively homogeneous: u(f) = f u(1).
    let small = square(16, "tension = 1\nload = 1e-4", "shape = 0\nstiffness = 1e7");
    let unit = square(16, "tension = 1\nload = 1", "shape = 0\nstiffness = 1e7");
    let (du, ru) = solve(&unit, Method::ActiveSet).unwrap();
    accepted("unit load", &ru);
    let u1: Vec<f64> = u_of(&du, &ru).iter().map(|v| 1e-4 * v).collect();
    linear_refused("small load", &small);
    for m in METHODS {
        let (d, r) = solve(&small, m).unwrap();
        accepted(m.name(), &r);
        assert!(r.iterations > 0, "{}", m.name());
        let e = max_diff(&u_of(&d, &r), &u1) / max_abs(&u1);
        assert!(e <= 1e-7, "{}: relative {e:.3e}", m.name());
    }
}

#[test]
fn a_stiff_region_beside_a_free_one_is_solved_by_every_method_alike() {
    let case = square(
        16,
        "tension = 1\nload = 10",
        "shape = 0.05\nstiffness = \"if(x < 0.5, 1e7, 0)\"",
    );
    let (d0, r0) = solve(&case, Method::ActiveSet).unwrap();
    accepted("active-set", &r0);
    let u0 = u_of(&d0, &r0);
    // The free half deflects (the load is not carried by a zero solution there).
    assert!(max_abs(&u0) > 0.1);
    linear_refused("stiff beside free", &case);
    for m in METHODS {
        let (d, r) = solve(&case, m).unwrap();
        accepted(m.name(), &r);
        let e = max_diff(&u_of(&d, &r), &u0) / max_abs(&u0);
        assert!(e <= 1e-7, "{}: {e:.3e}", m.name());
    }
}

#[test]
fn scales_from_tiny_to_huge_are_certified() {
    // t from 1e-8 to 1e8 and h from 1e-12 to 1e12: u scales like f/t, the contact changes
    // with h; each answer is certified, and for h → 0 it is the free membrane.
    for t in [1e-8, 1.0, 1e8] {
        for h in [1e-12, 1.0, 1e4, 1e12] {
            let f = 10.0 * t;
            let case = square(
                8,
                &format!("tension = {t:e}\nload = {f:e}"),
                &format!("shape = 0.1\nstiffness = {h:e}"),
            );
            for m in [Method::ActiveSet, Method::Multigrid] {
                let what = format!("t {t:e} h {h:e} {}", m.name());
                let (d, r) = solve(&case, m).unwrap();
                // h/t up to 10²⁰ is beyond double precision: a refusal that says so.
                if accepted_or_refused(&what, &r) {
                    let u = u_of(&d, &r);
                    // f/t = 10 in every case: the free membrane's maximum is about 0.73.
                    assert!(max_abs(&u) <= 0.8, "{what}: {}", max_abs(&u));
                } else {
                    assert!(h / t >= 1e12, "{what}: refused");
                }
            }
        }
    }
}

#[test]
fn zero_load_far_below_and_the_free_solution_as_obstacle() {
    // f = 0, body above: u = 0 is the answer (and certified at once), also where the
    // interior-point method stops without progress from it (16 × 16).
    for n in [8, 16] {
        let case = square(n, "tension = 1\nload = 0", "shape = 0.2\nstiffness = 100");
        for m in METHODS {
            let (_, r) = solve(&case, m).unwrap();
            accepted(m.name(), &r);
            assert!(r.u.iter().all(|&v| v == 0.0), "{}", m.name());
        }
        // Without a body, the linear problem: u = 0 too.
        let free = square(n, "tension = 1\nload = 0", "shape = 0.2\nstiffness = 0");
        let (_, r) = solve(&free, Method::Linear).unwrap();
        accepted("linear", &r);
        assert!(r.u.iter().all(|&v| v == 0.0));
    }
    // A body far below (φ = −10⁶, h = 1) pushes the membrane down: certified by every
    // method and equal among them.
    let below = square(8, "tension = 1\nload = 0", "shape = -1e6\nstiffness = 1");
    let (d0, r0) = solve(&below, Method::ActiveSet).unwrap();
    accepted("below", &r0);
    let u0 = u_of(&d0, &r0);
    assert!(u0.iter().all(|&v| v <= 0.0) && max_abs(&u0) > 1.0);
    for m in METHODS {
        let (d, r) = solve(&below, m).unwrap();
        accepted(m.name(), &r);
        assert!(
            max_diff(&u_of(&d, &r), &u0) <= 1e-8 * max_abs(&u0),
            "{}",
            m.name()
        );
    }
    // The obstacle is the free membrane of the disc, f = 8, t = 1, R = 1:
    // u = 2(1 − r²). The answer is certified and lies within the discretisation error of φ.
    let text = "[mesh]\ngenerator = \"disk\"\nsize = 0.15\n[membrane]\ntension = 1\nload = 8\n\
                [obstacle]\nshape = \"2*(1 - r^2)\"\nstiffness = 1000\n";
    let case = Case::from_toml_str(text, None).unwrap();
    for m in [Method::ActiveSet, Method::Qp, Method::Coordinate] {
        let (d, r) = solve(&case, m).unwrap();
        accepted(m.name(), &r);
        let u = u_of(&d, &r);
        let phi = &d.model.phi_vertices();
        assert!(max_diff(&u, phi) < 0.05, "{}", m.name());
    }
}

#[test]
fn slivers_and_a_single_unknown() {
    // Cells of 3.56 × 0.0625: angles of 1°.
    let text = "[mesh]\ngenerator = \"rectangle\"\nx1 = 57\nnx = 16\n[membrane]\ntension = 1\n\
                load = 0.01\n[obstacle]\nshape = 0.5\nstiffness = 100\n";
    let case = Case::from_toml_str(text, None).unwrap();
    let (d, _) = solve(&case, Method::ActiveSet).unwrap();
    let q = d.mesh().quality();
    assert!(
        q.min_angle_deg < 1.01 && q.min_angle_deg > 0.99,
        "{}",
        q.min_angle_deg
    );
    let (d0, r0) = solve(&case, Method::ActiveSet).unwrap();
    accepted("sliver active-set", &r0);
    let u0 = u_of(&d0, &r0);
    for m in METHODS {
        let (d, r) = solve(&case, m).unwrap();
        accepted(&format!("sliver {}", m.name()), &r);
        assert!(max_diff(&u_of(&d, &r), &u0) <= 1e-8 * max_abs(&u0));
    }
    // A 2 × 2 square has one interior vertex: the problem is one-dimensional and the
    // answer is the exact minimiser of a piecewise quadratic.
    let case = square(2, "tension = 1\nload = 12", "shape = 0.1\nstiffness = 50");
    for m in ANY_MESH {
        let (d, r) = solve(&case, m).unwrap();
        accepted(&format!("one unknown {}", m.name()), &r);
        assert_eq!(d.model.n(), 1);
        let (s, dd, l) = (d.model.s.get(0, 0), d.model.d[0], d.model.l.diag(0));
        // Minimise ½ s u² − d u + ½ l (u − φ)⁺²: penetrating when d/s > φ.
        let free = dd / s;
        let expect = if free > 0.1 {
            (dd + l * 0.1) / (s + l)
        } else {
            free
        };
        assert!(
            (r.u[0] - expect).abs() <= 1e-12 * expect.abs(),
            "{}",
            m.name()
        );
    }
}

#[test]
fn overflowing_data_is_refused_naming_it() {
    let cases = [
        (
            "tension = 1e308\nload = 1",
            "shape = 0.1\nstiffness = 1",
            "tension",
        ),
        (
            "tension = 1\nload = 1e300",
            "shape = 0.1\nstiffness = 1",
            "load",
        ),
        (
            "tension = 1\nload = -1e300",
            "shape = 0.1\nstiffness = 1",
            "load",
        ),
    ];
    for (membrane, obstacle, needle) in cases {
        let case = square(8, membrane, obstacle);
        for m in METHODS.into_iter().chain([Method::Linear]) {
            let e = solve(&case, m)
                .err()
                .unwrap_or_else(|| panic!("{membrane}"));
            assert!(e.to_string().contains(needle), "{membrane}: {e}");
            assert!(e.to_string().contains("overflow"), "{membrane}: {e}");
        }
    }
    // A rectangle 10⁻³⁰⁰ high: S overflows.
    let text = "[mesh]\ngenerator = \"rectangle\"\ny1 = 1e-300\nnx = 4\n[membrane]\ntension = 1\n\
                load = 1\n[obstacle]\nshape = 0.1\nstiffness = 1\n";
    let e = solve(&Case::from_toml_str(text, None).unwrap(), Method::ActiveSet).unwrap_err();
    assert!(
        e.to_string().contains("stiffness matrix S overflows"),
        "{e}"
    );
    // A far obstacle at 10³⁰⁸ does not overflow anything: the free membrane.
    let case = square(
        8,
        "tension = 1\nload = 20",
        "shape = 1e308\nstiffness = 1e300",
    );
    let (_, r) = solve(&case, Method::ActiveSet).unwrap();
    accepted("φ = 1e308", &r);
    assert!(r.energy.is_finite() && r.energy < 0.0);
}

#[test]
fn tolerances_that_certify_nothing_are_refused() {
    for tol in ["1.0", "0.01", "0", "-1e-9", "nan"] {
        let text = format!(
            "[mesh]\ngenerator = \"rectangle\"\n[membrane]\ntension = 1\nload = 1\n[obstacle]\n\
             shape = 0.1\nstiffness = 1\n[solver]\ntolerance = {tol}\n"
        );
        let e = Case::from_toml_str(&text, None).unwrap_err();
        assert!(e.to_string().contains("solver.tolerance"), "{tol}: {e}");
    }
}
