//! Output frames: parts, hand, events and force.
//!
//! Every output names the input it answers with an [`InputStamp`] per input stream (tracker,
//! glove and hand joints number their samples independently), so that latency can be traced end
//! to end and a lockstep replay can wait for the frame answering the sample it sent.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

use crate::input::FLEX_COUNT;
use crate::pose::WirePose;

/// The sequence number and timestamp of one input sample; all zero before the first sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
pub struct InputStamp {
    /// The sample's sequence number (0: no sample yet).
    pub seq: u64,
    /// The sample's timestamp in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
}

/// User header of a `vas/output/parts` sample; the payload is a slice of [`PartState`].
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::PartsFrameHeader::v2")]
#[repr(C)]
pub struct PartsFrameHeader {
    /// Frame number of the parts stream, from 1.
    pub frame: u64,
    /// The latest tracker sample taken into account.
    pub tracker: InputStamp,
    /// The latest glove sample taken into account.
    pub glove: InputStamp,
    /// The latest hand-joints sample taken into account.
    pub joints: InputStamp,
    /// When the frame was published, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// Number of parts in the payload slice.
    pub part_count: u32,
}

/// [`PartState::flags`] bit: the part is held by the hand.
pub const PART_GRASPED: u32 = 1 << 0;
/// [`PartState::flags`] bit: the part touches another part or the hand.
pub const PART_TOUCHING: u32 = 1 << 1;
/// [`PartState::flags`] bit: the part slides along a contact.
pub const PART_SLIDING: u32 = 1 << 2;
/// [`PartState::flags`] bit: a hand pushes the part without holding it.
pub const PART_PUSHED: u32 = 1 << 3;

/// The valid pose and state of one part.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::PartState::v1")]
#[repr(C)]
pub struct PartState {
    /// The part's id: its index in the scene (see the control service's part info).
    pub id: u32,
    /// State bits: [`PART_GRASPED`], [`PART_TOUCHING`], [`PART_SLIDING`], [`PART_PUSHED`].
    pub flags: u32,
    /// Position in metres.
    pub position: [f64; 3],
    /// Rotation as a unit quaternion in x, y, z, w order.
    pub rotation: [f64; 4],
}

impl PartState {
    /// The part's pose.
    pub fn pose(&self) -> WirePose {
        WirePose {
            position: self.position,
            rotation: self.rotation,
        }
    }

    /// Whether a hand holds the part ([`PART_GRASPED`]).
    pub fn is_grasped(&self) -> bool {
        self.flags & PART_GRASPED != 0
    }

    /// Whether the part touches another part or a hand ([`PART_TOUCHING`]).
    pub fn is_touching(&self) -> bool {
        self.flags & PART_TOUCHING != 0
    }

    /// Whether the part slides along a contact ([`PART_SLIDING`]).
    pub fn is_sliding(&self) -> bool {
        self.flags & PART_SLIDING != 0
    }

    /// Whether a hand pushes the part without holding it ([`PART_PUSHED`]).
    pub fn is_pushed(&self) -> bool {
        self.flags & PART_PUSHED != 0
    }
}

wire_code_enum! {
    /// Which hand a hand frame, event or hand geometry is about.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
    #[serde(rename_all = "snake_case")]
    pub enum HandSide {
        /// The right hand.
        Right = 0,
        /// The left hand.
        Left = 1,
    }
}

impl HandSide {
    /// The other hand.
    pub fn mirrored(self) -> HandSide {
        match self {
            Self::Right => Self::Left,
            Self::Left => Self::Right,
        }
    }

    /// The side in words.
    pub fn name(self) -> &'static str {
        match self {
            Self::Right => "right",
            Self::Left => "left",
        }
    }
}

/// Segments of a hand frame: [`HandSegment::ALL`].
pub const HAND_SEGMENT_COUNT: usize = 16;

