//! Movable parts no hand holds, moved by the sliding machinery towards a target: pushed by a hand,
//! or settling after a release.
//!
//! Each move is a frame of a [`SlideMachine`] made for it, from the part's visible pose against
//! the other parts at theirs (only those its sweep could reach), with the ghost at the target: the
//! part moves there exactly as a held part slides, never into anything, and stops at what it
//! cannot pass. A fresh machine each frame sees the other parts where they are now (a held part
//! moves between frames); a frame that runs out of cycles goes on between inputs. Driven parts
//! follow their target by the rubber band whatever the scene's metaphor: a push or a fall is a
//! translation, and the incremental metaphor would drop what a frame could not achieve.
//!
//! * **Push.** A hand touching a pushable part in a push gives it a displacement (the hand's
//!   motion into it along the contact normals, [`crate::grasping::push`]); the part slides there.
//!   The clasp stopped the hand at the part's surface; once the part has moved, the hand follows
//!   on its next frame. A part pushed against what it cannot pass stops, and the hand with it.
//! * **Settle.** A part released with `release = "settle"` moves down (against the scene's up),
//!   by the scene's speed each frame, until it rests on a surface no steeper than the scene's
//!   slope (friction holds it; along a steeper one, or a wall, it slides on down), its lowest
//!   point reaches the scene's floor, or it can move no farther.

use std::collections::BTreeSet;
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, Vector3};

use super::slide_stage::SlidePart;
use crate::collision::DopTree;
use crate::grasping::{PartId, Push};
use crate::scene::{ReleaseMode, UnheldParams};
use crate::sliding::world::{Obstacle, PairwiseWorld};
use crate::sliding::{RestReason, SlideMachine, SlideParams, SlidingMetaphor};

/// A displacement shorter than this (metres) moves nothing: the hand rests on the part.
const LEAST_MOVE: f64 = 1e-9;

/// One part's move under way.
struct Move {
    part: PartId,
    machine: SlideMachine,
    world: PairwiseWorld<DopTree>,
    rest: RestReason,
}

