//! The byte layout of every wire type, field by field, as tables built from the Rust types
//! themselves (`size_of`, `align_of`, `offset_of!`).
//!
//! The tables serve twice: the bridge copies a value's fields, and only its fields, into the
//! bytes it sends on zenoh (padding goes out as zeros, never as whatever memory held), and the
//! test of `docs/wire.md` checks every table of the specification against them, so that the
//! specification cannot drift from the types.

use std::mem::{align_of, offset_of, size_of};

use vas_protocol::{
    ClearanceFrame, ClearancePair, ControlRequest, ControlResponse, ForceFrame, GeometryHeader,
    GloveSample, HandDescription, HandFrame, HandJointsSample, InputStamp, InputStats,
    JointLocation, MAX_HANDS, MAX_NAME_BYTES, MAX_PATH_BYTES, MAX_STATUS_MESSAGE_BYTES, MAX_USERS,
    PartDescription, PartState, PartsFrameHeader, SimEvent, TrackerSample, WirePose, WireText,
};

/// A number as it lies on the wire: little-endian, of its natural size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Number {
    /// A byte (of text).
    U8,
    /// An unsigned 32-bit integer: counts, codes, flags.
    U32,
    /// An unsigned 64-bit integer: frame and sequence numbers, timestamps.
    U64,
    /// An IEEE 754 single: flex angles, radii.
    F32,
    /// An IEEE 754 double: positions, rotations, distances.
    F64,
}

impl Number {
    /// Bytes of one number.
    pub const fn size(self) -> usize {
        match self {
            Number::U8 => 1,
            Number::U32 | Number::F32 => 4,
            Number::U64 | Number::F64 => 8,
        }
    }

    /// The name `docs/wire.md` gives the type: `u8`, `u32`, `u64`, `f32`, `f64`.
    pub const fn name(self) -> &'static str {
        match self {
            Number::U8 => "u8",
            Number::U32 => "u32",
            Number::U64 => "u64",
            Number::F32 => "f32",
            Number::F64 => "f64",
        }
    }
}

/// What a field holds: numbers, or other wire types laid out in place.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// `count` numbers one after the other.
    Numbers(Number, usize),
    /// `count` values of a nested type one after the other.
    Nested(&'static Layout, usize),
}

impl Kind {
    /// Bytes of the field.
    pub const fn size(self) -> usize {
        match self {
            Kind::Numbers(number, count) => number.size() * count,
            Kind::Nested(layout, count) => layout.size * count,
        }
    }

    /// The type as `docs/wire.md` writes it: `u64`, `f64[3]`, `WirePose[16]`, `InputStamp`.
    pub fn spelling(self) -> String {
        let (name, count) = match self {
            Kind::Numbers(number, count) => (number.name(), count),
            Kind::Nested(layout, count) => (layout.name, count),
        };
        match count {
            1 => name.to_owned(),
            count => format!("{name}[{count}]"),
        }
    }
}

/// One field of a wire type.
#[derive(Debug, Clone, Copy)]
pub struct Field {
    /// The field's name, as in Rust, in the C header and in `docs/wire.md`.
    pub name: &'static str,
    /// Bytes from the start of the type.
    pub offset: usize,
    /// What it holds.
    pub kind: Kind,
}

/// A wire type's size, alignment and fields, in the order of their offsets.
#[derive(Debug)]
pub struct Layout {
    /// The type's name (`WireText` is written `Text64`, `Text256`, `Text512` by capacity).
    pub name: &'static str,
    /// `size_of` the type.
    pub size: usize,
    /// `align_of` the type.
    pub align: usize,
    /// Every field.
    pub fields: &'static [Field],
}

