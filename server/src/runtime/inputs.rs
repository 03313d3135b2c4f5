//! The I/O thread's input state: validation and counters of tracker, glove and hand-joints
//! samples, and the latest accepted target of each, as the hand input of the next frame.
//!
//! Every sample names its user and side, and drives that hand; a sample naming a user or side
//! the scene has no hand for is rejected and counted. Tracker samples also place their user's
//! cart, which carries every hand of that user. A hand's tracker pose and glove flex values drive
//! it until it has had a hand-joints sample; then it follows its joints (its root in the cart's
//! frame and flex values from its latest tracked joints sample). Joints take the hand over for
//! good rather than whichever stream spoke last, so that a tracker that only navigates the cart
//! never snaps a joints-driven hand to its own hand pose. Each user's first hand is tracked by
//! tracker and glove from the start (at the cart's origin before any sample, as a single glove
//! hand always was); a user's second hand without input yet stays parked at the cart's origin,
//! untracked.
//!
//! A joints-driven hand is untracked when its latest sample says so, or when that sample is
//! older than the scene's `params.tracking.lost_after`; it keeps its last tracked target, and
//! once untracked for `params.tracking.grace` after its last tracked sample, it lets go of what
//! it holds. The [`TrackingClock`] says what "now" and "older" mean: sample time in lockstep and
//! offline, so that a replay gives the same outcome every time; the system clock in a
//! free-running server, so that a hand whose samples simply stop (a headset taken off, a browser
//! closed) is noticed while no other input comes ([`Inputs::tick`]).
//!
//! Tracked input is smoothed by the scene's One Euro filter (`params.tracking.filter`): each
//! joints-driven hand's retargeted root and flex values ([`JointsHand`]), and each hand's
//! tracker root. Not the cart: it navigates, carries every hand of its user, and comes from a
//! device that is not hand tracking, so smoothing it would only make the hands trail a moving
//! cart. Nor the glove's flex values, measured by bend sensors rather than fitted to noisy
//! joints. A sample whose timestamp is not after its stream's previous one restarts the stream's
//! filter from it and is counted ([`Inputs::filter_restarts`]).

use std::time::Duration;

use nalgebra::Isometry3;
use vas_protocol::{
    FLEX_COUNT, GloveSample, HandJointsSample, HandSide, InputRejection, InputStamp, InputStats,
    MAX_TIMESTAMP_AHEAD_NS, TrackerSample, TrackerTarget, wall_clock_ns,
};

use super::hand_joints::{JointsHand, JointsOutcome, JointsRejection, JointsTarget};
use crate::grasping::retarget::JointsError;
use crate::grasping::{HandInput, HandModel};
use crate::scene::TrackingParams;
use crate::simulation::filter::{Passage, Sample, TimeFault};
use crate::simulation::frames::{HandTarget, InputFrame, Stamps};

mod hand;

use hand::HandInputs;

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
#[derive(Debug)]
pub struct Inputs {
    /// The scene's hands, in its order (grouped by user); in a scene without hand models, one:
    /// the first user's right hand, where tracker and glove put it.
    hands: Vec<HandInputs>,
    /// Each user's cart, from their latest accepted tracker sample.
    carts: Vec<Option<Isometry3<f64>>>,
    /// The latest accepted sample of each stream, of any hand.
    stamps: Stamps,
    /// Now on `clock`: the newest time an accepted sample, of any stream, was taken in (or a
    /// tick).
    now_ns: u64,
    clock: TrackingClock,
    tracking: TrackingParams,
    stats: InputStats,
    /// Samples whose stream's filter restarted for a timestamp not after the previous one's.
    filter_restarts: u64,
}

impl Default for Inputs {
    /// The input state of a scene without hand models.
    fn default() -> Self {
        Inputs::for_hands([], TrackingParams::default())
    }
}

