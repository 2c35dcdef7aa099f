//! Tests of the exact solutions.

use super::bessel::*;
use super::*;
use crate::error::Result;
use spec_math::cephes64::i0;
use std::f64::consts::PI;

fn disc(t: f64, f: f64, h: Option<f64>, phi: f64) -> DiskSolution {
    DiskSolution::new([0.0, 0.0], 1.0, t, f, h, phi).unwrap()
}

/// Sixth-order central difference of the closed-form u' (test only): an independent u''.
fn fd_second(s: &DiskSolution, r: f64, d: f64) -> f64 {
    let du = |x: f64| s.radial(x)[1];
    (45.0 * (du(r + d) - du(r - d)) - 9.0 * (du(r + 2.0 * d) - du(r - 2.0 * d))
        + (du(r + 3.0 * d) - du(r - 3.0 * d)))
        / (60.0 * d)
}

/// Sixth-order central difference of a function of one variable (test only).
fn fd1(g: impl Fn(f64) -> f64, x: f64, d: f64) -> f64 {
    (45.0 * (g(x + d) - g(x - d)) - 9.0 * (g(x + 2.0 * d) - g(x - 2.0 * d))
        + (g(x + 3.0 * d) - g(x - 3.0 * d)))
        / (60.0 * d)
}

/// The ODE residual `-t (u'' + u'/r) + h (u - φ)⁺ - f` relative to the size of its terms,
/// with u'' from the closed form and, away from r = a, from finite differences of u'.
fn check_ode(s: &DiskSolution, tol: f64) {
    let (t, f, h, phi, big_r) = (s.t, s.f, s.h, s.phi, s.radius);
    let n = 200;
    for i in 1..n {
        let r = big_r * i as f64 / n as f64;
        let [u, du, d2u] = s.radial(r);
        let pen = (u - phi).max(0.0);
        let react = if h.is_infinite() { 0.0 } else { h * pen };
        let res = -t * (d2u + du / r) + react - f;
        let scale = f.abs() + react.abs() + t * (d2u.abs() + (du / r).abs());
        if s.regime == DiskRegime::Rigid && r < s.a {
            // Coincidence set: u = φ, and the obstacle takes the load.
            assert_eq!([u, du, d2u], [phi, 0.0, 0.0]);
            continue;
        }
        // h (u - φ) computed from u carries the rounding h·ε·|u| of u itself.
        let rounding = if h.is_infinite() {
            0.0
        } else {
            4.0 * f64::EPSILON * h * u.abs()
        };
        assert!(
            res.abs() <= tol * scale + rounding,
            "r = {r}: residual {res:e}, scale {scale:e}"
        );
        // Laplacian of the trait = u'' + u'/r.
        let lap = s.laplacian([r, 0.0]);
        assert!((lap - (d2u + du / r)).abs() <= tol * scale / t, "r = {r}");
        // An independent u'' where the stencil stays on one side of the contact circle.
        // Step: r/1000 where u varies on the scale r (outside the contact disc: B ln r), and
        // min(R, 1/k)/1000 inside it; no check when that is below R/10⁶.
        let inner = r < s.a && s.regime != DiskRegime::NoContact;
        let d = if inner && s.k.is_finite() {
            1e-3 * big_r.min(1.0 / s.k)
        } else {
            1e-3 * r
        };
        if d >= 1e-6 * big_r && (r - s.a).abs() > 4.0 * d && r + 4.0 * d < big_r {
            let fd = fd_second(s, r, d);
            assert!(
                (fd - d2u).abs() <= 1e-7 * (d2u.abs() + (du / r).abs() + (f / t).abs()),
                "r = {r}: u'' {d2u:e}, finite differences {fd:e}"
            );
        }
    }
    // The centre: Δu = 2 u''(0), u'(0) = 0.
    let [u0, du0, d2u0] = s.radial(0.0);
    assert_eq!(du0, 0.0);
    let react = if h.is_infinite() {
        0.0
    } else {
        h * (u0 - phi).max(0.0)
    };
    let res0 = -2.0 * t * d2u0 + react - f;
    if !(s.regime == DiskRegime::Rigid && s.a > 0.0) {
        assert!(
            res0.abs() <= tol * (f.abs() + react.abs()) + 4.0 * f64::EPSILON * h * u0.abs(),
            "centre: {res0:e}"
        );
    }
    // The boundary condition u(R) = 0 (relative to the largest deflection).
    let umax = s.radial(0.0)[0]
        .abs()
        .max(phi.abs())
        .max((f / t).abs() * big_r * big_r);
    assert!(
        s.radial(big_r)[0].abs() <= 1e-13 * umax,
        "u(R) = {}",
        s.radial(big_r)[0]
    );
}

