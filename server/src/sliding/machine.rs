//! The sliding finite state machine (the paper's Figure 6) as an explicit type.
//!
//! ```text
//!            new ghost                      contacts still there / gone
//!  Resting ───────────▶ Validating ──────────────────────────────┐
//!     ▲                    (one probe per remembered cluster)     ▼
//!     │ reached, blocked,                                    Redirecting ◀──────────────┐
//!     │ stalled, cycle limit ◀───────────────────────────────── │  project the remaining │
//!     │                                                         ▼  motion on free space  │
//!     │                                                       Moving ── free ───────────┤
//!     │                                                         │ collides              │
//!     │                                                         ▼                       │
//!     │                                          Advancing (distance, conservative)     │
//!     │                                                         │ near, or grazing      │
//!     │                                                         ▼                       │
//!     │                                                   Approximating (bisection)     │
//!     │                                                         │ within tolerance      │
//!     │                                                         ▼                       │
//!     │                                                    Classifying ── Lifting ──────┘
//! ```
//!
//! Each [`SlideMachine::step`] runs one state and makes at most one query of the world (a
//! collision test, a distance query or a contact query), so the runtime can interleave the
//! machine with its rendezvous. The ghost follows the hand and may
//! penetrate; trial poses are tried on the collision copy (the [`SlideWorld`]); the visible pose
//! changes only to poses the collision copy found free. Contacts found by classification are
//! remembered (in the part's frame) while the part keeps pressing on them, so that a part sliding
//! along a plane or into a crease does not rediscover its contacts every cycle; at the start of
//! each frame a short probe towards every remembered surface checks that it is still there.

use nalgebra::{Point3, Translation3, Unit, Vector3, Vector6};

use super::SlidingMetaphor;
use super::advance::{Advance, Advanced};
use super::bisection::Bisection;
use super::contact::{Contact, reduce_contacts};
use super::direction::{FreeSpace, project_onto_free_space};
use super::motion::{Motion, Pose, pose_distance};
use super::params::SlideParams;
use crate::geometry::Point;

/// What the machine needs from collision detection: the grasped part's collision copy tested
/// against the obstacles around it.
pub trait SlideWorld {
    /// Whether the part, with its mesh frame at `part_pose`, intersects any obstacle (beyond the
    /// obstacle's slide-in allowance).
    fn collides(&mut self, part_pose: &Pose) -> bool;

    /// A lower bound on the distance from the part, with its mesh frame at `part_pose`, to the
    /// obstacles (0 when it touches one, or may overlap one within its allowance); `None` when
    /// the distance is at least `d_max`.
    fn clearance(&mut self, part_pose: &Pose, d_max: f64) -> Option<f64>;

    /// Appends the classified contacts of the part at `part_pose` to `out`; `approach` is the
    /// pivot's motion from the last free pose to `part_pose` and `pivot` the pivot's position
    /// there (see `classify_pairs`).
    fn contacts(
        &mut self,
        part_pose: &Pose,
        approach: &Motion,
        pivot: &Point,
        out: &mut Vec<Contact>,
    );
}

/// Why the machine came to rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum RestReason {
    /// Just grasped: the visible part is where the ghost is.
    Grasped,
    /// The part reached its target (within tolerance).
    Reached,
    /// The contacts leave no free motion towards the target.
    Blocked,
    /// Several cycles in a row made no progress.
    Stalled,
    /// The frame used up its cycles; the next frame goes on.
    CycleLimit,
}

