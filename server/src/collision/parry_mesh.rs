//! Peer: parry3d's triangle mesh (f32) behind the same interface, for benchmarks and as the
//! independent oracle of the tests.
//!
//! First hit is `parry3d::query::intersection_test` on the two meshes. All pairs walks parry's
//! two BVHs together (B's boxes moved into A's frame) and tests the leaf triangles with parry's
//! triangle-triangle intersection test. parry keeps no counters, so the stats stay zero.

use nalgebra::Isometry3;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::Isometry;
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryTriMesh;

use super::{MeshCollider, QueryStats};
use crate::geometry::TriMesh;

/// Millimetres per metre: the unit parry judges the scenes in when it is the tests' oracle.
/// parry's GJK counts distances below 1.2e-6 of its unit as touching, which in metres would flag
/// the clearance that the clasp and sliding keep.
pub const ORACLE_SCALE: f64 = 1000.0;

/// `mesh` (metres) as a parry mesh in millimetres: the oracle's copy of it.
pub fn millimetre_trimesh(mesh: &TriMesh) -> ParryTriMesh {
    scaled_trimesh(mesh, ORACLE_SCALE)
}

/// `pose` (metres) in parry's `f32`, its translation in millimetres.
pub fn millimetre_pose(pose: &Isometry3<f64>) -> Isometry<f32> {
    let mut pose = pose.cast::<f32>();
    pose.translation.vector *= ORACLE_SCALE as f32;
    pose
}

/// `mesh` scaled by `scale`, in parry's `f32`.
fn scaled_trimesh(mesh: &TriMesh, scale: f64) -> ParryTriMesh {
    let vertices = mesh
        .vertices()
        .iter()
        .map(|v| (v * scale).cast::<f32>())
        .collect();
    ParryTriMesh::new(vertices, mesh.triangles().to_vec())
        .expect("a TriMesh has at least one triangle, all indices in range")
}

/// A mesh as parry3d represents it.
#[derive(Clone)]
pub struct ParryMesh {
    mesh: ParryTriMesh,
}

impl ParryMesh {
    /// `mesh` in millimetres ([`ORACLE_SCALE`]), for judging contact in metre-sized scenes.
    pub fn in_millimetres(mesh: &TriMesh) -> Self {
        ParryMesh {
            mesh: millimetre_trimesh(mesh),
        }
    }

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
        ParryMesh {
            mesh: scaled_trimesh(mesh, 1.0),
        }
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
