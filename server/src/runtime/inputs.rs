//! The I/O thread's input state: validation and counters of tracker, glove and hand-joints
//! samples, and the latest accepted target of each, as the hand input of the next frame.
//!
//! Tracker samples place the cart, which carries every hand. Hand-joints samples drive the hand
//! of their side. The tracker's hand pose and the glove's flex values drive the scene's first
//! hand until it has had a hand-joints sample; then it follows its joints (its root in the
//! cart's frame and flex values from its latest tracked joints sample). Joints take the hand
//! over for good rather than whichever stream spoke last, so that a tracker that only navigates
//! the cart never snaps a joints-driven hand to its own hand pose. A second hand without joints
//! yet stays parked at the cart's origin, untracked.
//!
//! A joints-driven hand is untracked when its latest sample says so, or when that sample is
//! older than the scene's `params.tracking.lost_after`; it keeps its last tracked target, and
//! once untracked for `params.tracking.grace` after its last tracked sample, it lets go of what
//! it holds. The [`TrackingClock`] says what "now" and "older" mean: sample time in lockstep and
//! offline, so that a replay gives the same outcome every time; the system clock in a
//! free-running server, so that a hand whose samples simply stop (a headset taken off, a browser
//! closed) is noticed while no other input comes ([`Inputs::tick`]).

use std::time::Duration;

use nalgebra::Isometry3;
use vas_protocol::{
    FLEX_COUNT, GloveSample, GloveTarget, HandJointsSample, HandSide, InputRejection, InputStamp,
    InputStats, TrackerSample, TrackerTarget, wall_clock_ns,
};

use super::hand_joints::{JointsHand, JointsOutcome, JointsRejection, JointsTarget};
use crate::grasping::retarget::JointsError;
use crate::grasping::{HandInput, HandModel};
use crate::scene::TrackingParams;
use crate::simulation::frames::{HandTarget, InputFrame, Stamps};

/// The clock that times a joints-driven hand's tracking.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrackingClock {
    /// The samples' own timestamps: now is the newest timestamp among the accepted samples of
    /// every stream.
    #[default]
    SampleTime,
    /// The system clock when a sample is taken in, moved on by [`Inputs::tick`] while none
    /// comes.
    Arrival,
}

/// The latest validated targets and the input counters.
#[derive(Debug, Default)]
pub struct Inputs {
    tracker: Option<TrackerTarget>,
    glove: Option<GloveTarget>,
    /// The scene's hands, in its order, as hand-joints samples drive them (`None` for a model
    /// the retargeting cannot take); empty without hand models.
    hands: Vec<Option<JointsHand>>,
    /// The latest accepted hand-joints sample, of any hand.
    joints: InputStamp,
    /// Now on `clock`: the newest time an accepted sample, of any stream, was taken in (or a
    /// tick).
    now_ns: u64,
    clock: TrackingClock,
    tracking: TrackingParams,
    stats: InputStats,
}

