//! The answer of a distance query.

use nalgebra::{Isometry3, Point3};

/// The least distance between two meshes, where it is reached and between which triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoints {
    /// The least distance between the two triangle sets (0 when they touch or intersect).
    pub distance: f64,
    /// The closest point on A, in A's frame (a point of contact when the distance is 0).
    pub on_a: Point3<f64>,
    /// The closest point on B, in B's frame.
    pub on_b: Point3<f64>,
    /// The two triangles (indices in A's and B's meshes) on which the points lie.
    pub triangles: [u32; 2],
}

impl ClosestPoints {
    /// The two closest points in the world, A posed at `pose_a` and B at `pose_b`.
    pub fn in_world(
        &self,
        pose_a: &Isometry3<f64>,
        pose_b: &Isometry3<f64>,
    ) -> (Point3<f64>, Point3<f64>) {
        (pose_a * self.on_a, pose_b * self.on_b)
    }
}