/// The states of Figure 6; the data each carries is what the next step needs.
#[derive(Debug, Clone, PartialEq)]
pub enum SlideState {
    /// Waiting for the ghost to move.
    Resting(RestReason),
    /// Probing whether remembered contact `contact` (and its cluster) still touches.
    Validating {
        /// Index into the remembered contacts.
        contact: usize,
    },
    /// Computing the new direction from the remaining motion and the contacts.
    Redirecting,
    /// Checking the goal of the current direction on the collision copy.
    Moving {
        /// The pivot pose the part tries to reach.
        goal: Pose,
    },
    /// Advancing the last free pose towards the first colliding one by the distance measured.
    Advancing(Advance),
    /// Bisecting between the last free pose and the first colliding one.
    Approximating(Bisection),
    /// Moving the part off the contacts just classified by a fraction of the tolerance, so that
    /// the visible pose keeps a clearance instead of the bisection's last free pose, which may be
    /// arbitrarily close to a surface.
    Lifting {
        /// The lifted pivot pose.
        goal: Pose,
        /// The bisection's last free pose: where the part stays if the lift collides.
        fallback: Pose,
    },
    /// Classifying the contacts at the colliding end of a finished bisection.
    Classifying {
        /// The free end.
        valid: Pose,
        /// The colliding end.
        colliding: Pose,
    },
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Event {
    /// Resting, and the ghost has not moved.
    Idle,
    /// A new ghost pose started a frame.
    FrameStarted,
    /// A remembered contact cluster still touches.
    ContactConfirmed,
    /// A remembered contact cluster was left behind and forgotten.
    ContactLost,
    /// A new direction was computed.
    Redirected(FreeSpace),
    /// The goal was free: the visible part moved there.
    Moved,
    /// The lift off fresh contacts was free (true) or blocked (false, the part stays).
    Lifted(bool),
    /// The goal collided: contact approximation starts.
    Collided,
    /// One advancement step: the distance measured at the free end (`None`: more than the rest
    /// of the motion can cover).
    Advanced {
        /// The distance, metres.
        distance: Option<f64>,
    },
    /// One bisection check; whether the trial pose collided.
    Bisected {
        /// The trial pose collided.
        collides: bool,
    },
    /// The contacts were classified: how many contact points.
    Classified {
        /// Contact points classified (one per touching triangle pair).
        contacts: usize,
    },
    /// The machine came to rest.
    Rested(RestReason),
}

/// Counters over the machine's lifetime, for benchmarks and diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SlideStats {
    /// Frames started.
    pub frames: u64,
    /// Sliding cycles completed.
    pub cycles: u64,
    /// Static collision checks asked of the world.
    pub collision_checks: u64,
    /// Distance queries asked of the world (conservative advancement).
    pub distance_queries: u64,
    /// Contact queries asked of the world.
    pub contact_queries: u64,
    /// Contact points classified.
    pub contacts_classified: u64,
    /// Remembered contact points used as constraints of a new direction, summed over the new
    /// directions computed: what each cycle handles without detecting them again.
    pub contacts_projected: u64,
    /// Colliding poses for which the world reported no usable contact (the part stops there).
    pub contactless_collisions: u64,
}

/// A contact remembered in the part's frame: the point moves with the part, the normal (of a
/// static obstacle) stays in the world, and so does the anchor, where the contact was found.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Remembered {
    local_point: Point,
    contact: Contact,
}

impl Remembered {
    /// How far the part's contact point, at pivot pose `visible`, has moved off the surface.
    fn gap(&self, visible: &Pose) -> f64 {
        self.contact
            .normal
            .dot(&(visible * self.local_point - self.contact.point))
    }
}

/// The sliding simulation of one grasped part.
#[derive(Debug, Clone)]
pub struct SlideMachine {
    params: SlideParams,
    metaphor: SlidingMetaphor,
    tolerance: f64,
    /// The pivot in the part's mesh frame.
    pivot: Vector3<f64>,
    /// The part's radius about the pivot: converts rotations to lengths.
    radius: f64,
    state: SlideState,
    /// Pivot pose of the visible part: only ever a pose found free.
    visible: Pose,
    /// Pivot pose of the ghost: where the hand holds the part.
    ghost: Pose,
    /// The ghost pose the current target already accounts for.
    consumed_ghost: Pose,
    ghost_pending: bool,
    /// Pivot pose the current frame slides towards.
    target: Pose,
    remembered: Vec<Remembered>,
    cycles_this_frame: u32,
    stalled_cycles: u32,
    cycle_start: Pose,
    scratch: Vec<Contact>,
    /// The constraint rows of the remembered contacts (kept to reuse its allocation).
    rows: Vec<Vector6<f64>>,
    stats: SlideStats,
}