impl Layout {
    /// Copies the bytes of every field of the value at `value` into `out` (as long as the
    /// type), recursing into nested types; bytes of no field (padding) are left as they are.
    ///
    /// # Safety
    /// `value` must point to an initialised value of the type this layout describes.
    pub(crate) unsafe fn copy_fields(&self, value: *const u8, out: &mut [u8]) {
        for field in self.fields {
            match field.kind {
                Kind::Numbers(..) => {
                    let size = field.kind.size();
                    // SAFETY: a field of numbers has no padding, and the caller vouches for the
                    // value: these bytes are initialised.
                    let bytes =
                        unsafe { std::slice::from_raw_parts(value.add(field.offset), size) };
                    out[field.offset..field.offset + size].copy_from_slice(bytes);
                }
                Kind::Nested(nested, count) => {
                    for index in 0..count {
                        let at = field.offset + index * nested.size;
                        // SAFETY: the nested value lies initialised at `at`.
                        unsafe {
                            nested.copy_fields(value.add(at), &mut out[at..at + nested.size])
                        };
                    }
                }
            }
        }
    }
}

/// `count` numbers.
const fn numbers(number: Number, count: usize) -> Kind {
    Kind::Numbers(number, count)
}

/// One number.
const fn number(number: Number) -> Kind {
    Kind::Numbers(number, 1)
}

/// `count` nested values.
const fn nested(layout: &'static Layout, count: usize) -> Kind {
    Kind::Nested(layout, count)
}

/// One nested value.
const fn one(layout: &'static Layout) -> Kind {
    Kind::Nested(layout, 1)
}

/// The layout of a struct: `layout!(Type { field: kind, ... })`, the offsets from `offset_of!`.
macro_rules! layout {
    ($name:literal, $ty:ty { $($field:ident: $kind:expr),* $(,)? }) => {
        Layout {
            name: $name,
            size: size_of::<$ty>(),
            align: align_of::<$ty>(),
            fields: &[$(Field {
                name: stringify!($field),
                offset: offset_of!($ty, $field),
                kind: $kind,
            }),*],
        }
    };
}

/// The layout of a `WireText<N>`: a length and `N` bytes. Its fields are private to the
/// protocol, so their offsets are written here; `repr(C)` places them so, and the size (checked
/// against `size_of`) would tell otherwise.
macro_rules! text_layout {
    ($name:literal, $capacity:expr) => {
        Layout {
            name: $name,
            size: size_of::<WireText<$capacity>>(),
            align: align_of::<WireText<$capacity>>(),
            fields: &[
                Field {
                    name: "len",
                    offset: 0,
                    kind: number(U32),
                },
                Field {
                    name: "bytes",
                    offset: 4,
                    kind: numbers(U8, $capacity),
                },
            ],
        }
    };
}

use Number::{F32, F64, U8, U32, U64};

/// [`WirePose`].
pub static WIRE_POSE: Layout = layout!(
    "WirePose",
    WirePose {
        position: numbers(F64, 3),
        rotation: numbers(F64, 4),
    }
);
/// [`InputStamp`].
pub static INPUT_STAMP: Layout = layout!(
    "InputStamp",
    InputStamp {
        seq: number(U64),
        timestamp_ns: number(U64),
    }
);
/// `WireText<64>`: names.
pub static TEXT_64: Layout = text_layout!("Text64", MAX_NAME_BYTES);
/// `WireText<256>`: status messages.
pub static TEXT_256: Layout = text_layout!("Text256", MAX_STATUS_MESSAGE_BYTES);
/// `WireText<512>`: paths.
pub static TEXT_512: Layout = text_layout!("Text512", MAX_PATH_BYTES);

/// [`TrackerSample`].
pub static TRACKER_SAMPLE: Layout = layout!(
    "TrackerSample",
    TrackerSample {
        seq: number(U64),
        timestamp_ns: number(U64),
        hand: one(&WIRE_POSE),
        cart: one(&WIRE_POSE),
        sensor_id: number(U32),
        user: number(U32),
        side: number(U32),
        reserved: number(U32),
    }
);
/// [`GloveSample`].
pub static GLOVE_SAMPLE: Layout = layout!(
    "GloveSample",
    GloveSample {
        seq: number(U64),
        timestamp_ns: number(U64),
        flex: numbers(F32, vas_protocol::FLEX_COUNT),
        user: number(U32),
        side: number(U32),
    }
);
/// [`JointLocation`].
pub static JOINT_LOCATION: Layout = layout!(
    "JointLocation",
    JointLocation {
        position: numbers(F64, 3),
        rotation: numbers(F64, 4),
        radius: number(F32),
        flags: number(U32),
    }
);
/// [`HandJointsSample`].
pub static HAND_JOINTS_SAMPLE: Layout = layout!(
    "HandJointsSample",
    HandJointsSample {
        seq: number(U64),
        timestamp_ns: number(U64),
        joints: nested(&JOINT_LOCATION, vas_protocol::HAND_JOINT_COUNT),
        side: number(U32),
        user: number(U32),
    }
);

