//! One tracked hand as OpenXR's 26 joints (XR_EXT_hand_tracking), and its validation.
//!
//! Every joint frame follows OpenXR's convention for both hands: `-Z` along the bone toward the
//! fingertip, `+Y` on the back of the hand, `+X` completing a right-handed frame. WebXR's
//! `XRHand` has the same joints without the palm; [`HandJoints::from_webxr`] derives it.

use std::fmt;

use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};
use thiserror::Error;
use vas_protocol::MAX_POSITION_M;

use vas_protocol::HandSide;

/// Number of OpenXR hand joints.
pub const JOINT_COUNT: usize = 26;

/// Number of WebXR hand joints: OpenXR's without the palm.
pub const WEBXR_JOINT_COUNT: usize = JOINT_COUNT - 1;

/// A hand joint, in OpenXR order (its value is the joint's index); the names are OpenXR's
/// (`XR_HAND_JOINT_INDEX_PROXIMAL_EXT` is `IndexProximal`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Joint {
    Palm,
    Wrist,
    ThumbMetacarpal,
    ThumbProximal,
    ThumbDistal,
    ThumbTip,
    IndexMetacarpal,
    IndexProximal,
    IndexIntermediate,
    IndexDistal,
    IndexTip,
    MiddleMetacarpal,
    MiddleProximal,
    MiddleIntermediate,
    MiddleDistal,
    MiddleTip,
    RingMetacarpal,
    RingProximal,
    RingIntermediate,
    RingDistal,
    RingTip,
    LittleMetacarpal,
    LittleProximal,
    LittleIntermediate,
    LittleDistal,
    LittleTip,
}

impl Joint {
    /// Every joint, in OpenXR order.
    pub const ALL: [Joint; JOINT_COUNT] = [
        Joint::Palm,
        Joint::Wrist,
        Joint::ThumbMetacarpal,
        Joint::ThumbProximal,
        Joint::ThumbDistal,
        Joint::ThumbTip,
        Joint::IndexMetacarpal,
        Joint::IndexProximal,
        Joint::IndexIntermediate,
        Joint::IndexDistal,
        Joint::IndexTip,
        Joint::MiddleMetacarpal,
        Joint::MiddleProximal,
        Joint::MiddleIntermediate,
        Joint::MiddleDistal,
        Joint::MiddleTip,
        Joint::RingMetacarpal,
        Joint::RingProximal,
        Joint::RingIntermediate,
        Joint::RingDistal,
        Joint::RingTip,
        Joint::LittleMetacarpal,
        Joint::LittleProximal,
        Joint::LittleIntermediate,
        Joint::LittleDistal,
        Joint::LittleTip,
    ];

    /// WebXR's names (`XRHandJoint`), in OpenXR order; the palm, which WebXR lacks, first.
    const NAMES: [&'static str; JOINT_COUNT] = [
        "palm",
        "wrist",
        "thumb-metacarpal",
        "thumb-phalanx-proximal",
        "thumb-phalanx-distal",
        "thumb-tip",
        "index-finger-metacarpal",
        "index-finger-phalanx-proximal",
        "index-finger-phalanx-intermediate",
        "index-finger-phalanx-distal",
        "index-finger-tip",
        "middle-finger-metacarpal",
        "middle-finger-phalanx-proximal",
        "middle-finger-phalanx-intermediate",
        "middle-finger-phalanx-distal",
        "middle-finger-tip",
        "ring-finger-metacarpal",
        "ring-finger-phalanx-proximal",
        "ring-finger-phalanx-intermediate",
        "ring-finger-phalanx-distal",
        "ring-finger-tip",
        "pinky-finger-metacarpal",
        "pinky-finger-phalanx-proximal",
        "pinky-finger-phalanx-intermediate",
        "pinky-finger-phalanx-distal",
        "pinky-finger-tip",
    ];

    /// The joint's index in OpenXR order.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The joint's WebXR name (`"palm"` for the palm).
    pub fn name(self) -> &'static str {
        Joint::NAMES[self.index()]
    }

    /// The joints of each digit from its first joint to its tip, thumb first: the thumb's
    /// metacarpal, proximal, distal and tip, then each finger's metacarpal, proximal,
    /// intermediate, distal and tip.
    pub fn digit_chains() -> [&'static [Joint]; 5] {
        [
            &Joint::ALL[2..6],
            &Joint::ALL[6..11],
            &Joint::ALL[11..16],
            &Joint::ALL[16..21],
            &Joint::ALL[21..26],
        ]
    }
}

impl fmt::Display for Joint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// OpenXR's location flags of one joint (`XrSpaceLocationFlags`, the same bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct JointFlags(pub u8);

