//! Peer: parry3d's triangle mesh (f32) behind the same interface, for benchmarks and as the
//! independent oracle of the tests.
//!
//! First hit is `parry3d::query::intersection_test` on the two meshes. All pairs walks parry's
//! two BVHs together (B's boxes moved into A's frame) and tests the leaf triangles with parry's
//! triangle-triangle intersection test. parry keeps no counters, so the stats stay zero.

use nalgebra::Isometry3;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Isometry, Point};
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryTriMesh;

use super::{MeshCollider, QueryStats};
use crate::geometry::TriMesh;

/// A mesh as parry3d represents it.
#[derive(Clone)]
pub struct ParryMesh {
    mesh: ParryTriMesh,
}

impl ParryMesh {
    /// The parry mesh.
    pub fn shape(&self) -> &ParryTriMesh {
        &self.mesh
    }
}

/// B's pose in A's frame in parry's `f32`.
fn parry_pose(b_to_a: &Isometry3<f64>) -> Isometry<f32> {
    b_to_a.cast::<f32>()
}

impl MeshCollider for ParryMesh {
    fn build(mesh: &TriMesh) -> Self {
        let vertices = mesh
            .vertices()
            .iter()
            .map(|p| Point::new(p.x as f32, p.y as f32, p.z as f32))
            .collect();
        let mesh = ParryTriMesh::new(vertices, mesh.triangles().to_vec())
            .expect("a TriMesh has at least one triangle, all indices in range");
        ParryMesh { mesh }
    }

    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, _stats: &mut QueryStats) -> bool {
        intersection_test(
            &Isometry::identity(),
            &self.mesh,
            &parry_pose(b_to_a),
            &other.mesh,
        )
        .expect("parry supports triangle-mesh pairs")
    }

    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        _stats: &mut QueryStats,
    ) {
        let pose = parry_pose(b_to_a);
        let identity = Isometry::identity();
        let candidates = self.mesh.bvh().leaf_pairs(other.mesh.bvh(), |na, nb| {
            na.aabb().intersects(&nb.aabb().transform_by(&pose))
        });
        for (ta, tb) in candidates {
            let (triangle_a, triangle_b) = (self.mesh.triangle(ta), other.mesh.triangle(tb));
            if intersection_test(&identity, &triangle_a, &pose, &triangle_b)
                .expect("parry supports triangle pairs")
            {
                out.push([ta, tb]);
            }
        }
    }
}
