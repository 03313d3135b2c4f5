//! The clash check, independent of the DOP-trees: parry's triangle meshes, in millimetres, tested
//! for intersection at the parts' poses, as the tests' oracle judges penetrations.

use nalgebra::Isometry3;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::query::{contact, intersection_test};
use parry3d::shape::TriMesh as ParryTriMesh;

use crate::collision::parry_mesh::{millimetre_pose, millimetre_trimesh};
use crate::scene::Scene;

/// Interpenetration shallower than this (millimetres) is the rounding of parry's `f32` at these
/// sizes, not a clash: two parts in contact may overlap by that much in `f32`.
const DEPTH_SLACK_MM: f32 = 1e-3;

/// parry's copies of the parts a session measures.
pub(super) struct ClashJudge {
    /// By part id; `None` for parts in no measured pair.
    meshes: Vec<Option<ParryTriMesh>>,
}

impl ClashJudge {
    /// The copies of the `used` parts of `scene` (by id).
    pub(super) fn new(scene: &Scene, used: &[bool]) -> ClashJudge {
        let meshes = (scene.parts.iter().zip(used))
            .map(|(part, &used)| used.then(|| millimetre_trimesh(&part.mesh)))
            .collect();
        ClashJudge { meshes }
    }

    /// Whether parts `a` and `b` interpenetrate at `pose_a` and `pose_b`.
    pub(super) fn clashes(
        &self,
        (a, pose_a): (usize, &Isometry3<f64>),
        (b, pose_b): (usize, &Isometry3<f64>),
    ) -> bool {
        let (Some(mesh_a), Some(mesh_b)) = (&self.meshes[a], &self.meshes[b]) else {
            return false;
        };
        let (pose_a, pose_b) = (millimetre_pose(pose_a), millimetre_pose(pose_b));
        if !mesh_a.aabb(&pose_a).intersects(&mesh_b.aabb(&pose_b)) {
            return false;
        }
        if !intersection_test(&pose_a, mesh_a, &pose_b, mesh_b).unwrap_or(false) {
            return false;
        }
        let depth = contact(&pose_a, mesh_a, &pose_b, mesh_b, 0.0)
            .ok()
            .flatten()
            .map_or(0.0, |contact| -contact.dist);
        depth > DEPTH_SLACK_MM
    }
}