impl JointFlags {
    /// The orientation is valid.
    pub const ORIENTATION_VALID: JointFlags = JointFlags(1);
    /// The position is valid.
    pub const POSITION_VALID: JointFlags = JointFlags(2);
    /// The orientation is tracked, not inferred.
    pub const ORIENTATION_TRACKED: JointFlags = JointFlags(4);
    /// The position is tracked, not inferred.
    pub const POSITION_TRACKED: JointFlags = JointFlags(8);
    /// Valid and tracked, position and orientation.
    pub const ALL: JointFlags = JointFlags(15);
    /// Position and orientation valid.
    pub const VALID: JointFlags = JointFlags(3);

    /// True when every flag of `other` is set.
    pub fn contains(self, other: JointFlags) -> bool {
        self.0 & other.0 == other.0
    }
}

/// One joint's location: where it is, how it is turned, how thick the hand is there, and what
/// of that the tracker vouches for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPose {
    /// Position, in metres.
    pub position: Point3<f64>,
    /// Orientation as received; [`HandJoints::validate`] checks that it is a unit quaternion.
    pub orientation: Quaternion<f64>,
    /// Distance from the joint to the skin, in metres.
    pub radius: f64,
    /// OpenXR's validity and tracking flags.
    pub flags: JointFlags,
}

impl JointPose {
    /// A valid, tracked joint.
    pub fn tracked(position: Point3<f64>, orientation: UnitQuaternion<f64>, radius: f64) -> Self {
        JointPose {
            position,
            orientation: orientation.into_inner(),
            radius,
            flags: JointFlags::ALL,
        }
    }

    /// The orientation as a rotation, renormalised: validation accepts quaternions a little
    /// off unit length (as trackers send them), and a pose made from one must not scale what it
    /// moves. Meaningful once validated.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::new_normalize(self.orientation)
    }

    /// The joint's bone direction, `-Z` of its frame.
    fn forward(&self) -> Vector3<f64> {
        self.rotation() * -Vector3::z()
    }
}

/// One hand's 26 joints, in OpenXR order, and which hand it is.
#[derive(Debug, Clone, PartialEq)]
pub struct HandJoints {
    /// Left or right hand.
    pub side: HandSide,
    /// The joints, indexed by [`Joint::index`].
    pub joints: [JointPose; JOINT_COUNT],
}

/// The shortest and longest bone of a digit accepted, in metres: from a small child's to far
/// beyond any adult's.
pub const BONE_LENGTH_M: (f64, f64) = (0.003, 0.12);

/// The farthest a digit's first joint may be from the wrist, in metres.
pub const MAX_WRIST_REACH_M: f64 = 0.15;

/// How far a quaternion's norm may be from one.
const UNIT_TOLERANCE: f64 = 1e-3;

/// Why a hand sample was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum JointsError {
    /// A joint the retargeting needs has no valid position or orientation.
    #[error("{joint}: position or orientation not valid")]
    NotValid {
        /// The joint.
        joint: Joint,
    },
    /// A position or radius is not a finite number.
    #[error("{joint}: position or radius not finite")]
    NonFinite {
        /// The joint.
        joint: Joint,
    },
    /// A position is finite but beyond [`MAX_POSITION_M`], farther than any workspace.
    #[error("{joint}: position beyond {MAX_POSITION_M} m")]
    OutOfRange {
        /// The joint.
        joint: Joint,
    },
    /// An orientation is not a unit quaternion.
    #[error("{joint}: orientation is not a unit quaternion (norm {norm})")]
    NotUnit {
        /// The joint.
        joint: Joint,
        /// The quaternion's norm.
        norm: f64,
    },
    /// A joint is not where anatomy puts it relative to its neighbours.
    #[error("{joint}: out of anatomical order: {reason}")]
    OutOfOrder {
        /// The joint.
        joint: Joint,
        /// What is wrong.
        reason: &'static str,
    },
    /// A bone is shorter or longer than any hand's.
    #[error("bone {from} -> {to}: {length_m} m is not a possible length")]
    BoneLength {
        /// The joint at the bone's base.
        from: Joint,
        /// The joint at its end.
        to: Joint,
        /// Its length, in metres.
        length_m: f64,
    },
}

impl HandJoints {
    /// A hand from WebXR's 25 joints (wrist first). The palm, which WebXR lacks, is derived as
    /// OpenXR defines it: at the middle of the middle finger's metacarpal, turned as it is; it is
    /// valid or tracked where both joints it comes from are.
    pub fn from_webxr(side: HandSide, joints: [JointPose; WEBXR_JOINT_COUNT]) -> HandJoints {
        let metacarpal = joints[Joint::MiddleMetacarpal.index() - 1];
        let knuckle = joints[Joint::MiddleProximal.index() - 1];
        let palm = JointPose {
            position: nalgebra::center(&metacarpal.position, &knuckle.position),
            orientation: metacarpal.orientation,
            radius: metacarpal.radius,
            flags: JointFlags(metacarpal.flags.0 & knuckle.flags.0),
        };
        let mut all = [palm; JOINT_COUNT];
        all[1..].copy_from_slice(&joints);
        HandJoints { side, joints: all }
    }

