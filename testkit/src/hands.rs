//! Hand-joints input from the real captured hands in `tests/fixtures/hands/`.

use std::path::PathBuf;

use nalgebra::Quaternion;
use vas_protocol::HandSide;
use vas_server::grasping::retarget::{Capture, CaptureError, HandJoints, JointPose};

/// The captured pinch: thumb and index tips together.
pub const PINCH: &str = "webxr_pinch.json";

/// The captured open, relaxed hand.
pub const RELAXED: &str = "webxr_relaxed.json";

/// The path of the capture `name`.
pub fn capture_path(name: &str) -> PathBuf {
    crate::fixtures_dir().join("hands").join(name)
}

/// The capture `name` as a hand of `side` (the captures are left hands; a right hand is their
/// mirror image).
pub fn captured(name: &str, side: HandSide) -> Result<HandJoints, CaptureError> {
    Ok(Capture::read(&capture_path(name))?.joints_of(side))
}

/// The joints with positions rounded to a micrometre, quaternions to a millionth and radii to
/// a tenth of a micrometre: far below what hand tracking resolves, and recordings of them stay
/// small.
pub fn rounded(joints: &HandJoints) -> HandJoints {
    // Divided by an exact power of ten, a rounded value prints as its few decimals.
    let round = |value: f64, per_unit: f64| (value * per_unit).round() / per_unit;
    HandJoints {
        side: joints.side,
        joints: joints.joints.map(|joint| JointPose {
            position: joint.position.map(|c| round(c, 1e6)),
            orientation: Quaternion::from(joint.orientation.coords.map(|c| round(c, 1e6))),
            radius: round(joint.radius, 1e7),
            flags: joint.flags,
        }),
    }
}
