//! The grasping loop's state for one hand (the paper's Figure 10): per input sample, clasp the
//! collision copy toward the target, hand the result to the visible hand, find what it touches,
//! analyse the grasp, and grasp or release parts with hysteresis.
//!
//! Cart motion (navigation) is handled apart: while the cart moves the hand is not clasped; it
//! follows the tracked root, its fingers as they were, whenever the whole hand is free there,
//! and otherwise stays where it was. Once the hand has been left at its last valid place,
//! clasping resumes only when the user has moved the whole hand to a free place, where the hand
//! then jumps. The visible hand is thus never published at a colliding pose.
//!
//! Grasp hand-over: a grasp is an event carrying the part and its pose in the hand root's frame;
//! from then on the part follows the hand (`root · hand_to_part`, see
//! [`GraspingHand::held_part_pose`]), and the clasp treats it in the hand's frame, so moving the
//! hand never collides with it while the fingers still close on it. A release is an event with
//! the part's last pose.

use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Point3, Unit, Vector3};
use serde::Serialize;

use super::analysis::{AnalysisParams, Contact, GraspClass, Touch, classify};
use super::clasp::{
    ClaspParams, ClaspPlan, HandPose, ObjectSet, SEGMENT_COUNT, SegmentPlacement, clasp,
};
use super::collider::{HandGeometry, Obstacle, PartId, SceneCollider};
use super::flex::{FlexReport, sanitize_flex};
use super::model::{FLEX_COUNT, HandModel};
use super::push::{Push, pushes};
use super::segment_mesh::SegmentMeshError;
use crate::collision::QueryStats;
use crate::collision::orientation::DEFAULT_K;

/// Tuning of the grasping loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspParams {
    /// The clasp minimisation's tolerance, step cap and largest motion per frame.
    pub clasp: ClaspParams,
    /// The analysis' gravity direction and thresholds.
    pub analysis: AnalysisParams,
    /// How far beyond a segment (metres) a contact is looked for: more than the gap the clasp
    /// may leave (its root tolerance, or its flex tolerance times a finger's length).
    pub probe_margin: f64,
    /// Consecutive frames a part must be held by the analysis before it is grasped.
    pub grasp_frames: u32,
    /// Consecutive frames the analysis must not hold the part before it is released.
    pub release_frames: u32,
    /// The cart counts as moving when its pose changes by more than this (metres, or radians).
    pub cart_epsilon: f64,
    /// k of the segments' DOP-trees: the scene's, so that they can be tested against its
    /// parts' trees.
    pub dop_orientations: usize,
}

impl Default for GraspParams {
    fn default() -> Self {
        GraspParams {
            clasp: ClaspParams::default(),
            analysis: AnalysisParams::default(),
            probe_margin: 0.001,
            grasp_frames: 3,
            release_frames: 10,
            cart_epsilon: 1e-9,
            dop_orientations: DEFAULT_K,
        }
    }
}

/// One input sample for the hand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandInput {
    /// The cart (the user's navigated body) in the world.
    pub cart: Isometry3<f64>,
    /// The tracked hand root in the cart's frame.
    pub tracker: Isometry3<f64>,
    /// The glove's 22 flex values, radians, CyberGlove order.
    pub flex: [f32; FLEX_COUNT],
}

/// What the hand is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HandMode {
    /// Clasping toward the target every frame.
    Clasping,
    /// The cart moved this frame: no clasping.
    Navigating,
    /// The hand was left at its last valid place; waiting for the target to be free.
    AwaitingFreeHand,
}

/// A part the hand holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Held {
    /// The part.
    pub part: PartId,
    /// The part's pose in the hand root's frame, fixed at the grasp.
    pub hand_to_part: Isometry3<f64>,
    /// The latest grasp type the analysis found on it.
    pub grasp: GraspClass,
}