/// One hand as the collision loop verified it: root pose, flex vector, each segment's pose,
/// touching segments and grasp type.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::HandFrame::v4")]
#[repr(C)]
pub struct HandFrame {
    /// Frame number of the hand stream, from 1.
    pub frame: u64,
    /// The tracker sample this frame answers (or the latest one, when it answers another
    /// stream's sample).
    pub tracker: InputStamp,
    /// The glove sample this frame answers (or the latest one, when it answers another
    /// stream's sample).
    pub glove: InputStamp,
    /// The hand-joints sample of this hand this frame answers (or the latest one, when it
    /// answers another stream's sample).
    pub joints: InputStamp,
    /// When the frame was published, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// Pose of the hand root in the world (the tracker's cart pose times its hand pose).
    pub root: WirePose,
    /// Joint angles in radians, CyberGlove order.
    pub flex: [f32; FLEX_COUNT],
    /// Bit [`HandSegment::bit`] set: that segment touches a part.
    pub touching: u32,
    /// The recognised grasp, a [`GraspType`] code.
    pub grasp_type: u32,
    /// The hand, a [`HandSide`] code.
    pub hand: u32,
    /// 1 when the hand follows its input; 0 when its tracking is lost (it stays where it was).
    pub tracked: u32,
    /// Segments with a pose in [`HandFrame::segments`]: [`HAND_SEGMENT_COUNT`] with a hand
    /// model, 0 in a scene without one.
    pub segment_count: u32,
    /// The user whose hand it is, an index into the scene's users
    /// ([`ControlResponse::users`](crate::ControlResponse::users)).
    pub user: u32,
    /// Each segment's verified pose in the world, in [`HandSegment`] order: where a renderer
    /// places the segment's mesh from `vas/scene/geometry`.
    pub segments: [WirePose; HAND_SEGMENT_COUNT],
}

impl Default for HandFrame {
    /// A frame of nothing: frame 0, no input, the identity root and segments, a right hand.
    fn default() -> Self {
        Self {
            frame: 0,
            tracker: InputStamp::default(),
            glove: InputStamp::default(),
            joints: InputStamp::default(),
            timestamp_ns: 0,
            root: WirePose::IDENTITY,
            flex: [0.0; FLEX_COUNT],
            touching: 0,
            grasp_type: GraspType::None as u32,
            hand: HandSide::Right as u32,
            tracked: 0,
            segment_count: 0,
            user: 0,
            segments: [WirePose::IDENTITY; HAND_SEGMENT_COUNT],
        }
    }
}

impl HandFrame {
    /// The segments that have a pose.
    pub fn segment_poses(&self) -> &[WirePose] {
        &self.segments[..(self.segment_count as usize).min(HAND_SEGMENT_COUNT)]
    }

    /// The hand; `None` for a code this build does not know.
    pub fn side(&self) -> Option<HandSide> {
        HandSide::try_from(self.hand).ok()
    }

    /// The recognised grasp; `None` for a code this build does not know.
    pub fn grasp(&self) -> Option<GraspType> {
        GraspType::try_from(self.grasp_type).ok()
    }

    /// Whether the hand follows its input ([`HandFrame::tracked`]).
    pub fn is_tracked(&self) -> bool {
        self.tracked != 0
    }

    /// Whether `segment` touches a part ([`HandFrame::touching`]).
    pub fn is_touching(&self, segment: HandSegment) -> bool {
        self.touching & segment.bit() != 0
    }
}

/// The segments of the hand, as numbered in [`HandFrame::touching`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum HandSegment {
    /// The palm.
    Palm = 0,
    /// Thumb, segment next to the palm.
    ThumbProximal = 1,
    /// Thumb, middle segment.
    ThumbMiddle = 2,
    /// Thumb tip segment.
    ThumbDistal = 3,
    /// Index finger, segment next to the palm.
    IndexProximal = 4,
    /// Index finger, middle segment.
    IndexMiddle = 5,
    /// Index finger tip segment.
    IndexDistal = 6,
    /// Middle finger, segment next to the palm.
    MiddleProximal = 7,
    /// Middle finger, middle segment.
    MiddleMiddle = 8,
    /// Middle finger tip segment.
    MiddleDistal = 9,
    /// Ring finger, segment next to the palm.
    RingProximal = 10,
    /// Ring finger, middle segment.
    RingMiddle = 11,
    /// Ring finger tip segment.
    RingDistal = 12,
    /// Little finger, segment next to the palm.
    PinkyProximal = 13,
    /// Little finger, middle segment.
    PinkyMiddle = 14,
    /// Little finger tip segment.
    PinkyDistal = 15,
}

