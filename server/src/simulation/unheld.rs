//! Movable parts no hand holds, moved by the sliding machinery towards a target: pushed by a hand,
//! or settling after a release.
//!
//! Each move is a frame of a [`SlideMachine`] made for it, from the part's visible pose against
//! the other parts at theirs (only those its sweep could reach), with the ghost at the target: the
//! part moves there exactly as a held part slides, never into anything, and stops at what it
//! cannot pass. A fresh machine each frame sees the other parts where they are now (a held part
//! moves between frames); a push frame that runs out of cycles goes on between inputs. Whatever the
//! scene's metaphor (the incremental one would drop what a frame could not achieve), a push or a
//! fall follows its target by the rubber band, a translation, and a turning part by the spiral
//! spring, the metaphor that turns.
//!
//! * **Push.** A hand touching a pushable part in a push gives it a displacement (the hand's
//!   motion into it along the contact normals, [`crate::grasping::push`]); the part slides there.
//!   The clasp stopped the hand at the part's surface; once the part has moved, the hand follows
//!   on its next frame. A part pushed against what it cannot pass stops, and the hand with it.
//!   Friction decides what a pushed part can pass: at a contact where the push presses into the
//!   surface within the friction angle of its normal (the scene's steepest resting slope, the
//!   friction that holds a settling part on a shelf) the part stops, as a block pushed against a
//!   wall does though the palm's push is never quite square to it; along a surface the push
//!   meets more obliquely (a table below a block pushed a little downwards, a rail beside a
//!   slider) it slides.
//! * **Settle** ([`settle`]). A part released with `release = "settle"`, or whose push has ended
//!   there, falls against the scene's up at the scene's speed until it meets a surface no steeper
//!   than the scene's slope (friction holds it; along a steeper one, or a wall, it slides on
//!   down), its lowest point reaches the scene's floor, or it can move no farther. Resting with
//!   its centre of mass not above its supports (on a rim, an edge or a corner), it turns about
//!   them ([`balance`]) until it rests on a support that holds it.

use std::collections::BTreeMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, Vector3};

use super::slide_stage::SlidePart;
use crate::collision::DopTree;
use crate::grasping::{PartId, Push};
use crate::scene::{ReleaseMode, UnheldParams};
use crate::sliding::world::{Obstacle, PairwiseWorld};
use crate::sliding::{
    Contact, Event, RestReason, SlideMachine, SlideParams, SlideState, SlidingMetaphor,
};

mod balance;
mod settle;

use settle::Settling;

/// A displacement shorter than this (metres) moves nothing: the hand rests on the part.
const LEAST_MOVE: f64 = 1e-9;

/// How far (metres) a frame's push must move a part to begin a push: less is the creep of a part
/// pressed against what stops it, no visible motion.
const PUSH_BEGINS: f64 = 1e-5;

/// One part's move under way.
struct Move {
    part: PartId,
    machine: SlideMachine,
    world: PairwiseWorld<DopTree>,
    rest: RestReason,
}

impl Move {
    /// Slides the part towards `target` for one frame, which ends early once the machine has
    /// found a contact that `stops` it (and lifted the part off it); whether one did.
    fn run_until(&mut self, target: &Isometry3<f64>, stops: impl Fn(&Contact) -> bool) -> bool {
        let machine = &mut self.machine;
        machine.set_ghost(target);
        let mut stopped = false;
        loop {
            match machine.step(&mut self.world) {
                Event::Rested(reason) => {
                    self.rest = reason;
                    return stopped;
                }
                Event::Idle => return stopped,
                Event::Classified { .. } => {
                    stopped = machine.contacts().any(|contact| stops(&contact));
                }
                _ => {}
            }
            if stopped && !matches!(machine.state(), SlideState::Lifting { .. }) {
                self.rest = RestReason::Blocked;
                return true;
            }
        }
    }
}

/// A push under way: its move, and the pose the push carries the part to.
struct Pushing {
    moving: Move,
    target: Isometry3<f64>,
    /// The push's rigid motion, from where the part was to the target.
    motion: Isometry3<f64>,
}