/// Grasp and release, for the sliding module's hand-over and the event stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GraspEvent {
    /// The hand took hold of a part: it now follows `root · hand_to_part`.
    Grasp {
        /// The part.
        part: PartId,
        /// The grasp type.
        grasp: GraspClass,
        /// The part's pose in the hand root's frame.
        hand_to_part: Isometry3<f64>,
    },
    /// The hand let go of a part, which stays at `pose`.
    Release {
        /// The part.
        part: PartId,
        /// Its pose in the world when released.
        pose: Isometry3<f64>,
    },
}

/// What the clasp minimisation of one frame did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClaspRun {
    /// Iteration steps.
    pub steps: u32,
    /// Wall time: the figure of benchmark B6, also worth watching at run time.
    pub time: Duration,
}

/// A part a segment touches, and where.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentContact {
    /// The part touched.
    pub part: PartId,
    /// The centre of the contact region, in the world.
    pub point: Point3<f64>,
    /// The segment's outward normal over the contact, in the world (from the hand into the
    /// part).
    pub normal: Unit<Vector3<f64>>,
}

/// What one step of a grasping hand gives, for one input sample: the visible hand, its grasp
/// and events (the wire carries the published hand as a `vas_protocol::HandFrame`).
#[derive(Debug, Clone, PartialEq)]
pub struct HandStep {
    /// The visible hand: always a valid (collision-free) configuration.
    pub pose: HandPose,
    /// What the hand is doing.
    pub mode: HandMode,
    /// Per segment, the parts it touches (confirmed by a contact); empty unless clasping.
    pub touching: [Vec<SegmentContact>; SEGMENT_COUNT],
    /// The grasp on the held part, or else the firmest grasp found on a touched part.
    pub grasp: Option<GraspClass>,
    /// The held part and its pose in the world.
    pub held: Option<(PartId, Isometry3<f64>)>,
    /// Grasps and releases of this frame.
    pub events: Vec<GraspEvent>,
    /// The parts the hand pushes (touches in a push, holding none of them).
    pub pushes: Vec<Push>,
    /// The clasp minimisation of this frame; `None` when it did not run (navigation, waiting
    /// for a free hand).
    pub clasp: Option<ClaspRun>,
    /// Segment collision checks made this frame.
    pub segment_checks: u32,
    /// What the glove sample needed cleaning (clamped, rejected values).
    pub flex: FlexReport,
}

/// One hand: its model, collision copy and visible state.
pub struct GraspingHand {
    model: Arc<HandModel>,
    plan: ClaspPlan,
    geometry: HandGeometry,
    params: GraspParams,
    visible: HandPose,
    mode: HandMode,
    last_cart: Option<Isometry3<f64>>,
    last_flex: [f64; FLEX_COUNT],
    held: Option<Held>,
    /// Part the analysis holds but that is not grasped yet, and for how many frames.
    candidate: Option<(PartId, u32)>,
    /// Frames the held part has not been held by the analysis.
    release_count: u32,
    /// The part released last, not grasped again while any segment still touches it: fingers
    /// opening along a part they just let go of must not take hold of it again.
    released: Option<PartId>,
    /// Per segment, the contacts of the last analysed frame: what it touched then, and the
    /// contacts to reuse while the segment has not moved relative to the part (a held part, a
    /// hand at rest), as finding them costs more than the clasp.
    contacts: [Vec<CachedContact>; SEGMENT_COUNT],
    /// Running totals of glove cleaning and rejected tracker samples.
    flex_totals: FlexReport,
    rejected_samples: u64,
    /// Collision query work so far.
    stats: QueryStats,
}

impl GraspingHand {
    /// A hand parked at `initial`; it starts waiting for a free target, so `initial` need not
    /// be free.
    pub fn new(
        model: Arc<HandModel>,
        params: GraspParams,
        initial: HandPose,
    ) -> Result<GraspingHand, SegmentMeshError> {
        Ok(GraspingHand {
            plan: ClaspPlan::new(&model),
            geometry: HandGeometry::new(&model, params.probe_margin, params.dop_orientations)?,
            last_flex: initial.flex,
            model,
            params,
            visible: initial,
            mode: HandMode::AwaitingFreeHand,
            last_cart: None,
            held: None,
            candidate: None,
            release_count: 0,
            released: None,
            contacts: Default::default(),
            flex_totals: FlexReport::default(),
            rejected_samples: 0,
            stats: QueryStats::default(),
        })
    }

