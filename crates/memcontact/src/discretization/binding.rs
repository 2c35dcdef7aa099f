//! The problem's data bound to a mesh: region tables resolved against its regions, nodal
//! values against its vertices, boundary heights against its boundary regions.

use crate::error::{Error, Result};
use crate::field::BoundField;
use crate::mesh::Mesh;
use crate::model::{BodyData, BodyStiffness, BoundaryData, Extensions, Model, ProblemData};
use crate::problem::Problem;

/// The problem's data f, φ, h (and the data beyond the paper's frame: boundary heights,
/// rigid regions, the body below) bound to a mesh's regions.
#[derive(Debug, Clone)]
pub struct BoundData {
    /// The load f.
    pub load: BoundField,
    /// The obstacle's surface φ.
    pub shape: BoundField,
    /// The stiffness h (`None`: rigid).
    pub stiffness: Option<BoundField>,
    /// The obstacle's rigid regions when it is elastic elsewhere (mixed bodies).
    pub rigid_regions: Vec<u32>,
    /// The heights g on the fixed boundary, bound to the boundary regions, and the free
    /// regions (`None`: the whole boundary fixed at 0).
    pub boundary: Option<(BoundField, Vec<String>)>,
    /// The body below.
    pub lower: Option<BoundBody>,
}

/// A body's data bound to a mesh: surface, stiffness, rigid regions.
#[derive(Debug, Clone)]
pub struct BoundBody {
    /// The surface.
    pub shape: BoundField,
    /// The stiffness (`None`: rigid everywhere).
    pub stiffness: Option<BoundField>,
    /// The rigid regions when it is elastic elsewhere.
    pub rigid_regions: Vec<u32>,
}

impl BoundBody {
    fn new(section: &str, body: &crate::problem::Obstacle, mesh: &Mesh) -> Result<BoundBody> {
        let stiffness = body
            .stiffness
            .bind_to_mesh(&format!("{section}.stiffness"), mesh)?;
        let rigid_regions = if stiffness.is_rigid() {
            Vec::new()
        } else {
            stiffness.rigid_tags
        };
        Ok(BoundBody {
            shape: body.shape.bind_to_mesh(&format!("{section}.shape"), mesh)?,
            stiffness: stiffness.elastic,
            rigid_regions,
        })
    }

    fn stiffness(&self) -> BodyStiffness<'_> {
        match &self.stiffness {
            Some(h) => BodyStiffness::Elastic(h),
            None => BodyStiffness::Rigid,
        }
    }
}

impl BoundData {
    /// Binds the problem's f, φ and h to the regions of `mesh` (a region table must name
    /// regions the mesh has, or give a default) or, for nodal values, to its vertices; the
    /// boundary heights to the mesh's boundary regions.
    pub fn new(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
        let upper = BoundBody::new("obstacle", &problem.obstacle, mesh)?;
        let boundary = if problem.boundary.is_default() {
            None
        } else {
            let height = bind_height(&problem.boundary, mesh)?;
            Some((height, problem.boundary.free.clone()))
        };
        Ok(BoundData {
            load: problem.membrane.load.bind_to_mesh("membrane.load", mesh)?,
            shape: upper.shape,
            stiffness: upper.stiffness,
            rigid_regions: upper.rigid_regions,
            boundary,
            lower: match &problem.lower {
                Some(low) => Some(BoundBody::new("lower", low, mesh)?),
                None => None,
            },
        })
    }

    /// The model's view of the data, with the problem's tension and choices.
    pub fn data<'a>(&'a self, problem: &Problem) -> ProblemData<'a> {
        ProblemData {
            tension: problem.membrane.tension,
            load: &self.load,
            shape: &self.shape,
            stiffness: match &self.stiffness {
                Some(h) => BodyStiffness::Elastic(h),
                None => BodyStiffness::Rigid,
            },
            foundation: problem.obstacle.foundation,
            sampling: problem.obstacle.sampling(),
        }
    }

    /// The model's view of the data beyond the paper's frame (docs/theory.md#extensions).
    pub fn extensions<'a>(&'a self, problem: &Problem) -> Extensions<'a> {
        Extensions {
            boundary: self
                .boundary
                .as_ref()
                .map(|(height, free)| BoundaryData { free, height }),
            rigid_regions: &self.rigid_regions,
            lower: match (&self.lower, &problem.lower) {
                (Some(b), Some(p)) => Some(BodyData {
                    shape: &b.shape,
                    stiffness: b.stiffness(),
                    rigid_regions: &b.rigid_regions,
                    foundation: p.foundation,
                    sampling: p.sampling(),
                }),
                _ => None,
            },
        }
    }
}

/// Binds the boundary heights to the boundary regions of `mesh` that are fixed (a table
/// needs a value for each of them, or a default), or, for nodal values, to its vertices.
pub(crate) fn bind_height(boundary: &crate::problem::Boundary, mesh: &Mesh) -> Result<BoundField> {
    let name = "boundary.height";
    if let crate::field::Field::Nodal(_) = &boundary.height {
        return boundary.height.bind_to_mesh(name, mesh);
    }
    let adj = crate::fem::VertexTriangles::new(mesh);
    let fixed = crate::mesh::boundary::FixedBoundary::new(mesh, &adj, &boundary.free)?;
    let tagged = mesh.tagged_boundary(&adj);
    let present = tagged.present();
    // Keys may name the free regions too (the value is then not used). Messages call the
    // edges no region covers `default`.
    let names = &mesh.boundary.labels();
    if let crate::field::Field::Regions(table) = &boundary.height {
        for key in table.keys() {
            if key != crate::field::DEFAULT_KEY && mesh.boundary.resolve(key, &present).is_empty() {
                return Err(mesh.no_boundary_region(name, key, &tagged));
            }
        }
        let fixed_only: std::collections::BTreeMap<String, crate::field::Field> = table
            .iter()
            .filter(|(k, _)| {
                k.as_str() == crate::field::DEFAULT_KEY
                    || mesh
                        .boundary
                        .resolve(k, &present)
                        .iter()
                        .any(|t| fixed.fixed_tags.contains(t))
            })
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if fixed_only.is_empty() {
            return crate::field::Field::Constant(0.0).bind(name, names, &fixed.fixed_tags);
        }
        return crate::field::Field::Regions(fixed_only)
            .bind(name, names, &fixed.fixed_tags)
            .map_err(|e| match e {
                Error::Data(m) => Error::Data(m.replace("(regions:", "(fixed boundary regions:")),
                other => other,
            });
    }
    boundary.height.bind(name, names, &fixed.fixed_tags)
}

/// Binds the problem's data to `mesh`, checks it (on the boundary, and for overflow:
/// [`crate::model::assemble_checked`]) and assembles the model S, L, D, φₙ, M of the paper's §2.
/// `problem.mesh` is not used.
pub fn assemble_model(problem: &Problem, mesh: &Mesh) -> Result<Model> {
    let bound = BoundData::new(problem, mesh)?;
    crate::model::assemble_checked(mesh, &bound.data(problem), &bound.extensions(problem))
}

/// Binds the problem's data to `mesh` and checks it where assembly does not sample it (on
/// the boundary): the checks of [`assemble_model`] that need no assembly.
pub fn bind_and_check(problem: &Problem, mesh: &Mesh) -> Result<BoundData> {
    let bound = BoundData::new(problem, mesh)?;
    crate::model::check_boundary_data(mesh, &bound.data(problem), &bound.extensions(problem))?;
    Ok(bound)
}
