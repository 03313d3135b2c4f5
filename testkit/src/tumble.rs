//! The motion of B1, the tumbling pair (the paper's Figure 3): A stays at the identity while B
//! turns about two axes at a fixed distance. The collision tests replay it as a coherent motion.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// The pose of B1's tumbling pair at step `s` of `steps` at distance `d`: translation (d, 0, 0),
/// rotation Rz(a)·Rx(a), a = 2π s / steps.
pub fn tumble_pose(d: f64, s: usize, steps: usize) -> Isometry3<f64> {
    let a = std::f64::consts::TAU * s as f64 / steps as f64;
    let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a);
    Isometry3::from_parts(Translation3::new(d, 0.0, 0.0), rotation)
}
