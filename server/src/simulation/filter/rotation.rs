//! Smoothing of a rotation.
//!
//! The estimate moves toward each sample along the great arc between them by the gain's
//! fraction of the angle: `q̂ ← exp(α · log(q q̂⁻¹)) q̂`, a slerp from the estimate by `α`. This
//! is the exponential smoothing `x̂ ← x̂ + α (x − x̂)` of positions carried to the sphere of
//! unit quaternions, so the cut-off means the same in radians as in metres; the result is a
//! product of unit quaternions, renormalised against rounding, so it stays unit length. The
//! step is taken the short way round: `q` and `-q` are the same rotation, and the offset is
//! the one with a non-negative scalar part (an angle of at most π). Filtering the four
//! components as a vector would leave the sphere and, across a sign flip of the samples,
//! swing the long way round.

use nalgebra::{UnitQuaternion, Vector3};

/// The rotation from `estimate` to `sample` the short way, as a rotation vector (axis times
/// angle, radians, in the frame the rotations are given in).
pub fn offset(estimate: &UnitQuaternion<f64>, sample: &UnitQuaternion<f64>) -> Vector3<f64> {
    let mut step = sample * estimate.inverse();
    if step.w < 0.0 {
        step = UnitQuaternion::new_unchecked(-step.into_inner());
    }
    step.scaled_axis()
}

/// `estimate` moved by `fraction` of the rotation vector `offset`.
pub fn moved(
    estimate: &UnitQuaternion<f64>,
    offset: &Vector3<f64>,
    fraction: f64,
) -> UnitQuaternion<f64> {
    let mut next = UnitQuaternion::from_scaled_axis(offset * fraction) * estimate;
    next.renormalize();
    next
}