impl HandSegment {
    /// Every segment, in bit order.
    pub const ALL: [Self; HAND_SEGMENT_COUNT] = [
        Self::Palm,
        Self::ThumbProximal,
        Self::ThumbMiddle,
        Self::ThumbDistal,
        Self::IndexProximal,
        Self::IndexMiddle,
        Self::IndexDistal,
        Self::MiddleProximal,
        Self::MiddleMiddle,
        Self::MiddleDistal,
        Self::RingProximal,
        Self::RingMiddle,
        Self::RingDistal,
        Self::PinkyProximal,
        Self::PinkyMiddle,
        Self::PinkyDistal,
    ];

    /// The segment's bit in [`HandFrame::touching`].
    pub fn bit(self) -> u32 {
        1 << self as u32
    }

    /// The segment in words, e.g. `index_distal`.
    pub fn name(self) -> &'static str {
        const NAMES: [&str; HAND_SEGMENT_COUNT] = [
            "palm",
            "thumb_proximal",
            "thumb_middle",
            "thumb_distal",
            "index_proximal",
            "index_middle",
            "index_distal",
            "middle_proximal",
            "middle_middle",
            "middle_distal",
            "ring_proximal",
            "ring_middle",
            "ring_distal",
            "pinky_proximal",
            "pinky_middle",
            "pinky_distal",
        ];
        NAMES[self as usize]
    }
}

wire_code_enum! {
    /// The grasp the hand holds, by the paper's analysis and the classes it names.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
    #[serde(rename_all = "snake_case")]
    pub enum GraspType {
        /// Nothing is touched.
        None = 0,
        /// Touching without holding (one segment, or fingers without the thumb).
        Push = 1,
        /// Fingers against the thumb, no palm: a precision grasp not classified further.
        Precision = 2,
        /// Precision: thumb tip against one finger tip.
        TipPinch = 3,
        /// Precision: thumb against index and middle finger (tripod).
        ThreeJawChuck = 4,
        /// Precision: thumb against the side of the index finger (lateral).
        Key = 5,
        /// Held between two adjacent fingers.
        Cigarette = 6,
        /// Three fingers pinching without the palm.
        ThreePointPinch = 7,
        /// Fingers wrapped against the palm.
        Power = 8,
        /// Resting on the open hand (cradling).
        Gravity = 9,
    }
}

/// [`SimEvent::other`] value naming the hand rather than a part.
pub const HAND_PART_ID: u32 = u32::MAX;

wire_code_enum! {
    /// What a [`SimEvent`] reports.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
    #[serde(rename_all = "snake_case")]
    pub enum EventKind {
        /// The hand grasped `part` with `grasp_type`.
        Grasp = 1,
        /// The hand released `part`.
        Release = 2,
        /// `part` and `other` started touching.
        ContactBegin = 3,
        /// `part` and `other` stopped touching.
        ContactEnd = 4,
        /// The hand let go of `part` because another hand grasped it, of the same user or of
        /// another (that hand's grasp event comes in the same frame): a part is held by one hand
        /// at a time.
        HandOver = 5,
        /// `part` and `other` came closer than the scene's clearance threshold: `distance`,
        /// `point` on `part` and `other_point` on `other`.
        ClearanceBelow = 6,
        /// `part` and `other` are apart again by the threshold and its hysteresis (or one of them
        /// left the watch while apart, see `vas/output/clearance`).
        ClearanceRestored = 7,
        /// The hand started pushing `part`: it touches the part without holding it, and its
        /// motion into the part moves it.
        PushBegin = 8,
        /// The hand stopped pushing `part`.
        PushEnd = 9,
    }
}

impl GraspType {
    /// The grasp in words, e.g. `three_jaw_chuck`.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Push => "push",
            Self::Precision => "precision",
            Self::TipPinch => "tip_pinch",
            Self::ThreeJawChuck => "three_jaw_chuck",
            Self::Key => "key",
            Self::Cigarette => "cigarette",
            Self::ThreePointPinch => "three_point_pinch",
            Self::Power => "power",
            Self::Gravity => "gravity",
        }
    }
}

