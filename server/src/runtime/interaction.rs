//! The hand-over from grasping to sliding: the scene's hands and parts, stepped frame by frame.
//!
//! The work of one input sample is split in two stages, so that the runtime can run them on the
//! grasping and the sliding loop's threads, and so that [`Interaction`] can run them in sequence
//! (offline, in tests and for the recording generator) with the same outcome:
//!
//! * [`GraspStage`] steps each grasping hand against every part at its visible pose.
//! * [`SlideStage`] takes the hands' frames: a grasp event starts a [`SlideMachine`] for the
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

use std::sync::Arc;

use nalgebra::{Isometry3, Vector3};

use super::frames::{ContactAt, HandTarget};
use crate::collision::DopTree;
use crate::grasping::collider::MAX_OBJECTS;
use crate::grasping::{
    GraspEvent, GraspingHand, HandFrame, HandInput, Obstacle as HandObstacle, PartGeometry, PartId,
};
use crate::scene::Part;
use crate::sliding::force::{ForceModel, Wrench};
use crate::sliding::world::{Obstacle as SlideObstacle, PairwiseWorld, SlideBody};
use crate::sliding::{Metaphor, RestReason, SlideMachine, SlideParams};

/// One hand's outcome of a grasping step.
#[derive(Debug, Clone, PartialEq)]
pub struct SteppedHand {
    /// The hand's frame: visible hand, grasp, grasp and release events.
    pub frame: HandFrame,
    /// The parts it let go of because the other hand grasped them (their release events are
    /// in the frame's).
    pub handed_over: Vec<PartId>,
}

/// The grasping half of a frame: the hands among the parts' collision copies.
pub struct GraspStage {
    hands: Vec<GraspingHand>,
    parts: Vec<PartGeometry>,
    poses: Vec<Isometry3<f64>>,
}

impl GraspStage {
    /// The `hands` among `parts` (a part's id is its index), which start at their configured
    /// poses.
    pub fn new(hands: Vec<GraspingHand>, parts: &[Part]) -> GraspStage {
        GraspStage {
            hands,
            parts: parts.iter().map(Part::grasp_geometry).collect(),
            poses: parts.iter().map(|part| part.pose).collect(),
        }
    }

    /// The grasping hands.
    pub fn hands(&self) -> &[GraspingHand] {
        &self.hands
    }

    /// Takes the visible part poses the hands are stepped against from now on (the sliding
    /// stage's, once verified); a list of the wrong length is ignored.
    pub fn set_part_poses(&mut self, poses: &[Isometry3<f64>]) {
        if poses.len() == self.poses.len() {
            self.poses.copy_from_slice(poses);
        }
    }

    /// Steps each hand towards its target (`targets` in the hands' order) against the parts
    /// within its reach, at their visible poses: a hand whose target says to let go (its tracking lost beyond the grace
    /// period) first releases what it holds, and a hand that grasps the part another holds takes
    /// it over.
    pub fn step(&mut self, targets: &[HandTarget]) -> Vec<SteppedHand> {
        let mut stepped: Vec<SteppedHand> = self
            .hands
            .iter_mut()
            .zip(targets)
            .map(|(hand, target)| {
                let released = target.let_go.then(|| hand.let_go()).flatten();
                let obstacles =
                    obstacles_within_reach(hand, &self.parts, &self.poses, &target.input);
                let mut frame = hand.step(&target.input, &obstacles);
                frame.events.splice(0..0, released);
                SteppedHand {
                    frame,
                    handed_over: Vec::new(),
                }
            })
            .collect();
        for taker in 0..stepped.len() {
            let grasped: Vec<PartId> = (stepped[taker].frame.events.iter())
                .filter_map(|event| match *event {
                    GraspEvent::Grasp { part, .. } => Some(part),
                    GraspEvent::Release { .. } => None,
                })
                .collect();
            for part in grasped {
                for giver in (0..self.hands.len()).filter(|&giver| giver != taker) {
                    if self.hands[giver]
                        .held()
                        .is_some_and(|held| held.part == part)
                        && let Some(release) = self.hands[giver].let_go()
                    {
                        let given = &mut stepped[giver];
                        given.frame.events.push(release);
                        given.frame.held = None;
                        given.handed_over.push(part);
                    }
                }
            }
        }
        stepped
    }
}