/// `u(a⁻) = u(a⁺) = φ` and `u'(a⁻) = u'(a⁺)` from the inner and outer closed forms.
fn check_matching(s: &DiskSolution) {
    let (t, f, phi) = (s.t, s.f, s.phi);
    let q = ratios(s.k, s.a, s.a);
    let inner = [phi + f / t * q.w, -f / t * q.q1];
    let outer = s.outer(s.a);
    let scale_u = phi.abs() + f.abs() / t * s.radius * s.radius;
    let scale_du = (f / t).abs() * s.radius;
    assert!((inner[0] - phi).abs() <= 1e-14 * scale_u, "{inner:?} {phi}");
    assert!((outer[0] - phi).abs() <= 1e-12 * scale_u, "{outer:?} {phi}");
    assert!(
        (inner[1] - outer[1]).abs() <= 1e-12 * scale_du,
        "{inner:?} {outer:?}"
    );
    // B from the value condition agrees with B from the derivative condition.
    let b_value = (phi - f * (s.radius.powi(2) - s.a.powi(2)) / (4.0 * t)) / (s.a / s.radius).ln();
    // (The value form cancels when a ≪ R; its error is ε·scale_u/|ln(a/R)|.)
    let ln = (s.a / s.radius).ln().abs();
    assert!(
        (b_value - s.b).abs() <= 1e-11 * s.b.abs() + 1e-14 * scale_u / ln,
        "{b_value} {}",
        s.b
    );
    // The inner solution penetrates and the outer one stays clear.
    // (Strictly, unless the penetration ~ f/h is below the rounding of φ.)
    let inside = s.radial(0.5 * s.a)[0];
    assert!(inside > phi || (inside == phi && f / s.h < 1e-15 * phi.abs()));
    assert!(s.radial(0.5 * (s.a + s.radius))[0] < phi);
}

#[test]
fn contact_disc_solves_the_ode_and_matches_at_a() {
    let cases = [
        (1.0, 4.0, 100.0, 0.5), // k = 10
        (1.0, 4.0, 1e-3, 0.5),  // small k: the series branch everywhere
        (1.0, 4.0, 3.0, 0.5),   // k a crosses the series threshold 2 inside the disc
        (2.0, 1.0, 50.0, 0.1),  // t ≠ 1
        (1.0, 4.0, 1e6, 0.999), // a tiny contact disc
        (1.0, 1.0, 1e4, 1e-6),  // a close to R
    ];
    for (t, f, h, phi) in cases {
        let s = disc(t, f, Some(h), phi);
        assert_eq!(s.regime(), DiskRegime::ContactDisc, "{}", s.describe());
        assert!(s.a() > 0.0 && s.a() < 1.0);
        check_matching(&s);
        check_ode(&s, 1e-10);
        assert_eq!(s.c_scaled(), -f / h);
        let c = s.c();
        let i0a = i0(s.k() * s.a());
        assert!((c * i0a + f / h).abs() <= 1e-14 * f / h);
    }
}

#[test]
fn shifted_disc_with_gradient_against_finite_differences() {
    let s = DiskSolution::new([0.3, -1.0], 2.5, 2.0, 1.0, Some(50.0), 0.3).unwrap();
    assert_eq!(s.regime(), DiskRegime::ContactDisc);
    check_matching(&s);
    assert!(s.contains([0.3 + 2.5, -1.0]) && !s.contains([0.3 + 2.5001, -1.0]));
    assert!(s.value([0.3, 1.5]).abs() < 1e-14);
    for &(x, y) in &[
        (0.5, -0.7),
        (1.1, 0.2),
        (-1.5, -1.8),
        (0.31, -1.02),
        (2.0, -1.5),
    ] {
        let p = [x, y];
        let g = s.gradient(p);
        let d = 1e-3;
        let gx = fd1(|x| s.value([x, p[1]]), p[0], d);
        let gy = fd1(|y| s.value([p[0], y]), p[1], d);
        let scale = g[0].hypot(g[1]) + 1e-3;
        assert!((gx - g[0]).abs() <= 1e-9 * scale, "{p:?}: {gx} vs {}", g[0]);
        assert!((gy - g[1]).abs() <= 1e-9 * scale, "{p:?}: {gy} vs {}", g[1]);
    }
    assert_eq!(s.gradient([0.3, -1.0]), [0.0, 0.0]);
}

