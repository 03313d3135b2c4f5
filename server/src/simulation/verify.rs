//! The collision loop's verification: no frame leaves the server with a part or a hand segment at
//! a colliding pose.
//!
//! The scene's parts and the hands' segments (16 each) are objects of one
//! [`CollisionPipeline`]; each candidate frame moves those that moved, and the pipeline's stages
//! (moved-object queue, box sweep, interest matrix, separating planes, DOP-trees) find what
//! collides. A moved object in a colliding pair is put back at its last verified pose (a whole
//! hand at once), and the frame is checked again, until nothing moved collides. Pairs that
//! collided before anything moved (a scene that starts with parts touching) are left alone: no
//! move of this frame caused them.
//!
//! A hand and the part it holds are not checked against each other: the grasp is that contact,
//! and the clasp already keeps fingers out of the part. The hands are not checked against each
//! other either (they are the user's own). Contacts between parts and between the hands and parts
//! are turned into begin and end events here, where the frame is final, and so are the pushes:
//! a hand pushes a part from the frame it first touches it in a push to the frame it no longer
//! does (a hand put back keeps its last verified pushes, as its contacts).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use nalgebra::Isometry3;
use vas_protocol::{
    EventKind, HAND_PART_ID, PART_GRASPED, PART_PUSHED, PART_SLIDING, PART_TOUCHING,
};

use super::frames::{
    CandidateFrame, ContactAt, Event, ProposedHand, VerifiedFrame, VerifiedHand, VerifiedPart,
    wire_grasp,
};
use super::hand_bodies::HandBodies;
use crate::collision::DopTree;
use crate::collision::pipeline::{
    CollidingPair, CollisionModel, CollisionPipeline, Detail, KnownApart, ObjectDesc, ObjectId,
    PipelineConfig,
};
use crate::geometry::ConvexHull;
use crate::grasping::{FlexVector, GraspEvent, HandModel, PartId};
use crate::scene::Scene;

/// How often a frame is checked again after putting objects back before every moved object is
/// put back (a put-back object is free where it was, so the second pass settles all but chains
/// of objects pushed into each other).
const MAX_PASSES: usize = 3;

/// A hand's segments in the pipeline.
struct HandObjects {
    model: Arc<HandModel>,
    segments: Vec<ObjectId>,
}

/// A hand's last verified state.
struct CheckedHand {
    /// Its segments; `None` without a hand model, where the hand is where the tracker puts it.
    objects: Option<HandObjects>,
    root: Isometry3<f64>,
    flex: [f32; vas_protocol::FLEX_COUNT],
    touching: u32,
    held: Option<PartId>,
}

impl CheckedHand {
    /// Each segment's verified pose in the world; empty without a hand model.
    fn segment_poses(&self) -> Vec<Isometry3<f64>> {
        let Some(objects) = &self.objects else {
            return Vec::new();
        };
        let flex: FlexVector = self.flex.map(f64::from);
        (objects.model.segment_poses(&flex).iter())
            .map(|local| self.root * local)
            .collect()
    }

    fn owns(&self, object: ObjectId) -> bool {
        (self.objects.as_ref()).is_some_and(|objects| objects.segments.contains(&object))
    }
}

/// Verifies candidate frames against the scene and keeps the last verified state.
pub struct Verifier {
    pipeline: CollisionPipeline<DopTree>,
    parts: Vec<ObjectId>,
    /// In the scene's order; one without segments in a scene without hand models.
    hands: Vec<CheckedHand>,
    verified: Vec<VerifiedPart>,
    /// The contacts of the last frame, by (part, other, hand), each with where it was; the hand
    /// is the one touching (`other` is [`HAND_PART_ID`]) or holding `part`.
    contacts: BTreeMap<(PartId, u32, usize), ContactAt>,
    /// The parts pushed in the last frame, by (part, hand).
    pushed: BTreeSet<(PartId, usize)>,
    /// The pairs colliding after the last pipeline frame.
    colliding: BTreeSet<(ObjectId, ObjectId)>,
    refused_moves: u64,
}

