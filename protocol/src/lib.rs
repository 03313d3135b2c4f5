//! vas wire types and service names.
//!
//! Everything the server and its clients exchange over iceoryx2 is defined here, and nothing
//! else: the payload types of every service, their versioned type names, the service names and
//! the quality-of-service settings both sides must agree on.
//!
//! Conventions shared by every type:
//! * positions in metres as `[f64; 3]`; rotations as unit quaternions `[f64; 4]` in x, y, z, w
//!   order; flex angles in radians as `f32`, in CyberGlove order ([`FLEX_JOINT_NAMES`]);
//! * timestamps in nanoseconds since the Unix epoch ([`wall_clock_ns`]), so that a frame can be
//!   traced back to the input that produced it, even across processes;
//! * input sequence numbers start at 1; 0 in an [`InputStamp`] means "no input yet";
//! * enumerations travel as `u32` codes and are decoded with `TryFrom`, so that a corrupt or newer
//!   peer can never produce an invalid Rust enum.
//!
//! Every payload is `#[repr(C)]` and [`ZeroCopySend`](iceoryx2::prelude::ZeroCopySend); its
//! `type_name` ends in `::v1`. A change of layout must bump that version, and the layout tests
//! in `tests/layout.rs` fail until it does.

/// Defines a `#[repr(u32)]` enumeration that travels on the wire as its `u32` code, together with
/// the `TryFrom<u32>` that decodes it, so that each variant's code is written exactly once.
macro_rules! wire_code_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[$variant_meta:meta])* $variant:ident = $code:literal, )+
        }
    ) => {
        $(#[$meta])*
        #[repr(u32)]
        pub enum $name {
            $( $(#[$variant_meta])* $variant = $code, )+
        }

        impl TryFrom<u32> for $name {
            type Error = $crate::UnknownCode;

            fn try_from(code: u32) -> Result<Self, Self::Error> {
                match code {
                    $( $code => Ok(Self::$variant), )+
                    _ => Err($crate::UnknownCode { type_name: stringify!($name), code }),
                }
            }
        }
    };
}

mod clearance;
mod clock;
mod control;
mod geometry;
mod input;
mod number;
mod output;
mod pose;
pub mod services;
mod text;

pub use clearance::{CLEARANCE_STALE, ClearanceFrame, ClearancePair, MAX_CLEARANCE_PAIRS};
pub use clock::wall_clock_ns;
pub use control::{
    ControlRequest, ControlRequestKind, ControlResponse, ControlStatus, HandDescription,
    InputStats, MAX_HANDS, MAX_NAME_BYTES, MAX_PATH_BYTES, MAX_STATUS_MESSAGE_BYTES, MAX_USERS,
    PART_MOVABLE, PartDescription, SlidingMetaphor, UnknownMetaphor,
};
pub use geometry::{
    GeometryDecodeError, GeometryHeader, HandGeometry, MAX_MESH_NAME_BYTES, MeshData, SceneGeometry,
};
pub use input::{
    FLEX_COUNT, FLEX_JOINT_NAMES, FLEX_LIMITS_RAD, GloveSample, GloveTarget, HAND_JOINT_COUNT,
    HandJointsSample, InputRejection, JOINT_ORIENTATION_TRACKED, JOINT_ORIENTATION_VALID,
    JOINT_POSITION_TRACKED, JOINT_POSITION_VALID, JointLocation, MAX_POSITION_M,
    MAX_TIMESTAMP_AHEAD_NS, TrackerSample, TrackerTarget, UNIT_QUATERNION_TOLERANCE,
};
pub use number::Readable;
pub use output::{
    EventKind, ForceFrame, GraspType, HAND_PART_ID, HAND_SEGMENT_COUNT, HandFrame, HandSegment,
    HandSide, InputStamp, PART_GRASPED, PART_PUSHED, PART_SLIDING, PART_TOUCHING, PartState,
    PartsFrameHeader, SimEvent,
};
pub use pose::WirePose;
pub use text::{WireText, WireTextError};

/// An enumeration code on the wire that no variant of the named type has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("unknown {type_name} code {code}")]
pub struct UnknownCode {
    /// The enumeration that was decoded.
    pub type_name: &'static str,
    /// The code that was received.
    pub code: u32,
}