impl Inputs {
    /// The input state of a scene with the hand `models` (in the scene's order) and the
    /// `tracking` parameters.
    pub fn for_hands<'a>(
        models: impl IntoIterator<Item = &'a HandModel>,
        tracking: TrackingParams,
    ) -> Inputs {
        Inputs {
            hands: models.into_iter().map(JointsHand::new).collect(),
            tracking,
            ..Inputs::default()
        }
    }

    /// Times the hands' tracking by `clock` from now on (sample time until told).
    pub fn set_clock(&mut self, clock: TrackingClock) {
        self.clock = clock;
    }

    /// When a sample stamped `timestamp_ns` is taken in now, on the tracking clock.
    fn time_of(&self, timestamp_ns: u64) -> u64 {
        match self.clock {
            TrackingClock::SampleTime => timestamp_ns,
            TrackingClock::Arrival => wall_clock_ns(),
        }
    }

    /// Moves now on to `at_ns`, when an accepted sample was taken in.
    fn taken_at(&mut self, at_ns: u64) {
        self.now_ns = self.now_ns.max(at_ns);
    }

    /// On the arrival clock, moves now on to `now_ns` (the system clock) while no sample comes;
    /// whether that changed a hand's tracking (lost, or letting go), so that a frame must say
    /// so. On sample time only samples move time on: always false.
    pub fn tick(&mut self, now_ns: u64) -> bool {
        if self.clock != TrackingClock::Arrival || now_ns <= self.now_ns {
            return false;
        }
        let before = self.tracking_states();
        self.now_ns = now_ns;
        self.tracking_states() != before
    }

    /// Each joints-driven hand's tracking now: whether it is tracked and whether it lets go.
    fn tracking_states(&self) -> Vec<Option<(bool, bool)>> {
        (self.hands.iter().flatten())
            .map(|hand| hand.target().map(|target| self.tracking_of(target)))
            .collect()
    }

    /// Input counters since the server started.
    pub fn stats(&self) -> InputStats {
        self.stats
    }

    /// Validates a tracker sample and, if valid, makes it the hand root target; counts it
    /// either way.
    pub fn apply_tracker(&mut self, sample: &TrackerSample) -> Result<(), InputRejection> {
        match sample.validate() {
            Ok(target) => {
                self.stats.tracker_accepted += 1;
                self.tracker = Some(target);
                self.taken_at(self.time_of(sample.timestamp_ns));
                Ok(())
            }
            Err(rejection) => {
                match rejection {
                    InputRejection::NonFinite { .. } => self.stats.tracker_rejected_non_finite += 1,
                    InputRejection::NotUnitQuaternion { .. } => {
                        self.stats.tracker_rejected_quaternion += 1;
                    }
                    InputRejection::OutOfRange { .. } => {
                        self.stats.tracker_rejected_out_of_range += 1;
                    }
                }
                Err(rejection)
            }
        }
    }

    /// Validates a glove sample and, if finite, makes its clamped flex values the finger target;
    /// counts it, and the values clamped, either way. Returns the bits of the clamped values.
    pub fn apply_glove(&mut self, sample: &GloveSample) -> Result<u32, InputRejection> {
        match sample.validate() {
            Ok(target) => {
                self.stats.glove_accepted += 1;
                if target.clamped != 0 {
                    self.stats.glove_samples_clamped += 1;
                    self.stats.glove_values_clamped += u64::from(target.clamped_count());
                }
                self.glove = Some(target);
                self.taken_at(self.time_of(sample.timestamp_ns));
                Ok(target.clamped)
            }
            Err(rejection) => {
                self.stats.glove_rejected_non_finite += 1;
                Err(rejection)
            }
        }
    }

    /// Validates a hand-joints sample and, if it is a hand of the scene, retargets it into the
    /// hand's target (or notes that the hand is untracked); counts it either way.
    pub fn apply_hand_joints(
        &mut self,
        sample: &HandJointsSample,
    ) -> Result<JointsOutcome, JointsRejection> {
        let side = HandSide::try_from(sample.side).ok();
        let at_ns = self.time_of(sample.timestamp_ns);
        let hand = (self.hands.iter_mut().flatten()).find(|hand| Some(hand.side()) == side);
        let outcome = match hand {
            Some(hand) => hand.apply(sample, at_ns),
            None => Err(JointsRejection::NoSuchHand { side: sample.side }),
        };
        if outcome.is_ok() {
            self.joints = sample.stamp();
            self.taken_at(at_ns);
        }
        let stats = &mut self.stats;
        let counter = match &outcome {
            Ok(JointsOutcome::Tracked) => &mut stats.joints_accepted,
            Ok(JointsOutcome::Untracked) => &mut stats.joints_untracked,
            Err(JointsRejection::NoSuchHand { .. }) => &mut stats.joints_rejected_no_such_hand,
            Err(JointsRejection::Joints(error)) => match error {
                JointsError::NonFinite { .. } => &mut stats.joints_rejected_non_finite,
                JointsError::NotUnit { .. } => &mut stats.joints_rejected_quaternion,
                JointsError::OutOfRange { .. } => &mut stats.joints_rejected_out_of_range,
                // A joint not valid makes the hand untracked, never a rejection.
                JointsError::OutOfOrder { .. }
                | JointsError::BoneLength { .. }
                | JointsError::NotValid { .. } => &mut stats.joints_rejected_anatomy,
            },
        };
        *counter += 1;
        outcome
    }

    /// The next frame's input: the latest targets (the identity cart and root and a flat hand
    /// before the first sample of a stream), stamped with the samples they come from.
    pub fn frame(&self) -> InputFrame {
        let cart = self
            .tracker
            .map_or_else(Isometry3::identity, |target| target.cart);
        let hands = if self.hands.is_empty() {
            vec![self.glove_driven(cart)]
        } else {
            (self.hands.iter().enumerate())
                .map(|(index, hand)| {
                    let joints = hand.as_ref().and_then(JointsHand::target);
                    let stamp = joints.map_or_else(InputStamp::default, |target| target.stamp);
                    match joints.and_then(|target| target.pose.map(|pose| (target, pose))) {
                        Some((target, (tracker, flex))) => {
                            let (tracked, let_go) = self.tracking_of(target);
                            HandTarget {
                                input: HandInput {
                                    cart,
                                    tracker,
                                    flex,
                                },
                                joints: stamp,
                                tracked,
                                let_go,
                            }
                        }
                        // Until its first tracked joints, the first hand is the glove's; a
                        // hand whose joints so far all said "not tracked" is not tracked.
                        None if index == 0 => HandTarget {
                            joints: stamp,
                            tracked: joints.is_none(),
                            ..self.glove_driven(cart)
                        },
                        None => HandTarget {
                            input: HandInput {
                                cart,
                                tracker: Isometry3::identity(),
                                flex: [0.0; FLEX_COUNT],
                            },
                            joints: stamp,
                            tracked: false,
                            let_go: false,
                        },
                    }
                })
                .collect()
        };
        InputFrame {
            stamps: Stamps {
                tracker: self.tracker.map_or_else(InputStamp::default, |t| t.stamp),
                glove: self.glove.map_or_else(InputStamp::default, |g| g.stamp),
                joints: self.joints,
            },
            hands,
        }
    }

    /// The hand as tracker and glove drive it, on `cart`.
    fn glove_driven(&self, cart: Isometry3<f64>) -> HandTarget {
        HandTarget::tracking(HandInput {
            cart,
            tracker: (self.tracker).map_or_else(Isometry3::identity, |target| target.hand),
            flex: self.glove.map_or([0.0; FLEX_COUNT], |target| target.flex),
        })
    }

    /// Whether a joints-driven hand with `target` is tracked now, and whether it has been
    /// untracked long enough to let go.
    fn tracking_of(&self, target: &JointsTarget) -> (bool, bool) {
        let seconds = |ns: u64| Duration::from_nanos(self.now_ns.saturating_sub(ns)).as_secs_f64();
        let tracked = target.tracked && seconds(target.at_ns) <= self.tracking.lost_after;
        let let_go = !tracked
            && target
                .tracked_ns
                .is_none_or(|ns| seconds(ns) >= self.tracking.grace);
        (tracked, let_go)
    }

    /// Forgets the targets (a reset, or another scene) and takes the hand `models` and the
    /// `tracking` parameters; the counters and the clock go on.
    pub fn restart<'a>(
        &mut self,
        models: impl IntoIterator<Item = &'a HandModel>,
        tracking: TrackingParams,
    ) {
        *self = Inputs {
            stats: self.stats,
            clock: self.clock,
            ..Inputs::for_hands(models, tracking)
        };
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion, Vector3};
    use vas_protocol::{FLEX_LIMITS_RAD, WirePose};

    use super::*;
    use crate::grasping::Side;
    use crate::grasping::model::tests::right_hand;
    use crate::grasping::retarget::{Joint, Retargeter};
    use crate::runtime::hand_joints::tests::captured;
    use crate::runtime::hand_joints::wire_joints;

    fn tracker(seq: u64, hand: WirePose, cart: WirePose) -> TrackerSample {
        TrackerSample {
            seq,
            timestamp_ns: 1_000 + seq,
            hand,
            cart,
            sensor_id: 0,
        }
    }

    fn at(x: f64, y: f64, z: f64) -> WirePose {
        WirePose {
            position: [x, y, z],
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn accepted_tracker_samples_set_the_hand_root_in_the_world() {
        let mut inputs = Inputs::default();
        let before = inputs.frame();
        assert_eq!(before.stamps, Stamps::default());
        assert_eq!(
            before.hands[0].input.cart * before.hands[0].input.tracker,
            Isometry3::identity()
        );
        inputs
            .apply_tracker(&tracker(3, at(0.1, 0.0, 0.0), at(0.0, 0.0, 1.0)))
            .expect("valid");
        let frame = inputs.frame();
        assert_eq!(
            frame.stamps.tracker,
            InputStamp {
                seq: 3,
                timestamp_ns: 1_003
            }
        );
        assert_eq!(frame.stamps.glove, InputStamp::default());
        let root = frame.hands[0].input.cart * frame.hands[0].input.tracker;
        assert!((root.translation.vector - Vector3::new(0.1, 0.0, 1.0)).norm() < 1e-12);
        assert_eq!(frame.hands[0].input.flex, [0.0; FLEX_COUNT]);
    }

    #[test]
    fn rejected_tracker_samples_are_counted_and_keep_the_previous_target() {
        let mut inputs = Inputs::default();
        let turned = Translation3::new(0.0, 0.2, 0.0)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
        inputs
            .apply_tracker(&tracker(1, turned.into(), WirePose::IDENTITY))
            .expect("valid");
        let mut nan = tracker(2, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        nan.cart.position[2] = f64::NAN;
        assert!(inputs.apply_tracker(&nan).is_err());
        let mut stretched = tracker(3, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        stretched.hand.rotation = [0.0, 0.0, 0.0, 1.5];
        assert!(inputs.apply_tracker(&stretched).is_err());

        let stats = inputs.stats();
        assert_eq!(
            (
                stats.tracker_accepted,
                stats.tracker_rejected_non_finite,
                stats.tracker_rejected_quaternion
            ),
            (1, 1, 1)
        );
        let frame = inputs.frame();
        assert_eq!(frame.stamps.tracker.seq, 1);
        let root = frame.hands[0].input.cart * frame.hands[0].input.tracker;
        assert!((root.translation.vector - turned.translation.vector).norm() < 1e-12);
        assert!(root.rotation.angle_to(&turned.rotation) < 1e-9);
    }

    #[test]
    fn positions_whose_combination_would_overflow_are_rejected_and_counted() {
        // Each coordinate finite, their sum infinite: the combined root was once published as
        // [null, null, null].
        let mut inputs = Inputs::default();
        inputs
            .apply_tracker(&tracker(1, at(0.1, 0.0, 1.0), WirePose::IDENTITY))
            .expect("valid");
        let far = tracker(2, at(1e308, 1e308, 1e308), at(1e308, 1e308, 1e308));
        assert!(matches!(
            inputs.apply_tracker(&far),
            Err(InputRejection::OutOfRange { value, .. }) if value == 1e308
        ));
        let stats = inputs.stats();
        assert_eq!(
            (stats.tracker_accepted, stats.tracker_rejected_out_of_range),
            (1, 1)
        );
        assert_eq!(stats.rejected(), 1);
        let root = inputs.frame().hands[0].input.cart * inputs.frame().hands[0].input.tracker;
        assert!(root.translation.vector.iter().all(|c| c.is_finite()));
        assert!((root.translation.vector - Vector3::new(0.1, 0.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn glove_samples_are_clamped_and_counted() {
        let mut inputs = Inputs::default();
        let mut flex = [0.1f32; FLEX_COUNT];
        flex[6] = 2.0;
        flex[20] = -3.0;
        let sample = GloveSample {
            seq: 4,
            timestamp_ns: 40,
            flex,
        };
        assert_eq!(inputs.apply_glove(&sample), Ok((1 << 6) | (1 << 20)));
        let mut broken = sample;
        broken.flex[0] = f32::NAN;
        assert!(inputs.apply_glove(&broken).is_err());
        let stats = inputs.stats();
        assert_eq!(stats.glove_accepted, 1);
        assert_eq!(stats.glove_rejected_non_finite, 1);
        assert_eq!(stats.glove_samples_clamped, 1);
        assert_eq!(stats.glove_values_clamped, 2);
        assert_eq!(stats.rejected(), 1);
        let frame = inputs.frame();
        assert_eq!(
            frame.stamps.glove,
            InputStamp {
                seq: 4,
                timestamp_ns: 40
            }
        );
        assert_eq!(frame.hands[0].input.flex[6], FLEX_LIMITS_RAD[6].1);
        assert_eq!(frame.hands[0].input.flex[20], FLEX_LIMITS_RAD[20].0);
        assert_eq!(frame.hands[0].input.flex[1], 0.1);
    }

    #[test]
    fn forgetting_the_targets_keeps_the_counters() {
        let mut inputs = Inputs::default();
        inputs
            .apply_tracker(&tracker(8, at(1.0, 2.0, 3.0), WirePose::IDENTITY))
            .expect("valid");
        inputs.restart([], TrackingParams::default());
        let frame = inputs.frame();
        assert_eq!(frame.stamps, Stamps::default());
        assert_eq!(frame.hands[0].input.tracker, Isometry3::identity());
        assert_eq!(inputs.stats().tracker_accepted, 1);
    }

    /// A right hand's pinch, as a wire sample numbered `seq`.
    fn pinch(seq: u64) -> HandJointsSample {
        wire_joints(&captured("webxr_pinch.json", Side::Right), seq, 100 + seq)
    }

    #[test]
    fn hand_joints_drive_the_hand_and_the_tracker_keeps_the_cart() {
        let model = right_hand();
        let mut inputs = Inputs::for_hands([&model], TrackingParams::default());
        assert_eq!(
            inputs.apply_hand_joints(&pinch(1)),
            Ok(JointsOutcome::Tracked)
        );
        let fit = Retargeter::new(model)
            .expect("the right hand retargets")
            .fit(&captured("webxr_pinch.json", Side::Right))
            .expect("the pinch fits");
        let frame = inputs.frame();
        assert_eq!(
            frame.stamps.joints,
            InputStamp {
                seq: 1,
                timestamp_ns: 101
            }
        );
        assert!(frame.hands[0].tracked);
        assert_eq!(frame.hands[0].input.tracker, fit.root);
        assert_eq!(frame.hands[0].input.flex, fit.flex.map(|v| v as f32));

        // A tracker sample moves the cart; the hand stays with its joints.
        let cart = at(1.0, 2.0, 0.0);
        inputs
            .apply_tracker(&tracker(1, at(0.5, 0.5, 0.5), cart))
            .expect("valid");
        let frame = inputs.frame();
        assert_eq!(frame.hands[0].input.cart, cart.to_isometry());
        assert_eq!(frame.hands[0].input.tracker, fit.root);
        assert_eq!(frame.stamps.tracker.seq, 1);
        let stats = inputs.stats();
        assert_eq!((stats.joints_accepted, stats.rejected()), (1, 0));
    }

    #[test]
    fn impossible_hand_joints_are_rejected_counted_and_keep_the_target() {
        let mut inputs = Inputs::for_hands([&right_hand()], TrackingParams::default());
        inputs.apply_hand_joints(&pinch(1)).expect("a hand");
        let before = inputs.frame();
        let at = |joint: Joint| joint.index();
        type Edit<'a> = (&'a str, &'a dyn Fn(&mut HandJointsSample));
        let edits: [Edit; 7] = [
            ("NaN", &|s| {
                s.joints[at(Joint::RingDistal)].position[1] = f64::NAN
            }),
            ("radius", &|s| {
                s.joints[at(Joint::IndexTip)].radius = f32::INFINITY
            }),
            ("stretched quaternion", &|s| {
                s.joints[at(Joint::ThumbDistal)].rotation[3] *= 1.5;
            }),
            ("far away", &|s| {
                s.joints[at(Joint::Wrist)].position[0] = 2e6
            }),
            ("tip behind its joint", &|s| {
                s.joints.swap(at(Joint::IndexDistal), at(Joint::IndexTip));
            }),
            ("long bone", &|s| {
                s.joints[at(Joint::MiddleTip)].position[2] += 0.3;
            }),
            ("left side", &|s| s.side = HandSide::Left as u32),
        ];
        for (seq, (what, edit)) in (2..).zip(edits) {
            let mut sample = pinch(seq);
            edit(&mut sample);
            assert!(inputs.apply_hand_joints(&sample).is_err(), "{what}");
        }
        let mut no_side = pinch(9);
        no_side.side = 7;
        assert_eq!(
            inputs.apply_hand_joints(&no_side),
            Err(JointsRejection::NoSuchHand { side: 7 })
        );
        let stats = inputs.stats();
        assert_eq!(
            [
                stats.joints_rejected_non_finite,
                stats.joints_rejected_quaternion,
                stats.joints_rejected_out_of_range,
                stats.joints_rejected_anatomy,
                stats.joints_rejected_no_such_hand,
            ],
            [2, 1, 1, 2, 2]
        );
        assert_eq!(stats.rejected(), 8);
        assert_eq!(stats.joints_accepted, 1);
        assert_eq!(inputs.frame(), before);
    }

    #[test]
    fn a_scene_without_a_hand_takes_no_hand_joints() {
        let mut inputs = Inputs::default();
        assert_eq!(
            inputs.apply_hand_joints(&pinch(1)),
            Err(JointsRejection::NoSuchHand { side: 0 })
        );
        assert_eq!(inputs.stats().joints_rejected_no_such_hand, 1);
        assert_eq!(inputs.frame().stamps, Stamps::default());
    }

    #[test]
    fn an_untracked_hand_keeps_its_target_and_says_so() {
        let mut inputs = Inputs::for_hands([&right_hand()], TrackingParams::default());
        let mut never = pinch(1);
        never.joints.iter_mut().for_each(|joint| joint.flags = 0);
        assert_eq!(
            inputs.apply_hand_joints(&never),
            Ok(JointsOutcome::Untracked)
        );
        assert!(!inputs.frame().hands[0].tracked, "never tracked yet");
        inputs.apply_hand_joints(&pinch(1)).expect("a hand");
        let tracked = inputs.frame();
        let mut lost = pinch(2);
        for joint in &mut lost.joints {
            joint.flags = 0;
        }
        assert_eq!(
            inputs.apply_hand_joints(&lost),
            Ok(JointsOutcome::Untracked)
        );
        let frame = inputs.frame();
        assert!(!frame.hands[0].tracked);
        assert_eq!(frame.stamps.joints.seq, 2);
        assert_eq!(frame.hands[0].input, tracked.hands[0].input);
        let stats = inputs.stats();
        assert_eq!((stats.joints_untracked, stats.rejected()), (2, 0));
        // Tracked again.
        inputs.apply_hand_joints(&pinch(3)).expect("a hand");
        assert!(inputs.frame().hands[0].tracked);
    }

    #[test]
    fn a_restart_forgets_the_joints_and_keeps_the_counters() {
        let model = right_hand();
        let mut inputs = Inputs::for_hands([&model], TrackingParams::default());
        inputs.apply_hand_joints(&pinch(1)).expect("a hand");
        inputs.restart([&model], TrackingParams::default());
        let frame = inputs.frame();
        assert_eq!(frame.stamps, Stamps::default());
        assert_eq!(frame.hands[0].input.tracker, Isometry3::identity());
        assert_eq!(inputs.stats().joints_accepted, 1);
    }

    #[test]
    fn two_hands_take_the_glove_and_their_own_joints() {
        let right = right_hand();
        let left = right.mirrored();
        let mut inputs = Inputs::for_hands([&right, &left], TrackingParams::default());
        let glove = GloveSample {
            seq: 1,
            timestamp_ns: 1,
            flex: [0.2; FLEX_COUNT],
        };
        inputs.apply_glove(&glove).expect("valid");
        let frame = inputs.frame();
        assert_eq!(frame.hands.len(), 2);
        assert_eq!(frame.hands[0].input.flex, [0.2; FLEX_COUNT]);
        assert!(frame.hands[0].tracked);
        assert!(!frame.hands[1].tracked, "no input for the left hand yet");
        let sample = wire_joints(&captured("webxr_pinch.json", Side::Left), 1, 5);
        assert_eq!(
            inputs.apply_hand_joints(&sample),
            Ok(JointsOutcome::Tracked)
        );
        let frame = inputs.frame();
        assert_eq!(frame.hands[0].input.flex, [0.2; FLEX_COUNT]);
        assert!(frame.hands[1].tracked);
        assert_eq!(frame.hands[1].joints, sample.stamp());
        assert_eq!(frame.hands[0].joints, InputStamp::default());
        assert_eq!(frame.stamps.joints, sample.stamp());
        // A right-hand sample now drives the first hand instead of the glove.
        assert_eq!(
            inputs.apply_hand_joints(&pinch(2)),
            Ok(JointsOutcome::Tracked)
        );
        assert_ne!(inputs.frame().hands[0].input.flex, [0.2; FLEX_COUNT]);
    }

    #[test]
    fn a_joints_hand_untracked_or_silent_is_lost_and_lets_go_after_the_grace() {
        let tracking = TrackingParams {
            lost_after: 0.1,
            grace: 0.5,
        };
        let mut inputs = Inputs::for_hands([&right_hand()], tracking);
        const MS: u64 = 1_000_000;
        let joints = |seq: u64, ms: u64, tracked: bool| {
            let mut sample = pinch(seq);
            sample.timestamp_ns = ms * MS;
            if !tracked {
                sample.joints.iter_mut().for_each(|joint| joint.flags = 0);
            }
            sample
        };
        let state = |inputs: &Inputs| {
            let hand = inputs.frame().hands[0];
            (hand.tracked, hand.let_go)
        };
        inputs
            .apply_hand_joints(&joints(1, 0, true))
            .expect("a hand");
        assert_eq!(state(&inputs), (true, false));
        let pose = inputs.frame().hands[0].input;
        // Untracked samples: lost at once, letting go 0.5 s after the last tracked one.
        for (seq, ms, let_go) in [(2, 200, false), (3, 499, false), (4, 500, true)] {
            inputs
                .apply_hand_joints(&joints(seq, ms, false))
                .expect("untracked");
            assert_eq!(state(&inputs), (false, let_go), "at {ms} ms");
            assert_eq!(inputs.frame().hands[0].input, pose, "the hand stays");
        }
        inputs
            .apply_hand_joints(&joints(5, 600, true))
            .expect("a hand");
        assert_eq!(state(&inputs), (true, false), "tracked again");
        // Silence: other samples move time on.
        for (seq, ms, expected) in [
            (1, 690, (true, false)),
            (2, 750, (false, false)),
            (3, 1100, (false, true)),
        ] {
            let mut sample = tracker(seq, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
            sample.timestamp_ns = ms * MS;
            inputs.apply_tracker(&sample).expect("valid");
            assert_eq!(state(&inputs), expected, "at {ms} ms");
        }
    }

    #[test]
    fn on_the_arrival_clock_a_silent_hand_is_lost_by_ticks_alone() {
        const MS: u64 = 1_000_000;
        let mut inputs = Inputs::for_hands([&right_hand()], TrackingParams::default());
        inputs.set_clock(TrackingClock::Arrival);
        let start = wall_clock_ns();
        // Stamped long ago: on the arrival clock only when it came counts.
        inputs.apply_hand_joints(&pinch(1)).expect("a hand");
        let state = |inputs: &Inputs| {
            let hand = inputs.frame().hands[0];
            (hand.tracked, hand.let_go)
        };
        assert_eq!(state(&inputs), (true, false));
        assert!(!inputs.tick(start + 50 * MS), "still tracked");
        assert!(inputs.tick(start + 150 * MS), "lost");
        assert_eq!(state(&inputs), (false, false));
        assert!(!inputs.tick(start + 300 * MS), "within the grace");
        assert!(inputs.tick(start + 600 * MS), "the grace is over");
        assert_eq!(state(&inputs), (false, true));
        assert!(!inputs.tick(start + 400 * MS), "time never goes back");
        inputs.restart([&right_hand()], TrackingParams::default());
        inputs.apply_hand_joints(&pinch(2)).expect("a hand");
        assert!(
            inputs.tick(wall_clock_ns() + 150 * MS),
            "the clock outlives a restart"
        );
    }

    #[test]
    fn on_sample_time_ticks_change_nothing() {
        let mut inputs = Inputs::for_hands([&right_hand()], TrackingParams::default());
        inputs.apply_hand_joints(&pinch(1)).expect("a hand");
        assert!(!inputs.tick(u64::MAX));
        assert!(inputs.frame().hands[0].tracked);
    }
}
