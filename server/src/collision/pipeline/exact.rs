//! The exact test the pipeline ends with: the interface it needs, and a parry-based
//! implementation that serves as an independent oracle in tests.

use crate::geometry::TriMesh;
use nalgebra::Isometry3;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::shape::TriMesh as ParryTriMesh;

/// Work counters of exact tests, summed over a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct QueryStats {
    /// Triangle-triangle tests run.
    pub triangle_tests: u64,
}

/// An exact collision test between two meshes, each in its own frame.
pub trait MeshCollider {
    /// True when the meshes share a point, B being placed in A's frame by `b_to_a`.
    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, stats: &mut QueryStats) -> bool;

    /// Appends every intersecting triangle pair `[triangle of A, triangle of B]` to `out`.
    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    );
}

/// An exact test the pipeline can run on its thread pool: serially for a frame with many pairs,
/// or split across threads when a few pairs dominate the frame.
pub trait ExactTest: MeshCollider + Send + Sync {
    /// Like [`MeshCollider::intersects`], but free to split the work across the current rayon
    /// pool. Tests without a parallel traversal run serially.
    fn intersects_split(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
    ) -> bool {
        self.intersects(other, b_to_a, stats)
    }
}

/// A mesh as parry's `TriMesh` (f32, with parry's BVH): a collider written independently of ours,
/// used as the oracle that the pipeline's answers are checked against.
#[derive(Clone)]
pub struct ParryMesh {
    mesh: ParryTriMesh,
}

impl ParryMesh {
    /// Converts `mesh` to parry's representation.
    ///
    /// # Panics
    /// Never for a valid [`TriMesh`]: it has at least one triangle and in-range indices.
    pub fn new(mesh: &TriMesh) -> ParryMesh {
        let vertices = mesh
            .vertices()
            .iter()
            .map(|v| nalgebra::convert(*v))
            .collect();
        let mesh = ParryTriMesh::new(vertices, mesh.triangles().to_vec())
            .expect("a valid TriMesh is a valid parry TriMesh");
        ParryMesh { mesh }
    }

    /// Calls `visit` for every pair of triangles whose BVH leaves overlap, until it returns true.
    fn candidate_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f32>,
        mut visit: impl FnMut(u32, u32) -> bool,
    ) {
        let pairs = self
            .mesh
            .bvh()
            .leaf_pairs(other.mesh.bvh(), |node_a, node_b| {
                node_a
                    .aabb()
                    .intersects(&node_b.aabb().transform_by(b_to_a))
            });
        for (a, b) in pairs {
            if visit(a, b) {
                return;
            }
        }
    }

    fn triangles_intersect(&self, other: &Self, a: u32, b: u32, b_to_a: &Isometry3<f32>) -> bool {
        parry3d::query::intersection_test(
            &Isometry3::identity(),
            &self.mesh.triangle(a),
            b_to_a,
            &other.mesh.triangle(b),
        )
        .unwrap_or(false)
    }
}

impl MeshCollider for ParryMesh {
    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, stats: &mut QueryStats) -> bool {
        let b_to_a: Isometry3<f32> = nalgebra::convert(*b_to_a);
        let mut hit = false;
        self.candidate_pairs(other, &b_to_a, |a, b| {
            stats.triangle_tests += 1;
            hit = self.triangles_intersect(other, a, b, &b_to_a);
            hit
        });
        hit
    }

    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    ) {
        let b_to_a: Isometry3<f32> = nalgebra::convert(*b_to_a);
        self.candidate_pairs(other, &b_to_a, |a, b| {
            stats.triangle_tests += 1;
            if self.triangles_intersect(other, a, b, &b_to_a) {
                out.push([a, b]);
            }
            false
        });
    }
}

impl ExactTest for ParryMesh {}
