//! Movable parts no hand holds, moved by the sliding machinery towards a target: pushed by a hand,
//! or settling after a release.
//!
//! Each move is a frame of a [`SlideMachine`] made for it, from the part's visible pose against
//! the other parts at theirs (only those its sweep could reach), with the ghost at the target: the
//! part moves there exactly as a held part slides, never into anything, and stops at what it
//! cannot pass. A fresh machine each frame sees the other parts where they are now (a held part
//! moves between frames); a frame that runs out of cycles goes on between inputs. Whatever the
//! scene's metaphor (the incremental one would drop what a frame could not achieve), a push or a
//! fall follows its target by the rubber band, a translation, and a part tipping over follows it
//! by the spiral spring, the metaphor that turns the part.
//!
//! * **Push.** A hand touching a pushable part in a push gives it a displacement (the hand's
//!   motion into it along the contact normals, [`crate::grasping::push`]); the part slides there.
//!   The clasp stopped the hand at the part's surface; once the part has moved, the hand follows
//!   on its next frame. A part pushed against what it cannot pass stops, and the hand with it.
//! * **Settle.** A part released with `release = "settle"` moves down (against the scene's up),
//!   by the scene's speed each frame, until it rests on a surface no steeper than the scene's
//!   slope (friction holds it; along a steeper one, or a wall, it slides on down), its lowest
//!   point reaches the scene's floor, or it can move no farther. Resting on such surfaces with
//!   its centre of mass not above the contacts' support polygon (an edge or a corner), it tips
//!   ([`balance`]): each frame it turns about the support point nearest below its centre of mass,
//!   its rim moving at the scene's speed, while pressing into its supports along their normals
//!   (to keep finding them, never sliding along a slope), until it rests balanced on a face.

use std::collections::BTreeMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use super::slide_stage::SlidePart;
use crate::collision::DopTree;
use crate::geometry::Point;
use crate::grasping::{PartId, Push};
use crate::scene::{ReleaseMode, UnheldParams};
use crate::sliding::motion::pose_distance;
use crate::sliding::world::{Obstacle, PairwiseWorld};
use crate::sliding::{Motion, RestReason, SlideMachine, SlideParams, SlideWorld, SlidingMetaphor};

mod balance;

/// A displacement shorter than this (metres) moves nothing: the hand rests on the part.
const LEAST_MOVE: f64 = 1e-9;

/// One part's move under way.
struct Move {
    part: PartId,
    machine: SlideMachine,
    world: PairwiseWorld<DopTree>,
    rest: RestReason,
}

/// A released part on its way to rest.
#[derive(Debug, Clone, Copy)]
struct Settling {
    /// Its centre of mass, in its mesh frame.
    centre_of_mass: Point,
    /// How it tips, with the mean normal of its supports, when the last frame left it resting
    /// unbalanced; none while it falls.
    tip: Option<(balance::Tip, Unit<Vector3<f64>>)>,
}

