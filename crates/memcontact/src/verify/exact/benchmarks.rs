//! The obstacle benchmarks of PETSc SNES ex9 and MFEM ex36
//! (docs/theory.md#obstacle-benchmarks).

use super::solution::ExactSolution;
use std::f64::consts::PI;

/// PETSc SNES ex9's contact radius `a` (docs/theory.md#obstacle-benchmarks): where `√(1 −
/// a²)` meets `−A ln a + B` with matching slopes.
pub const EX9_RADIUS: f64 = 0.697965148223374;

/// The radius where PETSc SNES ex9's obstacle turns from the sphere to its tangent line.
pub const EX9_KNEE: f64 = 0.9;

/// The classical radial obstacle benchmarks (docs/theory.md#obstacle-benchmarks): a rigid
/// spherical cap with a conical skirt, `f = 0`, t = 1, the membrane lying on the cap for `r
/// ≤ a` and harmonic beyond.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchmarkKind {
    /// PETSc SNES ex9: Ω = (−2, 2)², `ψ = √(1 − r²)` for `r ≤ 0.9` and its tangent line
    /// beyond, `u = ψ` for `r ≤ a`, `u = −A ln r + B` beyond, `A = a²/√(1 − a²)`,
    /// `B = A ln 2`, `g = u` on ∂Ω.
    PetscEx9,
    /// MFEM ex36: the same problem scaled by ½ onto the unit disc (`g = 0` on the circle).
    MfemEx36,
}

/// A radial obstacle benchmark ([`BenchmarkKind`]) in either sign convention: the body
/// below as in the benchmark (`u ≥ ψ`, `sign = 1`), or this project's obstacle above
/// (`u ≤ φ = −ψ`, the solution `−u`, `sign = −1`).
#[derive(Debug, Clone, Copy)]
pub struct ObstacleBenchmark {
    pub(super) kind: BenchmarkKind,
    /// 1 for ex9, ½ for ex36: `u(r) = s u₉(r / s)`.
    pub(super) scale: f64,
    pub(super) sign: f64,
}

impl ObstacleBenchmark {
    /// The benchmark `kind`; `below = true` for the body below (the benchmark's own
    /// convention), `false` for the obstacle above (the solution and obstacle negated).
    pub fn new(kind: BenchmarkKind, below: bool) -> ObstacleBenchmark {
        ObstacleBenchmark {
            kind,
            scale: match kind {
                BenchmarkKind::PetscEx9 => 1.0,
                BenchmarkKind::MfemEx36 => 0.5,
            },
            sign: if below { 1.0 } else { -1.0 },
        }
    }

    /// `A = a²/√(1 − a²)` of ex9.
    fn big_a() -> f64 {
        EX9_RADIUS * EX9_RADIUS / (1.0 - EX9_RADIUS * EX9_RADIUS).sqrt()
    }

    /// ex9's radial profile at ρ: `[u, u', Δu]`.
    fn profile(rho: f64) -> [f64; 3] {
        let a = EX9_RADIUS;
        if rho <= a {
            let w = 1.0 - rho * rho;
            [
                w.sqrt(),
                -rho / w.sqrt(),
                -(2.0 - rho * rho) / (w * w.sqrt()),
            ]
        } else {
            let big_a = Self::big_a();
            [big_a * (2.0 / rho).ln(), -big_a / rho, 0.0]
        }
    }

    /// ex9's obstacle ψ at ρ: the sphere, then its tangent line beyond 0.9.
    pub fn ex9_obstacle(rho: f64) -> f64 {
        let k = EX9_KNEE;
        if rho <= k {
            (1.0 - rho * rho).sqrt()
        } else {
            let c = (1.0 - k * k).sqrt();
            c - k / c * (rho - k)
        }
    }

    /// The body's surface at `p` in this convention: `ψ` below, `φ = −ψ` above.
    pub fn surface(&self, p: [f64; 2]) -> f64 {
        let s = self.scale;
        self.sign * s * Self::ex9_obstacle(p[0].hypot(p[1]) / s)
    }

    /// `true` for the convention of the body below.
    pub fn below(&self) -> bool {
        self.sign > 0.0
    }

    /// Which benchmark.
    pub fn kind(&self) -> BenchmarkKind {
        self.kind
    }
}

impl ExactSolution for ObstacleBenchmark {
    fn value(&self, p: [f64; 2]) -> f64 {
        let s = self.scale;
        self.sign * s * Self::profile(p[0].hypot(p[1]) / s)[0]
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let r = p[0].hypot(p[1]);
        if r == 0.0 {
            return [0.0, 0.0];
        }
        let du = self.sign * Self::profile(r / self.scale)[1];
        [du * p[0] / r, du * p[1] / r]
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        self.sign * Self::profile(p[0].hypot(p[1]) / self.scale)[2] / self.scale
    }

    fn contact_radius(&self) -> Option<f64> {
        Some(self.scale * EX9_RADIUS)
    }

    fn contact_area(&self) -> Option<f64> {
        let a = self.scale * EX9_RADIUS;
        Some(PI * a * a)
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        match self.kind {
            BenchmarkKind::PetscEx9 => {
                let tol = 2.0 + 4e-10;
                p[0].abs() <= tol && p[1].abs() <= tol
            }
            BenchmarkKind::MfemEx36 => p[0].hypot(p[1]) <= 1.0 + 1e-10,
        }
    }

    fn disk(&self) -> Option<([f64; 2], f64)> {
        match self.kind {
            BenchmarkKind::PetscEx9 => None,
            BenchmarkKind::MfemEx36 => Some(([0.0, 0.0], 1.0)),
        }
    }

    fn describe(&self) -> String {
        let (name, domain) = match self.kind {
            BenchmarkKind::PetscEx9 => ("PETSc SNES ex9", "(−2, 2)², g = u on the boundary"),
            BenchmarkKind::MfemEx36 => ("MFEM ex36", "the unit disc, g = 0"),
        };
        let convention = if self.below() {
            "rigid body below, u ≥ ψ"
        } else {
            "rigid obstacle above, u ≤ φ = −ψ (the solution negated)"
        };
        format!(
            "{name}: f = 0, t = 1 on {domain}; {convention}; contact radius a = {}",
            self.scale * EX9_RADIUS
        )
    }
}