    /// The hand model.
    pub fn model(&self) -> &HandModel {
        &self.model
    }

    /// The hand's collision geometry.
    pub fn geometry(&self) -> &HandGeometry {
        &self.geometry
    }

    /// The visible hand.
    pub fn visible(&self) -> &HandPose {
        &self.visible
    }

    /// What the hand is doing.
    pub fn mode(&self) -> HandMode {
        self.mode
    }

    /// The held part, if any.
    pub fn held(&self) -> Option<&Held> {
        self.held.as_ref()
    }

    /// The held part and its pose in the world: the visible root times the grasp's offset.
    pub fn held_part_pose(&self) -> Option<(PartId, Isometry3<f64>)> {
        self.held
            .map(|h| (h.part, self.visible.root * h.hand_to_part))
    }

    /// Lets go of the held part now, whatever the analysis says (the other hand took it, or the
    /// hand's tracking was lost for too long); the release event, `None` when nothing is held. As after any release, the part is not grasped
    /// again while a segment still touches it.
    pub fn let_go(&mut self) -> Option<GraspEvent> {
        let mut events = Vec::new();
        self.release(&mut events);
        events.pop()
    }

    /// Totals of cleaned glove values, and tracker samples refused as not finite.
    pub fn input_counts(&self) -> (FlexReport, u64) {
        (self.flex_totals, self.rejected_samples)
    }

    /// Collision query work so far.
    pub fn query_stats(&self) -> QueryStats {
        self.stats
    }

    /// Processes one input sample against the parts near the hand (which must include the held
    /// part; at most 64 are considered).
    pub fn step(&mut self, input: &HandInput, obstacles: &[Obstacle]) -> HandStep {
        let (flex, flex_report) = sanitize_flex(&self.model, &input.flex, &self.last_flex);
        self.flex_totals.accumulate(flex_report);
        self.last_flex = flex;
        let root = input.cart * input.tracker;
        let finite = root
            .translation
            .vector
            .iter()
            .chain(root.rotation.coords.iter())
            .all(|c| c.is_finite());
        let mut frame = HandStep {
            pose: self.visible,
            mode: self.mode,
            touching: Default::default(),
            grasp: self.held.map(|h| h.grasp),
            held: self.held_part_pose(),
            events: Vec::new(),
            pushes: Vec::new(),
            clasp: None,
            segment_checks: 0,
            flex: flex_report,
        };
        if !finite {
            self.rejected_samples += 1;
            return frame;
        }
        let target = HandPose { root, flex };
        let cart_moved = self
            .last_cart
            .is_some_and(|c| moved(&c, &input.cart, self.params.cart_epsilon));
        self.last_cart = Some(input.cart);
        if self
            .held
            .is_some_and(|h| !obstacles.iter().any(|o| o.part == h.part))
        {
            // The caller no longer lists the held part: it is gone from the scene.
            self.release(&mut frame.events);
        }
        let held = self.held.map(|h| (h.part, h.hand_to_part));
        let mut collider = SceneCollider::new(&self.geometry, obstacles, held);

        if cart_moved || self.mode == HandMode::AwaitingFreeHand {
            // The whole hand moves to the tracked root with its fingers as they are; the clasp
            // brings them to the glove's values once it runs again (fingers closed on a held
            // part would otherwise keep the hand from ever being free).
            let moved_hand = HandPose {
                root: target.root,
                flex: self.visible.flex,
            };
            let poses = self.model.segment_poses(&moved_hand.flex);
            frame.segment_checks = SEGMENT_COUNT as u32;
            let free = collider.hand_is_free(&moved_hand.root, &poses);
            self.stats += collider.stats;
            if free {
                self.visible = moved_hand;
                self.mode = if cart_moved {
                    HandMode::Navigating
                } else {
                    HandMode::Clasping
                };
            } else {
                self.mode = HandMode::AwaitingFreeHand;
            }
        } else {
            self.mode = HandMode::Clasping;
            let started = Instant::now();
            let outcome = clasp(
                &self.model,
                &self.plan,
                &self.visible,
                &target,
                &self.params.clasp,
                |s, placement| collider.collisions(s, placement),
            );
            frame.clasp = Some(ClaspRun {
                steps: outcome.steps,
                time: started.elapsed(),
            });
            self.visible = outcome.pose;
            frame.segment_checks = outcome.checks;
            let (touches, analysed) = analyse(
                &self.model,
                &self.params.analysis,
                &self.visible,
                &mut collider,
                &outcome.touching,
                self.held.map(|h| h.part),
                &mut self.contacts,
            );
            self.stats += collider.stats;
            let pushed = (analysed.iter())
                .filter(|a| a.grasp == GraspClass::Push && Some(a.part) != held.map(|h| h.0))
                .map(|a| a.part);
            frame.pushes = pushes(&self.visible.root, &target.root, &touches, pushed);
            frame.touching = touches;
            self.update_hold(&analysed, &mut frame.events);
            frame.grasp = self.held.map(|h| h.grasp).or_else(|| {
                analysed
                    .iter()
                    .map(|a| a.grasp)
                    .max_by_key(|g| g.firmness())
            });
        }
        frame.pose = self.visible;
        frame.mode = self.mode;
        frame.held = self.held_part_pose();
        frame
    }