#[test]
fn series_and_direct_branches_agree() {
    for &(k, a, r) in &[(1.0, 1.99, 0.3), (1.0, 1.99, 1.9), (4.0, 0.4999, 0.1)] {
        let q = ratios(k, a, r);
        let direct = (1.0 - i0(k * r) / i0(k * a)) / (k * k);
        assert!((q.w - direct).abs() <= 1e-13 * direct, "{} {direct}", q.w);
    }
    // I₂/I₀ both ways around x = 2, against 1 - 2 I₁/(x I₀) where it is well conditioned.
    for &x in &[1.999_999, 2.0, 2.000_001] {
        let direct = 1.0 - 2.0 * spec_math::cephes64::i1(x) / (x * i0(x));
        assert!((ratio_i2_i0(x) - direct).abs() <= 1e-14, "{x}");
    }
    // Small x: I₂/I₀ ≈ x²/8.
    assert!((ratio_i2_i0(1e-6) / 1.25e-13 - 1.0).abs() < 1e-11);
}

#[test]
fn rigid_limit_is_approached_as_h_grows() {
    let (t, f, phi) = (1.0, 4.0, 0.5);
    let rigid = disc(t, f, None, phi);
    assert_eq!(rigid.regime(), DiskRegime::Rigid);
    check_matching_rigid(&rigid);
    check_ode(&rigid, 1e-10);
    let same = disc(t, f, Some(f64::INFINITY), phi);
    assert_eq!(same.a(), rigid.a());
    let mut prev_da = f64::INFINITY;
    let mut prev_du = f64::INFINITY;
    for j in 1..=8 {
        let h = 10f64.powi(j);
        let s = disc(t, f, Some(h), phi);
        let da = s.a() - rigid.a();
        // The softer obstacle is penetrated further: a_h > a_rigid, decreasing in h.
        assert!(da > 0.0 && da < prev_da, "h = {h}: a - a_rigid = {da}");
        // First-order asymptotics: a_h - a_rigid = 1/k + O(1/k²).
        if j >= 4 {
            assert!(
                (da * s.k() - 1.0).abs() < 3.0 / (s.k() * rigid.a()),
                "h = {h}: {}",
                da * s.k()
            );
        }
        let du = (0..=100)
            .map(|i| {
                let r = i as f64 / 100.0;
                (s.radial(r)[0] - rigid.radial(r)[0]).abs()
            })
            .fold(0.0, f64::max);
        assert!(du < prev_du, "h = {h}: {du}");
        prev_da = da;
        prev_du = du;
        check_ode(&s, 1e-10);
    }
    assert!(prev_da < 2e-4 && prev_du < 1e-7, "{prev_da} {prev_du}");
}

fn check_matching_rigid(s: &DiskSolution) {
    let o = s.outer(s.a);
    assert!((o[0] - s.phi).abs() <= 1e-14 * s.f * s.radius.powi(2));
    assert!(o[1].abs() <= 1e-14 * s.f * s.radius);
}

#[test]
fn large_k_is_finite_and_accurate() {
    for &h in &[1e8, 1e12, 1e30] {
        let s = disc(1.0, 4.0, Some(h), 0.5);
        assert_eq!(s.regime(), DiskRegime::ContactDisc);
        for i in 0..=1000 {
            let r = i as f64 / 1000.0;
            let v = s.radial(r);
            assert!(v.iter().all(|x| x.is_finite()), "h = {h}, r = {r}: {v:?}");
        }
        check_matching(&s);
        check_ode(&s, 1e-10);
        assert!(s.c().is_finite() && s.c() <= 0.0);
        let full = disc(1.0, 4.0, Some(h), -0.5);
        assert_eq!(full.regime(), DiskRegime::FullContact);
        check_ode(&full, 1e-10);
        assert!((0..=100).all(|i| full.radial(i as f64 / 100.0)[0].is_finite()));
    }
}