/// The parts no hand holds that pushes and releases move.
pub(super) struct Unheld {
    params: UnheldParams,
    /// The scene's sliding parameters with the rubber band.
    sliding: SlideParams,
    /// How far a settling part moves in one frame (metres).
    settle_step: f64,
    /// Released parts on their way down.
    settling: BTreeSet<PartId>,
    /// Moves whose latest frame ran out of cycles.
    unfinished: Vec<Move>,
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
            sliding: SlideParams {
                metaphor: SlidingMetaphor::RubberBand,
                ..sliding.clone()
            },
            settle_step: params.release.speed * period,
            settling: BTreeSet::new(),
            unfinished: Vec::new(),
            pushed: vec![Vec::new(); hands],
        }
    }

    /// The parts `hand` pushes this frame.
    pub(super) fn pushed_by(&self, hand: usize) -> &[PartId] {
        self.pushed.get(hand).map_or(&[], Vec::as_slice)
    }

    /// Whether a part still moves without new input: one settling, or a move that ran out of
    /// cycles.
    pub(super) fn has_motion_left(&self) -> bool {
        !self.settling.is_empty()
            || (self.unfinished.iter()).any(|m| m.rest == RestReason::CycleLimit)
    }

    /// `part` was released: it settles if it is to.
    pub(super) fn released(&mut self, part: PartId, parts: &[SlidePart]) {
        let Some(slide) = parts.get(part as usize) else {
            return;
        };
        if self.params.release.mode_of(slide.movable, slide.release) == ReleaseMode::Settle {
            self.settling.insert(part);
        }
    }

    /// `part` is held, or was put back: whatever moved it stops.
    pub(super) fn forget(&mut self, part: PartId) {
        self.settling.remove(&part);
        self.unfinished.retain(|m| m.part != part);
    }

    /// One frame: each hand's `pushes` (in the hands' order) move the pushable parts no hand
    /// holds (`held`), then the settling parts go on down; `poses` take the parts' new visible
    /// poses.
    pub(super) fn frame(
        &mut self,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
        held: &[PartId],
        pushes: &[&[Push]],
    ) {
        self.unfinished.clear();
        let mut displacements: Vec<(PartId, Vector3<f64>)> = Vec::new();
        for (hand, pushes) in pushes.iter().enumerate() {
            let pushed = (pushes.iter())
                .filter(|push| !held.contains(&push.part))
                .filter(|push| {
                    (parts.get(push.part as usize))
                        .is_some_and(|p| self.params.push.pushes(p.movable, p.push))
                })
                .inspect(|push| {
                    match (displacements.iter_mut()).find(|(part, _)| *part == push.part) {
                        Some((_, sum)) => *sum += push.displacement,
                        None => displacements.push((push.part, push.displacement)),
                    }
                })
                .map(|push| push.part)
                .collect();
            if let Some(slot) = self.pushed.get_mut(hand) {
                *slot = pushed;
            }
        }
        for (part, displacement) in displacements {
            // A push takes over from a fall.
            self.settling.remove(&part);
            if displacement.norm() > LEAST_MOVE && displacement.iter().all(|c| c.is_finite()) {
                let target = Translation3::from(displacement) * poses[part as usize];
                self.drive(part, target, parts, poses);
            }
        }
        self.settle_all(parts, poses, held);
    }

    /// Between inputs: another frame of each push that ran out of cycles, and another step down
    /// for the settling parts; the poses that changed go to `poses`.
    pub(super) fn keep_moving(
        &mut self,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
        held: &[PartId],
    ) {
        for slide in &mut self.unfinished {
            if slide.rest == RestReason::CycleLimit && !self.settling.contains(&slide.part) {
                slide.rest = slide.machine.run_frame(&mut slide.world);
                poses[slide.part as usize] = slide.machine.visible_pose();
            }
        }
        self.settle_all(parts, poses, held);
    }

    /// Moves every settling part no hand holds one step down, and forgets those come to rest.
    fn settle_all(&mut self, parts: &[SlidePart], poses: &mut [Isometry3<f64>], held: &[PartId]) {
        for part in std::mem::take(&mut self.settling) {
            if !held.contains(&part) && self.settle(part, parts, poses) {
                self.settling.insert(part);
            }
        }
    }

    /// Moves settling `part` one step down; false once it has come to rest.
    fn settle(&mut self, part: PartId, parts: &[SlidePart], poses: &mut [Isometry3<f64>]) -> bool {
        let release = self.params.release;
        let up = release.up_direction();
        let pose = poses[part as usize];
        let lowest = (parts[part as usize].body.mesh().vertices().iter())
            .map(|v| (pose * v).coords.dot(&up))
            .fold(f64::INFINITY, f64::min);
        let above_floor = lowest - release.floor;
        if above_floor.is_nan() || above_floor <= LEAST_MOVE {
            return false;
        }
        let step = self.settle_step.min(above_floor);
        let target = Translation3::from(-step * up.into_inner()) * pose;
        let Some(moved) = self.drive(part, target, parts, poses) else {
            return false;
        };
        let supported = moved
            .contacts()
            .any(|contact| contact.normal.dot(&up) >= release.max_slope_degrees.to_radians().cos());
        let progress = (poses[part as usize].translation.vector - pose.translation.vector).norm();
        !supported && progress > LEAST_MOVE
    }

    /// Slides `part` from its visible pose towards `target` for one frame; its new pose goes to
    /// `poses`. The machine, which keeps the part's contacts, stays for another frame if this one
    /// ran out of cycles.
    fn drive(
        &mut self,
        part: PartId,
        target: Isometry3<f64>,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
    ) -> Option<&SlideMachine> {
        let driven = parts.get(part as usize)?;
        let from = poses[part as usize];
        let (pivot, radius) = driven.body.pivot_and_radius();
        let centre = from * pivot;
        let reach = radius + (target.translation.vector - from.translation.vector).norm();
        let obstacles = (parts.iter().zip(poses.iter()))
            .enumerate()
            .filter(|&(id, _)| id != part as usize)
            .filter(|(_, (other, pose))| {
                let (other_pivot, other_radius) = other.body.pivot_and_radius();
                (*pose * other_pivot - centre).norm() <= reach + other_radius
            })
            .map(|(_, (other, pose))| {
                let allowance = self.sliding.allowance_between(&driven.name, &other.name);
                Obstacle::new(Arc::clone(&other.body), *pose, allowance)
            })
            .collect();
        let mut machine = SlideMachine::new(&from, pivot.coords, radius, self.sliding.clone());
        let mut world = PairwiseWorld::new(Arc::clone(&driven.body), obstacles);
        machine.set_ghost(&target);
        let rest = machine.run_frame(&mut world);
        poses[part as usize] = machine.visible_pose();
        self.unfinished.retain(|m| m.part != part);
        self.unfinished.push(Move {
            part,
            machine,
            world,
            rest,
        });
        self.unfinished.last().map(|m| &m.machine)
    }
}

#[cfg(test)]
mod tests;
