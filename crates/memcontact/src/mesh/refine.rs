//! Uniform refinement (every triangle into four) and the hierarchy of nested levels that
//! multigrid needs, with the prolongation between consecutive levels.

use super::Mesh;

/// How the vertices of a fine level come from the coarse one: fine vertex `v` has the
/// value `0.5 * (coarse[parents[v][0]] + coarse[parents[v][1]])` of a coarse P1 function
/// (`parents[v] = [c, c]` when `v` sits on coarse vertex `c`). This is the exact P1
/// prolongation for nested meshes.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// One pair of coarse vertices per fine vertex.
    pub parents: Vec<[u32; 2]>,
}

impl Refinement {
    /// Interpolates a coarse vertex vector onto the fine vertices.
    pub fn prolongate(&self, coarse: &[f64]) -> Vec<f64> {
        self.parents
            .iter()
            .map(|&[a, b]| 0.5 * (coarse[a as usize] + coarse[b as usize]))
            .collect()
    }
}

/// Nested meshes, coarsest first; `refinements[k]` maps level `k` to level `k + 1`.
#[derive(Debug, Clone)]
pub struct Hierarchy {
    /// The levels, coarsest first; the last one is the mesh the problem is solved on.
    pub levels: Vec<Mesh>,
    /// The vertex relations between consecutive levels.
    pub refinements: Vec<Refinement>,
}

impl Hierarchy {
    /// A hierarchy of one level (no multigrid possible).
    pub fn single(mesh: Mesh) -> Hierarchy {
        Hierarchy {
            levels: vec![mesh],
            refinements: vec![],
        }
    }

    /// The finest level.
    pub fn finest(&self) -> &Mesh {
        self.levels
            .last()
            .expect("a hierarchy has at least one level")
    }

    /// Number of levels.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }
}
