//! Input samples (tracker, glove and hand joints) and their validation.
//!
//! The server trusts no input: [`TrackerSample::validate`] rejects non-finite values and
//! rotations that are not unit quaternions, [`GloveSample::validate`] rejects non-finite flex
//! values and clamps the others into the joint limits, reporting which were clamped. A
//! [`HandJointsSample`] is validated by the server against the anatomy of a hand as well
//! (`vas_server::grasping::retarget`), so its checks live there.

use iceoryx2::prelude::ZeroCopySend;
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::number::Readable;
use crate::output::InputStamp;
use crate::pose::WirePose;

/// Number of flex values of a glove sample (the 22-sensor CyberGlove).
pub const FLEX_COUNT: usize = 22;

/// How far the norm of a received quaternion may be from 1 before the sample is rejected.
///
/// Generous enough for quaternions normalised in single precision by a tracker driver, tight
/// enough to catch a wrong component order or an unnormalised matrix conversion. Accepted
/// quaternions are renormalised.
pub const UNIT_QUATERNION_TOLERANCE: f64 = 1e-3;

/// The largest accepted magnitude of a position coordinate, in metres: a thousand kilometres,
/// far beyond any workspace, and small enough that every pose derived from accepted ones (the
/// cart and the hand combined, a segment placed on the hand) stays finite, also in the single
/// precision of the collision structures.
pub const MAX_POSITION_M: f64 = 1e6;

/// How far beyond the server's clock (the system clock, [`wall_clock_ns`](crate::wall_clock_ns))
/// a sample's timestamp may be: one second, far more than any sender on the machine is ahead.
/// The server times tracking by the samples' own stamps in lockstep, so that one sample from
/// the far future would make every later sample look old.
pub const MAX_TIMESTAMP_AHEAD_NS: u64 = 1_000_000_000;

/// One 6-DOF tracker report of one user's hand: the hand root and that user's cart (navigation)
/// pose.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::input::TrackerSample::v2")]
#[repr(C)]
pub struct TrackerSample {
    /// Sender's sequence number, from 1, increasing by one per sample.
    pub seq: u64,
    /// When the sample was taken, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// Pose of the hand root (the tracker on the back of the hand) in the cart's frame, i.e. in
    /// tracking space.
    pub hand: WirePose,
    /// Pose of the cart in the world: the navigation frame that carries the tracking space (and
    /// with it the hand) through the scene. The hand root in the world is `cart * hand`.
    pub cart: WirePose,
    /// Which tracker sent the sample (the VRPN sensor number).
    pub sensor_id: u32,
    /// The user whose hand it tracks: see [`HandJointsSample::user`].
    #[serde(default, skip_serializing_if = "is_zero")]
    pub user: u32,
    /// Which of the user's hands, a [`HandSide`](crate::HandSide) code (0, right, when a
    /// recording made before users names none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub side: u32,
    /// Padding, 0 (not in recordings).
    #[serde(skip)]
    pub reserved: u32,
}

/// One glove report of one user's hand: the 22 calibrated joint angles.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::input::GloveSample::v2")]
#[repr(C)]
pub struct GloveSample {
    /// Sender's sequence number, from 1, increasing by one per sample.
    pub seq: u64,
    /// When the sample was taken, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// Joint angles in radians, in CyberGlove order ([`FLEX_JOINT_NAMES`]).
    pub flex: [f32; FLEX_COUNT],
    /// The user whose hand wears the glove: see [`HandJointsSample::user`].
    #[serde(default, skip_serializing_if = "is_zero")]
    pub user: u32,
    /// Which of the user's hands, a [`HandSide`](crate::HandSide) code (0, right, when a
    /// recording made before users names none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub side: u32,
}

/// Whether a user or side code is 0, the first user's right hand: recordings leave it out, so
/// that a recording of one user's right hand reads as it did before samples named their user.
fn is_zero(code: &u32) -> bool {
    *code == 0
}

/// Number of joints of a [`HandJointsSample`]: OpenXR's hand joints (XR_EXT_hand_tracking).
pub const HAND_JOINT_COUNT: usize = 26;

