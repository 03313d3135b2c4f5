//! Retargeting of tracked hand joints (OpenXR's 26, WebXR's 25) onto the 22-DOF hand model:
//! the root from the wrist, every flex value from the joints, within the model's limits.
//!
//! * `joints`: one hand sample in OpenXR order, with its validation.
//! * `capture`: captured WebXR poses read from JSON, and mirrored to the other hand.
//! * `skeleton`: which joint each segment corresponds to, and how their frames differ.
//! * `fit`: the [`Retargeter`]: the angles from the joints' relative rotations, then a few
//!   damped least-squares steps on the fingertips.
//! * `calibrate`: the model resized to one user's hand from one sample.
//! * `tip_distances`: the distance of the model's fingertips from the tracked tips.
//! * `synthesize`: the joints a tracker would report for a posed model.

pub(crate) mod calibrate;
pub(crate) mod capture;
pub(crate) mod fit;
pub(crate) mod joints;
pub(crate) mod skeleton;
pub(crate) mod synthesize;
#[cfg(test)]
mod tests;
pub(crate) mod tip_distances;

pub use capture::{Capture, CaptureError};
pub use fit::{Retarget, RetargetError, Retargeter};
pub use joints::{HandJoints, Joint, JointFlags, JointPose, JointsError};
pub use tip_distances::FingertipDistances;