impl Verifier {
    /// The scene's parts at their configured poses and the `hands`' segments (the scene's, in
    /// its order) with flat hands at the identity root.
    pub fn new(scene: &Scene, hands: &[HandBodies]) -> Verifier {
        let mut pipeline = CollisionPipeline::new(PipelineConfig::default());
        // The parts' trees and hulls are the scene's, which the other loops use too (a clone of
        // a tree shares it; a hull is small, its vertices bounded).
        let model =
            |tree: &DopTree, hull: ConvexHull| Arc::new(CollisionModel::new(tree.clone(), hull));
        let parts: Vec<ObjectId> = scene
            .parts
            .iter()
            .enumerate()
            .map(|(id, part)| {
                pipeline
                    .add(ObjectDesc {
                        model: model(part.tree(), part.hull().clone()),
                        pose: part.pose,
                        group: scene.group_id(id),
                        is_static: !part.movable,
                    })
                    .expect("a validated scene's poses are valid and its parts fit")
            })
            .collect();
        // The hands' segments get a group of their own, never tested among themselves
        // (neighbouring segments touch at their joints by design, and the hands are the user's):
        // the one after the scene's, so that the interest matrix stays as small as the scene's
        // groups.
        let hand_group = scene.groups.spare_id();
        let mut interest = scene.interest_matrix(&parts);
        interest.disallow_groups(hand_group, hand_group);
        let checked = |objects| CheckedHand {
            objects,
            root: Isometry3::identity(),
            flex: [0.0; vas_protocol::FLEX_COUNT],
            touching: 0,
            held: None,
        };
        let mut checked_hands: Vec<CheckedHand> = hands
            .iter()
            .map(|bodies| {
                let poses = bodies.model.segment_poses(&[0.0; vas_protocol::FLEX_COUNT]);
                let segments = bodies
                    .meshes
                    .iter()
                    .zip(&bodies.trees)
                    .zip(poses)
                    .map(|((mesh, tree), pose)| {
                        pipeline
                            .add(ObjectDesc {
                                model: model(tree, ConvexHull::of(mesh)),
                                pose,
                                group: hand_group,
                                is_static: false,
                            })
                            .expect("segment poses of a flat hand are valid")
                    })
                    .collect();
                checked(Some(HandObjects {
                    model: Arc::clone(&bodies.model),
                    segments,
                }))
            })
            .collect();
        if checked_hands.is_empty() {
            checked_hands.push(checked(None));
        }
        pipeline.set_interest(interest);
        // Settle the pairs that collide as configured, so that they are not blamed on a move.
        let colliding = pairs(&pipeline.run_frame(Detail::Pairs).colliding);
        if !colliding.is_empty() {
            // Named as `check-scene --prepare` names them; a hand's segments at its flat start
            // pose are counted apart.
            let part_of = |object: ObjectId| parts.iter().position(|&part| part == object);
            let part_pairs: Vec<[usize; 2]> = (colliding.iter())
                .filter_map(|&(a, b)| Some([part_of(a)?, part_of(b)?]))
                .collect();
            tracing::warn!(
                pairs = %scene.pair_names(&part_pairs),
                with_hands = colliding.len() - part_pairs.len(),
                "parts collide as the scene places them; those pairs are not checked until they part"
            );
        }
        Verifier {
            pipeline,
            parts,
            hands: checked_hands,
            verified: scene
                .parts
                .iter()
                .map(|part| VerifiedPart {
                    pose: part.pose,
                    flags: 0,
                })
                .collect(),
            contacts: BTreeMap::new(),
            pushed: BTreeSet::new(),
            colliding,
            refused_moves: 0,
        }
    }

    /// Moves put back because they collided, since the start.
    pub fn refused_moves(&self) -> u64 {
        self.refused_moves
    }

    /// The verified pose of every part, by id.
    pub fn part_poses(&self) -> Vec<Isometry3<f64>> {
        self.verified.iter().map(|part| part.pose).collect()
    }