    /// The joint's location.
    pub fn get(&self, joint: Joint) -> &JointPose {
        &self.joints[joint.index()]
    }

    /// The mirror image in the `x = 0` plane of the frame the joints are in, with the other
    /// side: positions get `x` negated, orientations `R` become `S R S` for `S = diag(-1, 1, 1)`,
    /// so each joint frame keeps OpenXR's convention (`-Z` to the tip, `+Y` dorsal).
    pub fn mirrored(&self) -> HandJoints {
        let joints = self.joints.map(|j| {
            let q = j.orientation;
            JointPose {
                position: Point3::new(-j.position.x, j.position.y, j.position.z),
                // S R S is the rotation about axis -S a, by the same angle.
                orientation: Quaternion::new(q.w, q.i, -q.j, -q.k),
                ..j
            }
        });
        HandJoints {
            side: self.side.mirrored(),
            joints,
        }
    }

    /// The same hand moved rigidly: every joint's pose `J` becomes `pose · J`.
    pub fn transformed(&self, pose: &Isometry3<f64>) -> HandJoints {
        let joints = self.joints.map(|j| JointPose {
            position: pose * j.position,
            orientation: pose.rotation.quaternion() * j.orientation,
            ..j
        });
        HandJoints {
            side: self.side,
            joints,
        }
    }

    /// Checks what the retargeting relies on: every joint but the palm valid, finite within
    /// [`MAX_POSITION_M`] (so that poses made from it stay finite), with a unit orientation;
    /// each digit's bones of a possible length and pointing from joint to
    /// joint toward the tip (a joint's `-Z` toward the next); the knuckles across the hand in
    /// the order of the side (index on the thumb's side of the little finger).
    pub fn validate(&self) -> Result<(), JointsError> {
        for joint in &Joint::ALL[1..] {
            let pose = self.get(*joint);
            if !pose.flags.contains(JointFlags::VALID) {
                return Err(JointsError::NotValid { joint: *joint });
            }
            let finite = pose.position.iter().all(|c| c.is_finite())
                && pose.radius.is_finite()
                && pose.radius >= 0.0;
            if !finite {
                return Err(JointsError::NonFinite { joint: *joint });
            }
            if pose.position.iter().any(|c| c.abs() > MAX_POSITION_M) {
                return Err(JointsError::OutOfRange { joint: *joint });
            }
            let norm = pose.orientation.norm();
            let unit = (norm - 1.0).abs() <= UNIT_TOLERANCE; // false for NaN
            if !unit {
                return Err(JointsError::NotUnit {
                    joint: *joint,
                    norm,
                });
            }
        }
        let wrist = self.get(Joint::Wrist);
        for chain in Joint::digit_chains() {
            let reach = (self.get(chain[0]).position - wrist.position).norm();
            if reach > MAX_WRIST_REACH_M {
                return Err(JointsError::BoneLength {
                    from: Joint::Wrist,
                    to: chain[0],
                    length_m: reach,
                });
            }
            for bone in chain.windows(2) {
                let (from, to) = (self.get(bone[0]), self.get(bone[1]));
                let vector = to.position - from.position;
                let length_m = vector.norm();
                if !(BONE_LENGTH_M.0..=BONE_LENGTH_M.1).contains(&length_m) {
                    return Err(JointsError::BoneLength {
                        from: bone[0],
                        to: bone[1],
                        length_m,
                    });
                }
                if from.forward().dot(&vector) <= 0.0 {
                    return Err(JointsError::OutOfOrder {
                        joint: bone[1],
                        reason: "behind the joint before it (against its -Z)",
                    });
                }
            }
        }
        // Across the hand: with the wrist's +Y dorsal and -Z toward the fingers, a left hand's
        // thumb side is +X and a right hand's -X.
        let across = wrist.rotation() * Vector3::x();
        let sign = match self.side {
            HandSide::Left => 1.0,
            HandSide::Right => -1.0,
        };
        let knuckles = [
            Joint::IndexProximal,
            Joint::MiddleProximal,
            Joint::RingProximal,
            Joint::LittleProximal,
        ];
        for pair in knuckles.windows(2) {
            let step = self.get(pair[1]).position - self.get(pair[0]).position;
            if sign * across.dot(&step) >= 0.0 {
                return Err(JointsError::OutOfOrder {
                    joint: pair[1],
                    reason: "knuckles not in order across the hand for its side",
                });
            }
        }
        Ok(())
    }
}