#[test]
fn full_contact_branch() {
    // (t, f, h, φ): φ < 0 ≤ f, φ = 0 < f, and φ < 0, f < 0 with u(0) ≥ φ.
    for (t, f, h, phi) in [
        (1.0, 1.0, 10.0, -0.1),
        (1.0, 1.0, 10.0, 0.0),
        (1.0, 0.0, 10.0, -0.2),
        (1.0, -0.5, 10.0, -1.0),
        (2.0, 3.0, 1e-4, -0.01),
        (0.5, 1.0, 2.0, -0.3),
    ] {
        let s = disc(t, f, Some(h), phi);
        assert_eq!(s.regime(), DiskRegime::FullContact, "{}", s.describe());
        assert_eq!(s.a(), 1.0);
        check_ode(&s, 1e-10);
        // Penetration everywhere in the open disc.
        for i in 0..100 {
            let r = i as f64 / 100.0;
            assert!(s.radial(r)[0] > phi, "{} r = {r}", s.describe());
        }
        assert_eq!(s.contact_area(), Some(PI));
    }
    // The boundary case u(0) = φ: f (I₀(kR) - 1) = hφ, just inside the full-contact range.
    let (t, h, phi) = (1.0, 4.0, -0.25);
    let f = h * phi / (i0(2.0) - 1.0) * (1.0 - 1e-12);
    let s = disc(t, f, Some(h), phi);
    assert_eq!(s.regime(), DiskRegime::FullContact);
    assert!((s.radial(0.0)[0] - phi).abs() < 1e-11);
}

#[test]
fn contact_disc_tends_to_full_contact_as_phi_tends_to_zero() {
    let full = disc(1.0, 1.0, Some(10.0), 0.0);
    let near = disc(1.0, 1.0, Some(10.0), 1e-13);
    assert_eq!(near.regime(), DiskRegime::ContactDisc);
    assert!(1.0 - near.a() < 1e-6, "{}", near.a());
    for i in 0..=20 {
        let r = i as f64 / 20.0;
        assert!((near.radial(r)[0] - full.radial(r)[0]).abs() < 1e-11);
    }
}

#[test]
fn no_contact_branch() {
    for (f, h, phi) in [
        (4.0, Some(10.0), 1.0), // u₀(0) = φ: touches at the centre only
        (4.0, Some(10.0), 2.0),
        (4.0, Some(0.0), 0.5), // h = 0: plain Poisson
        (4.0, Some(0.0), -0.5),
        (-1.0, Some(10.0), 0.0), // pulled away from the obstacle
        (-1.0, None, 0.3),
        (4.0, None, 1.5),
    ] {
        let s = disc(1.0, f, h, phi);
        assert_eq!(s.regime(), DiskRegime::NoContact, "{}", s.describe());
        assert_eq!(s.contact_radius(), Some(0.0));
        for i in 0..=10 {
            let r = i as f64 / 10.0;
            assert_eq!(s.radial(r)[0], f * (1.0 - r) * (1.0 + r) / 4.0);
        }
        assert_eq!(s.laplacian([0.2, 0.1]), -f);
    }
    // Rigid obstacle at φ = 0 pushed upwards: u ≡ 0, everything in contact.
    let s = disc(1.0, 1.0, None, 0.0);
    assert_eq!((s.regime(), s.a()), (DiskRegime::Rigid, 1.0));
    assert_eq!(s.value([0.3, 0.2]), 0.0);
}

#[test]
fn small_contact_disc_near_the_threshold() {
    // u₀(0) slightly above φ: a tiny contact disc, radius ~ √(R² - ψ) for small h.
    let (t, f) = (1.0, 4.0);
    let phi = 1.0 - 1e-6;
    let s = disc(t, f, Some(1e-6), phi);
    assert_eq!(s.regime(), DiskRegime::ContactDisc);
    let expected = (1.0 - 4.0 * t * phi / f).sqrt();
    assert!(
        (s.a() / expected - 1.0).abs() < 1e-6,
        "{} {expected}",
        s.a()
    );
    check_matching(&s);
    check_ode(&s, 1e-10);
}