    /// Grasps the firmest held part after `grasp_frames` frames, releases the held part after
    /// `release_frames` frames without a holding grasp.
    fn update_hold(&mut self, analysed: &[Analysed], events: &mut Vec<GraspEvent>) {
        if let Some(held) = &mut self.held {
            match analysed
                .iter()
                .find(|a| a.part == held.part && a.grasp.holds())
            {
                Some(a) => {
                    held.grasp = a.grasp;
                    self.release_count = 0;
                }
                None => {
                    self.release_count += 1;
                    if self.release_count >= self.params.release_frames {
                        self.release(events);
                    }
                }
            }
            return;
        }
        if let Some(part) = self.released
            && analysed.iter().all(|a| a.part != part)
        {
            self.released = None;
        }
        let Some(best) = analysed
            .iter()
            .filter(|a| a.grasp.holds() && Some(a.part) != self.released)
            .max_by_key(|a| a.grasp.firmness())
        else {
            self.candidate = None;
            return;
        };
        let frames = match self.candidate {
            Some((p, n)) if p == best.part => n + 1,
            _ => 1,
        };
        self.candidate = Some((best.part, frames));
        if frames >= self.params.grasp_frames {
            let hand_to_part = self.visible.root.inv_mul(&best.pose);
            self.held = Some(Held {
                part: best.part,
                hand_to_part,
                grasp: best.grasp,
            });
            self.candidate = None;
            self.release_count = 0;
            events.push(GraspEvent::Grasp {
                part: best.part,
                grasp: best.grasp,
                hand_to_part,
            });
        }
    }

    fn release(&mut self, events: &mut Vec<GraspEvent>) {
        if let Some((part, pose)) = self.held_part_pose() {
            events.push(GraspEvent::Release { part, pose });
            self.released = Some(part);
        }
        self.held = None;
        self.release_count = 0;
    }
}

/// A contact found for a segment and a part, in the part's frame, with the segment's pose in
/// that frame when it was found.
#[derive(Debug, Clone)]
struct CachedContact {
    part: PartId,
    to_object: Isometry3<f64>,
    contact: Option<Contact>,
}

