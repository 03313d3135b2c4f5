//! What the loops hand each other: one frame's data at each stage, and the control changes that
//! travel between frames.

use nalgebra::{Isometry3, Point3, Vector3};
use vas_protocol::{EventKind, FLEX_COUNT, GraspType, InputStamp};

use crate::grasping::{GraspClass, GraspEvent, HandInput, HandStep, PartId, SegmentContact};
use crate::sliding::{RestReason, Wrench};

/// A frame that can absorb an older one it overtook in a queue between two loops.
pub trait Coalesce {
    /// Merges `older` into `self`: `self`'s state stands, `older`'s events go first.
    fn absorb_older(&mut self, older: Self);
}

/// The input samples a frame answers: the latest tracker, glove and hand-joints sample when it
/// was made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stamps {
    /// The latest accepted tracker sample.
    pub tracker: InputStamp,
    /// The latest accepted glove sample.
    pub glove: InputStamp,
    /// The latest accepted hand-joints sample.
    pub joints: InputStamp,
}

/// One hand's target, for the grasping loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandTarget {
    /// Cart, tracked hand root and flex values.
    pub input: HandInput,
    /// The hand's latest hand-joints sample (zero before one came).
    pub joints: InputStamp,
    /// Whether the input tracks the hand (false: its hand-joints samples say it is not tracked
    /// or have stopped coming, or it has no input yet; `input` holds the last tracked target).
    pub tracked: bool,
    /// The hand has been untracked for longer than the scene's grace period: it lets go of the
    /// part it holds.
    pub let_go: bool,
}

impl HandTarget {
    /// A tracked hand's target, from a tracker and a glove.
    pub fn tracking(input: HandInput) -> HandTarget {
        HandTarget {
            input,
            joints: InputStamp::default(),
            tracked: true,
            let_go: false,
        }
    }
}

/// The I/O thread's hand targets, for the grasping loop.
#[derive(Debug, Clone, PartialEq)]
pub struct InputFrame {
    /// The samples it comes from.
    pub stamps: Stamps,
    /// Per hand of the scene, in the scene's order; in a scene without a hand model, one: where
    /// the tracker puts the hand.
    pub hands: Vec<HandTarget>,
}

impl Coalesce for InputFrame {
    /// A target holds no events: the newer one simply replaces the older.
    fn absorb_older(&mut self, _older: Self) {}
}

/// One hand in the grasping loop's frame.
#[derive(Debug, Clone)]
pub struct GraspedHand {
    /// The target it was stepped towards.
    pub target: HandTarget,
    /// The grasping hand's frame; `None` in a scene without a hand model, where the hand is
    /// published where the tracker puts it.
    pub frame: Option<HandStep>,
    /// The parts this hand let go of because the other hand grasped them; their release events
    /// are in the frame's.
    pub handed_over: Vec<PartId>,
}

/// The grasping loop's frame, for the sliding loop.
#[derive(Debug, Clone)]
pub struct GraspedFrame {
    /// The samples it answers.
    pub stamps: Stamps,
    /// Every hand, in the scene's order.
    pub hands: Vec<GraspedHand>,
}

impl Coalesce for GraspedFrame {
    fn absorb_older(&mut self, older: Self) {
        for (hand, older) in self.hands.iter_mut().zip(older.hands) {
            if let (Some(frame), Some(older_frame)) = (&mut hand.frame, older.frame) {
                frame.events = prepended(older_frame.events, &mut frame.events);
            }
            hand.handed_over = prepended(older.handed_over, &mut hand.handed_over);
        }
    }
}

/// `older` followed by `newer` (emptied).
fn prepended<T>(mut older: Vec<T>, newer: &mut Vec<T>) -> Vec<T> {
    older.append(newer);
    older
}

/// A hand as a frame proposes it.
#[derive(Debug, Clone, PartialEq)]
pub struct ProposedHand {
    /// The root in the world.
    pub root: Isometry3<f64>,
    /// Joint angles, radians.
    pub flex: [f32; FLEX_COUNT],
    /// Per hand segment (in [`vas_protocol::HandSegment`] order), the parts it touches.
    pub touching: Vec<Vec<SegmentContact>>,
    /// The grasp the hand has or would have.
    pub grasp: GraspType,
    /// Whether the input tracks the hand.
    pub tracked: bool,
    /// The hand's latest hand-joints sample.
    pub joints: InputStamp,
    /// The part it holds, if any.
    pub held: Option<HeldPart>,
    /// The parts it pushes (touches without holding, moving them by its motion into them).
    pub pushing: Vec<PartId>,
    /// Its grasps and releases since the previous frame.
    pub events: Vec<GraspEvent>,
    /// The parts it handed over to the other hand since the previous frame.
    pub handed_over: Vec<PartId>,
}

/// The sliding loop's frame, for the collision loop to verify.
#[derive(Debug, Clone)]
pub struct CandidateFrame {
    /// The samples it answers.
    pub stamps: Stamps,
    /// The configuration a [`Change::Restart`](super::restart::Change::Restart) started, so that frames of an older one are known.
    pub epoch: u64,
    /// Every hand, in the scene's order.
    pub hands: Vec<ProposedHand>,
    /// Every part's proposed pose, by id.
    pub part_poses: Vec<Isometry3<f64>>,
}