/// The parts no hand holds that pushes and releases move.
pub(super) struct Unheld {
    params: UnheldParams,
    /// The scene's sliding parameters (the metaphor chosen per move).
    sliding: SlideParams,
    /// How far a settling part moves in one frame (metres).
    settle_step: f64,
    /// Released parts on their way down.
    settling: BTreeMap<PartId, Settling>,
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
            let settling = Settling {
                centre_of_mass: balance::centre_of_mass(slide.body.mesh()),
                tip: None,
            };
            self.settling.insert(part, settling);
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
                self.drive(part, target, SlidingMetaphor::RubberBand, parts, poses);
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
            if slide.rest == RestReason::CycleLimit && !self.settling.contains_key(&slide.part) {
                slide.rest = slide.machine.run_frame(&mut slide.world);
                poses[slide.part as usize] = slide.machine.visible_pose();
            }
        }
        self.settle_all(parts, poses, held);
    }

    /// Moves every settling part no hand holds one step, and forgets those come to rest.
    fn settle_all(&mut self, parts: &[SlidePart], poses: &mut [Isometry3<f64>], held: &[PartId]) {
        for (part, settling) in std::mem::take(&mut self.settling) {
            if held.contains(&part) {
                continue;
            }
            if let Some(next) = self.settle(part, settling, parts, poses) {
                self.settling.insert(part, next);
            }
        }
    }

    /// Moves settling `part` one step down, or one step over if it tips; what it does next, or
    /// none once it has come to rest.
    fn settle(
        &mut self,
        part: PartId,
        settling: Settling,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
    ) -> Option<Settling> {
        let release = self.params.release;
        let up = release.up_direction();
        let pose = poses[part as usize];
        let body = &parts.get(part as usize)?.body;
        let lowest = (body.mesh().vertices().iter())
            .map(|v| (pose * v).coords.dot(&up))
            .fold(f64::INFINITY, f64::min);
        let above_floor = lowest - release.floor;
        if above_floor.is_nan() || above_floor <= LEAST_MOVE {
            return None;
        }
        let step = self.settle_step.min(above_floor);
        let (pivot, radius) = body.pivot_and_radius();
        let (target, metaphor) = match settling.tip {
            None => (
                Translation3::from(-step * up.into_inner()) * pose,
                SlidingMetaphor::RubberBand,
            ),
            Some((tip, press)) => {
                let turn = UnitQuaternion::from_axis_angle(&tip.axis, self.settle_step / radius);
                let over = Isometry3::rotation_wrt_point(turn, tip.point);
                let target = Translation3::from(-step * press.into_inner()) * over * pose;
                (target, SlidingMetaphor::SpiralSpring)
            }
        };
        let mut moving = self.prepare(part, &target, metaphor, parts, poses)?;
        let target = if settling.tip.is_none() {
            // No farther than the clearance below and the tolerance: landing on a slope, a part
            // slides along it within the frame by no more than the tolerance.
            let tolerance = moving.machine.tolerance();
            let fall =
                (moving.world.clearance(&pose, step)).map_or(step, |c| step.min(c + tolerance));
            Translation3::from(-fall * up.into_inner()) * pose
        } else {
            target
        };
        let moved = self.run(moving, &target, poses);
        let now = poses[part as usize];
        if pose_distance(&pose, &now, radius) <= LEAST_MOVE {
            return None;
        }
        // What it rests on: every contact of the part pressed down by the sliding tolerance (the
        // machine keeps only the few contacts that shape its motion, too few for a polygon).
        let press = -moved.machine.tolerance() * up.into_inner();
        let pressed = Translation3::from(press) * now;
        let approach = Motion {
            translation: press,
            rotation: Vector3::zeros(),
        };
        let mut touching = Vec::new();
        let centre = pressed * pivot;
        (moved.world).contacts(&pressed, &approach, &centre, &mut touching);
        let least_cosine = release.max_slope_degrees.to_radians().cos();
        let supports: Vec<_> = (touching.into_iter())
            .filter(|contact| contact.normal.dot(&up) >= least_cosine)
            .collect();
        if supports.is_empty() {
            return Some(Settling {
                tip: None,
                ..settling
            });
        }
        let points: Vec<Point> = supports.iter().map(|contact| contact.point).collect();
        let tip = balance::tipping(&(now * settling.centre_of_mass), &points, &up)?;
        let press = Unit::new_normalize(supports.iter().map(|c| c.normal.into_inner()).sum());
        Some(Settling {
            tip: Some((tip, press)),
            ..settling
        })
    }

    /// Slides `part` from its visible pose towards `target` under `metaphor` for one frame; its
    /// new pose goes to `poses`.
    fn drive(
        &mut self,
        part: PartId,
        target: Isometry3<f64>,
        metaphor: SlidingMetaphor,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
    ) -> Option<&mut Move> {
        let moving = self.prepare(part, &target, metaphor, parts, poses)?;
        Some(self.run(moving, &target, poses))
    }

    /// A move of `part` from its visible pose, with a machine under `metaphor` and the other parts
    /// that a move to `target` could reach.
    fn prepare(
        &self,
        part: PartId,
        target: &Isometry3<f64>,
        metaphor: SlidingMetaphor,
        parts: &[SlidePart],
        poses: &[Isometry3<f64>],
    ) -> Option<Move> {
        let driven = parts.get(part as usize)?;
        let from = poses[part as usize];
        let (pivot, radius) = driven.body.pivot_and_radius();
        let centre = from * pivot;
        let to_pivot = Translation3::from(pivot.coords);
        let reach = radius + pose_distance(&(from * to_pivot), &(target * to_pivot), radius);
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

    /// Runs one frame of `moving` towards `target`; the part's new pose goes to `poses`. The
    /// move, which keeps the part's contacts, stays for another frame if this one ran out of
    /// cycles.
    fn run(
        &mut self,
        mut moving: Move,
        target: &Isometry3<f64>,
        poses: &mut [Isometry3<f64>],
    ) -> &mut Move {
        moving.machine.set_ghost(target);
        moving.rest = moving.machine.run_frame(&mut moving.world);
        poses[moving.part as usize] = moving.machine.visible_pose();
        self.unfinished.retain(|m| m.part != moving.part);
        self.unfinished.push(moving);
        let last = self.unfinished.len() - 1;
        &mut self.unfinished[last]
    }
}

#[cfg(test)]
mod tests;
