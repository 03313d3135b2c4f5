//! Rigid motions of the grasped part's pivot, and the pose interpolation the bisection uses.
//!
//! The sliding code works on *pivot poses*: the pose of a frame at the part's pivot (its
//! bounding-box centre), so that rotations turn the part about itself, not about the origin of its
//! mesh file. A [`Motion`] is the displacement between two pivot poses: a translation of the pivot
//! and a rotation vector (axis times angle, world frame) about it. Interpolating along a motion is
//! the "translation linearly, rotation by slerp", written as `exp(s * rotation)` so that
//! it is defined for every pair of poses, including rotations of half a turn.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};

/// A pose in the world frame (rotation and translation), in metres.
pub type Pose = Isometry3<f64>;

/// The displacement of the pivot between two poses: world-frame translation and rotation vector.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Translation of the pivot, metres.
    pub translation: Vector3<f64>,
    /// Rotation about the pivot as axis times angle (radians), in the world frame.
    pub rotation: Vector3<f64>,
}

impl Motion {
    /// The motion that takes pivot pose `from` to pivot pose `to` (the shorter way round).
    pub fn between(from: &Pose, to: &Pose) -> Motion {
        let delta = to.rotation * from.rotation.inverse();
        Motion {
            translation: to.translation.vector - from.translation.vector,
            rotation: delta.scaled_axis(),
        }
    }

    /// The pose reached by moving `pose` by the fraction `s` of this motion.
    pub fn apply_fraction(&self, pose: &Pose, s: f64) -> Pose {
        let rotation = UnitQuaternion::from_scaled_axis(self.rotation * s) * pose.rotation;
        Isometry3::from_parts(
            Translation3::from(pose.translation.vector + self.translation * s),
            rotation,
        )
    }

    /// The pose reached by moving `pose` by this whole motion.
    pub fn apply(&self, pose: &Pose) -> Pose {
        self.apply_fraction(pose, 1.0)
    }

    /// The length of the motion in metres: pivot travel plus the arc a point at `radius` from the
    /// pivot travels. This one number compares motions that mix translation and rotation.
    pub fn length(&self, radius: f64) -> f64 {
        self.translation.norm() + radius * self.rotation.norm()
    }

    /// The motion as one 6-vector `(translation, radius * rotation)`, whose components all have
    /// the unit metre; the new-direction projection works in this space.
    pub fn to_scaled(self, radius: f64) -> Vector6<f64> {
        let r = self.rotation * radius;
        Vector6::new(
            self.translation.x,
            self.translation.y,
            self.translation.z,
            r.x,
            r.y,
            r.z,
        )
    }

    /// The inverse of [`Motion::to_scaled`].
    pub fn from_scaled(v: &Vector6<f64>, radius: f64) -> Motion {
        Motion {
            translation: v.fixed_rows::<3>(0).into_owned(),
            rotation: v.fixed_rows::<3>(3).into_owned() / radius,
        }
    }

    /// The world-frame displacement, under this whole motion, of a point at `offset` from the
    /// pivot (first order: `translation + rotation × offset`).
    pub fn point_displacement(&self, offset: &Vector3<f64>) -> Vector3<f64> {
        self.translation + self.rotation.cross(offset)
    }
}

/// Interpolates between two pivot poses: translation linearly, rotation along the great arc.
pub fn interpolate(from: &Pose, to: &Pose, s: f64) -> Pose {
    Motion::between(from, to).apply_fraction(from, s)
}

/// The distance between two pivot poses in metres, as [`Motion::length`].
pub fn pose_distance(a: &Pose, b: &Pose, radius: f64) -> f64 {
    Motion::between(a, b).length(radius)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn pose(t: [f64; 3], axis_angle: [f64; 3]) -> Pose {
        Isometry3::new(Vector3::from(t), Vector3::from(axis_angle))
    }

    #[test]
    fn interpolation_hits_both_ends_and_agrees_with_slerp() {
        let a = pose([1.0, 2.0, 3.0], [0.1, -0.4, 0.2]);
        let b = pose([-2.0, 0.5, 1.0], [0.7, 0.3, -0.5]);
        assert!((interpolate(&a, &b, 0.0).to_homogeneous() - a.to_homogeneous()).norm() < 1e-12);
        assert!((interpolate(&a, &b, 1.0).to_homogeneous() - b.to_homogeneous()).norm() < 1e-12);
        for s in [0.1, 0.25, 0.5, 0.9] {
            let ours = interpolate(&a, &b, s);
            let reference = a.lerp_slerp(&b, s);
            assert!(
                (ours.to_homogeneous() - reference.to_homogeneous()).norm() < 1e-12,
                "s = {s}"
            );
        }
    }

    #[test]
    fn half_turns_interpolate_without_panicking() {
        let a = pose([0.0; 3], [0.0; 3]);
        let b = pose([1.0, 0.0, 0.0], [0.0, 0.0, PI]);
        let mid = interpolate(&a, &b, 0.5);
        assert!((mid.rotation.angle() - PI / 2.0).abs() < 1e-12);
        assert!((mid.translation.vector.x - 0.5).abs() < 1e-12);
    }

    #[test]
    fn length_mixes_translation_and_arc() {
        let a = pose([0.0; 3], [0.0; 3]);
        let b = pose([3.0, 4.0, 0.0], [0.0, 0.5, 0.0]);
        assert!((pose_distance(&a, &b, 2.0) - (5.0 + 1.0)).abs() < 1e-12);
        let m = Motion::between(&a, &b);
        let back = Motion::from_scaled(&m.to_scaled(2.0), 2.0);
        assert!((back.translation - m.translation).norm() < 1e-15);
        assert!((back.rotation - m.rotation).norm() < 1e-15);
    }

    #[test]
    fn point_displacement_is_first_order_exact() {
        let a = pose([0.0; 3], [0.0; 3]);
        let m = Motion {
            translation: Vector3::new(0.0, 0.0, 1e-4),
            rotation: Vector3::new(0.0, 0.0, 1e-4),
        };
        let offset = Vector3::new(1.0, 0.0, 0.0);
        let moved = m.apply(&a) * nalgebra::Point3::from(offset);
        let predicted = offset + m.point_displacement(&offset);
        assert!((moved.coords - predicted).norm() < 1e-7);
    }
}