impl Coalesce for CandidateFrame {
    fn absorb_older(&mut self, older: Self) {
        for (hand, older) in self.hands.iter_mut().zip(older.hands) {
            hand.events = prepended(older.events, &mut hand.events);
            hand.handed_over = prepended(older.handed_over, &mut hand.handed_over);
        }
    }
}

/// A held part after a frame: where the hand holds it and where it is seen.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldPart {
    /// The part.
    pub part: PartId,
    /// The ghost: the pose the hand holds the part at (may penetrate other parts).
    pub ghost: Isometry3<f64>,
    /// The visible pose: always free.
    pub visible: Isometry3<f64>,
    /// Why the sliding frame ended.
    pub rest: RestReason,
    /// The visible hand root: the tracked root moved by the offset from ghost to visible part.
    pub hand_root: Isometry3<f64>,
    /// The force and torque pulling the hand towards the visible part.
    pub wrench: Wrench,
    /// The obstacles the part touches, by part id, sorted, each with one of its contacts.
    pub touching: Vec<(PartId, ContactAt)>,
    /// The parts the sliding world proved apart from this one at its visible pose, each at the
    /// pose it was tested at: the collision loop need not test them again there.
    pub apart: Vec<(PartId, Isometry3<f64>)>,
}

impl HeldPart {
    /// True when the sliding frame ran out of cycles before the part came to rest: another
    /// frame towards the same ghost moves it on.
    pub fn has_sliding_left(&self) -> bool {
        self.rest == RestReason::CycleLimit
    }
}

/// Where two things touch, in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactAt {
    /// The hand segment, for a contact with the hand; 0 otherwise.
    pub segment: u32,
    /// A point of the contact.
    pub point: Point3<f64>,
    /// The unit normal there, from the other towards the part.
    pub normal: Vector3<f64>,
}

/// A discrete event of a verified frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// What happened.
    pub kind: EventKind,
    /// The hand it is about (or whose held part touched), by its place in the scene's hands.
    pub hand: usize,
    /// The grasp, for grasp events.
    pub grasp: GraspType,
    /// The part.
    pub part: PartId,
    /// The other part of a contact, or [`vas_protocol::HAND_PART_ID`].
    pub other: u32,
    /// Where, for contact events.
    pub at: Option<ContactAt>,
}

/// One part in a verified frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifiedPart {
    /// Its pose: free.
    pub pose: Isometry3<f64>,
    /// [`vas_protocol::PART_GRASPED`], `PART_TOUCHING`, `PART_SLIDING`, `PART_PUSHED` bits.
    pub flags: u32,
}

/// One hand of a verified frame.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifiedHand {
    /// The root in the world.
    pub root: Isometry3<f64>,
    /// Joint angles, radians.
    pub flex: [f32; FLEX_COUNT],
    /// Each segment's pose in the world, as verified; empty without a hand model.
    pub segments: Vec<Isometry3<f64>>,
    /// Bits of the segments touching a part.
    pub touching: u32,
    /// The grasp.
    pub grasp: GraspType,
    /// Whether the input tracks the hand.
    pub tracked: bool,
    /// The hand's latest hand-joints sample.
    pub joints: InputStamp,
    /// The wrench for a force-feedback device while the hand holds a part; zero on the frame
    /// that releases it, `None` otherwise.
    pub force: Option<Wrench>,
}

/// A frame the collision loop verified, for the I/O thread to publish.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifiedFrame {
    /// The samples it answers.
    pub stamps: Stamps,
    /// The restart it belongs to.
    pub epoch: u64,
    /// Every hand, in the scene's order.
    pub hands: Vec<VerifiedHand>,
    /// Every part, by id.
    pub parts: Vec<VerifiedPart>,
    /// Grasps, releases, hand-overs, contact and push begins and ends of this frame.
    pub events: Vec<Event>,
}

/// The wire code of an analysed grasp.
pub fn wire_grasp(grasp: Option<GraspClass>) -> GraspType {
    use crate::grasping::PrecisionKind;
    match grasp {
        None => GraspType::None,
        Some(GraspClass::Push) => GraspType::Push,
        Some(GraspClass::Precision(PrecisionKind::TipPinch)) => GraspType::TipPinch,
        Some(GraspClass::Precision(PrecisionKind::ThreeJawChuck)) => GraspType::ThreeJawChuck,
        Some(GraspClass::Precision(PrecisionKind::Key)) => GraspType::Key,
        Some(GraspClass::Precision(PrecisionKind::Other)) => GraspType::Precision,
        Some(GraspClass::ThreePointPinch) => GraspType::ThreePointPinch,
        Some(GraspClass::Cigarette) => GraspType::Cigarette,
        Some(GraspClass::Power) => GraspType::Power,
        Some(GraspClass::Gravity) => GraspType::Gravity,
    }
}
