//! The wire's numbers a C program needs: array lengths, flag bits and codes.
//!
//! cbindgen writes only this crate's constants into the header, not those of vas-protocol, so
//! each is written here as a literal, and checked against the protocol's own at compile time: a
//! change on the wire that is not made here does not build.

use vas_protocol::{HandSide, SlidingMetaphor};

/// Flex angles of a glove sample and a hand frame (CyberGlove order).
pub const VAS_FLEX_COUNT: usize = 22;
/// Segments of a hand frame and of a hand's geometry (`vas_hand_segment_name` names them).
pub const VAS_HAND_SEGMENT_COUNT: usize = 16;
/// OpenXR joints of a hand-joints sample.
pub const VAS_HAND_JOINT_COUNT: usize = 26;

/// `VasPartState::flags` bit: a hand holds the part.
pub const VAS_PART_GRASPED: u32 = 1 << 0;
/// `VasPartState::flags` bit: the part touches another part or a hand.
pub const VAS_PART_TOUCHING: u32 = 1 << 1;
/// `VasPartState::flags` bit: the part slides along a contact.
pub const VAS_PART_SLIDING: u32 = 1 << 2;
/// `VasPartState::flags` bit: a hand pushes the part without holding it.
pub const VAS_PART_PUSHED: u32 = 1 << 3;

/// `VasSimEvent::other` when the other side of a contact is a hand, not a part.
pub const VAS_HAND_PART_ID: u32 = u32::MAX;

/// `VasJointLocation::flags` bit: the orientation is valid.
pub const VAS_JOINT_ORIENTATION_VALID: u32 = 1 << 0;
/// `VasJointLocation::flags` bit: the position is valid.
pub const VAS_JOINT_POSITION_VALID: u32 = 1 << 1;
/// `VasJointLocation::flags` bit: the orientation is tracked, not inferred.
pub const VAS_JOINT_ORIENTATION_TRACKED: u32 = 1 << 2;
/// `VasJointLocation::flags` bit: the position is tracked, not inferred.
pub const VAS_JOINT_POSITION_TRACKED: u32 = 1 << 3;

/// Hand side code (`VasHandFrame::hand`, `VasSimEvent::hand`, ...): the right hand.
pub const VAS_HAND_RIGHT: u32 = 0;
/// Hand side code: the left hand.
pub const VAS_HAND_LEFT: u32 = 1;

/// Sliding metaphor code: the position is pulled towards the hand's ghost.
pub const VAS_METAPHOR_RUBBER_BAND: u32 = 1;
/// Sliding metaphor code: position and orientation are both pulled towards the ghost.
pub const VAS_METAPHOR_SPIRAL_SPRING: u32 = 2;
/// Sliding metaphor code: the part repeats the ghost's motion increment.
pub const VAS_METAPHOR_INCREMENTAL: u32 = 3;

const _: () = {
    assert!(VAS_FLEX_COUNT == vas_protocol::FLEX_COUNT);
    assert!(VAS_HAND_SEGMENT_COUNT == vas_protocol::HAND_SEGMENT_COUNT);
    assert!(VAS_HAND_JOINT_COUNT == vas_protocol::HAND_JOINT_COUNT);
    assert!(VAS_PART_GRASPED == vas_protocol::PART_GRASPED);
    assert!(VAS_PART_TOUCHING == vas_protocol::PART_TOUCHING);
    assert!(VAS_PART_SLIDING == vas_protocol::PART_SLIDING);
    assert!(VAS_PART_PUSHED == vas_protocol::PART_PUSHED);
    assert!(VAS_HAND_PART_ID == vas_protocol::HAND_PART_ID);
    assert!(VAS_JOINT_ORIENTATION_VALID == vas_protocol::JOINT_ORIENTATION_VALID);
    assert!(VAS_JOINT_POSITION_VALID == vas_protocol::JOINT_POSITION_VALID);
    assert!(VAS_JOINT_ORIENTATION_TRACKED == vas_protocol::JOINT_ORIENTATION_TRACKED);
    assert!(VAS_JOINT_POSITION_TRACKED == vas_protocol::JOINT_POSITION_TRACKED);
    assert!(VAS_HAND_RIGHT == HandSide::Right as u32);
    assert!(VAS_HAND_LEFT == HandSide::Left as u32);
    assert!(VAS_METAPHOR_RUBBER_BAND == SlidingMetaphor::RubberBand as u32);
    assert!(VAS_METAPHOR_SPIRAL_SPRING == SlidingMetaphor::SpiralSpring as u32);
    assert!(VAS_METAPHOR_INCREMENTAL == SlidingMetaphor::Incremental as u32);
};