/// The parts the hand can touch in this step: those whose bounding sphere comes within the
/// hand's reach of the path of its root, from where it is seen to where the input puts it,
/// and the held part. A scene of a thousand parts gives the clasp the few near the hand;
/// should more than [`MAX_OBJECTS`] be near, the nearest are kept (the held part first).
fn obstacles_within_reach<'p>(
    hand: &GraspingHand,
    parts: &'p [PartGeometry],
    poses: &[Isometry3<f64>],
    input: &HandInput,
) -> Vec<HandObstacle<'p>> {
    let from = hand.visible().root.translation.vector;
    let to = (input.cart * input.tracker).translation.vector;
    let reach = hand.model().reach() + REACH_MARGIN;
    let held = hand.held().map(|held| held.part);
    let mut near: Vec<(f64, HandObstacle)> = (parts.iter().zip(poses).enumerate())
        .filter_map(|(id, (geometry, pose))| {
            let (centre, radius) = geometry.bound();
            let distance = distance_to_segment(&(pose * centre).coords, &from, &to);
            let id = id as PartId;
            let key = if held == Some(id) { -1.0 } else { distance };
            (held == Some(id) || distance <= reach + radius).then_some((
                key,
                HandObstacle {
                    part: id,
                    geometry,
                    pose: *pose,
                },
            ))
        })
        .collect();
    if near.len() > MAX_OBJECTS {
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(MAX_OBJECTS);
        near.sort_by_key(|(_, obstacle)| obstacle.part);
    }
    near.into_iter().map(|(_, obstacle)| obstacle).collect()
}

/// Added to the hand's reach when choosing the parts it may touch: covers the clasp's contact
/// probes, which reach a little beyond the segments.
const REACH_MARGIN: f64 = 0.05;