#[test]
fn invalid_data_are_errors() {
    let e = |r: Result<DiskSolution>| r.unwrap_err().to_string();
    assert!(e(DiskSolution::new([0.0, 0.0], 1.0, 0.0, 1.0, Some(1.0), 0.1)).contains("tension"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        f64::NAN,
        1.0,
        Some(1.0),
        0.1
    ))
    .contains("tension"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        -1.0,
        1.0,
        1.0,
        Some(1.0),
        0.1
    ))
    .contains("radius"));
    assert!(e(DiskSolution::new(
        [f64::NAN, 0.0],
        1.0,
        1.0,
        1.0,
        Some(1.0),
        0.1
    ))
    .contains("centre"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        1.0,
        1.0,
        Some(-1.0),
        0.1
    ))
    .contains("stiffness"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        1.0,
        1.0,
        Some(f64::NAN),
        0.1
    ))
    .contains("stiffness"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        1.0,
        f64::INFINITY,
        Some(1.0),
        0.1
    ))
    .contains("load"));
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        1.0,
        1.0,
        Some(1.0),
        f64::NAN
    ))
    .contains("obstacle"));
    assert!(e(DiskSolution::new([0.0, 0.0], 1.0, 1.0, 1.0, None, -0.1)).contains("rigid"));
    // Annular contact: pulled down in the middle, obstacle below the rim.
    assert!(e(DiskSolution::new(
        [0.0, 0.0],
        1.0,
        1.0,
        -10.0,
        Some(10.0),
        -0.01
    ))
    .contains("annulus"));
}

#[test]
fn manufactured_derivatives_against_finite_differences() {
    let sols = [
        Manufactured::rectangle(-1.0, 0.5, 2.0, 1.5, 0.7).unwrap(),
        Manufactured::disk([0.2, -0.4], 1.3, -2.0).unwrap(),
    ];
    let pts = [[0.1, 0.8], [1.2, 1.1], [-0.5, 0.6], [0.6, 0.7]];
    for s in &sols {
        for &p0 in &pts {
            let p = if s.disk().is_some() {
                [p0[0] * 0.8, p0[1] - 1.0]
            } else {
                p0
            };
            assert!(s.contains(p), "{p:?}");
            let d = 1e-3;
            let g = s.gradient(p);
            let gx = fd1(|x| s.value([x, p[1]]), p[0], d);
            let gy = fd1(|y| s.value([p[0], y]), p[1], d);
            assert!(
                (gx - g[0]).abs() < 1e-10 && (gy - g[1]).abs() < 1e-10,
                "{p:?}"
            );
            let lx = fd1(|x| s.gradient([x, p[1]])[0], p[0], d);
            let ly = fd1(|y| s.gradient([p[0], y])[1], p[1], d);
            let lap = s.laplacian(p);
            assert!(
                (lx + ly - lap).abs() < 1e-9 * (1.0 + lap.abs()),
                "{p:?}: {} {lap}",
                lx + ly
            );
            // The load helper is Problem 1 read from left to right.
            let (t, h, phi) = (1.5, 20.0, 0.05);
            let load = manufactured_load(s, p, t, h, phi).unwrap();
            assert_eq!(load, -t * lap + h * (s.value(p) - phi).max(0.0));
        }
    }
    // Zero on the boundary.
    let r = &sols[0];
    for i in 0..=10 {
        let x = -1.0 + 3.0 * i as f64 / 10.0;
        assert!(r.value([x, 0.5]).abs() < 1e-15 && r.value([x, 1.5]).abs() < 1e-15);
    }
    let d = &sols[1];
    for i in 0..16 {
        let th = 2.0 * PI * i as f64 / 16.0;
        let p = [0.2 + 1.3 * th.cos(), -0.4 + 1.3 * th.sin()];
        assert!(d.contains(p) && d.value(p).abs() < 1e-14);
    }
    assert_eq!(d.disk(), Some(([0.2, -0.4], 1.3)));
    assert!(!d.contains([1.6, -0.4]));
    assert!(manufactured_load(d, [1.6, -0.4], 1.0, 0.0, 0.0).is_err());
    assert!(manufactured_load(d, [0.0, 0.0], 0.0, 0.0, 0.0).is_err());
    assert!(Manufactured::rectangle(1.0, 0.0, 0.0, 1.0, 1.0).is_err());
    assert!(Manufactured::disk([0.0, 0.0], 0.0, 1.0).is_err());
}

#[test]
fn brent_finds_roots_to_machine_precision() {
    let g = |x: f64| x * x - 2.0;
    let r = brent(g, 0.0, 2.0, -2.0, 2.0);
    assert!((r - 2f64.sqrt()).abs() <= 4.0 * f64::EPSILON);
    let g = |x: f64| (x - 1e-9).powi(3);
    let r = brent(g, 0.0, 1.0, g(0.0), g(1.0));
    assert!((r - 1e-9).abs() <= 1e-12, "{r}");
}

