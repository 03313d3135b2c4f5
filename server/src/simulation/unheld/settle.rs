//! Settling: a released part falls until it meets a support, and turns about its supports until
//! it rests on ones that hold it.
//!
//! Each frame of a settling part that has landed starts from what supports it: its contacts with
//! the part pressed a few contact tolerances down, kept where the surface is no steeper than the
//! scene's slope.
//! * None: it falls by the scene's speed (the rubber band, a translation), and the frame ends at
//!   the first support it meets: the rest of the fall would slide it along a slope, which
//!   friction forbids.
//! * Supports that hold it (its centre of mass above their polygon, [`super::balance`]): it rests.
//! * Supports that do not (a rim, an edge, a corner): it turns about their point nearest below its
//!   centre of mass (the spiral spring), its farthest point moving at the scene's speed, and the
//!   frame ends at the first contact it meets, a face come down onto its support: the next frame
//!   judges the new supports, rather than the part turning on about that contact or sliding.
//!
//! A part that can turn no farther about supports that do not hold it (an edge it leans on)
//! falls instead. A part at rest stays until a hand touches or takes it; so does one that can
//! move no farther, or that has turned half a turn in all: a degenerate support never spins a
//! part for ever.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use super::{LEAST_MOVE, Move, Unheld, balance};
use crate::geometry::{Point, TriMesh};
use crate::grasping::PartId;
use crate::simulation::slide_stage::SlidePart;
use crate::sliding::{Contact, Motion, SlideWorld, SlidingMetaphor};

/// How far (in contact tolerances) a resting part is pressed down to find its supports: beyond
/// the bisection's tolerance and the lift that keep a resting part off its supports, so that a
/// face lying on a face touches all over.
const PROBE_TOLERANCES: f64 = 4.0;

/// The most a settling part turns in all (radians).
const MOST_TURN: f64 = PI;

/// A released part on its way to rest.
#[derive(Debug, Clone, Copy)]
pub(super) struct Settling {
    /// Its centre of mass, in its mesh frame.
    centre_of_mass: Point,
    /// Whether its last frame ended on a support (or it was just released): its supports are
    /// looked at before it moves. A part falling freely falls on without looking.
    landed: bool,
    /// How much more it may turn (radians).
    turn_left: f64,
}

impl Settling {
    /// A part of `mesh` just released.
    pub(super) fn new(mesh: &TriMesh) -> Settling {
        Settling {
            centre_of_mass: balance::centre_of_mass(mesh),
            landed: true,
            turn_left: MOST_TURN,
        }
    }
}

impl Unheld {
    /// Moves every settling part no hand holds one frame on, and forgets those come to rest.
    pub(super) fn settle_all(
        &mut self,
        parts: &[SlidePart],
        poses: &mut [Isometry3<f64>],
        held: &[PartId],
    ) {
        for (part, settling) in std::mem::take(&mut self.settling) {
            if held.contains(&part) {
                continue;
            }
            if let Some(next) = self.settle(part, settling, parts, poses) {
                self.settling.insert(part, next);
            }
        }
    }

    /// One frame of settling `part`: a fall or a turn; how it goes on, or none once it rests.
    fn settle(
        &self,
        part: PartId,
        mut settling: Settling,
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
        let (pivot, radius) = body.pivot_and_radius();
        let probe = PROBE_TOLERANCES * self.sliding.tolerance_for(2.0 * radius);
        let reach = self.settle_step + probe;
        let mut moving = self.prepare(part, reach, SlidingMetaphor::RubberBand, parts, poses)?;
        let least_cosine = self.friction_cosine();
        let holds = |contact: &Contact| contact.normal.dot(&up) >= least_cosine;
        if settling.landed {
            let supports = supports(&mut moving, &pose, &pivot, probe, &up, holds);
            if !supports.is_empty() {
                let tip = balance::tipping(&(pose * settling.centre_of_mass), &supports, &up)?;
                let angle = (self.settle_step / radius).min(settling.turn_left);
                if angle <= 0.0 {
                    return None;
                }
                // Spent whether it turns or, unable to, falls: turning attempts are bounded.
                settling.turn_left -= angle;
                let turn = UnitQuaternion::from_axis_angle(&tip.axis, angle);
                let target = Isometry3::rotation_wrt_point(turn, tip.point) * pose;
                moving.machine.set_metaphor(SlidingMetaphor::SpiralSpring);
                moving.run_until(&target, |_| true);
                let now = moving.machine.visible_pose();
                if radius * pose.rotation.angle_to(&now.rotation) > LEAST_MOVE {
                    poses[part as usize] = now;
                    return Some(settling);
                }
                // It cannot turn about its supports, nor rest on them: it slides off them.
                moving = self.prepare(part, reach, SlidingMetaphor::RubberBand, parts, poses)?;
            }
        }
        let step = self.settle_step.min(above_floor);
        let target = Translation3::from(-step * up.into_inner()) * pose;
        let landed = moving.run_until(&target, holds);
        let now = moving.machine.visible_pose();
        poses[part as usize] = now;
        let progress = (now.translation.vector - pose.translation.vector).norm();
        // Stuck, unless it has just met a support falling freely: then its supports decide.
        if progress <= LEAST_MOVE && (settling.landed || !landed) {
            return None;
        }
        Some(Settling { landed, ..settling })
    }
}

/// The points where `moving`'s part at `pose`, pressed `probe` metres against `up`, touches
/// surfaces that `hold` it.
fn supports(
    moving: &mut Move,
    pose: &Isometry3<f64>,
    pivot: &Point,
    probe: f64,
    up: &Unit<Vector3<f64>>,
    hold: impl Fn(&Contact) -> bool,
) -> Vec<Point> {
    let press = -probe * up.into_inner();
    let pressed = Translation3::from(press) * pose;
    let approach = Motion {
        translation: press,
        rotation: Vector3::zeros(),
    };
    let mut touching = Vec::new();
    (moving.world).contacts(&pressed, &approach, &(pressed * pivot), &mut touching);
    (touching.iter())
        .filter(|contact| hold(contact))
        .map(|contact| contact.point)
        .collect()
}
