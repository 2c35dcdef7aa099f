//! The assembled data's derivatives in one datum (docs/theory.md#sensitivities): S, L, D,
//! φₙ and the lifting `S_fix G` are each linear in one of t, h, f, φ and g, so the
//! derivative of, say, L in a region's stiffness is L assembled with that region's
//! derivative coefficient (1 on the region, 0 elsewhere; the entry's expression for a
//! factor). Here: that assembly, by the very kernels [`super::Model::assemble_on`] uses,
//! so that the derivative data are those of the discrete problem solved (same quadrature,
//! same sampling of φ and its mollifier radius, same averaging of boundary heights, the
//! rigid regions masked as in the solve).

use super::assemble::Masked;
use super::body::FoundationMatrix;
use super::data::{BodyData, BodyStiffness, Foundation, Sampling};
use super::sampling::{mollify, vertex_average};
use crate::error::Result;
use crate::fem::{assemble_lift, assemble_mass, mass_quad_form, Loads, VertexTriangles};
use crate::field::Coefficient;
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::{DofMap, Mesh};
use crate::sparse::Pattern;
use std::sync::{Arc, OnceLock};

/// `xᵀ dL x` for the consistent foundation matrix dL of the derivative coefficient `c` of a
/// body's stiffness (its rigid regions masked), from the element matrices: the energy's
/// derivative `½ p̂ᵀ dL p̂` (docs/theory.md#envelope) needs no assembled dL.
pub fn consistent_foundation_form(
    mesh: &Mesh,
    dofs: &DofMap,
    c: &dyn Coefficient,
    rigid_regions: &[u32],
    x: &[f64],
) -> f64 {
    let masked = masked(c, rigid_regions);
    mass_quad_form(
        mesh,
        dofs,
        masked.elastic().expect("an elastic coefficient"),
        x,
    )
}

/// The derivative coefficient `c` of a body's stiffness with the body's rigid regions
/// masked to 0, as the model masks the stiffness ([`Masked`]).
fn masked<'b>(c: &'b dyn Coefficient, rigid_regions: &'b [u32]) -> Masked<'b> {
    Masked::new(BodyData {
        shape: &0.0,
        stiffness: BodyStiffness::Elastic(c),
        rigid_regions,
        foundation: Foundation::Consistent,
        sampling: Sampling::Nodal,
    })
}

/// The mesh and numbering the derivative data are assembled on (those of the model), with
/// the vertex → triangles adjacency and the triangles' areas built on first use and shared
/// by every parameter's assembly.
pub struct DerivativeAssembly<'a> {
    /// The solved mesh (the solver's numbering).
    pub mesh: &'a Mesh,
    /// The model's unknowns.
    pub dofs: &'a DofMap,
    /// The pattern of S (and of a consistent L).
    pub pattern: &'a Arc<Pattern>,
    /// The vertex → triangles adjacency.
    adjacency: OnceLock<VertexTriangles>,
    /// The triangles' areas ([`Mesh::areas`]).
    triangle_areas: OnceLock<Vec<f64>>,
}

impl<'a> DerivativeAssembly<'a> {
    /// The assembly on `mesh` with the unknowns `dofs` and the pattern of S.
    pub fn new(mesh: &'a Mesh, dofs: &'a DofMap, pattern: &'a Arc<Pattern>) -> Self {
        DerivativeAssembly {
            mesh,
            dofs,
            pattern,
            adjacency: OnceLock::new(),
            triangle_areas: OnceLock::new(),
        }
    }

    /// The vertex → triangles adjacency (built on the first call).
    fn adj(&self) -> &VertexTriangles {
        self.adjacency
            .get_or_init(|| VertexTriangles::new(self.mesh))
    }

    /// The triangles' areas (computed on the first call).
    fn areas(&self) -> &[f64] {
        self.triangle_areas.get_or_init(|| self.mesh.areas())
    }

    /// `∫ c gᵢ` over the unknowns and `∫_Ω c`: the derivative of D and of the total load in
    /// a datum of f whose derivative coefficient is `c`.
    pub fn load(&self, c: &dyn Coefficient) -> (Vec<f64>, f64) {
        Loads::new(self.mesh, self.dofs, self.adj(), self.areas()).vector_and_integral(c)
    }

    /// The foundation matrix of the derivative coefficient `c` of a body's stiffness, with
    /// the body's rigid regions masked (0 there) and its foundation (consistent or lumped):
    /// the derivative of L.
    pub fn foundation(
        &self,
        c: &dyn Coefficient,
        rigid_regions: &[u32],
        foundation: Foundation,
    ) -> FoundationMatrix {
        let masked = masked(c, rigid_regions);
        let h = masked.elastic().expect("an elastic coefficient");
        match foundation {
            Foundation::Consistent => FoundationMatrix::Consistent(assemble_mass(
                self.mesh,
                self.dofs,
                self.adj(),
                self.pattern,
                h,
            )),
            Foundation::Lumped => FoundationMatrix::Lumped(
                Loads::new(self.mesh, self.dofs, self.adj(), self.areas()).vector(h),
            ),
        }
    }

    /// The derivative coefficient `c` of a body's stiffness at every vertex (the average
    /// over the triangles around it, rigid regions masked), as the model keeps h for its
    /// outputs.
    pub fn vertex_stiffness(&self, c: &dyn Coefficient, rigid_regions: &[u32]) -> Vec<f64> {
        let masked = masked(c, rigid_regions);
        vertex_average(
            self.mesh,
            self.adj(),
            masked.elastic().expect("an elastic coefficient"),
        )
    }

    /// The derivative coefficient `c` of a surface sampled as the model sampled the
    /// surface (nodal, or mollified with the radius `epsilon` the model used), at every
    /// vertex.
    pub fn surface(&self, c: &dyn Coefficient, epsilon: Option<f64>) -> Vec<f64> {
        match epsilon {
            None => vertex_average(self.mesh, self.adj(), c),
            Some(eps) => mollify(self.mesh, self.adj(), c, eps),
        }
    }

    /// The derivative coefficient `c` of the boundary heights, averaged at the fixed
    /// vertices as the model averages g (0 elsewhere), over all vertices.
    pub fn heights(&self, c: &dyn Coefficient, free: &[String]) -> Result<Vec<f64>> {
        let fixed = FixedBoundary::new(self.mesh, self.adj(), free)?;
        super::boundary::boundary_heights(self.mesh, &fixed, c)
    }

    /// The lifting `S_fix G` of heights `g` (over all vertices) for the tension `t`.
    pub fn lift(&self, t: f64, g: &[f64]) -> Vec<f64> {
        assemble_lift(self.mesh, self.dofs, self.adj(), t, g)
    }
}