#[test]
fn obstacle_benchmarks_are_continuous_c1_and_harmonic_outside() {
    let a = EX9_RADIUS;
    for kind in [BenchmarkKind::PetscEx9, BenchmarkKind::MfemEx36] {
        for below in [true, false] {
            let b = ObstacleBenchmark::new(kind, below);
            let s = b.scale;
            let r = s * a;
            // Value and slope match at the contact radius.
            let (lo, hi) = ([r * (1.0 - 1e-12), 0.0], [r * (1.0 + 1e-12), 0.0]);
            assert!((b.value(lo) - b.value(hi)).abs() < 1e-10);
            assert!((b.gradient(lo)[0] - b.gradient(hi)[0]).abs() < 1e-9);
            // u = ψ on the contact disc, u above ψ (below φ) beyond.
            for k in 0..=40 {
                let rho = 1.9 * s * k as f64 / 40.0;
                let p = [rho * 0.6, rho * 0.8];
                let gap = b.sign * (b.value(p) - b.surface(p));
                if rho <= r {
                    assert!(gap.abs() < 1e-14, "{kind:?} r {rho}");
                } else {
                    assert!(gap > 0.0, "{kind:?} r {rho}: {gap}");
                }
            }
            // The outer part is harmonic: a finite-difference Laplacian vanishes.
            let p = [0.8 * s, 0.5 * s];
            let d = 1e-4 * s;
            let fd = (b.value([p[0] + d, p[1]])
                + b.value([p[0] - d, p[1]])
                + b.value([p[0], p[1] + d])
                + b.value([p[0], p[1] - d])
                - 4.0 * b.value(p))
                / (d * d);
            assert!(fd.abs() < 1e-5, "{fd}");
            assert_eq!(b.laplacian(p), 0.0);
        }
    }
    // MFEM ex36 is ex9 scaled by ½: u = ln r × A₃₆ outside, A₃₆ = −0.340129705945858.
    let m = ObstacleBenchmark::new(BenchmarkKind::MfemEx36, true);
    let p: [f64; 2] = [0.5, 0.3];
    let r = p[0].hypot(p[1]);
    assert!((m.value(p) - (-0.340129705945858) * r.ln()).abs() < 1e-13);
    assert!(m.value([1.0, 0.0]).abs() < 1e-15);
    // ex9's boundary values: u = A ln(2/r), zero at the midpoints of the sides.
    let e = ObstacleBenchmark::new(BenchmarkKind::PetscEx9, true);
    assert!(e.value([2.0, 0.0]).abs() < 1e-15);
    assert!(e.value([2.0, 2.0]) < 0.0);
}

#[test]
fn the_cosine_manufactured_solution_has_its_derivatives() {
    let m = ManufacturedCosine::rectangle(0.0, 0.0, 2.0, 1.0, 0.3).unwrap();
    let d = 1e-5;
    for p in [[0.3, 0.2], [1.1, 0.7], [1.9, 0.45]] {
        let g = m.gradient(p);
        let fx = (m.value([p[0] + d, p[1]]) - m.value([p[0] - d, p[1]])) / (2.0 * d);
        let fy = (m.value([p[0], p[1] + d]) - m.value([p[0], p[1] - d])) / (2.0 * d);
        assert!((g[0] - fx).abs() < 1e-8 && (g[1] - fy).abs() < 1e-8);
        let lap = (m.value([p[0] + d, p[1]])
            + m.value([p[0] - d, p[1]])
            + m.value([p[0], p[1] + d])
            + m.value([p[0], p[1] - d])
            - 4.0 * m.value(p))
            / (d * d);
        assert!(
            (m.laplacian(p) - lap).abs() < 1e-4,
            "{} {lap}",
            m.laplacian(p)
        );
    }
    // The normal derivative vanishes on every side.
    for t in [0.1, 0.5, 0.9] {
        assert!(m.gradient([0.0, t])[0].abs() < 1e-14);
        assert!(m.gradient([2.0, t])[0].abs() < 1e-14);
        assert!(m.gradient([2.0 * t, 0.0])[1].abs() < 1e-14);
        assert!(m.gradient([2.0 * t, 1.0])[1].abs() < 1e-14);
    }
}