/// The distance from `point` to the segment from `a` to `b` (NaN when a coordinate is not
/// finite).
fn distance_to_segment(point: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let along = b - a;
    let length_squared = along.norm_squared();
    let t = if length_squared > 0.0 {
        ((point - a).dot(&along) / length_squared).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (point - (a + t * along)).norm()
}

/// A part as the sliding stage needs it.
struct SlidePart {
    name: String,
    movable: bool,
    body: Arc<SlideBody<DopTree>>,
}

/// A held part's sliding simulation: its machine and its collision copy against the other parts,
/// as they were when it was grasped.
struct HeldSlide {
    part: PartId,
    machine: SlideMachine,
    world: PairwiseWorld<DopTree>,
    force: ForceModel,
    /// The latest hand frame's root and ghost, to go on sliding towards between input samples.
    root: Isometry3<f64>,
    ghost: Isometry3<f64>,
    /// Why the latest sliding frame ended.
    rest: RestReason,
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
}

impl HeldPart {
    /// True when the sliding frame ran out of cycles before the part came to rest: another
    /// frame towards the same ghost moves it on.
    pub fn has_sliding_left(&self) -> bool {
        self.rest == RestReason::CycleLimit
    }
}

/// The sliding half of a frame: the visible part poses and the held parts' machines.
pub struct SlideStage {
    parts: Vec<SlidePart>,
    poses: Vec<Isometry3<f64>>,
    params: SlideParams,
    /// Seconds between sliding frames, for the force model's damping.
    period: f64,
    /// Per hand, the part it holds.
    held: Vec<Option<HeldSlide>>,
}

impl SlideStage {
    /// The `parts` at their configured poses, for `hands` hands; `params` (validated) drive the
    /// sliding of grasped parts, whose frames are `period` seconds apart.
    pub fn new(parts: &[Part], params: SlideParams, period: f64, hands: usize) -> SlideStage {
        SlideStage {
            parts: parts
                .iter()
                .map(|part| SlidePart {
                    name: part.name.clone(),
                    movable: part.movable,
                    body: Arc::new(SlideBody::with_parts(
                        part.mesh.clone(),
                        Arc::clone(part.adjacency()),
                        part.tree().clone(),
                    )),
                })
                .collect(),
            poses: parts.iter().map(|part| part.pose).collect(),
            params,
            period,
            held: (0..hands).map(|_| None).collect(),
        }
    }

    /// The visible pose of every part, by id.
    pub fn part_poses(&self) -> &[Isometry3<f64>] {
        &self.poses
    }

    /// The sliding machine of the part `hand` holds, if it holds a movable part.
    pub fn slide_machine(&self, hand: usize) -> Option<&SlideMachine> {
        let held = self.held.get(hand)?.as_ref()?;
        Some(&held.machine)
    }

    /// Selects how grasped parts follow the hand, from the next frame on (held parts too).
    pub fn set_metaphor(&mut self, metaphor: Metaphor) {
        self.params.metaphor = metaphor;
        for held in self.held.iter_mut().flatten() {
            held.machine.set_metaphor(metaphor);
        }
    }

    /// Puts `part` back at `pose`, a pose known to be free (the collision loop refused the one
    /// sliding gave it); a held part restarts sliding from there.
    pub fn restore(&mut self, part: PartId, pose: Isometry3<f64>) {
        let Some(slot) = self.poses.get_mut(part as usize) else {
            return;
        };
        *slot = pose;
        for hand in 0..self.held.len() {
            if let Some(held) = self.held[hand].take_if(|held| held.part == part) {
                self.start_sliding(hand, part);
                if let Some(restarted) = &mut self.held[hand] {
                    restarted.root = held.root;
                    restarted.ghost = held.ghost;
                }
            }
        }
    }

    /// Takes the hands' frames (in the hands' order): hands grasped parts over to sliding and
    /// back, and slides each held part one frame towards where its hand holds it.
    pub fn apply(&mut self, frames: &[&HandFrame]) -> Vec<Option<HeldPart>> {
        // Releases first: in a hand-over the part leaves one hand before the other takes it.
        for (hand, frame) in frames.iter().enumerate() {
            for event in &frame.events {
                if let GraspEvent::Release { part, .. } = *event
                    && let Some(slot) = self.held.get_mut(hand)
                {
                    // The part stays at its last visible pose, which the machine found free.
                    slot.take_if(|held| held.part == part);
                }
            }
        }
        for (hand, frame) in frames.iter().enumerate() {
            for event in &frame.events {
                if let GraspEvent::Grasp { part, .. } = *event {
                    self.start_sliding(hand, part);
                }
            }
        }
        frames
            .iter()
            .enumerate()
            .map(|(hand, frame)| {
                let slot = self.held.get_mut(hand)?;
                match (slot.as_mut(), frame.held) {
                    (Some(slide), Some((part, ghost))) if slide.part == part => {
                        slide.root = frame.pose.root;
                        slide.ghost = ghost;
                        slide.machine.set_ghost(&ghost);
                        self.slide_frame(hand)
                    }
                    _ => {
                        *slot = None;
                        None
                    }
                }
            })
            .collect()
    }

    /// One more sliding frame towards the latest ghost for each hand whose last one ran out of
    /// cycles before reaching it; `None` for a hand that holds nothing or whose part came to
    /// rest (reached, blocked or stalled: only a new ghost can move it then).
    pub fn keep_sliding(&mut self) -> Vec<Option<HeldPart>> {
        (0..self.held.len())
            .map(|hand| {
                let slide = self.held[hand].as_ref()?;
                if slide.rest == RestReason::CycleLimit {
                    self.slide_frame(hand)
                } else {
                    None
                }
            })
            .collect()
    }

    fn slide_frame(&mut self, hand: usize) -> Option<HeldPart> {
        let slide = self.held.get_mut(hand)?.as_mut()?;
        let rest = slide.machine.run_frame(&mut slide.world);
        slide.rest = rest;
        let visible = slide.machine.visible_pose();
        self.poses[slide.part as usize] = visible;
        let wrench = slide.force.update(
            slide.machine.visible_pivot_pose(),
            slide.machine.ghost_pivot_pose(),
            self.period,
        );
        let mut touching: Vec<(PartId, ContactAt)> = slide
            .machine
            .contacts()
            .map(|contact| {
                let at = ContactAt {
                    segment: 0,
                    point: contact.point,
                    normal: contact.normal.into_inner(),
                };
                (obstacle_part(slide.part, contact.obstacle), at)
            })
            .collect();
        touching.sort_by_key(|&(part, _)| part);
        touching.dedup_by_key(|&mut (part, _)| part);
        Some(HeldPart {
            part: slide.part,
            ghost: slide.ghost,
            visible,
            rest,
            hand_root: visible * slide.ghost.inverse() * slide.root,
            wrench,
            touching,
        })
    }

    /// Starts sliding `part` for `hand` from its visible pose against every other part; static
    /// parts are never moved.
    fn start_sliding(&mut self, hand: usize, part: PartId) {
        let Some(slot) = self.held.get_mut(hand) else {
            return;
        };
        let Some(grasped) = self.parts.get(part as usize).filter(|p| p.movable) else {
            *slot = None;
            return;
        };
        let pose = self.poses[part as usize];
        let obstacles = self
            .parts
            .iter()
            .zip(&self.poses)
            .enumerate()
            .filter(|&(id, _)| id != part as usize)
            .map(|(_, (other, other_pose))| {
                SlideObstacle::new(
                    other.body.clone(),
                    *other_pose,
                    self.params.allowance_between(&grasped.name, &other.name),
                )
            })
            .collect();
        let (pivot, radius) = grasped.body.pivot_and_radius();
        *slot = Some(HeldSlide {
            part,
            machine: SlideMachine::new(&pose, pivot.coords, radius, self.params.clone()),
            world: PairwiseWorld::new(grasped.body.clone(), obstacles),
            force: ForceModel::new(self.params.force),
            root: Isometry3::identity(),
            ghost: pose,
            rest: RestReason::Grasped,
        });
    }
}

/// The part id of obstacle `index` of the world built for `held`: every part but the held one,
/// in id order.
fn obstacle_part(held: PartId, index: usize) -> PartId {
    let index = index as PartId;
    if index < held { index } else { index + 1 }
}

/// One hand's outcome of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct InteractionFrame {
    /// The hand's frame: visible hand, grasp, grasp and release events. While a held part lags
    /// behind its ghost, the visible root is [`HeldPart::hand_root`].
    pub hand: HandFrame,
    /// The held part, if the hand holds a movable part.
    pub held: Option<HeldPart>,
    /// The parts the hand handed over to the other hand this frame.
    pub handed_over: Vec<PartId>,
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
    /// apart.
    pub fn new(
        hands: Vec<GraspingHand>,
        parts: &[Part],
        slide_params: SlideParams,
        period: f64,
    ) -> Interaction {
        let count = hands.len();
        Interaction {
            grasp: GraspStage::new(hands, parts),
            slide: SlideStage::new(parts, slide_params, period, count),
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
        let frames: Vec<&HandFrame> = stepped.iter().map(|hand| &hand.frame).collect();
        let held = self.slide.apply(&frames);
        stepped
            .into_iter()
            .zip(held)
            .map(
                |(
                    SteppedHand {
                        mut frame,
                        handed_over,
                    },
                    held,
                )| {
                    if let Some(held) = &held {
                        frame.pose.root = held.hand_root;
                    }
                    InteractionFrame {
                        hand: frame,
                        held,
                        handed_over,
                    }
                },
            )
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use nalgebra::{Translation3, Vector3};
    use parry3d::query::intersection_test;
    use parry3d::shape::TriMesh as ParryTriMesh;

    use crate::collision::orientation::DEFAULT_K;
    use crate::collision::parry_mesh::{millimetre_pose, millimetre_trimesh};
    use crate::geometry::{TriMesh, shapes};
    use crate::grasping::model::tests::right_hand;
    use crate::grasping::{FLEX_COUNT, GraspParams, GraspType, HandPose};
    use crate::scene::PartTree;
    use crate::scene::script::{Keyframe, ScriptedGrasp, open_hand, sample};
    use crate::sliding::Metaphor;
    use crate::sliding::motion::pose_distance;

    /// Input samples per second (a tracker and glove at 1 kHz).
    const RATE: f64 = 1000.0;

    /// The handle's id, and the table's in the scenes with one.
    const HANDLE: PartId = 0;
    const TABLE: PartId = 1;

    /// Top of the table, 5.5 mm below the scripted handle's lowest point.
    const TABLE_TOP: f64 = -0.08;

    /// The table's edge towards the hand, beyond the hand's reach in x.
    const TABLE_EDGE: f64 = 0.08;

    fn part(name: &str, mesh: TriMesh, pose: Isometry3<f64>, movable: bool) -> Part {
        Part {
            name: name.into(),
            mesh: Arc::new(mesh),
            mesh_source: format!("shape:{name}"),
            scale: 1.0,
            pose,
            movable,
            group: "default".into(),
            tree: PartTree::new(DEFAULT_K, None),
        }
    }

    /// parry's copy of each part, in millimetres: an oracle independent of the DOP-trees.
    struct Oracle {
        meshes: Vec<ParryTriMesh>,
    }

    impl Oracle {
        fn new(parts: &[Part]) -> Oracle {
            let meshes = parts.iter().map(|p| millimetre_trimesh(&p.mesh)).collect();
            Oracle { meshes }
        }

        /// Whether parts `a` and `b` intersect at the given poses.
        fn intersects(
            &self,
            a: PartId,
            pose_a: &Isometry3<f64>,
            b: PartId,
            pose_b: &Isometry3<f64>,
        ) -> bool {
            intersection_test(
                &millimetre_pose(pose_a),
                &self.meshes[a as usize],
                &millimetre_pose(pose_b),
                &self.meshes[b as usize],
            )
            .expect("parry supports mesh pairs")
        }
    }

    /// A scripted interaction: the parts, the interaction and every frame it gave, with the
    /// handle's visible pose after each.
    struct Run {
        parts: Vec<Part>,
        interaction: Interaction,
        frames: Vec<InteractionFrame>,
        handle_poses: Vec<Isometry3<f64>>,
    }

    impl Run {
        /// The right hand parked at `start` among `parts`, sliding by spiral spring (so that the
        /// carried handle turns with the hand).
        fn new(parts: Vec<Part>, start: Isometry3<f64>) -> Run {
            let hand = GraspingHand::new(
                Arc::new(right_hand()),
                GraspParams::default(),
                HandPose {
                    root: start,
                    flex: [0.0; FLEX_COUNT],
                },
            )
            .expect("the right hand's segment meshes build");
            let params = SlideParams {
                metaphor: Metaphor::SpiralSpring,
                ..SlideParams::default()
            };
            let interaction = Interaction::new(vec![hand], &parts, params, 1.0 / RATE);
            Run {
                parts,
                interaction,
                frames: Vec::new(),
                handle_poses: Vec::new(),
            }
        }

        fn play(&mut self, keys: &[Keyframe]) {
            for key in sample(keys, RATE) {
                let frame = (self.interaction)
                    .step(&[HandTarget::tracking(key.input())])
                    .remove(0);
                self.handle_poses
                    .push(self.interaction.part_pose(HANDLE).expect("the handle"));
                self.frames.push(frame);
            }
        }

        /// The handle's grasp and release events, with their frame numbers.
        fn handle_events(&self) -> impl Iterator<Item = (usize, GraspEvent)> + '_ {
            self.frames.iter().enumerate().flat_map(|(i, frame)| {
                frame
                    .hand
                    .events
                    .iter()
                    .filter_map(move |&event| match event {
                        GraspEvent::Grasp { part, .. } | GraspEvent::Release { part, .. }
                            if part == HANDLE =>
                        {
                            Some((i, event))
                        }
                        _ => None,
                    })
            })
        }

        /// The handle's grasps: frame and grasp type.
        fn grasps(&self) -> Vec<(usize, GraspType)> {
            self.handle_events()
                .filter_map(|(i, event)| match event {
                    GraspEvent::Grasp { grasp, .. } => Some((i, grasp)),
                    GraspEvent::Release { .. } => None,
                })
                .collect()
        }

        /// The handle's releases: frame and the pose the event carries (the ghost's).
        fn releases(&self) -> Vec<(usize, Isometry3<f64>)> {
            self.handle_events()
                .filter_map(|(i, event)| match event {
                    GraspEvent::Release { pose, .. } => Some((i, pose)),
                    GraspEvent::Grasp { .. } => None,
                })
                .collect()
        }
    }

    /// The scripted handle, 24 cm long instead of 12 (the hand closes on the same cross-section),
    /// so that one end reaches past the hand over a table that the hand itself never touches.
    fn handle_and_table() -> Vec<Part> {
        let script = ScriptedGrasp::PowerOnHandle;
        let handle = shapes::cylinder(0.016, 0.24, 2_000);
        let table = shapes::cuboid(Vector3::new(0.2, 0.3, 0.05), 400);
        let table_pose = Isometry3::from(Translation3::new(
            TABLE_EDGE + 0.1,
            0.075,
            TABLE_TOP - 0.025,
        ));
        vec![
            part("handle", handle, script.part_pose(), true),
            part("table", table, table_pose, false),
        ]
    }

    /// The scripted power grasp up to the closed fist, then the hand pressing 3 cm down.
    fn grasp_and_press_down() -> Vec<Keyframe> {
        let mut keys = ScriptedGrasp::PowerOnHandle.keyframes();
        let grasped_by = ScriptedGrasp::PowerOnHandle.milestones().grasped_by;
        keys.retain(|k| k.time <= grasped_by);
        let last = *keys.last().expect("keyframes");
        let mut pressed = last;
        pressed.tracker = Translation3::new(0.0, 0.0, -0.03) * last.tracker;
        for (dt, key) in [(0.3, pressed), (0.35, pressed)] {
            keys.push(Keyframe {
                time: last.time + dt,
                ..key
            });
        }
        keys
    }

    /// The lowest point of the handle at `pose` over the table (which starts at x = 0.08).
    fn lowest(parts: &[Part], pose: &Isometry3<f64>) -> f64 {
        parts[HANDLE as usize]
            .mesh
            .vertices()
            .iter()
            .map(|v| pose * v)
            .filter(|v| v.x >= TABLE_EDGE)
            .map(|v| v.z)
            .fold(f64::INFINITY, f64::min)
    }

    /// Checks every frame of a run among the handle and the table: the visible handle never
    /// intersects the table (by parry) nor goes below its top. Returns how deep the ghost went.
    fn assert_visible_handle_never_enters_the_table(run: &Run) -> f64 {
        let oracle = Oracle::new(&run.parts);
        let table_pose = run.parts[TABLE as usize].pose;
        let mut ghost_depth = 0.0_f64;
        for (i, pose) in run.handle_poses.iter().enumerate() {
            assert!(
                !oracle.intersects(HANDLE, pose, TABLE, &table_pose),
                "frame {i}: the visible handle intersects the table"
            );
            assert!(
                lowest(&run.parts, pose) > TABLE_TOP,
                "frame {i}: the visible handle is below the table top"
            );
            if let Some(held) = &run.frames[i].held {
                ghost_depth = ghost_depth.max(TABLE_TOP - lowest(&run.parts, &held.ghost));
            }
        }
        ghost_depth
    }

    #[test]
    fn the_hand_is_stepped_against_the_parts_within_its_reach_however_many_there_are() {
        let hand = GraspingHand::new(
            Arc::new(right_hand()),
            GraspParams::default(),
            HandPose {
                root: Isometry3::identity(),
                flex: [0.0; FLEX_COUNT],
            },
        )
        .expect("the right hand's segment meshes build");
        let reach = hand.model().reach();
        assert!((0.1..0.5).contains(&reach), "reach {reach} m");
        let cube = || shapes::cuboid(Vector3::repeat(0.01), 12);
        let at = |x: f64| Isometry3::translation(x, 0.0, 0.0);
        // A hundred cubes: every fourth within reach of the hand's path, the rest far off.
        let parts: Vec<Part> = (0..100)
            .map(|i| {
                let x = if i % 4 == 3 {
                    0.001 * i as f64
                } else {
                    10.0 + i as f64
                };
                part(&format!("cube {i}"), cube(), at(x), false)
            })
            .collect();
        let mut stage = GraspStage::new(vec![hand], &parts);
        let moving_to = |x: f64| HandInput {
            cart: Isometry3::identity(),
            tracker: at(x),
            flex: [0.0; FLEX_COUNT],
        };
        let ids = |stage: &GraspStage, input| -> Vec<PartId> {
            (obstacles_within_reach(&stage.hands[0], &stage.parts, &stage.poses, &input).iter())
                .map(|o| o.part)
                .collect()
        };
        let near: Vec<PartId> = (3..100).step_by(4).collect();
        assert_eq!(ids(&stage, moving_to(0.0)), near);
        // Every cube far off: none; every cube in reach, 2 mm apart: the nearest ones.
        stage.set_part_poses(&vec![at(100.0); 100]);
        assert!(ids(&stage, moving_to(0.0)).is_empty());
        let poses: Vec<_> = (0..100).map(|i| at(0.002 * i as f64)).collect();
        stage.set_part_poses(&poses);
        let nearest: Vec<PartId> = (0..MAX_OBJECTS as PartId).collect();
        assert_eq!(ids(&stage, moving_to(0.0)), nearest);
    }

    #[test]
    fn a_grasped_handle_follows_the_hand_where_nothing_is_in_the_way() {
        let script = ScriptedGrasp::PowerOnHandle;
        let milestones = script.milestones();
        let start = script.part_pose();
        let parts = vec![part("handle", script.part_mesh(2_000), start, true)];
        let mut keys = script.keyframes();
        keys.retain(|k| k.time <= milestones.carried);
        let mut run = Run::new(parts, keys[0].tracker);
        run.play(&keys);

        let (grasps, releases) = (run.grasps(), run.releases());
        assert_eq!(grasps.len(), 1, "one grasp: {grasps:?}");
        let (grasped_at, grasp) = grasps[0];
        assert_eq!(grasp, GraspType::Power);
        assert!(grasped_at as f64 <= milestones.grasped_by * RATE);
        assert!(releases.is_empty(), "released while carried: {releases:?}");

        let machine = run
            .interaction
            .slide_machine(0)
            .expect("the handle is held");
        let (_, radius) = SlideBody::<DopTree>::new(run.parts[0].mesh.clone()).pivot_and_radius();
        for (i, frame) in run.frames.iter().enumerate().skip(grasped_at) {
            let held = frame.held.as_ref().expect("held from the grasp on");
            assert_eq!(held.rest, RestReason::Reached, "frame {i}");
            assert_eq!(held.visible, run.handle_poses[i]);
            let lag = pose_distance(&held.visible, &held.ghost, radius);
            assert!(
                lag <= 2.0 * machine.tolerance(),
                "frame {i}: visible {lag:.2e} m from the ghost"
            );
        }
        // It was carried away and turned with the hand.
        let end = run.handle_poses.last().expect("frames");
        assert!((end.translation.vector - start.translation.vector).norm() > 0.08);
        assert!(end.rotation.angle_to(&start.rotation) > 0.3);
    }

    #[test]
    fn a_handle_pressed_into_a_table_slides_on_it_and_never_enters_it() {
        let parts = handle_and_table();
        let keys = grasp_and_press_down();
        let mut run = Run::new(parts, keys[0].tracker);
        run.play(&keys);

        let (grasps, releases) = (run.grasps(), run.releases());
        assert_eq!(grasps.len(), 1, "one grasp: {grasps:?}");
        assert!(releases.is_empty(), "released while pressed: {releases:?}");
        let ghost_depth = assert_visible_handle_never_enters_the_table(&run);
        assert!(
            ghost_depth > 0.015,
            "the ghost went only {ghost_depth} m into the table"
        );
        // The handle rests on the table, not where it was grasped.
        let end = run.handle_poses.last().expect("frames");
        let gap = lowest(&run.parts, end) - TABLE_TOP;
        assert!(gap < 0.001, "the handle stays {gap} m above the table");
        let held = run
            .frames
            .last()
            .and_then(|f| f.held.clone())
            .expect("held");
        assert!(
            run.interaction
                .slide_machine(0)
                .expect("held")
                .contacts()
                .next()
                .is_some()
        );
        assert!(held.visible != held.ghost);
    }

    #[test]
    fn opening_the_hand_leaves_the_handle_at_its_last_valid_pose() {
        let parts = handle_and_table();
        let mut keys = grasp_and_press_down();
        let pressed = *keys.last().expect("keyframes");
        for (dt, flex) in [(0.2, open_hand()), (0.3, open_hand())] {
            keys.push(Keyframe {
                time: pressed.time + dt,
                flex,
                ..pressed
            });
        }
        let mut run = Run::new(parts, keys[0].tracker);
        run.play(&keys);

        let (grasps, releases) = (run.grasps(), run.releases());
        assert_eq!(grasps[0].1, GraspType::Power);
        let (released_at, ghost) = *releases.first().expect("the open hand releases the handle");
        assert!(released_at as f64 > pressed.time * RATE);
        assert!(run.frames[released_at].held.is_none());
        // The handle stays where sliding last left it, above the table, not at the ghost's pose
        // under its top, and the opening fingers, still brushing it, do not take hold of it
        // again.
        let last_valid = run.handle_poses[released_at - 1];
        assert!(lowest(&run.parts, &ghost) < TABLE_TOP - 0.015);
        assert_eq!(grasps.len(), 1, "grasped once: {grasps:?}");
        for (i, pose) in run.handle_poses.iter().enumerate().skip(released_at) {
            assert_eq!(*pose, last_valid, "frame {i}");
        }
        assert_visible_handle_never_enters_the_table(&run);
    }

    /// The scripted hand-over (`scene::hand_over`): the right hand grasps the handle, the left
    /// takes it over in the frame it grasps it, the right opens and withdraws without another
    /// event, and the left pushes the handle into the block's hole and lets go.
    #[test]
    fn the_left_hand_takes_the_handle_over_from_the_right_and_inserts_it() {
        use crate::scene::hand_over::{self, MILESTONES};
        use crate::scene::script::HANDLE_RADIUS;
        use vas_protocol::EventKind;
        const RATE: f64 = 200.0;
        let start = hand_over::handle_pose();
        let parts = vec![
            part("handle", hand_over::handle_mesh(3_000), start, true),
            part(
                "block",
                hand_over::block_mesh(3_000),
                hand_over::block_pose(),
                false,
            ),
        ];
        let [right, left] = hand_over::keyframes().map(|keys| sample(&keys, RATE));
        assert_eq!(right.len(), left.len(), "one time line");
        let right_model = Arc::new(right_hand());
        let left_model = Arc::new(right_model.mirrored());
        let hands = [(right_model, &right[0]), (left_model, &left[0])]
            .map(|(model, first)| {
                let parked = HandPose {
                    root: first.tracker,
                    flex: [0.0; FLEX_COUNT],
                };
                GraspingHand::new(model, GraspParams::default(), parked).expect("segments build")
            })
            .into();
        let mut interaction = Interaction::new(hands, &parts, SlideParams::default(), 1.0 / RATE);
        let mut events = Vec::new();
        for (frame, (right, left)) in right.iter().zip(&left).enumerate() {
            let stepped = interaction.step(&[
                HandTarget::tracking(right.input()),
                HandTarget::tracking(left.input()),
            ]);
            for (hand, stepped) in stepped.iter().enumerate() {
                events.extend(stepped.hand.events.iter().map(|event| {
                    let kind = match *event {
                        GraspEvent::Grasp { .. } => EventKind::Grasp,
                        GraspEvent::Release { part, .. } if stepped.handed_over.contains(&part) => {
                            EventKind::HandOver
                        }
                        GraspEvent::Release { .. } => EventKind::Release,
                    };
                    (frame, hand, kind)
                }));
            }
        }
        // As the server publishes them: a hand-over after the grasp of its frame.
        events.sort_by_key(|&(frame, _, kind)| (frame, kind == EventKind::HandOver));
        let kinds: Vec<(usize, EventKind)> =
            events.iter().map(|&(_, hand, kind)| (hand, kind)).collect();
        assert_eq!(
            kinds,
            [
                (0, EventKind::Grasp),
                (1, EventKind::Grasp),
                (0, EventKind::HandOver),
                (1, EventKind::Release)
            ],
            "{events:?}"
        );
        let at = |index: usize| events[index].0 as f64 / RATE;
        assert!(at(0) <= MILESTONES.right_grasped_by, "{events:?}");
        assert!(at(1) <= MILESTONES.left_grasped_by, "{events:?}");
        assert_eq!(
            events[1].0, events[2].0,
            "the hand-over comes with the grasp"
        );
        assert!(at(3) > MILESTONES.inserted, "{events:?}");
        // Pushed along its axis into the hole, sunk the few millimetres the hands' scripts press.
        let end = interaction.part_pose(HANDLE).expect("the handle");
        let moved = end.translation.vector - start.translation.vector;
        assert!(
            (hand_over::INSERT - 0.002..=hand_over::INSERT + 0.001).contains(&-moved.x)
                && moved.yz().norm() < hand_over::HOLE_RADIUS - HANDLE_RADIUS,
            "the handle moved by {moved:?}"
        );
        assert!(end.rotation.angle_to(&start.rotation) < 0.05);
    }
}
