//! The sliding half of a frame: a grasped part slides from its visible pose towards where its
//! hand holds it, on a collision copy of the part against the other parts; parts no hand holds
//! are pushed and settle ([`super::unheld`]).

use std::sync::Arc;

use nalgebra::Isometry3;

use super::frames::{ContactAt, HeldPart};
use super::unheld::Unheld;
use crate::collision::DopTree;
use crate::grasping::{GraspEvent, HandStep, PartId};
use crate::scene::{Part, ReleaseMode, UnheldParams};
use crate::sliding::force::ForceModel;
use crate::sliding::world::{Obstacle as SlideObstacle, PairwiseWorld, SlideBody};
use crate::sliding::{RestReason, SlideMachine, SlideParams, SlidingMetaphor};

/// A part as the sliding stage needs it.
pub(super) struct SlidePart {
    pub(super) name: String,
    pub(super) movable: bool,
    /// Its own `push` and `release` keys.
    pub(super) push: Option<bool>,
    pub(super) release: Option<ReleaseMode>,
    pub(super) body: Arc<SlideBody<DopTree>>,
}

impl SlidePart {
    /// `part` as the sliding stage needs it, sharing its mesh, adjacency and tree.
    pub(super) fn of(part: &Part) -> SlidePart {
        SlidePart {
            name: part.name.clone(),
            movable: part.movable,
            push: part.push,
            release: part.release,
            body: Arc::new(SlideBody::with_parts(
                part.mesh.clone(),
                Arc::clone(part.adjacency()),
                part.tree().clone(),
            )),
        }
    }
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

/// The sliding half of a frame: the visible part poses and the held parts' machines.
pub struct SlideStage {
    parts: Vec<SlidePart>,
    poses: Vec<Isometry3<f64>>,
    params: SlideParams,
    /// Seconds between sliding frames, for the force model's damping.
    period: f64,
    /// Per hand, the part it holds.
    held: Vec<Option<HeldSlide>>,
    /// The movable parts no hand holds: pushed, settling.
    unheld: Unheld,
}

impl SlideStage {
    /// The `parts` at their configured poses, for `hands` hands; `params` (validated) drive the
    /// sliding of grasped parts, whose frames are `period` seconds apart, and `unheld` what the
    /// parts no hand holds do.
    pub fn new(
        parts: &[Part],
        params: SlideParams,
        unheld: UnheldParams,
        period: f64,
        hands: usize,
    ) -> SlideStage {
        SlideStage {
            unheld: Unheld::new(unheld, &params, period, hands),
            parts: parts.iter().map(SlidePart::of).collect(),
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

    /// The parts `hand` pushed in the latest frame.
    pub fn pushed_by(&self, hand: usize) -> &[PartId] {
        self.unheld.pushed_by(hand)
    }

    /// Whether a part no hand holds still moves without new input (settling, or a push that ran
    /// out of cycles): the sliding loop goes on then.
    pub fn has_motion_left(&self) -> bool {
        self.unheld.has_motion_left()
    }

    /// The sliding machine of the part `hand` holds, if it holds a movable part.
    pub fn slide_machine(&self, hand: usize) -> Option<&SlideMachine> {
        let held = self.held.get(hand)?.as_ref()?;
        Some(&held.machine)
    }

    /// Selects how grasped parts follow the hand, from the next frame on (held parts too).
    pub fn set_metaphor(&mut self, metaphor: SlidingMetaphor) {
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
        self.unheld.forget(part);
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
    /// back, slides each held part one frame towards where its hand holds it, then moves the
    /// parts the hands push and those settling.
    pub fn apply(&mut self, frames: &[&HandStep]) -> Vec<Option<HeldPart>> {
        // Releases first: in a hand-over the part leaves one hand before the other takes it.
        for (hand, frame) in frames.iter().enumerate() {
            for event in &frame.events {
                if let GraspEvent::Release { part, .. } = *event
                    && let Some(slot) = self.held.get_mut(hand)
                {
                    // The part stays at its last visible pose, which the machine found free,
                    // or settles from there.
                    if slot.take_if(|held| held.part == part).is_some() {
                        self.unheld.released(part, &self.parts);
                    }
                }
            }
        }
        for (hand, frame) in frames.iter().enumerate() {
            for event in &frame.events {
                if let GraspEvent::Grasp { part, .. } = *event {
                    self.unheld.forget(part);
                    self.start_sliding(hand, part);
                }
            }
        }
        let held_parts: Vec<Option<HeldPart>> = frames
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
            .collect();
        let held: Vec<PartId> = (self.held.iter().flatten()).map(|h| h.part).collect();
        let pushes: Vec<&[crate::grasping::Push]> =
            frames.iter().map(|frame| frame.pushes.as_slice()).collect();
        (self.unheld).frame(&self.parts, &mut self.poses, &held, &pushes);
        held_parts
    }

    /// One more sliding frame towards the latest ghost for each hand whose last one ran out of
    /// cycles before reaching it; `None` for a hand that holds nothing or whose part came to
    /// rest (reached, blocked or stalled: only a new ghost can move it then). The parts no hand
    /// holds move on too (pushes that ran out of cycles, settling parts).
    pub fn keep_sliding(&mut self) -> Vec<Option<HeldPart>> {
        let held: Vec<PartId> = (self.held.iter().flatten()).map(|h| h.part).collect();
        (self.unheld).keep_moving(&self.parts, &mut self.poses, &held);
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
        let apart = (slide.world.proved_apart(&visible).into_iter())
            .map(|(index, pose)| (obstacle_part(slide.part, index), pose))
            .collect();
        Some(HeldPart {
            part: slide.part,
            ghost: slide.ghost,
            visible,
            rest,
            hand_root: visible * slide.ghost.inverse() * slide.root,
            wrench,
            touching,
            apart,
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
