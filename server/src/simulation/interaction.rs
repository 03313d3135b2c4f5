//! The hand-over from grasping to sliding: the scene's hands and parts, stepped frame by frame.
//!
//! The work of one input sample is split in two stages, so that the runtime can run them on the
//! grasping and the sliding loop's threads, and so that [`Interaction`] can run them in sequence
//! (offline, in tests and for the recording generator) with the same outcome:
//!
//! * `GraspStage` steps each grasping hand against every part at its visible pose.
//! * `SlideStage` takes the hands' frames: a grasp event starts a [`SlideMachine`] for the
//!   grasped part at its current visible pose, with the other parts as static obstacles. While
//!   the part is held its ghost is where the hand holds it (the hand's pose times the grasp's
//!   offset, which may penetrate), and one sliding frame brings the visible part as close to it
//!   as the obstacles allow; the visible pose only ever takes poses the machine found free. A
//!   release drops the machine and leaves the part at its last visible pose (not at the ghost's
//!   pose the release event carries).
//!
//! While a held part lags behind its ghost, the visible hand keeps its grip on the visible part:
//! its root is moved by the same offset that takes the ghost to the visible part, so the hand is
//! never drawn sunk into a part it holds (the grasping hand's own state follows the tracker, as
//! the clasp needs).
//!
//! Two hands: each holds at most one part, and a part is held by one hand at a time. A hand that
//! grasps the part the other holds takes it over: the other hand lets go at once, in the same
//! frame (a hand-over; its fingers stay on the part, which it does not grasp again until they
//! leave it), and the part slides with the new hand from where it is. Each hand's clasp sees the
//! part the other holds as an obstacle at its visible pose; a held part's sliding sees every
//! other part where it was when the grasp began. The hands are the user's own and are not tested
//! against each other.
//!
//! A hand whose tracking is lost keeps what it holds (its target stays where tracking left it)
//! until its target says to let go; then it releases the part where the part is.
//!
//! This is plain state, no threads and no ports: the runtime's loops drive it.

use nalgebra::Isometry3;

use super::frames::{HandTarget, HeldPart};
use super::grasp_stage::{GraspStage, SteppedHand};
use super::slide_stage::SlideStage;
use crate::grasping::{GraspingHand, HandStep, PartId};
use crate::scene::{Part, UnheldParams};
use crate::sliding::{SlideMachine, SlideParams};

/// One hand's outcome of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct InteractionFrame {
    /// The hand's frame: visible hand, grasp, grasp and release events. While a held part lags
    /// behind its ghost, the visible root is [`HeldPart::hand_root`].
    pub hand: HandStep,
    /// The held part, if the hand holds a movable part.
    pub held: Option<HeldPart>,
    /// The parts the hand handed over to the other hand this frame.
    pub handed_over: Vec<PartId>,
    /// The parts the hand pushes this frame.
    pub pushed: Vec<PartId>,
}

/// The scene's grasping hands among its parts, with sliding for the parts they hold: the two
/// stages run in sequence, one frame per input sample, as the server's loops run them in
/// lockstep.
pub struct Interaction {
    grasp: GraspStage,
    slide: SlideStage,
}

impl Interaction {
    /// The `hands` among `parts` (a part's id is its index), which start at their configured
    /// poses; `slide_params` (validated) drive the sliding of grasped parts, `period` seconds
    /// apart, and `unheld` the pushing and settling of parts no hand holds.
    pub fn new(
        hands: Vec<GraspingHand>,
        parts: &[Part],
        slide_params: SlideParams,
        unheld: UnheldParams,
        period: f64,
    ) -> Interaction {
        let count = hands.len();
        Interaction {
            grasp: GraspStage::new(hands, parts),
            slide: SlideStage::new(parts, slide_params, unheld, period, count),
        }
    }

    /// The grasping hands.
    pub fn hands(&self) -> &[GraspingHand] {
        self.grasp.hands()
    }

    /// The visible pose of every part, by id.
    pub fn part_poses(&self) -> impl ExactSizeIterator<Item = Isometry3<f64>> + '_ {
        self.slide.part_poses().iter().copied()
    }

    /// The visible pose of one part, `None` for an unknown id.
    pub fn part_pose(&self, part: PartId) -> Option<Isometry3<f64>> {
        self.slide.part_poses().get(part as usize).copied()
    }

    /// Puts `part` back at `pose`, where the collision loop kept it when it refused the pose
    /// this interaction proposed (a held part restarts sliding from there).
    pub fn restore(&mut self, part: PartId, pose: Isometry3<f64>) {
        self.slide.restore(part, pose);
    }

    /// The sliding machine of the part `hand` holds, if it holds a movable part.
    pub fn slide_machine(&self, hand: usize) -> Option<&SlideMachine> {
        self.slide.slide_machine(hand)
    }

    /// Processes one input sample (`targets`: each hand's, in the hands' order): steps the
    /// hands, hands grasped parts over to sliding and back, and slides each held part one frame
    /// towards where its hand holds it.
    pub fn step(&mut self, targets: &[HandTarget]) -> Vec<InteractionFrame> {
        self.grasp.set_part_poses(self.slide.part_poses());
        let stepped = self.grasp.step(targets);
        let frames: Vec<&HandStep> = stepped.iter().map(|hand| &hand.frame).collect();
        let held = self.slide.apply(&frames);
        stepped
            .into_iter()
            .zip(held)
            .enumerate()
            .map(
                |(
                    hand,
                    (
                        SteppedHand {
                            mut frame,
                            handed_over,
                        },
                        held,
                    ),
                )| {
                    if let Some(held) = &held {
                        frame.pose.root = held.hand_root;
                    }
                    InteractionFrame {
                        hand: frame,
                        held,
                        handed_over,
                        pushed: self.slide.pushed_by(hand).to_vec(),
                    }
                },
            )
            .collect()
    }
}
