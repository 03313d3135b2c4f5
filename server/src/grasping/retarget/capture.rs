//! Captured hand poses in WebXR's terms, read from JSON.
//!
//! A capture holds `joints`: WebXR's 25 joints in `XRHand` order, each with its `name`, its
//! `matrix` (the joint's 4x4 transform, column-major as WebXR and three.js give it, metres)
//! and its `radius` (metres). An optional `side` (`"left"` or `"right"`) says which hand it is;
//! without it the side is read from the hand itself (a left hand's index finger is on the `+X`
//! side of its wrist frame). A `pose` name is kept; other keys (`source`, `convention` ...) are
//! ignored.

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};
use serde::Deserialize;
use thiserror::Error;

use super::joints::{HandJoints, Joint, JointFlags, JointPose, JointsError, WEBXR_JOINT_COUNT};
use crate::geometry::{ConfigFileError, read_config_text};
use vas_protocol::HandSide;

/// The largest capture file read, in bytes: a capture is a few kilobytes.
pub const MAX_CAPTURE_BYTES: u64 = 1 << 20;

/// How far a joint matrix's rotation part may be from a rotation (each entry of `RᵀR - I`, and
/// the determinant from 1).
const ROTATION_TOLERANCE: f64 = 1e-3;

/// A captured hand pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Capture {
    /// The capture's `pose` key, if any (`"pinch"`, `"relaxed"`).
    pub pose: Option<String>,
    /// The joints.
    pub joints: HandJoints,
}

/// Why a capture file was refused: the file and the reason.
#[derive(Debug, Error)]
pub enum CaptureError {
    /// The file could not be read, is not JSON of the expected shape, or an entry is wrong
    /// (`joints`, or the entry, as `joints[3]`).
    #[error(transparent)]
    File(#[from] ConfigFileError),
    /// The joints are not a possible hand.
    #[error("{file}: {source}")]
    Hand {
        /// The file.
        file: PathBuf,
        /// What is wrong.
        source: JointsError,
    },
}

#[derive(Debug, Deserialize)]
struct CaptureFile {
    pose: Option<String>,
    side: Option<HandSide>,
    joints: Vec<JointEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointEntry {
    name: String,
    matrix: Vec<f64>,
    radius: f64,
}

impl Capture {
    /// Reads and validates a capture file.
    pub fn read(path: &Path) -> Result<Capture, CaptureError> {
        Capture::from_json(path, &read_config_text(path, MAX_CAPTURE_BYTES)?)
    }

    /// A capture from its JSON text; errors name `path`.
    pub fn from_json(path: &Path, text: &str) -> Result<Capture, CaptureError> {
        let file: CaptureFile = serde_json::from_str(text)
            .map_err(|error| ConfigFileError::syntax(path, error.to_string()))?;
        let refuse = |key: String, reason: String| {
            CaptureError::from(ConfigFileError::invalid(path, key, reason))
        };
        if file.joints.len() != WEBXR_JOINT_COUNT {
            return Err(refuse(
                "joints".into(),
                format!(
                    "expected {WEBXR_JOINT_COUNT} joints (WebXR's, wrist first), found {}",
                    file.joints.len()
                ),
            ));
        }
        let mut poses = Vec::with_capacity(WEBXR_JOINT_COUNT);
        for (index, (entry, joint)) in file.joints.iter().zip(&Joint::ALL[1..]).enumerate() {
            if entry.name != joint.name() {
                return Err(refuse(
                    format!("joints[{index}]"),
                    format!("expected joint {:?}, found {:?}", joint.name(), entry.name),
                ));
            }
            poses.push(
                joint_pose(&entry.matrix, entry.radius)
                    .map_err(|r| refuse(format!("joints[{index}]"), r))?,
            );
        }
        let poses: [JointPose; WEBXR_JOINT_COUNT] =
            poses.try_into().expect("one pose per WebXR joint");
        let side = file.side.unwrap_or_else(|| side_of(&poses));
        let joints = HandJoints::from_webxr(side, poses);
        joints.validate().map_err(|source| CaptureError::Hand {
            file: path.to_path_buf(),
            source,
        })?;
        Ok(Capture {
            pose: file.pose,
            joints,
        })
    }

    /// The same capture of the other hand: its mirror image in the `x = 0` plane.
    pub fn mirrored(&self) -> Capture {
        Capture {
            pose: self.pose.clone(),
            joints: self.joints.mirrored(),
        }
    }

    /// The captured joints as a hand of `side`: as captured, or mirrored.
    pub fn joints_of(&self, side: HandSide) -> HandJoints {
        if self.joints.side == side {
            self.joints.clone()
        } else {
            self.joints.mirrored()
        }
    }
}

/// A joint from its column-major 4x4 matrix: a rigid transform (rotation and translation, last
/// row 0 0 0 1) of finite numbers.
fn joint_pose(matrix: &[f64], radius: f64) -> Result<JointPose, String> {
    let m: [f64; 16] = matrix
        .try_into()
        .map_err(|_| format!("matrix: expected 16 numbers, found {}", matrix.len()))?;
    if !m.iter().all(|v| v.is_finite()) {
        return Err("matrix: not finite".into());
    }
    if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        return Err("matrix: the last row must be 0 0 0 1 (column-major order)".into());
    }
    let rotation = Matrix3::new(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]);
    let orthogonal = (rotation.transpose() * rotation - Matrix3::identity()).amax();
    if orthogonal > ROTATION_TOLERANCE || (rotation.determinant() - 1.0).abs() > ROTATION_TOLERANCE
    {
        return Err("matrix: the upper 3x3 is not a rotation".into());
    }
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(format!("radius: {radius} is not a length"));
    }
    Ok(JointPose {
        position: Point3::new(m[12], m[13], m[14]),
        orientation: UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&rotation))
            .into_inner(),
        radius,
        flags: JointFlags::ALL,
    })
}

/// Which hand WebXR joints are: a left hand's index knuckle is on the `+X` side of its wrist
/// frame from the little finger's knuckle, a right hand's on the `-X` side.
fn side_of(webxr: &[JointPose; WEBXR_JOINT_COUNT]) -> HandSide {
    let at = |joint: Joint| webxr[joint.index() - 1];
    let wrist = at(Joint::Wrist);
    let across = wrist.rotation() * Vector3::x();
    let index_from_little = at(Joint::IndexProximal).position - at(Joint::LittleProximal).position;
    if across.dot(&index_from_little) >= 0.0 {
        HandSide::Left
    } else {
        HandSide::Right
    }
}