impl Inputs {
    /// The input state of a scene with the hand `models`, each with its user's index (in the
    /// scene's order), and the `tracking` parameters.
    pub fn for_hands<'a>(
        models: impl IntoIterator<Item = (u32, &'a HandModel)>,
        tracking: TrackingParams,
    ) -> Inputs {
        let mut hands: Vec<HandInputs> = (models.into_iter())
            .map(|(user, model)| HandInputs::of_model(user, model, &tracking))
            .collect();
        if hands.is_empty() {
            hands.push(HandInputs::without_model(0, HandSide::Right, &tracking));
        }
        let users = hands.iter().map(|hand| hand.user as usize + 1).max();
        Inputs {
            carts: vec![None; users.unwrap_or(1)],
            hands,
            stamps: Stamps::default(),
            now_ns: 0,
            clock: TrackingClock::default(),
            tracking,
            stats: InputStats::default(),
            filter_restarts: 0,
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

    /// Refuses a sample stamped more than [`MAX_TIMESTAMP_AHEAD_NS`] beyond the system clock,
    /// on either tracking clock: on sample time it would move now far ahead, and every later
    /// sample of a hand would be older than `lost_after`, untracked until a reset.
    fn not_ahead(&self, timestamp_ns: u64) -> Result<(), InputRejection> {
        let ahead_ns = timestamp_ns.saturating_sub(wall_clock_ns());
        if ahead_ns > MAX_TIMESTAMP_AHEAD_NS {
            return Err(InputRejection::Ahead { ahead_ns });
        }
        Ok(())
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
        (self.hands.iter().filter_map(|hand| hand.joints.as_ref()))
            .map(|hand| hand.target().map(|target| self.tracking_of(target)))
            .collect()
    }

    /// Input counters since the server started.
    pub fn stats(&self) -> InputStats {
        self.stats
    }

    /// Samples, since the server started, whose timestamp was not after their stream's previous
    /// one, so that the stream's filter started afresh from them.
    pub fn filter_restarts(&self) -> u64 {
        self.filter_restarts
    }

    /// Counts a filter restart for a faulty timestamp of `stream`.
    fn count_restart(&mut self, stream: &'static str, fault: TimeFault) {
        self.filter_restarts += 1;
        tracing::debug!(stream, %fault, "the input filter restarted");
    }

    /// The index of the hand of `user` and `side`, or why there is none.
    fn hand_of(&self, user: u32, side: u32) -> Result<usize, InputRejection> {
        if user as usize >= self.carts.len() {
            return Err(InputRejection::NoSuchUser { user });
        }
        let side_code = HandSide::try_from(side).ok();
        (self.hands.iter())
            .position(|hand| hand.user == user && Some(hand.side) == side_code)
            .ok_or(InputRejection::NoSuchHand { user, side })
    }

    /// The tracker `target` for hand `index` with its hand root smoothed by that hand's filter.
    fn smooth_tracker(
        &mut self,
        index: usize,
        mut target: TrackerTarget,
        timestamp_ns: u64,
    ) -> Result<TrackerTarget, InputRejection> {
        let raw = Sample {
            root: target.hand,
            values: [],
        };
        let filtered = (self.hands[index].tracker_filter)
            .apply_stamped(timestamp_ns, raw)
            .map_err(|_| InputRejection::NonFinite { field: "hand" })?;
        if let Passage::Restarted(fault) = filtered.passage {
            self.count_restart("tracker", fault);
        }
        target.hand = filtered.sample.root;
        Ok(target)
    }

    /// Validates a tracker sample and, if valid, makes it the root target of its user's hand of
    /// its side and its cart that user's; counts it either way.
    pub fn apply_tracker(&mut self, sample: &TrackerSample) -> Result<(), InputRejection> {
        let validated = (self.not_ahead(sample.timestamp_ns))
            .and_then(|()| self.hand_of(sample.user, sample.side))
            .and_then(|index| Ok((index, sample.validate()?)));
        let smoothed = validated.and_then(|(index, target)| {
            Ok((
                index,
                self.smooth_tracker(index, target, sample.timestamp_ns)?,
            ))
        });
        match smoothed {
            Ok((index, target)) => {
                self.stats.tracker_accepted += 1;
                self.hands[index].tracker = Some(target);
                self.carts[sample.user as usize] = Some(target.cart);
                self.stamps.tracker = target.stamp;
                self.taken_at(self.time_of(sample.timestamp_ns));
                Ok(())
            }
            Err(rejection) => {
                let stats = &mut self.stats;
                *match rejection {
                    InputRejection::NonFinite { .. } => &mut stats.tracker_rejected_non_finite,
                    InputRejection::NotUnitQuaternion { .. } => {
                        &mut stats.tracker_rejected_quaternion
                    }
                    InputRejection::OutOfRange { .. } => &mut stats.tracker_rejected_out_of_range,
                    InputRejection::Ahead { .. } => &mut stats.rejected_ahead,
                    InputRejection::NoSuchUser { .. } => &mut stats.rejected_no_such_user,
                    InputRejection::NoSuchHand { .. } => &mut stats.rejected_no_such_hand,
                } += 1;
                Err(rejection)
            }
        }
    }

    /// Validates a glove sample and, if finite, makes its clamped flex values the finger target
    /// of its user's hand of its side; counts it, and the values clamped, either way. Returns
    /// the bits of the clamped values.
    pub fn apply_glove(&mut self, sample: &GloveSample) -> Result<u32, InputRejection> {
        let validated = (self.not_ahead(sample.timestamp_ns))
            .and_then(|()| self.hand_of(sample.user, sample.side))
            .and_then(|index| Ok((index, sample.validate()?)));
        match validated {
            Ok((index, target)) => {
                self.stats.glove_accepted += 1;
                if target.clamped != 0 {
                    self.stats.glove_samples_clamped += 1;
                    self.stats.glove_values_clamped += u64::from(target.clamped_count());
                }
                self.hands[index].glove = Some(target);
                self.stamps.glove = target.stamp;
                self.taken_at(self.time_of(sample.timestamp_ns));
                Ok(target.clamped)
            }
            Err(rejection) => {
                let stats = &mut self.stats;
                *match rejection {
                    InputRejection::Ahead { .. } => &mut stats.rejected_ahead,
                    InputRejection::NoSuchUser { .. } => &mut stats.rejected_no_such_user,
                    InputRejection::NoSuchHand { .. } => &mut stats.rejected_no_such_hand,
                    _ => &mut stats.glove_rejected_non_finite,
                } += 1;
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
        let at_ns = self.time_of(sample.timestamp_ns);
        let routed = (self.not_ahead(sample.timestamp_ns))
            .and_then(|()| self.hand_of(sample.user, sample.side))
            .map_err(|rejection| match rejection {
                InputRejection::NoSuchHand { side, .. } => JointsRejection::NoSuchHand { side },
                other => JointsRejection::Sample(other),
            });
        let outcome = routed.and_then(|index| {
            let hand = (self.hands[index].joints.as_mut())
                .ok_or(JointsRejection::NoSuchHand { side: sample.side })?;
            let (outcome, fault) = hand.apply(sample, at_ns)?;
            if let Some(fault) = fault {
                self.count_restart("hand_joints", fault);
            }
            Ok(outcome)
        });
        if outcome.is_ok() {
            self.stamps.joints = sample.stamp();
            self.taken_at(at_ns);
        }
        let stats = &mut self.stats;
        let counter = match &outcome {
            Ok(JointsOutcome::Tracked) => &mut stats.joints_accepted,
            Ok(JointsOutcome::Untracked) => &mut stats.joints_untracked,
            Err(JointsRejection::NoSuchHand { .. }) => &mut stats.joints_rejected_no_such_hand,
            Err(JointsRejection::Sample(InputRejection::NoSuchUser { .. })) => {
                &mut stats.rejected_no_such_user
            }
            Err(JointsRejection::Sample(_)) => &mut stats.rejected_ahead,
            Err(JointsRejection::Filter(_)) => &mut stats.joints_rejected_non_finite,
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
        let hands = (self.hands.iter().enumerate())
            .map(|(index, hand)| {
                let cart = (self.carts[hand.user as usize]).unwrap_or_else(Isometry3::identity);
                let joints = hand.joints.as_ref().and_then(JointsHand::target);
                let stamp = joints.map_or_else(InputStamp::default, |target| target.stamp);
                let users_first = index == 0 || self.hands[index - 1].user != hand.user;
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
                    // Until its first tracked joints, a hand is its tracker's and glove's; a
                    // hand whose joints so far all said "not tracked" is not tracked.
                    None if users_first || hand.tracker.is_some() || hand.glove.is_some() => {
                        HandTarget {
                            joints: stamp,
                            tracked: joints.is_none(),
                            ..HandTarget::tracking(hand.glove_driven(cart))
                        }
                    }
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
            .collect();
        InputFrame {
            stamps: self.stamps,
            hands,
        }
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

    /// Forgets the targets (a reset, or another scene) and takes the hand `models` with their
    /// users' indices and the `tracking` parameters; the counters and the clock go on.
    pub fn restart<'a>(
        &mut self,
        models: impl IntoIterator<Item = (u32, &'a HandModel)>,
        tracking: TrackingParams,
    ) {
        *self = Inputs {
            stats: self.stats,
            filter_restarts: self.filter_restarts,
            clock: self.clock,
            ..Inputs::for_hands(models, tracking)
        };
    }
}

#[cfg(test)]
mod tests;