impl Pushing {
    /// Another frame towards the target, stopped by a contact where friction holds the part
    /// (`least_cosine`: the cosine of the friction angle).
    fn run(&mut self, least_cosine: f64) {
        let motion = self.motion;
        let holds = |contact: &Contact| friction_holds(contact, &motion, least_cosine);
        self.moving.run_until(&self.target, holds);
    }
}

/// Whether friction holds a part that `motion` moves at `contact`: the contact point's motion
/// presses into the surface within the friction angle of its normal, whose cosine is
/// `least_cosine`.
fn friction_holds(contact: &Contact, motion: &Isometry3<f64>, least_cosine: f64) -> bool {
    let moved = motion * contact.point - contact.point;
    let length = moved.norm();
    length > 0.0 && -contact.normal.dot(&moved) >= least_cosine * length
}

/// The parts no hand holds that pushes and releases move.
pub(super) struct Unheld {
    params: UnheldParams,
    /// The scene's sliding parameters (the metaphor chosen per move).
    sliding: SlideParams,
    /// How far a settling part moves in one frame (metres).
    settle_step: f64,
    /// Released parts on their way to rest.
    settling: BTreeMap<PartId, Settling>,
    /// This frame's pushes: those that ran out of cycles go on between inputs.
    unfinished: Vec<Pushing>,
    /// Per hand, the parts it pushes this frame.
    pushed: Vec<Vec<PartId>>,
}

impl Unheld {
    /// For `hands` hands, with the scene's sliding parameters and sliding frames `period` seconds
    /// apart.
    pub(super) fn new(
        params: UnheldParams,
        sliding: &SlideParams,
        period: f64,
        hands: usize,
    ) -> Unheld {
        Unheld {
            params,
            sliding: sliding.clone(),
            settle_step: params.release.speed * period,
            settling: BTreeMap::new(),
            unfinished: Vec::new(),
            pushed: vec![Vec::new(); hands],
        }
    }

    /// The parts `hand` pushes this frame.
    pub(super) fn pushed_by(&self, hand: usize) -> &[PartId] {
        self.pushed.get(hand).map_or(&[], Vec::as_slice)
    }

    /// Whether a part still moves without new input: one settling, or a push that ran out of
    /// cycles.
    pub(super) fn has_motion_left(&self) -> bool {
        !self.settling.is_empty()
            || (self.unfinished.iter()).any(|p| p.moving.rest == RestReason::CycleLimit)
    }

    /// `part` was released, or its push ended: it settles if it is to.
    pub(super) fn released(&mut self, part: PartId, parts: &[SlidePart]) {
        let Some(slide) = parts.get(part as usize) else {
            return;
        };
        if self.params.release.mode_of(slide.movable, slide.release) == ReleaseMode::Settle {
            self.settling.insert(part, Settling::new(slide.body.mesh()));
        }
    }

    /// `part` is held, or was put back: whatever moved it stops.
    pub(super) fn forget(&mut self, part: PartId) {
        self.settling.remove(&part);
        self.unfinished.retain(|p| p.moving.part != part);
    }