/// [`JointLocation::flags`] bit: the orientation is valid (OpenXR's
/// `XR_SPACE_LOCATION_ORIENTATION_VALID_BIT`).
pub const JOINT_ORIENTATION_VALID: u32 = 1 << 0;
/// [`JointLocation::flags`] bit: the position is valid (`XR_SPACE_LOCATION_POSITION_VALID_BIT`).
pub const JOINT_POSITION_VALID: u32 = 1 << 1;
/// [`JointLocation::flags`] bit: the orientation is tracked, not inferred
/// (`XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT`).
pub const JOINT_ORIENTATION_TRACKED: u32 = 1 << 2;
/// [`JointLocation::flags`] bit: the position is tracked, not inferred
/// (`XR_SPACE_LOCATION_POSITION_TRACKED_BIT`).
pub const JOINT_POSITION_TRACKED: u32 = 1 << 3;

/// One hand joint's location, as OpenXR's `XrHandJointLocationEXT` gives it.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
pub struct JointLocation {
    /// Position in metres, in tracking space (the cart's frame).
    pub position: [f64; 3],
    /// Orientation as a unit quaternion in x, y, z, w order; the joint frame is OpenXR's: `-Z`
    /// along the bone toward the fingertip, `+Y` on the back of the hand.
    pub rotation: [f64; 4],
    /// Distance from the joint to the skin, in metres (OpenXR's radius is a `float`).
    pub radius: f32,
    /// Which of position and orientation are valid and tracked: the `JOINT_*` bits, OpenXR's
    /// `XrSpaceLocationFlags`.
    pub flags: u32,
}

impl JointLocation {
    /// The joint's pose.
    pub fn pose(&self) -> WirePose {
        WirePose {
            position: self.position,
            rotation: self.rotation,
        }
    }
}

/// One hand's tracked joints: OpenXR's 26 in OpenXR order, each with its pose, radius and
/// validity flags, and which hand it is.
///
/// The order is `XrHandJointEXT`'s: palm 0, wrist 1, thumb metacarpal, proximal, distal, tip
/// 2-5, then index, middle, ring and little finger each metacarpal, proximal, intermediate,
/// distal, tip (6-10, 11-15, 16-20, 21-25).
///
/// WebXR's `XRHand` has the same joints without the palm (25, wrist first). A WebXR producer
/// sends its joints at indices 1-25 and the palm with `flags` 0: OpenXR's own way of saying
/// that a joint's location is unknown. No separate "WebXR" mode is needed, because the server
/// uses no palm (the hand's root comes from the wrist and the fingers from their own joints);
/// a producer that has a palm simply sends it.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::input::HandJointsSample::v2")]
#[repr(C)]
pub struct HandJointsSample {
    /// Sender's sequence number, from 1, increasing by one per sample.
    pub seq: u64,
    /// When the sample was taken, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// The joints, in OpenXR order.
    pub joints: [JointLocation; HAND_JOINT_COUNT],
    /// Which hand, a [`HandSide`](crate::HandSide) code.
    pub side: u32,
    /// The user whose hand it is: an index into the scene's users, as the control service
    /// lists them ([`ControlResponse::users`](crate::ControlResponse::users)); 0 in a scene
    /// of one user.
    ///
    /// An index rather than the user's name: four bytes in a sample sent at the tracking rate,
    /// compared without text, and a sender learns its index once from the scene info (names
    /// are for people; the control response carries them). A scene's users keep their indices
    /// until another scene is loaded, whose info a sender reads anyway.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub user: u32,
}

impl HandJointsSample {
    /// The stamp an output frame carries when it answers this sample.
    pub fn stamp(&self) -> InputStamp {
        InputStamp {
            seq: self.seq,
            timestamp_ns: self.timestamp_ns,
        }
    }

    /// Whether every position, rotation and radius is finite.
    pub fn is_finite(&self) -> bool {
        self.joints
            .iter()
            .all(|joint| joint.pose().is_finite() && joint.radius.is_finite())
    }
}