/// The grasp the analysis found on one touched part this frame.
struct Analysed {
    part: PartId,
    grasp: GraspClass,
    /// The part's pose in the world.
    pose: Isometry3<f64>,
}

/// Contacts of the segments touching at the visible hand, and the grasp on every touched part
/// (the held part with the relaxed thresholds that keep a grasp from flickering).
///
/// A segment touches a part when its contact probe reaches the part and either the clasp marked
/// it touching by the paper's flags this frame, or it touched the part in the last frame. The
/// second case keeps a contact that persists without new collisions: a hand holding still on a
/// part, or carrying a held part, which moves with the root and so no longer collides with it.
fn analyse(
    model: &HandModel,
    params: &AnalysisParams,
    visible: &HandPose,
    collider: &mut SceneCollider,
    flagged: &[ObjectSet; SEGMENT_COUNT],
    held: Option<PartId>,
    cache: &mut [Vec<CachedContact>; SEGMENT_COUNT],
) -> ([Vec<SegmentContact>; SEGMENT_COUNT], Vec<Analysed>) {
    let poses = model.segment_poses(&visible.flex);
    let mut per_object: Vec<Vec<Touch>> = vec![Vec::new(); collider.obstacles().len()];
    let mut touched: [Vec<SegmentContact>; SEGMENT_COUNT] = Default::default();
    for (s, flagged) in flagged.iter().enumerate() {
        let segment = &model.segments()[s];
        let still = collider
            .obstacles()
            .iter()
            .enumerate()
            .filter(|(_, o)| {
                cache[s]
                    .iter()
                    .any(|c| c.part == o.part && c.contact.is_some())
            })
            .fold(ObjectSet::EMPTY, |acc, (k, _)| {
                acc.union(ObjectSet::single(k))
            });
        let objects = flagged.union(still);
        let placement = SegmentPlacement {
            root: visible.root,
            local: poses[s],
            flex_valid: false,
        };
        let mut kept = Vec::new();
        for k in objects.iter() {
            let part = collider.obstacles()[k].part;
            let to_object = collider.segment_in_object(k, &placement);
            let cached = cache[s]
                .iter()
                .find(|c| c.part == part && c.to_object == to_object);
            let contact = match cached {
                Some(c) => c.contact.clone(),
                None => collider.contact(s, segment.level, k, &to_object),
            };
            if let Some(contact) = &contact {
                let contact = contact.transformed(&collider.object_pose(k, &visible.root));
                touched[s].push(SegmentContact {
                    part,
                    point: contact.centre(),
                    normal: contact.normal,
                });
                per_object[k].push(Touch {
                    segment: s,
                    finger: segment.finger,
                    level: segment.level,
                    contact,
                });
            }
            kept.push(CachedContact {
                part,
                to_object,
                contact,
            });
        }
        cache[s] = kept;
    }
    let analysed = per_object
        .iter()
        .enumerate()
        .filter_map(|(k, touches)| {
            let pose = collider.object_pose(k, &visible.root);
            let centre = pose * collider.obstacles()[k].geometry.centre_of_mass();
            let part = collider.obstacles()[k].part;
            let thresholds = if held == Some(part) {
                params.for_held()
            } else {
                *params
            };
            classify(touches, &centre, &thresholds).map(|grasp| Analysed { part, grasp, pose })
        })
        .collect();
    (touched, analysed)
}

