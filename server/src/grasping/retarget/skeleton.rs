//! Which OpenXR joint each segment of the hand model corresponds to, and how their frames turn
//! into each other.
//!
//! The palm corresponds to the wrist joint (OpenXR's wrist turns with the palm; the forearm is
//! not tracked), each digit's inner, middle and outer segment to the joints at the base of its
//! three outer bones (the thumb's metacarpal, proximal and distal; a finger's proximal,
//! intermediate and distal), and the end of its outer segment, the model's fingertip point, to
//! the tip joint. A finger's metacarpal has no segment: the palm is rigid.
//!
//! Frames: a model segment has `+y` along the segment and `+z` on the back of the hand, an
//! OpenXR joint `-Z` along the bone and `+Y` on the back, for both hands; so a segment's frame
//! is its joint's frame turned by [`joint_to_segment`]. The model may also turn a digit's
//! segments about their own axes where OpenXR does not (the thumb's phalanges are turned 90
//! degrees from its metacarpal); each segment's frame correction undoes the base rotations of
//! the segments beyond it, so that a straight digit has one OpenXR frame along its length.

use nalgebra::{Point3, Unit, UnitQuaternion, Vector3};

use super::joints::Joint;
use crate::grasping::{Finger, HandModel, JointLevel, SegmentId};

/// The rotation from an OpenXR joint frame to a model segment frame: `x` stays, the segment's
/// `+y` is the joint's `-Z`, its `+z` the joint's `+Y` (a quarter turn about `-x`).
pub fn joint_to_segment() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2)
}

/// One digit: its segments and joints.
#[derive(Debug, Clone, PartialEq)]
pub struct Digit {
    /// The digit.
    pub finger: Finger,
    /// Inner, middle and outer segment.
    pub segments: [SegmentId; 3],
    /// The joints at the bases of the inner, middle and outer segment, then the tip.
    pub joints: [Joint; 4],
    /// The fingertip point in the outer segment's frame: the end of its axis.
    pub tip: Point3<f64>,
}

/// A digit segment's bone: from its joint to the next joint (or the tip).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bone {
    /// The joint at the segment's origin.
    pub from: Joint,
    /// The joint at its end: the next segment's, or the tip.
    pub to: Joint,
    /// The direction from the origin to the end in the segment's own frame.
    pub rest: Unit<Vector3<f64>>,
}

/// The correspondence between a hand model and OpenXR's joints.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    /// Thumb, index, middle, ring, pinky.
    pub digits: [Digit; 5],
    /// For every segment, its joint (the wrist for the palm).
    pub joint_of: Vec<Joint>,
    /// For every segment, the rotation from its joint's frame to its own:
    /// [`joint_to_segment`] followed by the digit's correction.
    pub frame: Vec<UnitQuaternion<f64>>,
    /// For every segment, the digits (bit `d` for `digits[d]`) whose tips it carries.
    pub carries: Vec<u8>,
    /// For every digit segment, its bone; `None` for the palm.
    pub bones: Vec<Option<Bone>>,
}

impl Skeleton {
    /// The correspondence for a validated model (a palm and five digits of three segments).
    pub fn new(model: &HandModel) -> Skeleton {
        let segments = model.segments();
        let find = |finger: Finger, level: JointLevel| {
            segments
                .iter()
                .position(|s| s.finger == finger && s.level == level)
                .expect("a validated hand has every segment of every digit")
        };
        let chains = Joint::digit_chains();
        let digits = std::array::from_fn(|d| {
            let finger = Finger::DIGITS[d];
            let ids = [JointLevel::Inner, JointLevel::Middle, JointLevel::Outer]
                .map(|level| find(finger, level));
            // The thumb's chain starts at its metacarpal, a finger's at its proximal joint.
            let chain = chains[d];
            let joints: [Joint; 4] = std::array::from_fn(|i| chain[chain.len() - 4 + i]);
            let outer = &segments[ids[2]].shape;
            let tip = outer
                .centres
                .iter()
                .copied()
                .max_by(|a, b| a.coords.norm().total_cmp(&b.coords.norm()))
                .unwrap_or_else(Point3::origin);
            Digit {
                finger,
                segments: ids,
                joints,
                tip,
            }
        });
        let mut joint_of = vec![Joint::Wrist; segments.len()];
        let mut frame = vec![joint_to_segment(); segments.len()];
        let mut carries = vec![0u8; segments.len()];
        let mut bones = vec![None; segments.len()];
        for (d, digit) in digits.iter().enumerate() {
            let mut correction = UnitQuaternion::identity();
            for i in (0..3).rev() {
                let id = digit.segments[i];
                joint_of[id] = digit.joints[i];
                let end = match digit.segments.get(i + 1) {
                    Some(&child) => segments[child].origin,
                    None => digit.tip.coords,
                };
                bones[id] = Some(Bone {
                    from: digit.joints[i],
                    to: digit.joints[i + 1],
                    rest: Unit::try_new(end, 0.0).unwrap_or(Vector3::y_axis()),
                });
                frame[id] = joint_to_segment() * correction;
                correction *= segments[id].base_rotation.inverse();
            }
            let mut id = Some(digit.segments[2]);
            while let Some(s) = id {
                carries[s] |= 1 << d;
                id = segments[s].parent;
            }
        }
        Skeleton {
            digits,
            joint_of,
            frame,
            carries,
            bones,
        }
    }
}