    /// Checks `candidate` and returns the frame to publish, with the parts whose proposed pose
    /// was refused (and the pose they keep).
    pub fn verify(
        &mut self,
        candidate: CandidateFrame,
    ) -> (VerifiedFrame, Vec<(PartId, Isometry3<f64>)>) {
        let colliding_before = self.colliding.clone();
        self.pipeline.set_known_apart(self.known_apart(&candidate));
        let mut moved_parts: Vec<PartId> = Vec::new();
        for (id, pose) in candidate.part_poses.iter().enumerate() {
            let changed = self
                .verified
                .get(id)
                .is_some_and(|verified| verified.pose != *pose);
            if changed && self.move_object(self.parts[id], pose) {
                moved_parts.push(id as PartId);
            }
        }
        let moved: Vec<bool> = (self.hands.iter())
            .zip(&candidate.hands)
            .map(|(checked, proposed)| {
                proposed.root != checked.root || proposed.flex != checked.flex
            })
            .collect();
        let mut hand_checked: Vec<bool> = (0..self.hands.len())
            .map(|hand| {
                let proposed = &candidate.hands[hand];
                moved[hand] && self.move_hand(hand, &proposed.root, &proposed.flex)
            })
            .collect();
        let held: Vec<Option<PartId>> = (candidate.hands.iter())
            .map(|hand| hand.held.as_ref().map(|held| held.part))
            .collect();
        let mut refused: Vec<(PartId, Isometry3<f64>)> = Vec::new();
        for pass in 0.. {
            let offending = self.offending(&colliding_before, &held);
            if offending.is_empty() {
                break;
            }
            let last_pass = pass + 1 >= MAX_PASSES;
            moved_parts.retain(|&part| {
                let blamed = last_pass || offending.contains(&self.parts[part as usize]);
                if blamed {
                    refused.push((part, self.verified[part as usize].pose));
                }
                !blamed
            });
            for &(part, pose) in &refused {
                self.move_object(self.parts[part as usize], &pose);
            }
            for (hand, checked) in hand_checked.iter_mut().enumerate() {
                let blamed = *checked
                    && (last_pass
                        || offending
                            .iter()
                            .any(|&object| self.hands[hand].owns(object)));
                if blamed {
                    let (root, flex) = (self.hands[hand].root, self.hands[hand].flex);
                    self.move_hand(hand, &root, &flex);
                    *checked = false;
                    self.refused_moves += 1;
                }
            }
            self.refused_moves += refused.len() as u64;
            if last_pass {
                self.colliding = pairs(&self.pipeline.run_frame(Detail::Pairs).colliding);
                break;
            }
        }
        let accepted: Vec<bool> = (0..self.hands.len())
            .map(|hand| hand_checked[hand] || (moved[hand] && self.hands[hand].objects.is_none()))
            .collect();
        self.accept(&candidate, &refused, &accepted);
        let frame = self.frame(candidate, &accepted);
        (frame, refused)
    }

    /// What the sliding worlds proved of the held parts at their proposed poses: the pipeline
    /// skips those pairs while both parts stay there (a part put back is tested as usual).
    fn known_apart(&self, candidate: &CandidateFrame) -> Vec<KnownApart> {
        let object = |part: PartId| self.parts.get(part as usize).copied();
        (candidate.hands.iter())
            .filter_map(|hand| hand.held.as_ref())
            .flat_map(|held| {
                (held.apart.iter()).filter_map(move |&(other, pose)| {
                    Some(KnownApart {
                        a: (object(held.part)?, held.visible),
                        b: (object(other)?, pose),
                    })
                })
            })
            .collect()
    }

    /// Queues a move; false for a pose the pipeline refuses (not finite), which stays unmoved.
    fn move_object(&mut self, object: ObjectId, pose: &Isometry3<f64>) -> bool {
        self.pipeline.queue_move(object, *pose).is_ok()
    }

    /// Queues `hand`'s segments at `root` with `flex`; false without a hand model.
    fn move_hand(
        &mut self,
        hand: usize,
        root: &Isometry3<f64>,
        flex: &[f32; vas_protocol::FLEX_COUNT],
    ) -> bool {
        let Some(objects) = &self.hands[hand].objects else {
            return false;
        };
        let flex: FlexVector = flex.map(f64::from);
        let local = objects.model.segment_poses(&flex);
        let segments = objects.segments.clone();
        segments
            .iter()
            .zip(local)
            .all(|(&segment, local)| self.move_object(segment, &(root * local)))
    }

    /// Runs the pipeline and returns the objects in pairs that collide now but did not before,
    /// except each hand's segments against the part it holds (`held`, by hand).
    fn offending(
        &mut self,
        colliding_before: &BTreeSet<(ObjectId, ObjectId)>,
        held: &[Option<PartId>],
    ) -> BTreeSet<ObjectId> {
        let report = self.pipeline.run_frame(Detail::Pairs);
        self.colliding = pairs(&report.colliding);
        let held: Vec<Option<ObjectId>> = (held.iter())
            .map(|part| part.map(|part| self.parts[part as usize]))
            .collect();
        let grasp_contact = |segment: ObjectId, part: ObjectId| {
            (self.hands.iter().zip(&held))
                .any(|(hand, &held)| held == Some(part) && hand.owns(segment))
        };
        report
            .colliding
            .iter()
            .filter(|pair| !colliding_before.contains(&(pair.a, pair.b)))
            .filter(|&&CollidingPair { a, b, .. }| !grasp_contact(a, b) && !grasp_contact(b, a))
            .flat_map(|pair| [pair.a, pair.b])
            .collect()
    }