    /// One frame: each hand's `pushes` (in the hands' order) move the pushable parts no hand
    /// holds (`held`), the parts whose push ended start settling, then the settling parts move
    /// on; `poses` take the parts' new visible poses.
    pub(super) fn frame(
        &mut self,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
        held: &[PartId],
        pushes: &[&[Push]],
    ) {
        self.unfinished.clear();
        // A part a hand can push: one it may push that no hand holds.
        let pushable = |part: PartId| {
            !held.contains(&part)
                && (parts.get(part as usize))
                    .is_some_and(|p| self.params.push.pushes(p.movable, p.push))
        };
        // Per hand, the pushable parts it touches in a push.
        let touched: Vec<Vec<PartId>> = (pushes.iter())
            .map(|pushes| {
                (pushes.iter())
                    .map(|push| push.part)
                    .filter(|&part| pushable(part))
            })
            .map(Iterator::collect)
            .collect();
        let mut displacements: Vec<(PartId, Vector3<f64>)> = Vec::new();
        for push in (pushes.iter().copied().flatten()).filter(|push| pushable(push.part)) {
            match (displacements.iter_mut()).find(|(part, _)| *part == push.part) {
                Some((_, sum)) => *sum += push.displacement,
                None => displacements.push((push.part, push.displacement)),
            }
        }
        let mut moved = Vec::new();
        for (part, displacement) in displacements {
            // A push takes over from a fall.
            self.settling.remove(&part);
            if displacement.norm() > LEAST_MOVE && displacement.iter().all(|c| c.is_finite()) {
                let motion = Isometry3::from(Translation3::from(displacement));
                let reach = displacement.norm();
                if let Some(moving) =
                    self.prepare(part, reach, SlidingMetaphor::RubberBand, parts, poses)
                {
                    let from = poses[part as usize];
                    let target = motion * from;
                    let mut push = Pushing {
                        moving,
                        target,
                        motion,
                    };
                    push.run(self.friction_cosine());
                    // The rubber band translates the part only.
                    let to = push.moving.machine.visible_pose();
                    if (to.translation.vector - from.translation.vector).norm() > PUSH_BEGINS {
                        moved.push(part);
                    }
                    poses[part as usize] = to;
                    self.unfinished.push(push);
                }
            }
        }
        // A push begins when the hand's motion moves the part (a touch that moves nothing is
        // no push: the first touch of a grasp in the making, a hand resting on a part) and lasts
        // while that hand touches it.
        let was_pushed = std::mem::take(&mut self.pushed);
        self.pushed = (was_pushed.iter().enumerate())
            .map(|(hand, before)| {
                (touched.get(hand).into_iter().flatten())
                    .filter(|part| before.contains(part) || moved.contains(part))
                    .copied()
                    .collect()
            })
            .collect();
        for part in was_pushed.into_iter().flatten() {
            let still = self.pushed.iter().flatten().any(|&p| p == part);
            if !still && !held.contains(&part) {
                self.released(part, parts);
            }
        }
        self.settle_all(parts, poses, held);
    }

    /// Between inputs: another frame of each push that ran out of cycles, and another step of
    /// the settling parts; the poses that changed go to `poses`.
    pub(super) fn keep_moving(
        &mut self,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
        held: &[PartId],
    ) {
        let least_cosine = self.friction_cosine();
        for push in &mut self.unfinished {
            let part = push.moving.part;
            if push.moving.rest == RestReason::CycleLimit && !self.settling.contains_key(&part) {
                push.run(least_cosine);
                poses[part as usize] = push.moving.machine.visible_pose();
            }
        }
        self.settle_all(parts, poses, held);
    }

    /// The cosine of the scene's friction angle: its steepest resting slope.
    fn friction_cosine(&self) -> f64 {
        self.params.release.max_slope_degrees.to_radians().cos()
    }

    /// A move of `part` from its visible pose, with a machine under `metaphor` and, as its
    /// obstacles, the other parts that a point of it moving up to `reach` metres could touch.
    fn prepare(
        &self,
        part: PartId,
        reach: f64,
        metaphor: SlidingMetaphor,
        parts: &[SlidePart],
        poses: &[Isometry3<f64>],
    ) -> Option<Move> {
        let driven = parts.get(part as usize)?;
        let from = poses[part as usize];
        let (pivot, radius) = driven.body.pivot_and_radius();
        let centre = from * pivot;
        let obstacles = (parts.iter().zip(poses.iter()))
            .enumerate()
            .filter(|&(id, _)| id != part as usize)
            .filter(|(_, (other, pose))| {
                let (other_pivot, other_radius) = other.body.pivot_and_radius();
                (*pose * other_pivot - centre).norm() <= radius + reach + other_radius
            })
            .map(|(_, (other, pose))| {
                let allowance = self.sliding.allowance_between(&driven.name, &other.name);
                Obstacle::new(Arc::clone(&other.body), *pose, allowance)
            })
            .collect();
        let params = SlideParams {
            metaphor,
            ..self.sliding.clone()
        };
        Some(Move {
            part,
            machine: SlideMachine::new(&from, pivot.coords, radius, params),
            world: PairwiseWorld::new(Arc::clone(&driven.body), obstacles),
            rest: RestReason::Grasped,
        })
    }
}

#[cfg(test)]
mod tests;
