//! Exact collision detection between triangle meshes: k-DOPs, the DOP-tree with O(k)
//! re-alignment, parry as the independent oracle of the tests, and the exact triangle-triangle
//! test; the convex separating-plane pre-check, the broad phase and the pipeline over a scene.
//! (The paper's comparison baselines, the k-DOP tree re-aligned by brute force and the OBB-tree,
//! live with the benchmarks in `vas-bench`.)
//!
//! Every algorithm answers the same two queries through [`MeshCollider`]: does B, posed in A's
//! frame, touch A (first hit), and which triangle pairs touch (all pairs, for sliding contact).
//! Touching counts as intersecting (see [`triangle`]).

pub mod broad_phase;
pub(crate) mod brute_force;
pub mod distance;
pub mod dop_tree;
pub mod orientation;
pub mod oriented_box;
pub mod parry_mesh;
pub mod pipeline;
pub mod separating_plane;
pub mod triangle;

use std::ops::AddAssign;

use nalgebra::Isometry3;

use crate::geometry::TriMesh;

pub use brute_force::brute_force_pairs;
pub use dop_tree::DopTree;
pub use orientation::OrientationSet;
pub use parry_mesh::ParryMesh;

/// Work done by one or more queries: what explains their time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct QueryStats {
    /// Bounding-volume overlap tests.
    pub bv_tests: u64,
    /// Bounding volumes of B moved into A's frame (DOP re-alignments, OBB transforms).
    pub realignments: u64,
    /// Node pairs whose bounding volumes overlapped and were opened.
    pub nodes_visited: u64,
    /// Exact triangle-triangle tests.
    pub tri_tests: u64,
    /// Traversals split across threads (long DOP-tree queries asked to split).
    pub split_walks: u64,
}

impl AddAssign for QueryStats {
    fn add_assign(&mut self, other: Self) {
        self.bv_tests += other.bv_tests;
        self.realignments += other.realignments;
        self.nodes_visited += other.nodes_visited;
        self.tri_tests += other.tri_tests;
        self.split_walks += other.split_walks;
    }
}

/// An exact mesh-mesh collision test: a structure built once per mesh, queried with B's pose in
/// A's frame (`b_to_a` = A⁻¹·B).
pub trait MeshCollider: Send + Sync {
    /// Builds the structure over `mesh` with the algorithm's default parameters.
    fn build(mesh: &TriMesh) -> Self
    where
        Self: Sized;

    /// True when the two meshes touch or intersect; stops at the first intersecting pair.
    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, stats: &mut QueryStats) -> bool;

    /// Appends every intersecting pair `[triangle of A, triangle of B]` (mesh indices) to `out`.
    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    );
}

#[cfg(test)]
pub(crate) mod oracle_tests;