impl EventKind {
    /// The event in words, e.g. `contact_begin`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Grasp => "grasp",
            Self::Release => "release",
            Self::ContactBegin => "contact_begin",
            Self::ContactEnd => "contact_end",
            Self::HandOver => "hand_over",
            Self::ClearanceBelow => "clearance_below",
            Self::ClearanceRestored => "clearance_restored",
            Self::PushBegin => "push_begin",
            Self::PushEnd => "push_end",
        }
    }
}

/// A discrete simulation event on `vas/output/events`.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::SimEvent::v5")]
#[repr(C)]
pub struct SimEvent {
    /// Number of the hand frame during which the event happened.
    pub frame: u64,
    /// The tracker sample that led to the event.
    pub tracker: InputStamp,
    /// The glove sample that led to the event.
    pub glove: InputStamp,
    /// The hand-joints sample that led to the event.
    pub joints: InputStamp,
    /// When the event was published, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// An [`EventKind`] code.
    pub kind: u32,
    /// A [`GraspType`] code for grasp events, 0 otherwise.
    pub grasp_type: u32,
    /// The part the event is about.
    pub part: u32,
    /// The other part of a contact or clearance, or [`HAND_PART_ID`].
    pub other: u32,
    /// The hand the event is about (grasp, release, hand-over, a contact with the hand) or whose
    /// held part touched, a [`HandSide`] code; 0 for clearance events.
    pub hand: u32,
    /// The hand segment of a contact with the hand, a [`HandSegment`] code; 0 otherwise.
    pub segment: u32,
    /// The user whose hand `hand` is, an index into the scene's users
    /// ([`ControlResponse::users`](crate::ControlResponse::users)); 0 for clearance events.
    pub user: u32,
    /// Padding, 0.
    #[serde(skip)]
    pub reserved: u32,
    /// Contacts: where the two touch; clearances: the closest point on `part`. In the world
    /// (metres); zero for other events.
    pub point: [f64; 3],
    /// Contacts: the unit normal at `point`, pointing from `other` towards `part`; zero for other
    /// events.
    pub normal: [f64; 3],
    /// Clearances: the closest point on `other`, in the world (metres); zero for other events.
    pub other_point: [f64; 3],
    /// Clearances: the distance between `part` and `other` (metres); zero for other events.
    pub distance: f64,
}

impl SimEvent {
    /// What the event reports; `None` for a code this build does not know.
    pub fn kind(&self) -> Option<EventKind> {
        EventKind::try_from(self.kind).ok()
    }

    /// The hand the event is about; `None` for a clearance event (its code 0 names no hand) and
    /// for a code this build does not know.
    pub fn side(&self) -> Option<HandSide> {
        match self.kind() {
            Some(EventKind::ClearanceBelow | EventKind::ClearanceRestored) => None,
            _ => HandSide::try_from(self.hand).ok(),
        }
    }

    /// A grasp event's grasp; `None` for a code this build does not know.
    pub fn grasp(&self) -> Option<GraspType> {
        GraspType::try_from(self.grasp_type).ok()
    }
}

/// Force and torque a force-feedback device should render, on `vas/output/force`.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::ForceFrame::v3")]
#[repr(C)]
pub struct ForceFrame {
    /// Number of the hand frame the force belongs to.
    pub frame: u64,
    /// The tracker sample the force answers.
    pub tracker: InputStamp,
    /// The glove sample the force answers.
    pub glove: InputStamp,
    /// The hand-joints sample the force answers.
    pub joints: InputStamp,
    /// When the frame was published, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// Force on the hand root in newtons, world frame.
    pub force: [f64; 3],
    /// Torque about the hand root in newton metres, world frame.
    pub torque: [f64; 3],
    /// The hand whose held part pulls, a [`HandSide`] code.
    pub hand: u32,
    /// The user whose hand `hand` is, an index into the scene's users
    /// ([`ControlResponse::users`](crate::ControlResponse::users)).
    pub user: u32,
}

impl ForceFrame {
    /// The hand whose held part pulls; `None` for a code this build does not know.
    pub fn side(&self) -> Option<HandSide> {
        HandSide::try_from(self.hand).ok()
    }
}