    fn accept(
        &mut self,
        candidate: &CandidateFrame,
        refused: &[(PartId, Isometry3<f64>)],
        accepted: &[bool],
    ) {
        for (id, pose) in candidate.part_poses.iter().enumerate() {
            if pose.translation.vector.iter().all(|v| v.is_finite())
                && !refused.iter().any(|&(part, _)| part as usize == id)
                && let Some(verified) = self.verified.get_mut(id)
            {
                verified.pose = *pose;
            }
        }
        for ((checked, proposed), _) in (self.hands.iter_mut())
            .zip(&candidate.hands)
            .zip(accepted)
            .filter(|(_, accepted)| **accepted)
        {
            checked.root = proposed.root;
            checked.flex = proposed.flex;
            checked.touching = (proposed.touching.iter())
                .enumerate()
                .filter(|(_, parts)| !parts.is_empty())
                .fold(0, |bits, (segment, _)| bits | 1 << segment);
        }
    }

    /// The frame to publish: verified poses, part flags, grasp, release, hand-over and contact
    /// events (a hand-over after the other hand's grasp that caused it).
    fn frame(&mut self, candidate: CandidateFrame, accepted: &[bool]) -> VerifiedFrame {
        let mut events = grasp_events(&candidate);
        let contacts = self.contacts_of(&candidate, accepted);
        self.contact_events(&contacts, &mut events);
        let pushed = self.pushed_of(&candidate, accepted);
        self.push_events(&pushed, &mut events);
        self.flag_parts(&candidate, &contacts, &pushed);
        self.contacts = contacts;
        self.pushed = pushed;
        let hands = self.verified_hands(candidate.hands);
        VerifiedFrame {
            stamps: candidate.stamps,
            epoch: candidate.epoch,
            hands,
            parts: self.verified.clone(),
            events,
        }
    }

    /// The frame's contacts, by (part, other, hand): each accepted hand's touches, a refused
    /// hand's last verified ones (it stays where it was), and the held parts' contacts.
    fn contacts_of(
        &self,
        candidate: &CandidateFrame,
        accepted: &[bool],
    ) -> BTreeMap<(PartId, u32, usize), ContactAt> {
        let mut contacts = BTreeMap::new();
        for (hand, proposed) in candidate.hands.iter().enumerate() {
            if accepted[hand] || self.hands[hand].objects.is_none() {
                for (segment, touches) in (0u32..).zip(&proposed.touching) {
                    for touch in touches {
                        let at = ContactAt {
                            segment,
                            point: touch.point,
                            normal: touch.normal.into_inner(),
                        };
                        contacts
                            .entry((touch.part, HAND_PART_ID, hand))
                            .or_insert(at);
                    }
                }
            } else {
                contacts.extend(
                    self.contacts
                        .iter()
                        .filter(|&(&(_, other, of), _)| other == HAND_PART_ID && of == hand),
                );
            }
            if let Some(held) = &proposed.held {
                contacts.extend(
                    (held.touching.iter()).map(|&(other, at)| ((held.part, other, hand), at)),
                );
            }
        }
        contacts
    }

    /// Appends the contacts that ended since the last frame, then those that began.
    fn contact_events(
        &self,
        contacts: &BTreeMap<(PartId, u32, usize), ContactAt>,
        events: &mut Vec<Event>,
    ) {
        for (&(part, other, hand), &at) in &self.contacts {
            if !contacts.contains_key(&(part, other, hand)) {
                events.push(contact_event(EventKind::ContactEnd, hand, part, other, at));
            }
        }
        for (&(part, other, hand), &at) in contacts {
            if !self.contacts.contains_key(&(part, other, hand)) {
                events.push(contact_event(
                    EventKind::ContactBegin,
                    hand,
                    part,
                    other,
                    at,
                ));
            }
        }
    }

    /// The frame's pushes, by (part, hand): each accepted hand's, a refused hand's last verified
    /// ones.
    fn pushed_of(
        &self,
        candidate: &CandidateFrame,
        accepted: &[bool],
    ) -> BTreeSet<(PartId, usize)> {
        let mut pushed = BTreeSet::new();
        for (hand, proposed) in candidate.hands.iter().enumerate() {
            if accepted[hand] || self.hands[hand].objects.is_none() {
                pushed.extend(proposed.pushing.iter().map(|&part| (part, hand)));
            } else {
                pushed.extend(self.pushed.iter().filter(|&&(_, of)| of == hand));
            }
        }
        pushed
    }