/// Why an input sample was rejected.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum InputRejection {
    /// A value is NaN or infinite.
    #[error("{field} is not finite")]
    NonFinite {
        /// The offending field, e.g. `hand.position` or `flex[3]`.
        field: &'static str,
    },
    /// A position coordinate is finite but beyond [`MAX_POSITION_M`].
    #[error("{field} is beyond {MAX_POSITION_M} m (found {})", Readable(*value))]
    OutOfRange {
        /// The offending field, `hand.position` or `cart.position`.
        field: &'static str,
        /// The coordinate received.
        value: f64,
    },
    /// A rotation is not a unit quaternion within [`UNIT_QUATERNION_TOLERANCE`].
    #[error("{field} is not a unit quaternion (norm {})", Readable(*norm))]
    NotUnitQuaternion {
        /// The offending field, `hand.rotation` or `cart.rotation`.
        field: &'static str,
        /// The norm received.
        norm: f64,
    },
    /// The timestamp is more than [`MAX_TIMESTAMP_AHEAD_NS`] beyond the server's clock.
    #[error(
        "timestamp_ns is {} s ahead of the server's clock, more than the {} s allowed",
        Readable(*ahead_ns as f64 * 1e-9),
        MAX_TIMESTAMP_AHEAD_NS as f64 * 1e-9
    )]
    Ahead {
        /// How far ahead, in nanoseconds.
        ahead_ns: u64,
    },
    /// The sample names a user the scene does not have.
    #[error("user {user} is no user of the scene")]
    NoSuchUser {
        /// The user index received.
        user: u32,
    },
    /// The sample names a side its user has no hand for (or a code that is no side).
    #[error("user {user} has no hand of side code {side}")]
    NoSuchHand {
        /// The user index received.
        user: u32,
        /// The side code received.
        side: u32,
    },
}

/// A validated tracker sample: finite poses with unit rotations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerTarget {
    /// Sequence number and timestamp of the sample.
    pub stamp: InputStamp,
    /// The sending tracker.
    pub sensor_id: u32,
    /// Hand root pose in the cart's frame.
    pub hand: Isometry3<f64>,
    /// Cart pose in the world.
    pub cart: Isometry3<f64>,
}

impl TrackerTarget {
    /// The hand root in the world: the cart carries the tracking space.
    pub fn hand_in_world(&self) -> Isometry3<f64> {
        self.cart * self.hand
    }
}

/// A validated glove sample: finite flex values within the joint limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GloveTarget {
    /// Sequence number and timestamp of the sample.
    pub stamp: InputStamp,
    /// Joint angles in radians, clamped into [`FLEX_LIMITS_RAD`].
    pub flex: [f32; FLEX_COUNT],
    /// Bit `i` set: `flex[i]` was outside its limits and has been clamped.
    pub clamped: u32,
}

impl GloveTarget {
    /// How many flex values were clamped.
    pub fn clamped_count(&self) -> u32 {
        self.clamped.count_ones()
    }
}

impl TrackerSample {
    /// The stamp an output frame carries when it answers this sample.
    pub fn stamp(&self) -> InputStamp {
        InputStamp {
            seq: self.seq,
            timestamp_ns: self.timestamp_ns,
        }
    }

    /// Checks the sample: every value finite, both rotations unit quaternions within
    /// [`UNIT_QUATERNION_TOLERANCE`] (renormalised in the result).
    pub fn validate(&self) -> Result<TrackerTarget, InputRejection> {
        Ok(TrackerTarget {
            stamp: self.stamp(),
            sensor_id: self.sensor_id,
            hand: validate_pose(&self.hand, "hand.position", "hand.rotation")?,
            cart: validate_pose(&self.cart, "cart.position", "cart.rotation")?,
        })
    }
}

fn validate_pose(
    pose: &WirePose,
    position_field: &'static str,
    rotation_field: &'static str,
) -> Result<Isometry3<f64>, InputRejection> {
    if !pose.position.iter().all(|v| v.is_finite()) {
        return Err(InputRejection::NonFinite {
            field: position_field,
        });
    }
    if let Some(&value) = pose.position.iter().find(|v| v.abs() > MAX_POSITION_M) {
        return Err(InputRejection::OutOfRange {
            field: position_field,
            value,
        });
    }
    if !pose.rotation.iter().all(|v| v.is_finite()) {
        return Err(InputRejection::NonFinite {
            field: rotation_field,
        });
    }
    let norm = pose.quaternion().norm();
    if (norm - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
        return Err(InputRejection::NotUnitQuaternion {
            field: rotation_field,
            norm,
        });
    }
    Ok(pose.to_isometry())
}

