//! Offline replay: a recording stepped through the server's in-process replay
//! ([`vas_server::replay`], one frame per sample as in lockstep, without threads or IPC), checked
//! frame by frame for penetrations by parry, an oracle independent of the DOP-trees.
//!
//! parry judges each frame as the server would publish it ([`Replay::published`], verified by
//! the collision loop's verifier), not the interaction's proposal: the promise is that nothing
//! published penetrates, and the verifier is what keeps a proposal that does from being
//! published (a part a hand holds pushed into the other hand, say, is kept where it was).
//!
//! The inputs reach the interaction as the server hands them over (through its own input state,
//! [`Inputs`]): the tracker's cart, and each hand's root and flex values from its joints once it
//! has had a tracked hand-joints sample, else (the first hand) from the tracker and the glove (a
//! flat hand before the first glove sample).

use std::sync::Arc;

use nalgebra::Isometry3;
use parry3d::query::{contact, intersection_test};
use parry3d::shape::{ConvexPolyhedron, TriMesh as ParryTriMesh};
use vas_client::recording::{InputSample, Recording};
use vas_protocol::{EventKind, FLEX_COUNT, GraspType as WireGrasp};
use vas_server::collision::parry_mesh::{ORACLE_SCALE, millimetre_pose, millimetre_trimesh};
use vas_server::grasping::{GraspEvent, HandModel};
use vas_server::replay::{Outcome, Replay, ReplayError};
use vas_server::runtime::inputs::Inputs;
use vas_server::scene::Scene;
use vas_server::simulation::frames::{HandTarget, wire_grasp};
use vas_server::simulation::hand_bodies::HandBodies;
use vas_server::simulation::interaction::InteractionFrame;

/// A penetration deeper than this (millimetres) is reported: parry computes in `f32`, whose
/// rounding at these sizes stays well below it.
const DEPTH_SLACK_MM: f32 = 1e-3;

/// Why a recording cannot be replayed in a scene.
#[derive(Debug, thiserror::Error)]
pub enum OfflineError {
    /// The scene has no hand, or its hand cannot be built.
    #[error(transparent)]
    Replay(#[from] ReplayError),
    /// The recording has no valid sample that places the hand.
    #[error("the recording has no valid tracker or hand-joints sample")]
    Unplaced,
}

/// A grasp, release, hand-over, push begin or push end during the replay.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayEvent {
    /// The frame (input sample index, from 0) it happened in.
    pub frame: usize,
    /// The hand, by its place in the scene's hands.
    pub hand: usize,
    /// Grasp, release, hand-over, push begin or push end.
    pub kind: EventKind,
    /// The part's name.
    pub part: String,
    /// The grasp type, on the wire's scale; [`WireGrasp::None`] for a release.
    pub grasp: WireGrasp,
}

/// What an offline replay gave.
#[derive(Debug, Clone, PartialEq)]
pub struct OfflineRun {
    /// Frames stepped: one per valid input sample.
    pub frames: usize,
    /// Input samples refused as invalid.
    pub rejected: usize,
    /// Grasps, releases, hand-overs and pushes, in order (as the server publishes them).
    pub events: Vec<ReplayEvent>,
    /// Every part's visible pose after the last frame, by id.
    pub final_poses: Vec<Isometry3<f64>>,
    /// Per part id, how many frames some hand segment touched it in.
    pub touched_frames: Vec<usize>,
    /// The farthest the held part's visible pose was from where the hand held it (metres, the
    /// distance between their origins): how far obstacles held it back.
    pub max_held_back: f64,
    /// Every penetration parry found: frame, what entered what, and how deep.
    pub penetrations: Vec<String>,
}

impl OfflineRun {
    /// The final pose of the part named `name`, if the scene has it.
    pub fn final_pose(&self, scene: &Scene, name: &str) -> Option<Isometry3<f64>> {
        let id = scene.parts.iter().position(|p| p.name == name)?;
        self.final_poses.get(id).copied()
    }
}

/// The hand targets the server steps with after each sample: each hand's target in the
/// server's own input state ([`Inputs`], for `scene`'s hands and tracking parameters) after each
/// valid sample of `samples`, from the first one that places a hand (a tracker sample, or a
/// hand-joints sample), and how many were refused.
pub fn hand_targets(
    scene: &Scene,
    samples: impl IntoIterator<Item = InputSample>,
) -> (Vec<Vec<HandTarget>>, usize) {
    let mut state = Inputs::for_hands(scene.hand_models(), scene.params.tracking);
    let mut inputs = Vec::new();
    let mut rejected = 0;
    for sample in samples {
        let valid = match sample {
            InputSample::Tracker(s) => state.apply_tracker(&s).is_ok(),
            InputSample::Glove(s) => state.apply_glove(&s).is_ok(),
            InputSample::HandJoints(s) => state.apply_hand_joints(&s).is_ok(),
        };
        let frame = state.frame();
        let placed = frame.stamps.tracker.seq != 0 || frame.stamps.joints.seq != 0;
        match (valid, placed) {
            (true, true) => inputs.push(frame.hands),
            (true, false) => {}
            (false, _) => rejected += 1,
        }
    }
    (inputs, rejected)
}