    /// Appends the pushes that ended since the last frame, then those that began.
    fn push_events(&self, pushed: &BTreeSet<(PartId, usize)>, events: &mut Vec<Event>) {
        let event = |kind, &(part, hand): &(PartId, usize)| Event {
            kind,
            hand,
            grasp: wire_grasp(None),
            part,
            other: HAND_PART_ID,
            at: None,
        };
        let ended = self.pushed.difference(pushed);
        events.extend(ended.map(|push| event(EventKind::PushEnd, push)));
        let began = pushed.difference(&self.pushed);
        events.extend(began.map(|push| event(EventKind::PushBegin, push)));
    }

    /// Sets every part's grasped, touching, sliding and pushed flags.
    fn flag_parts(
        &mut self,
        candidate: &CandidateFrame,
        contacts: &BTreeMap<(PartId, u32, usize), ContactAt>,
        pushed: &BTreeSet<(PartId, usize)>,
    ) {
        let held: Vec<Option<PartId>> = (candidate.hands.iter())
            .map(|hand| hand.held.as_ref().map(|held| held.part))
            .collect();
        for (id, part) in self.verified.iter_mut().enumerate() {
            let id = id as PartId;
            let touching = contacts
                .keys()
                .any(|&(a, b, _)| a == id || (b == id && b != HAND_PART_ID));
            let sliding = (candidate.hands.iter()).any(|hand| {
                (hand.held.as_ref())
                    .is_some_and(|held| held.part == id && !held.touching.is_empty())
            });
            part.flags = if held.contains(&Some(id)) {
                PART_GRASPED
            } else {
                0
            } | if touching { PART_TOUCHING } else { 0 }
                | if sliding { PART_SLIDING } else { 0 }
                | if pushed.iter().any(|&(part, _)| part == id) {
                    PART_PUSHED
                } else {
                    0
                };
        }
    }

    /// Each hand as verified, with the wrench of the part it holds (zero on the frame that
    /// releases it).
    fn verified_hands(&mut self, proposed: Vec<ProposedHand>) -> Vec<VerifiedHand> {
        (proposed.into_iter())
            .zip(&mut self.hands)
            .map(|(proposed, checked)| {
                let now = proposed.held.as_ref().map(|held| held.part);
                let released = checked.held.is_some() && now.is_none();
                checked.held = now;
                VerifiedHand {
                    root: checked.root,
                    flex: checked.flex,
                    segments: checked.segment_poses(),
                    touching: checked.touching,
                    grasp: proposed.grasp,
                    tracked: proposed.tracked,
                    joints: proposed.joints,
                    force: match (&proposed.held, released) {
                        (Some(held), _) => Some(held.wrench),
                        (None, true) => Some(crate::sliding::Wrench::default()),
                        (None, false) => None,
                    },
                }
            })
            .collect()
    }
}

/// The grasps, releases and hand-overs the hands propose, hand-overs last (after the other
/// hand's grasp that caused them).
fn grasp_events(candidate: &CandidateFrame) -> Vec<Event> {
    let mut events = Vec::new();
    let mut hand_overs = Vec::new();
    for (hand, proposed) in candidate.hands.iter().enumerate() {
        for event in &proposed.events {
            let (kind, grasp, part) = match *event {
                GraspEvent::Grasp { part, grasp, .. } => {
                    (EventKind::Grasp, wire_grasp(Some(grasp)), part)
                }
                GraspEvent::Release { part, .. } if proposed.handed_over.contains(&part) => {
                    (EventKind::HandOver, wire_grasp(None), part)
                }
                GraspEvent::Release { part, .. } => (EventKind::Release, wire_grasp(None), part),
            };
            let event = Event {
                kind,
                hand,
                grasp,
                part,
                other: HAND_PART_ID,
                at: None,
            };
            if kind == EventKind::HandOver {
                hand_overs.push(event);
            } else {
                events.push(event);
            }
        }
    }
    events.append(&mut hand_overs);
    events
}

fn pairs(colliding: &[CollidingPair]) -> BTreeSet<(ObjectId, ObjectId)> {
    colliding.iter().map(|pair| (pair.a, pair.b)).collect()
}

fn contact_event(kind: EventKind, hand: usize, part: PartId, other: u32, at: ContactAt) -> Event {
    Event {
        kind,
        hand,
        grasp: wire_grasp(None),
        part,
        other,
        at: Some(at),
    }
}

#[cfg(test)]
mod tests;