/// [`GeometryHeader`].
pub static GEOMETRY_HEADER: Layout = layout!(
    "GeometryHeader",
    GeometryHeader {
        generation: number(U64),
        byte_len: number(U64),
        part_count: number(U32),
        hand_count: number(U32),
    }
);
/// [`PartsFrameHeader`].
pub static PARTS_FRAME_HEADER: Layout = layout!(
    "PartsFrameHeader",
    PartsFrameHeader {
        frame: number(U64),
        tracker: one(&INPUT_STAMP),
        glove: one(&INPUT_STAMP),
        joints: one(&INPUT_STAMP),
        timestamp_ns: number(U64),
        part_count: number(U32),
    }
);
/// [`PartState`].
pub static PART_STATE: Layout = layout!(
    "PartState",
    PartState {
        id: number(U32),
        flags: number(U32),
        position: numbers(F64, 3),
        rotation: numbers(F64, 4),
    }
);
/// [`HandFrame`].
pub static HAND_FRAME: Layout = layout!(
    "HandFrame",
    HandFrame {
        frame: number(U64),
        tracker: one(&INPUT_STAMP),
        glove: one(&INPUT_STAMP),
        joints: one(&INPUT_STAMP),
        timestamp_ns: number(U64),
        root: one(&WIRE_POSE),
        flex: numbers(F32, vas_protocol::FLEX_COUNT),
        touching: number(U32),
        grasp_type: number(U32),
        hand: number(U32),
        tracked: number(U32),
        segment_count: number(U32),
        user: number(U32),
        segments: nested(&WIRE_POSE, vas_protocol::HAND_SEGMENT_COUNT),
    }
);
/// [`SimEvent`].
pub static SIM_EVENT: Layout = layout!(
    "SimEvent",
    SimEvent {
        frame: number(U64),
        tracker: one(&INPUT_STAMP),
        glove: one(&INPUT_STAMP),
        joints: one(&INPUT_STAMP),
        timestamp_ns: number(U64),
        kind: number(U32),
        grasp_type: number(U32),
        part: number(U32),
        other: number(U32),
        hand: number(U32),
        segment: number(U32),
        user: number(U32),
        reserved: number(U32),
        point: numbers(F64, 3),
        normal: numbers(F64, 3),
        other_point: numbers(F64, 3),
        distance: number(F64),
    }
);
/// [`ForceFrame`].
pub static FORCE_FRAME: Layout = layout!(
    "ForceFrame",
    ForceFrame {
        frame: number(U64),
        tracker: one(&INPUT_STAMP),
        glove: one(&INPUT_STAMP),
        joints: one(&INPUT_STAMP),
        timestamp_ns: number(U64),
        force: numbers(F64, 3),
        torque: numbers(F64, 3),
        hand: number(U32),
        user: number(U32),
    }
);
/// [`ClearancePair`].
pub static CLEARANCE_PAIR: Layout = layout!(
    "ClearancePair",
    ClearancePair {
        part: number(U32),
        other: number(U32),
        triangles: numbers(U32, 2),
        flags: number(U32),
        reserved: number(U32),
        distance: number(F64),
        point: numbers(F64, 3),
        other_point: numbers(F64, 3),
    }
);
/// [`ClearanceFrame`].
pub static CLEARANCE_FRAME: Layout = layout!(
    "ClearanceFrame",
    ClearanceFrame {
        frame: number(U64),
        tracker: one(&INPUT_STAMP),
        glove: one(&INPUT_STAMP),
        joints: one(&INPUT_STAMP),
        timestamp_ns: number(U64),
        threshold: number(F64),
        pair_count: number(U32),
        more: number(U32),
        pairs: nested(&CLEARANCE_PAIR, vas_protocol::MAX_CLEARANCE_PAIRS),
    }
);

