//! In-process replay: input samples stepped through the simulation one frame per sample, as a
//! lockstep server steps them, without threads or IPC.
//!
//! The samples go through the server's own input state ([`Inputs`], on sample time): every
//! valid sample updates the latest tracker, glove or hand-joints target, and from the first one
//! that places a hand (a tracker or a hand-joints sample) the [`Interaction`] steps once after
//! each valid sample with each hand's latest target. Each hand starts parked at its first
//! target with a flat hand; invalid samples are counted and skipped.
//!
//! Each frame is then verified as the collision loop verifies it ([`Verifier`]): the frame a
//! server would publish is [`Replay::published`], and a part whose proposed pose was refused is
//! put back where the verifier kept it, as the collision loop's refusals put it back in the
//! sliding loop.
//!
//! The caller reads the recording and feeds it sample by sample ([`Replay::tracker`],
//! [`Replay::glove`], [`Replay::hand_joints`]): the library names no recording format, which is
//! the client's. Testkit's offline replay and `vas-server report` both drive this one.

use std::sync::Arc;

use vas_protocol::{FLEX_COUNT, GloveSample, HandJointsSample, TrackerSample};

use crate::grasping::{GraspingHand, HandPose};
use crate::runtime::inputs::Inputs;
use crate::scene::Scene;
use crate::simulation::frames::{
    CandidateFrame, HandTarget, ProposedHand, VerifiedFrame, wire_grasp,
};
use crate::simulation::hand_bodies::HandBodies;
use crate::simulation::interaction::{Interaction, InteractionFrame};
use crate::simulation::verify::Verifier;

/// Why a recording cannot be replayed in a scene.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The scene names no hand model.
    #[error("scene {0:?} names no hand")]
    NoHand(String),
    /// The hand model cannot be loaded or its collision geometry built.
    #[error("hand model: {0}")]
    Hand(String),
}

/// What one sample did.
#[derive(Debug)]
pub enum Outcome {
    /// The sample was invalid and skipped (counted in [`Replay::rejected`]).
    Rejected,
    /// Valid, but no sample has placed a hand yet: no frame.
    Unplaced,
    /// The frame it caused: each hand's outcome, in the scene's order.
    Stepped(Vec<InteractionFrame>),
}

/// The hands and parts once a sample placed a hand.
struct Placed {
    interaction: Interaction,
    bodies: Vec<HandBodies>,
    verifier: Verifier,
    /// The last frame as verified.
    published: Option<VerifiedFrame>,
}

/// A scene replayed sample by sample.
pub struct Replay<'s> {
    scene: &'s Scene,
    inputs: Inputs,
    placed: Option<Placed>,
    frames: usize,
    rejected: usize,
}

impl<'s> Replay<'s> {
    /// A replay in `scene`, which must name a hand.
    pub fn new(scene: &'s Scene) -> Result<Replay<'s>, ReplayError> {
        if scene.hands.is_empty() {
            return Err(ReplayError::NoHand(scene.name.clone()));
        }
        Ok(Replay {
            scene,
            inputs: Inputs::for_hands(scene.hand_models(), scene.params.tracking),
            placed: None,
            frames: 0,
            rejected: 0,
        })
    }

    /// Takes a tracker sample.
    pub fn tracker(&mut self, sample: &TrackerSample) -> Result<Outcome, ReplayError> {
        let valid = self.inputs.apply_tracker(sample).is_ok();
        self.step(valid)
    }

    /// Takes a glove sample.
    pub fn glove(&mut self, sample: &GloveSample) -> Result<Outcome, ReplayError> {
        let valid = self.inputs.apply_glove(sample).is_ok();
        self.step(valid)
    }

    /// Takes a hand-joints sample.
    pub fn hand_joints(&mut self, sample: &HandJointsSample) -> Result<Outcome, ReplayError> {
        let valid = self.inputs.apply_hand_joints(sample).is_ok();
        self.step(valid)
    }

    /// Frames stepped so far: one per valid sample from the first that placed a hand.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Samples refused as invalid so far.
    pub fn rejected(&self) -> usize {
        self.rejected
    }

    /// The interaction, once a sample placed a hand.
    pub fn interaction(&self) -> Option<&Interaction> {
        self.placed.as_ref().map(|placed| &placed.interaction)
    }

    /// The last frame as the collision loop verified it: what a server would publish.
    pub fn published(&self) -> Option<&VerifiedFrame> {
        self.placed.as_ref()?.published.as_ref()
    }

    /// The hands' kinematics and segment meshes, in the scene's order (empty before a sample
    /// placed a hand).
    pub fn hand_bodies(&self) -> &[HandBodies] {
        self.placed.as_ref().map_or(&[], |placed| &placed.bodies)
    }

    fn step(&mut self, valid: bool) -> Result<Outcome, ReplayError> {
        if !valid {
            self.rejected += 1;
            return Ok(Outcome::Rejected);
        }
        let frame = self.inputs.frame();
        if frame.stamps.tracker.seq == 0 && frame.stamps.joints.seq == 0 {
            return Ok(Outcome::Unplaced);
        }
        let placed = match &mut self.placed {
            Some(placed) => placed,
            None => self.placed.insert(place(self.scene, &frame.hands)?),
        };
        self.frames += 1;
        let steps = placed.interaction.step(&frame.hands);
        let candidate = CandidateFrame {
            stamps: frame.stamps,
            epoch: 0,
            hands: (steps.iter().zip(&frame.hands))
                .map(|(step, target)| proposed(step, target))
                .collect(),
            part_poses: placed.interaction.part_poses().collect(),
        };
        let (published, refused) = placed.verifier.verify(candidate);
        for (part, pose) in refused {
            placed.interaction.restore(part, pose);
        }
        placed.published = Some(published);
        Ok(Outcome::Stepped(steps))
    }
}

/// A hand's interaction frame as the sliding loop proposes it to the collision loop (the
/// visible root already the held part's hand root).
fn proposed(step: &InteractionFrame, target: &HandTarget) -> ProposedHand {
    ProposedHand {
        root: step.hand.pose.root,
        flex: step.hand.pose.flex.map(|v| v as f32),
        touching: step.hand.touching.to_vec(),
        grasp: wire_grasp(step.hand.grasp),
        tracked: target.tracked,
        joints: target.joints,
        held: step.held.clone(),
        pushing: step.pushed.clone(),
        events: step.hand.events.clone(),
        handed_over: step.handed_over.clone(),
    }
}

/// The scene's hands parked flat at their first targets (`first`, in the scene's order) among
/// its parts.
fn place(scene: &Scene, first: &[HandTarget]) -> Result<Placed, ReplayError> {
    let params = scene.params.grasp();
    let hands = (scene.hands.iter())
        .zip(first)
        .map(|(scene_hand, first)| {
            GraspingHand::new(
                Arc::clone(&scene_hand.model),
                params,
                HandPose {
                    root: first.input.cart * first.input.tracker,
                    flex: [0.0; FLEX_COUNT],
                },
            )
            .map_err(|error| ReplayError::Hand(error.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let bodies = (scene.hands.iter())
        .zip(&hands)
        .map(|(scene_hand, hand)| HandBodies::of(Arc::clone(&scene_hand.model), hand))
        .collect::<Vec<_>>();
    let verifier = Verifier::new(scene, &bodies);
    let interaction = Interaction::new(
        hands,
        &scene.parts,
        scene.params.sliding.clone(),
        scene.params.unheld(),
        1.0 / scene.rates.sliding_hz,
    );
    Ok(Placed {
        interaction,
        bodies,
        verifier,
        published: None,
    })
}
