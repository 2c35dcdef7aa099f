//! `[exact]`: the closed-form solution a case has, for convergence studies.

use serde::{Deserialize, Serialize};

/// `[exact]`: a closed-form solution of the case, for `memcontact convergence`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum ExactSpec {
    /// The axisymmetric disc (constant t, f, h, φ on a disc mesh): Bessel functions.
    Disk {},
    /// A manufactured solution: the load is replaced by `f = −tΔu + h(u − φ)⁺` (minus
    /// `h_low(φ_low − u)⁺` with a body below) and the heights of the fixed boundary by u.
    Manufactured {
        /// The domain of the manufactured u (it vanishes on its boundary).
        domain: ManufacturedDomain,
        /// The scale of u.
        amplitude: f64,
        /// Which u: one vanishing on the boundary (default), or, on a rectangle, one with
        /// zero normal derivative on every side (any side may then be free).
        #[serde(default, skip_serializing_if = "ManufacturedForm::is_default")]
        form: ManufacturedForm,
    },
    /// PETSc SNES ex9: the rigid spherical obstacle on (−2, 2)² with its boundary data.
    #[serde(rename = "petsc-ex9")]
    PetscEx9 {
        /// Which body is the obstacle: `"obstacle"` above (u ≤ φ = −ψ, the solution
        /// negated; default) or `"lower"` (u ≥ ψ, as in PETSc).
        #[serde(default, skip_serializing_if = "BenchmarkBody::is_default")]
        body: BenchmarkBody,
    },
    /// MFEM ex36: PETSc SNES ex9 scaled by ½ onto the unit disc (g = 0).
    #[serde(rename = "mfem-ex36")]
    MfemEx36 {
        /// As for `petsc-ex9`.
        #[serde(default, skip_serializing_if = "BenchmarkBody::is_default")]
        body: BenchmarkBody,
    },
}

impl ExactSpec {
    /// The name used in case files.
    pub fn kind(&self) -> &'static str {
        match self {
            ExactSpec::Disk {} => "disk",
            ExactSpec::Manufactured { .. } => "manufactured",
            ExactSpec::PetscEx9 { .. } => "petsc-ex9",
            ExactSpec::MfemEx36 { .. } => "mfem-ex36",
        }
    }
}

/// The domain of a manufactured solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ManufacturedDomain {
    /// The rectangle of `[mesh]`.
    Rectangle,
    /// The disc of `[mesh]`.
    Disk,
}

/// Which manufactured solution.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ManufacturedForm {
    /// u vanishes on the boundary (the paper's frame).
    #[default]
    Vanishing,
    /// On a rectangle, `u = A (cos(πX) cos(πY) + ½ cos(2πY))`: zero normal derivative on
    /// every side, so sides may be free, and non-zero heights on the fixed ones.
    Cosine,
}

impl ManufacturedForm {
    fn is_default(&self) -> bool {
        *self == ManufacturedForm::Vanishing
    }
}

/// The body of a rigid obstacle benchmark.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BenchmarkBody {
    /// The obstacle above (`[obstacle]`), with the problem negated.
    #[default]
    Obstacle,
    /// The body below (`[lower]`), the benchmark's own convention.
    Lower,
}

impl BenchmarkBody {
    fn is_default(&self) -> bool {
        *self == BenchmarkBody::Obstacle
    }
}