/// [`ControlRequest`].
pub static CONTROL_REQUEST: Layout = layout!(
    "ControlRequest",
    ControlRequest {
        kind: number(U32),
        argument: number(U32),
        path: one(&TEXT_512),
    }
);
/// [`PartDescription`].
pub static PART_DESCRIPTION: Layout = layout!(
    "PartDescription",
    PartDescription {
        id: number(U32),
        flags: number(U32),
        initial_pose: one(&WIRE_POSE),
        name: one(&TEXT_64),
        group: one(&TEXT_64),
        mesh_source: one(&TEXT_512),
        truncated: number(U32),
        scale: number(F64),
    }
);
/// [`InputStats`].
pub static INPUT_STATS: Layout = layout!(
    "InputStats",
    InputStats {
        tracker_accepted: number(U64),
        tracker_rejected_non_finite: number(U64),
        tracker_rejected_quaternion: number(U64),
        glove_accepted: number(U64),
        glove_rejected_non_finite: number(U64),
        glove_samples_clamped: number(U64),
        glove_values_clamped: number(U64),
        tracker_rejected_out_of_range: number(U64),
        joints_accepted: number(U64),
        joints_untracked: number(U64),
        joints_rejected_non_finite: number(U64),
        joints_rejected_quaternion: number(U64),
        joints_rejected_out_of_range: number(U64),
        joints_rejected_anatomy: number(U64),
        joints_rejected_no_such_hand: number(U64),
        rejected_ahead: number(U64),
        rejected_no_such_user: number(U64),
        rejected_no_such_hand: number(U64),
    }
);
/// [`HandDescription`].
pub static HAND_DESCRIPTION: Layout = layout!(
    "HandDescription",
    HandDescription {
        side: number(U32),
        user: number(U32),
        model: one(&TEXT_64),
    }
);
/// [`ControlResponse`].
pub static CONTROL_RESPONSE: Layout = layout!(
    "ControlResponse",
    ControlResponse {
        status: number(U32),
        kind: number(U32),
        part_count: number(U32),
        scene_truncated: number(U32),
        scene_name: one(&TEXT_64),
        scene_source: one(&TEXT_512),
        part: one(&PART_DESCRIPTION),
        stats: one(&INPUT_STATS),
        message: one(&TEXT_256),
        up: numbers(F64, 3),
        metres_per_unit: number(F64),
        hand_count: number(U32),
        listed_count: number(U32),
        hands: nested(&HAND_DESCRIPTION, MAX_HANDS),
        listed: one(&TEXT_64),
        generation: number(U64),
        metaphor: number(U32),
        user_count: number(U32),
        users: nested(&TEXT_64, MAX_USERS),
    }
);

/// Every layout, nested types first: what `docs/wire.md` specifies.
pub static ALL: [&Layout; 22] = [
    &WIRE_POSE,
    &INPUT_STAMP,
    &TEXT_64,
    &TEXT_256,
    &TEXT_512,
    &TRACKER_SAMPLE,
    &GLOVE_SAMPLE,
    &JOINT_LOCATION,
    &HAND_JOINTS_SAMPLE,
    &GEOMETRY_HEADER,
    &PARTS_FRAME_HEADER,
    &PART_STATE,
    &HAND_FRAME,
    &SIM_EVENT,
    &FORCE_FRAME,
    &CLEARANCE_PAIR,
    &CLEARANCE_FRAME,
    &CONTROL_REQUEST,
    &PART_DESCRIPTION,
    &INPUT_STATS,
    &HAND_DESCRIPTION,
    &CONTROL_RESPONSE,
];
