//! The pose of B1's tumbling pair, shared by the collision tests and the benchmark.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Step `s` of `steps` of the tumbling pair: translation (d, 0, 0), rotation Rz(a) * Rx(a),
/// a = 2 * pi * s / steps.
pub fn tumble_pose(d: f64, s: usize, steps: usize) -> Isometry3<f64> {
    let a = std::f64::consts::TAU * s as f64 / steps as f64;
    let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a);
    Isometry3::from_parts(Translation3::new(d, 0.0, 0.0), rotation)
}