/// parry's copies of the parts and of the hands' segments, in millimetres: the independent
/// judge of penetrations, for offline runs and for the live server's frames.
pub struct Oracle {
    parts: Vec<ParryTriMesh>,
    /// Per hand, its model and its segments.
    hands: Vec<(Arc<HandModel>, Vec<ConvexPolyhedron>)>,
}

/// The visible hand of a frame, for the [`Oracle`].
#[derive(Debug, Clone, Copy)]
pub struct VisibleHand {
    /// The root in the world.
    pub root: Isometry3<f64>,
    /// Joint angles, radians.
    pub flex: [f64; FLEX_COUNT],
    /// The part it holds, not checked against it.
    pub held: Option<usize>,
}

impl Oracle {
    /// The judge of `scene` with its hands' segments (`bodies`, as the server builds them, in
    /// the scene's order).
    pub fn new(scene: &Scene, bodies: &[HandBodies]) -> Oracle {
        let parts = scene
            .parts
            .iter()
            .map(|p| millimetre_trimesh(&p.mesh))
            .collect();
        let hands = bodies
            .iter()
            .map(|bodies| {
                let segments = bodies
                    .meshes
                    .iter()
                    .map(|mesh| {
                        let points: Vec<_> = mesh
                            .vertices()
                            .iter()
                            .map(|v| (v * ORACLE_SCALE).cast::<f32>())
                            .collect();
                        ConvexPolyhedron::from_convex_hull(&points)
                            .expect("segment meshes are convex")
                    })
                    .collect();
                (Arc::clone(&bodies.model), segments)
            })
            .collect();
        Oracle { parts, hands }
    }

    /// How deep two shapes that parry finds intersecting overlap (millimetres).
    fn depth(
        a_pose: &Isometry3<f32>,
        a: &dyn parry3d::shape::Shape,
        b_pose: &Isometry3<f32>,
        b: &dyn parry3d::shape::Shape,
    ) -> Option<f32> {
        if !intersection_test(a_pose, a, b_pose, b).expect("parry supports these pairs") {
            return None;
        }
        let depth = contact(a_pose, a, b_pose, b, 0.0)
            .expect("parry supports these pairs")
            .map_or(0.0, |c| -c.dist);
        Some(depth).filter(|&d| d > DEPTH_SLACK_MM)
    }

    /// Every penetration of a frame: parts of interest to each other at their visible poses,
    /// and each visible hand's segments (`hands`, in the scene's order) against every part it
    /// does not hold.
    pub fn penetrations(
        &self,
        scene: &Scene,
        part_poses: &[Isometry3<f64>],
        hands: &[VisibleHand],
        frame: usize,
    ) -> Vec<String> {
        let poses: Vec<Isometry3<f32>> = part_poses.iter().map(millimetre_pose).collect();
        let mut found = Vec::new();
        for a in 0..poses.len() {
            for b in a + 1..poses.len() {
                if !scene.pair_of_interest(a, b) {
                    continue;
                }
                if let Some(depth) =
                    Self::depth(&poses[a], &self.parts[a], &poses[b], &self.parts[b])
                {
                    found.push(format!(
                        "frame {frame}: parts {} and {} overlap by {depth:.4} mm",
                        scene.parts[a].name, scene.parts[b].name
                    ));
                }
            }
        }
        for ((model, segments), hand) in self.hands.iter().zip(hands) {
            for (s, local) in model.segment_poses(&hand.flex).iter().enumerate() {
                let segment_pose = millimetre_pose(&(hand.root * local));
                for (p, part_pose) in poses.iter().enumerate() {
                    if Some(p) == hand.held {
                        continue;
                    }
                    if let Some(depth) =
                        Self::depth(&segment_pose, &segments[s], part_pose, &self.parts[p])
                    {
                        found.push(format!(
                            "frame {frame}: hand segment {} of {} enters part {} by {depth:.4} mm",
                            model.segments()[s].name,
                            model.name(),
                            scene.parts[p].name
                        ));
                    }
                }
            }
        }
        found
    }
}