/// True when two cart poses differ by more than `epsilon` (metres of translation or radians).
fn moved(a: &Isometry3<f64>, b: &Isometry3<f64>, epsilon: f64) -> bool {
    (a.translation.vector - b.translation.vector).norm() > epsilon
        || a.rotation.angle_to(&b.rotation) > epsilon
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasping::analysis::PrecisionKind;
    use crate::grasping::model::tests::right_hand;

    fn hand() -> GraspingHand {
        let rest = HandPose {
            root: Isometry3::identity(),
            flex: [0.0; FLEX_COUNT],
        };
        GraspingHand::new(Arc::new(right_hand()), GraspParams::default(), rest).unwrap()
    }

    fn analysed(part: PartId, grasp: GraspClass) -> Analysed {
        Analysed {
            part,
            grasp,
            pose: Isometry3::translation(0.0, 0.0, -0.05),
        }
    }

    #[test]
    fn grasp_and_release_wait_for_consecutive_frames() {
        let mut hand = hand();
        let params = GraspParams::default();
        let mut events = Vec::new();
        let power = [analysed(3, GraspClass::Power)];
        // Interrupted runs of holding frames do not grasp.
        for _ in 0..params.grasp_frames - 1 {
            hand.update_hold(&power, &mut events);
        }
        hand.update_hold(&[analysed(3, GraspClass::Push)], &mut events);
        for _ in 0..params.grasp_frames - 1 {
            hand.update_hold(&power, &mut events);
        }
        assert!(events.is_empty() && hand.held().is_none());
        hand.update_hold(&power, &mut events);
        assert_eq!(
            events,
            vec![GraspEvent::Grasp {
                part: 3,
                grasp: GraspClass::Power,
                hand_to_part: Isometry3::translation(0.0, 0.0, -0.05),
            }]
        );
        // Short gaps in the grasp do not release; a long one does, once.
        events.clear();
        for _ in 0..3 {
            for _ in 0..params.release_frames - 1 {
                hand.update_hold(&[], &mut events);
            }
            hand.update_hold(
                &[analysed(3, GraspClass::Precision(PrecisionKind::TipPinch))],
                &mut events,
            );
        }
        assert!(events.is_empty());
        assert_eq!(
            hand.held().unwrap().grasp,
            GraspClass::Precision(PrecisionKind::TipPinch)
        );
        for _ in 0..params.release_frames {
            hand.update_hold(&[analysed(3, GraspClass::Push)], &mut events);
        }
        assert_eq!(events.len(), 1);
        assert!(matches!(events[0], GraspEvent::Release { part: 3, .. }));
        assert!(hand.held().is_none());
    }

    #[test]
    fn the_firmest_of_several_touched_parts_is_grasped() {
        let mut hand = hand();
        let mut events = Vec::new();
        let both = [
            analysed(1, GraspClass::Gravity),
            analysed(2, GraspClass::Power),
            analysed(4, GraspClass::Push),
        ];
        for _ in 0..GraspParams::default().grasp_frames {
            hand.update_hold(&both, &mut events);
        }
        assert_eq!(hand.held().map(|h| h.part), Some(2));
    }

    #[test]
    fn bad_samples_are_refused_and_counted() {
        let mut hand = hand();
        let mut input = HandInput {
            cart: Isometry3::identity(),
            tracker: Isometry3::translation(0.0, 0.0, 0.1),
            flex: [0.1; FLEX_COUNT],
        };
        let first = hand.step(&input, &[]);
        assert_eq!(first.mode, HandMode::Clasping);
        input.tracker.translation.x = f64::NAN;
        let refused = hand.step(&input, &[]);
        assert_eq!(refused.pose, first.pose);
        input.tracker.translation.x = 0.0;
        input.flex[5] = f32::NAN;
        input.flex[4] = 3.0;
        let cleaned = hand.step(&input, &[]);
        assert_eq!(
            cleaned.flex,
            FlexReport {
                clamped: 1,
                rejected: 1
            }
        );
        assert_eq!(cleaned.pose.flex[5], f64::from(0.1f32));
        // The clamped target is reached over the next frames, and no further.
        input.flex[5] = 0.1;
        let limit = hand.model().limits()[4].max;
        for _ in 0..100 {
            hand.step(&input, &[]);
        }
        assert_eq!(hand.visible().flex[4], limit);
        let (totals, refused_samples) = hand.input_counts();
        assert_eq!(
            (totals.clamped, totals.rejected, refused_samples),
            (101, 1, 1)
        );
    }
}