impl GloveSample {
    /// The stamp an output frame carries when it answers this sample.
    pub fn stamp(&self) -> InputStamp {
        InputStamp {
            seq: self.seq,
            timestamp_ns: self.timestamp_ns,
        }
    }

    /// Checks the sample: every flex value finite (else rejected), then clamped into
    /// [`FLEX_LIMITS_RAD`], with the clamped joints reported in [`GloveTarget::clamped`].
    pub fn validate(&self) -> Result<GloveTarget, InputRejection> {
        if let Some(index) = self.flex.iter().position(|v| !v.is_finite()) {
            return Err(InputRejection::NonFinite {
                field: FLEX_FIELD_NAMES[index],
            });
        }
        let mut flex = self.flex;
        let mut clamped = 0u32;
        for (index, (value, (low, high))) in flex.iter_mut().zip(FLEX_LIMITS_RAD).enumerate() {
            let limited = value.clamp(low, high);
            if limited != *value {
                clamped |= 1 << index;
                *value = limited;
            }
        }
        Ok(GloveTarget {
            stamp: self.stamp(),
            flex,
            clamped,
        })
    }
}

/// The joint each flex value measures, in CyberGlove order.
pub const FLEX_JOINT_NAMES: [&str; FLEX_COUNT] = [
    "thumb roll",
    "thumb inner (MCP)",
    "thumb outer (IP)",
    "thumb-index abduction",
    "index inner (MCP)",
    "index middle (PIP)",
    "index outer (DIP)",
    "middle inner (MCP)",
    "middle middle (PIP)",
    "middle outer (DIP)",
    "middle-index abduction",
    "ring inner (MCP)",
    "ring middle (PIP)",
    "ring outer (DIP)",
    "ring-middle abduction",
    "pinky inner (MCP)",
    "pinky middle (PIP)",
    "pinky outer (DIP)",
    "pinky-ring abduction",
    "palm arch",
    "wrist flexion (pitch)",
    "wrist abduction (yaw)",
];

/// Field names used in rejection reports, one per flex index.
const FLEX_FIELD_NAMES: [&str; FLEX_COUNT] = [
    "flex[0]", "flex[1]", "flex[2]", "flex[3]", "flex[4]", "flex[5]", "flex[6]", "flex[7]",
    "flex[8]", "flex[9]", "flex[10]", "flex[11]", "flex[12]", "flex[13]", "flex[14]", "flex[15]",
    "flex[16]", "flex[17]", "flex[18]", "flex[19]", "flex[20]", "flex[21]",
];

const fn degrees(low: f32, high: f32) -> (f32, f32) {
    let to_radians = std::f32::consts::PI / 180.0;
    (low * to_radians, high * to_radians)
}

/// Joint limits `(low, high)` in radians, per flex index: typical limits of a 22-DOF hand.
///
/// Finger abduction -20..20 degrees, inner joints -15..90, middle joints 0..90, outer joints
/// 0..80, thumb roll -60..60, wrist flexion -70..70, wrist abduction -20..40. Two sensors have no
/// published typical range: the thumb-index abduction gets -20..60 (the thumb spreads much
/// farther than a finger) and the palm arch 0..60 (it only cups the palm).
pub const FLEX_LIMITS_RAD: [(f32, f32); FLEX_COUNT] = {
    let abduction = degrees(-20.0, 20.0);
    let inner = degrees(-15.0, 90.0);
    let middle = degrees(0.0, 90.0);
    let outer = degrees(0.0, 80.0);
    [
        degrees(-60.0, 60.0),
        inner,
        outer,
        degrees(-20.0, 60.0),
        inner,
        middle,
        outer,
        inner,
        middle,
        outer,
        abduction,
        inner,
        middle,
        outer,
        abduction,
        inner,
        middle,
        outer,
        abduction,
        degrees(0.0, 60.0),
        degrees(-70.0, 70.0),
        degrees(-20.0, 40.0),
    ]
};