/// Replays `recording` in `scene` through the server's in-process replay
/// ([`vas_server::replay`]), checking every frame with the [`Oracle`].
pub fn replay(scene: &Scene, recording: &Recording) -> Result<OfflineRun, OfflineError> {
    let mut replay = Replay::new(scene)?;
    let mut oracle = None;
    let mut pushed = Vec::new();
    let mut run = OfflineRun {
        frames: 0,
        rejected: 0,
        events: Vec::new(),
        final_poses: Vec::new(),
        touched_frames: vec![0; scene.parts.len()],
        max_held_back: 0.0,
        penetrations: Vec::new(),
    };
    for recorded in &recording.samples {
        let outcome = match &recorded.input {
            InputSample::Tracker(sample) => replay.tracker(sample)?,
            InputSample::Glove(sample) => replay.glove(sample)?,
            InputSample::HandJoints(sample) => replay.hand_joints(sample)?,
        };
        let Outcome::Stepped(steps) = outcome else {
            continue;
        };
        let frame = replay.frames() - 1;
        let oracle = oracle.get_or_insert_with(|| Oracle::new(scene, replay.hand_bodies()));
        record_frame(scene, &mut run, frame, &steps);
        record_pushes(scene, &mut run, frame, &steps, &mut pushed);
        let Some(published) = replay.published() else {
            continue;
        };
        let poses: Vec<Isometry3<f64>> = published.parts.iter().map(|part| part.pose).collect();
        let hands: Vec<VisibleHand> = (published.hands.iter().zip(&steps))
            .map(|(hand, step)| VisibleHand {
                root: hand.root,
                flex: hand.flex.map(f64::from),
                held: step.held.as_ref().map(|held| held.part as usize),
            })
            .collect();
        run.penetrations
            .extend(oracle.penetrations(scene, &poses, &hands, frame));
    }
    let interaction = replay.interaction().ok_or(OfflineError::Unplaced)?;
    run.frames = replay.frames();
    run.rejected = replay.rejected();
    run.final_poses = interaction.part_poses().collect();
    Ok(run)
}

/// Adds one frame's push begins and ends to `run`, as the server's verifier makes them: the
/// pushes that ended, then those that began, each by part and hand; `pushed` holds the last
/// frame's (part, hand) pairs.
fn record_pushes(
    scene: &Scene,
    run: &mut OfflineRun,
    frame: usize,
    steps: &[InteractionFrame],
    pushed: &mut Vec<(usize, usize)>,
) {
    let mut now: Vec<(usize, usize)> = (steps.iter().enumerate())
        .flat_map(|(hand, step)| step.pushed.iter().map(move |&part| (part as usize, hand)))
        .collect();
    now.sort_unstable();
    now.dedup();
    let event = |kind, &(part, hand): &(usize, usize)| ReplayEvent {
        frame,
        hand,
        kind,
        part: scene.parts[part].name.clone(),
        grasp: WireGrasp::None,
    };
    let ended = pushed.iter().filter(|push| !now.contains(push));
    let ended: Vec<ReplayEvent> = ended.map(|push| event(EventKind::PushEnd, push)).collect();
    let began = now.iter().filter(|push| !pushed.contains(push));
    let began: Vec<ReplayEvent> = began
        .map(|push| event(EventKind::PushBegin, push))
        .collect();
    run.events.extend(ended.into_iter().chain(began));
    *pushed = now;
}

/// Adds one frame's events, touches and held-back distance to `run`.
fn record_frame(scene: &Scene, run: &mut OfflineRun, frame: usize, steps: &[InteractionFrame]) {
    let mut touched: Vec<usize> = Vec::new();
    let mut hand_overs = Vec::new();
    for (hand, step) in steps.iter().enumerate() {
        for event in &step.hand.events {
            let (kind, part, grasp) = match *event {
                GraspEvent::Grasp { part, grasp, .. } => {
                    (EventKind::Grasp, part, wire_grasp(Some(grasp)))
                }
                GraspEvent::Release { part, .. } if step.handed_over.contains(&part) => {
                    (EventKind::HandOver, part, WireGrasp::None)
                }
                GraspEvent::Release { part, .. } => (EventKind::Release, part, WireGrasp::None),
            };
            let event = ReplayEvent {
                frame,
                hand,
                kind,
                part: scene.parts[part as usize].name.clone(),
                grasp,
            };
            // As the server publishes them: a hand-over after the grasp that caused it.
            if kind == EventKind::HandOver {
                hand_overs.push(event);
            } else {
                run.events.push(event);
            }
        }
        touched.extend((step.hand.touching.iter().flatten()).map(|contact| contact.part as usize));
        if let Some(held) = &step.held {
            let back = (held.ghost.translation.vector - held.visible.translation.vector).norm();
            run.max_held_back = run.max_held_back.max(back);
        }
    }
    run.events.append(&mut hand_overs);
    touched.sort_unstable();
    touched.dedup();
    for p in touched {
        run.touched_frames[p] += 1;
    }
}