impl SlideMachine {
    /// A machine for a part grasped at `part_pose` (pose of its mesh frame, which must be free),
    /// with its pivot at `pivot` and its radius about the pivot `radius` (both in the mesh frame,
    /// metres), and the scene's sliding parameters (already validated). The tolerance is the
    /// parameters' one or 1e-4 of the part's diameter.
    pub fn new(part_pose: &Pose, pivot: Vector3<f64>, radius: f64, params: SlideParams) -> Self {
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            1.0
        };
        let tolerance = params.tolerance_for(2.0 * radius);
        let visible = part_pose * Translation3::from(pivot);
        SlideMachine {
            metaphor: params.metaphor,
            params,
            tolerance,
            pivot,
            radius,
            state: SlideState::Resting(RestReason::Grasped),
            visible,
            ghost: visible,
            consumed_ghost: visible,
            ghost_pending: false,
            target: visible,
            remembered: Vec::new(),
            cycles_this_frame: 0,
            stalled_cycles: 0,
            cycle_start: visible,
            scratch: Vec::new(),
            rows: Vec::new(),
            stats: SlideStats::default(),
        }
    }

    /// Sets the ghost: the pose (of the part's mesh frame) where the hand now holds the part.
    /// The next step from rest starts a frame towards it; a frame under way picks it up at its
    /// next new direction.
    pub fn set_ghost(&mut self, part_pose: &Pose) {
        self.ghost = part_pose * Translation3::from(self.pivot);
        self.ghost_pending = true;
    }

    /// Switches the grasping metaphor at run time; the current frame ends.
    pub fn set_metaphor(&mut self, metaphor: SlidingMetaphor) {
        self.metaphor = metaphor;
        self.consumed_ghost = self.ghost;
        self.target = self.visible;
        self.remembered.clear();
        self.state = SlideState::Resting(RestReason::Reached);
        self.ghost_pending = true;
    }

    /// The current metaphor.
    pub fn metaphor(&self) -> SlidingMetaphor {
        self.metaphor
    }

    /// The contact tolerance in metres.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The current state.
    pub fn state(&self) -> &SlideState {
        &self.state
    }

    /// The visible part's pose (its mesh frame): always a pose found free.
    pub fn visible_pose(&self) -> Pose {
        self.visible * Translation3::from(-self.pivot)
    }

    /// The visible part's pivot pose (for the force model).
    pub fn visible_pivot_pose(&self) -> &Pose {
        &self.visible
    }

    /// The ghost's pivot pose (for the force model).
    pub fn ghost_pivot_pose(&self) -> &Pose {
        &self.ghost
    }

    /// The contacts the part currently presses on, in the world frame.
    pub fn contacts(&self) -> impl Iterator<Item = Contact> + '_ {
        self.remembered.iter().map(|r| Contact {
            point: self.visible * r.local_point,
            ..r.contact
        })
    }

    /// Lifetime counters.
    pub fn stats(&self) -> &SlideStats {
        &self.stats
    }

    /// Steps until the machine rests (a whole frame when a ghost is pending); returns why it rests.
    pub fn run_frame(&mut self, world: &mut impl SlideWorld) -> RestReason {
        loop {
            if let Event::Rested(reason) = self.step(world) {
                return reason;
            }
            if let (SlideState::Resting(reason), false) = (&self.state, self.ghost_pending) {
                return *reason;
            }
        }
    }

    /// Runs the current state once, with at most one query to `world`, and moves to the next.
    pub fn step(&mut self, world: &mut impl SlideWorld) -> Event {
        match std::mem::replace(&mut self.state, SlideState::Redirecting) {
            SlideState::Resting(reason) => self.start_frame(reason),
            SlideState::Validating { contact } => self.validate(world, contact),
            SlideState::Redirecting => self.redirect(),
            SlideState::Moving { goal } => self.move_to(world, goal),
            SlideState::Lifting { goal, fallback } => self.lift_to(world, goal, fallback),
            SlideState::Advancing(advance) => self.advance(world, advance),
            SlideState::Approximating(bisection) => self.approximate(world, bisection),
            SlideState::Classifying { valid, colliding } => self.classify(world, valid, colliding),
        }
    }

    fn start_frame(&mut self, reason: RestReason) -> Event {
        if !self.ghost_pending {
            self.state = SlideState::Resting(reason);
            return Event::Idle;
        }
        self.stats.frames += 1;
        self.cycles_this_frame = 0;
        self.stalled_cycles = 0;
        if self.metaphor == SlidingMetaphor::Incremental {
            // What the last frame did not achieve is dropped: the user is in control again.
            self.target = self.visible;
        }
        self.state = if self.remembered.is_empty() {
            SlideState::Redirecting
        } else {
            SlideState::Validating { contact: 0 }
        };
        Event::FrameStarted
    }

    /// Probes towards one remembered cluster; forgets it if nothing is there any more.
    fn validate(&mut self, world: &mut impl SlideWorld, index: usize) -> Event {
        let normal = self.remembered[index].contact.normal;
        let probe_distance = self.release_distance();
        let probe = Translation3::from(-normal.into_inner() * probe_distance) * self.visible;
        self.stats.collision_checks += 1;
        let still_touching = world.collides(&self.part_pose(&probe));
        let cos_limit = self.params.cluster_angle.cos();
        let same_cluster = |r: &Remembered| r.contact.normal.dot(&normal) >= cos_limit;
        let event = if still_touching {
            Event::ContactConfirmed
        } else {
            Event::ContactLost
        };
        // The next cluster to probe: the first remembered contact after this one of another
        // cluster than every one probed so far.
        if !still_touching {
            self.remembered.retain(|r| !same_cluster(r));
        }
        let probed_until = if still_touching { index + 1 } else { index };
        let next = (probed_until..self.remembered.len()).find(|&i| {
            let n = self.remembered[i].contact.normal;
            !self.remembered[..i]
                .iter()
                .any(|r| r.contact.normal.dot(&n) >= cos_limit)
        });
        self.state = match next {
            Some(contact) => SlideState::Validating { contact },
            None => SlideState::Redirecting,
        };
        event
    }

    /// The target of the current frame under the metaphor, refreshed from the newest ghost.
    fn refresh_target(&mut self) {
        if self.ghost_pending {
            if self.metaphor == SlidingMetaphor::Incremental {
                self.target =
                    Motion::between(&self.consumed_ghost, &self.ghost).apply(&self.target);
            }
            self.consumed_ghost = self.ghost;
            self.ghost_pending = false;
        }
        match self.metaphor {
            SlidingMetaphor::RubberBand => {
                self.target = Pose::from_parts(self.ghost.translation, self.visible.rotation);
            }
            SlidingMetaphor::SpiralSpring => self.target = self.ghost,
            SlidingMetaphor::Incremental => {}
        }
    }

    fn rest(&mut self, reason: RestReason) -> Event {
        self.state = SlideState::Resting(reason);
        Event::Rested(reason)
    }

    /// Projects the remaining motion onto the free space the remembered contacts leave.
    fn redirect(&mut self) -> Event {
        self.refresh_target();
        let remaining = Motion::between(&self.visible, &self.target);
        if remaining.length(self.radius) <= self.tolerance {
            return self.rest(RestReason::Reached);
        }
        if self.stalled_cycles >= self.params.stall_cycles {
            return self.rest(RestReason::Stalled);
        }
        if self.cycles_this_frame >= self.params.max_iterations {
            return self.rest(RestReason::CycleLimit);
        }
        // A contact the part has moved away from (by turning, or by a lift) no longer constrains.
        let release = self.release_distance();
        let visible = self.visible;
        self.remembered.retain(|r| r.gap(&visible) <= release);
        let rotates = self.metaphor.rotates();
        let pivot = Point3::from(self.visible.translation.vector);
        self.rows.clear();
        self.rows.extend(self.remembered.iter().map(|r| {
            let n = r.contact.normal.into_inner();
            let torque = if rotates {
                ((self.visible * r.local_point) - pivot).cross(&n) / self.radius
            } else {
                Vector3::zeros()
            };
            Vector6::new(n.x, n.y, n.z, torque.x, torque.y, torque.z)
        }));
        self.stats.contacts_projected += self.rows.len() as u64;
        let projection = project_onto_free_space(&remaining.to_scaled(self.radius), &self.rows);
        let mut active = projection.active.iter().peekable();
        let mut index = 0;
        self.remembered.retain(|_| {
            let kept = active.next_if_eq(&&index).is_some();
            index += 1;
            kept
        });
        if projection.free_space == FreeSpace::Stop {
            return self.rest(RestReason::Blocked);
        }
        let motion = Motion::from_scaled(&projection.motion, self.radius);
        self.cycle_start = self.visible;
        self.state = SlideState::Moving {
            goal: motion.apply(&self.visible),
        };
        Event::Redirected(projection.free_space)
    }

    fn move_to(&mut self, world: &mut impl SlideWorld, goal: Pose) -> Event {
        self.stats.collision_checks += 1;
        if world.collides(&self.part_pose(&goal)) {
            // Pressed on remembered contacts, the part is within their release distance of an
            // obstacle: a distance could not advance it, so bisection goes on alone.
            self.state = if self.params.conservative_advancement && self.remembered.is_empty() {
                let advance = Advance::new(self.visible, goal, self.tolerance, self.radius);
                SlideState::Advancing(advance)
            } else {
                let bisection = Bisection::new(self.visible, goal, self.tolerance, self.radius);
                self.approximating(bisection)
            };
            Event::Collided
        } else {
            self.visible = goal;
            self.end_cycle();
            self.state = SlideState::Redirecting;
            Event::Moved
        }
    }

    fn lift_to(&mut self, world: &mut impl SlideWorld, goal: Pose, fallback: Pose) -> Event {
        self.stats.collision_checks += 1;
        let free = !world.collides(&self.part_pose(&goal));
        self.visible = if free { goal } else { fallback };
        self.end_cycle();
        self.state = SlideState::Redirecting;
        Event::Lifted(free)
    }

    fn advance(&mut self, world: &mut impl SlideWorld, advance: Advance) -> Event {
        let (from, d_max) = advance.query();
        self.stats.distance_queries += 1;
        let distance = world.clearance(&self.part_pose(&from), d_max);
        self.state = match advance.record(distance) {
            Advanced::Again(advance) => SlideState::Advancing(advance),
            Advanced::Bisect(bisection) => self.approximating(bisection),
        };
        Event::Advanced { distance }
    }

    fn approximate(&mut self, world: &mut impl SlideWorld, mut bisection: Bisection) -> Event {
        let trial = bisection.trial();
        self.stats.collision_checks += 1;
        let collides = world.collides(&self.part_pose(&trial));
        bisection.record(trial, collides);
        self.state = self.approximating(bisection);
        Event::Bisected { collides }
    }

    /// The state after a bisection check: more checks, or classification once within tolerance.
    fn approximating(&mut self, bisection: Bisection) -> SlideState {
        if bisection.is_done() {
            SlideState::Classifying {
                valid: *bisection.valid(),
                colliding: *bisection.colliding(),
            }
        } else {
            SlideState::Approximating(bisection)
        }
    }

    fn classify(&mut self, world: &mut impl SlideWorld, valid: Pose, colliding: Pose) -> Event {
        let approach = Motion::between(&valid, &colliding);
        self.scratch.clear();
        self.stats.contact_queries += 1;
        let pivot = Point3::from(colliding.translation.vector);
        world.contacts(
            &self.part_pose(&colliding),
            &approach,
            &pivot,
            &mut self.scratch,
        );
        let classified = self.scratch.len();
        self.stats.contacts_classified += classified as u64;
        if classified == 0 {
            self.visible = valid;
            self.end_cycle();
            self.stats.contactless_collisions += 1;
            return self.rest(RestReason::Blocked);
        }
        let lift: Vector3<f64> = self.scratch.iter().map(|c| c.normal.into_inner()).sum();
        // Remember the new contacts beside the old ones and reduce the lot.
        let inverse = valid.inverse();
        self.remembered
            .extend(self.scratch.iter().map(|&contact| Remembered {
                local_point: inverse * contact.point,
                contact,
            }));
        reduce_contacts(
            &mut self.remembered,
            |r| &r.contact,
            self.params.cluster_angle,
        );
        self.state = match Unit::try_new(lift, 1e-9) {
            Some(direction) if self.params.lift > 0.0 => {
                let offset = direction.into_inner() * (self.params.lift * self.tolerance);
                SlideState::Lifting {
                    goal: Translation3::from(offset) * valid,
                    fallback: valid,
                }
            }
            _ => {
                self.visible = valid;
                self.end_cycle();
                SlideState::Redirecting
            }
        };
        Event::Classified {
            contacts: classified,
        }
    }

    /// The gap beyond which a remembered contact is no longer touched: the bisection's tolerance,
    /// the lift, and as much again for rounding.
    fn release_distance(&self) -> f64 {
        self.tolerance * (2.0 + self.params.lift)
    }

    fn end_cycle(&mut self) {
        self.cycles_this_frame += 1;
        self.stats.cycles += 1;
        let progress = pose_distance(&self.cycle_start, &self.visible, self.radius);
        if progress < 0.1 * self.tolerance {
            self.stalled_cycles += 1;
        } else {
            self.stalled_cycles = 0;
        }
    }

    /// The mesh-frame pose of the part whose pivot is at `pivot_pose`.
    fn part_pose(&self, pivot_pose: &Pose) -> Pose {
        pivot_pose * Translation3::from(-self.pivot)
    }
}

#[cfg(test)]
mod tests;
