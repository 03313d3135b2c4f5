//! The input state's unit tests: validation, counters, hands driven by joints, tracking.

use nalgebra::{Translation3, UnitQuaternion, Vector3};
use vas_protocol::{FLEX_LIMITS_RAD, WirePose};

use super::*;
use crate::grasping::model::tests::right_hand;
use crate::grasping::retarget::{Joint, Retargeter};
use crate::runtime::hand_joints::tests::captured;
use crate::runtime::hand_joints::wire_joints;
use vas_protocol::HandSide;

fn tracker(seq: u64, hand: WirePose, cart: WirePose) -> TrackerSample {
    TrackerSample {
        seq,
        timestamp_ns: 1_000 + seq,
        hand,
        cart,
        sensor_id: 0,
        user: 0,
        side: 0,
        reserved: 0,
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
    let turned =
        Translation3::new(0.0, 0.2, 0.0) * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
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
        user: 0,
        side: 0,
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
    wire_joints(
        &captured("webxr_pinch.json", HandSide::Right),
        seq,
        100 + seq,
    )
}

#[test]
fn hand_joints_drive_the_hand_and_the_tracker_keeps_the_cart() {
    let model = right_hand();
    let mut inputs = Inputs::for_hands([(0, &model)], TrackingParams::default());
    assert_eq!(
        inputs.apply_hand_joints(&pinch(1)),
        Ok(JointsOutcome::Tracked)
    );
    let fit = Retargeter::new(model)
        .expect("the right hand retargets")
        .fit(&captured("webxr_pinch.json", HandSide::Right))
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
    let mut inputs = Inputs::for_hands([(0, &right_hand())], TrackingParams::default());
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
    let mut inputs = Inputs::for_hands([(0, &right_hand())], TrackingParams::default());
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
    let mut inputs = Inputs::for_hands([(0, &model)], TrackingParams::default());
    inputs.apply_hand_joints(&pinch(1)).expect("a hand");
    inputs.restart([(0, &model)], TrackingParams::default());
    let frame = inputs.frame();
    assert_eq!(frame.stamps, Stamps::default());
    assert_eq!(frame.hands[0].input.tracker, Isometry3::identity());
    assert_eq!(inputs.stats().joints_accepted, 1);
}

#[test]
fn two_hands_take_the_glove_and_their_own_joints() {
    let right = right_hand();
    let left = right.mirrored();
    let mut inputs = Inputs::for_hands([(0, &right), (0, &left)], TrackingParams::default());
    let glove = GloveSample {
        seq: 1,
        timestamp_ns: 1,
        flex: [0.2; FLEX_COUNT],
        user: 0,
        side: 0,
    };
    inputs.apply_glove(&glove).expect("valid");
    let frame = inputs.frame();
    assert_eq!(frame.hands.len(), 2);
    assert_eq!(frame.hands[0].input.flex, [0.2; FLEX_COUNT]);
    assert!(frame.hands[0].tracked);
    assert!(!frame.hands[1].tracked, "no input for the left hand yet");
    let sample = wire_joints(&captured("webxr_pinch.json", HandSide::Left), 1, 5);
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
        ..TrackingParams::default()
    };
    let mut inputs = Inputs::for_hands([(0, &right_hand())], tracking);
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
    let mut inputs = Inputs::for_hands([(0, &right_hand())], TrackingParams::default());
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
    inputs.restart([(0, &right_hand())], TrackingParams::default());
    inputs.apply_hand_joints(&pinch(2)).expect("a hand");
    assert!(
        inputs.tick(wall_clock_ns() + 150 * MS),
        "the clock outlives a restart"
    );
}

#[test]
fn on_sample_time_ticks_change_nothing() {
    let mut inputs = Inputs::for_hands([(0, &right_hand())], TrackingParams::default());
    inputs.apply_hand_joints(&pinch(1)).expect("a hand");
    assert!(!inputs.tick(u64::MAX));
    assert!(inputs.frame().hands[0].tracked);
}

#[test]
fn samples_stamped_beyond_the_servers_clock_are_rejected_and_keep_no_hand_untracked() {
    const HOUR_NS: u64 = 3_600_000_000_000;
    let mut inputs = Inputs::for_hands([(0, &right_hand())], TrackingParams::default());
    let now = wall_clock_ns();
    let mut future = pinch(1);
    future.timestamp_ns = now + HOUR_NS;
    assert!(matches!(
        inputs.apply_hand_joints(&future),
        Err(JointsRejection::Sample(InputRejection::Ahead { ahead_ns })) if ahead_ns > HOUR_NS / 2
    ));
    let mut sample = tracker(1, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
    sample.timestamp_ns = u64::MAX;
    assert!(matches!(
        inputs.apply_tracker(&sample),
        Err(InputRejection::Ahead { .. })
    ));
    let glove = GloveSample {
        seq: 1,
        timestamp_ns: now + HOUR_NS,
        flex: [0.0; FLEX_COUNT],
        user: 0,
        side: 0,
    };
    assert!(matches!(
        inputs.apply_glove(&glove),
        Err(InputRejection::Ahead { .. })
    ));
    // The hand's next samples, stamped now, keep it tracked (they were an hour old before).
    for seq in 2..4 {
        let mut sample = pinch(seq);
        sample.timestamp_ns = now + seq;
        assert_eq!(
            inputs.apply_hand_joints(&sample),
            Ok(JointsOutcome::Tracked)
        );
        assert!(inputs.frame().hands[0].tracked, "sample {seq}");
    }
    let stats = inputs.stats();
    assert_eq!((stats.rejected_ahead, stats.rejected()), (3, 3));
    assert_eq!(stats.joints_accepted, 2);
    assert!(inputs.frame().hands[0].tracked);
}

#[test]
fn the_tracker_root_is_smoothed_and_a_timestamp_going_back_restarts_it() {
    const MS: u64 = 1_000_000;
    let stamped = |seq: u64, ms: u64, x: f64| TrackerSample {
        timestamp_ns: ms * MS,
        ..tracker(seq, at(x, 0.0, 0.0), at(0.0, 0.0, 0.0))
    };
    let root_x = |inputs: &Inputs| inputs.frame().hands[0].input.tracker.translation.x;
    let mut inputs = Inputs::for_hands([], TrackingParams::default());
    inputs.apply_tracker(&stamped(1, 10, 0.0)).expect("valid");
    inputs.apply_tracker(&stamped(2, 30, 0.002)).expect("valid");
    let smoothed = root_x(&inputs);
    assert!(0.0 < smoothed && smoothed < 0.002, "{smoothed}");
    assert_eq!(inputs.filter_restarts(), 0);
    // Back in time: taken as it is, the filter restarted from it, and counted.
    inputs.apply_tracker(&stamped(3, 20, 0.005)).expect("valid");
    assert_eq!(root_x(&inputs), 0.005);
    assert_eq!(inputs.filter_restarts(), 1);
    // A restart (reset or another scene) forgets the samples, not the count.
    inputs.restart([], TrackingParams::default());
    inputs.apply_tracker(&stamped(4, 0, 0.01)).expect("valid");
    assert_eq!((root_x(&inputs), inputs.filter_restarts()), (0.01, 1));

    let off = TrackingParams {
        filter: false,
        ..TrackingParams::default()
    };
    let mut inputs = Inputs::for_hands([], off);
    inputs.apply_tracker(&stamped(1, 10, 0.0)).expect("valid");
    inputs.apply_tracker(&stamped(2, 30, 0.002)).expect("valid");
    assert_eq!(root_x(&inputs), 0.002);
}

#[test]
fn a_joints_hand_is_smoothed_and_starts_afresh_when_tracking_returns() {
    const MS: u64 = 1_000_000;
    let model = right_hand();
    let retargeter = Retargeter::new(model.clone()).expect("the right hand retargets");
    let pinch = captured("webxr_pinch.json", HandSide::Right);
    let moved = pinch.transformed(&Isometry3::translation(0.002, 0.0, 0.0));
    let mut inputs = Inputs::for_hands([(0, &model)], TrackingParams::default());
    let root = |inputs: &Inputs| inputs.frame().hands[0].input.tracker;
    inputs
        .apply_hand_joints(&wire_joints(&pinch, 1, 10 * MS))
        .expect("a hand");
    assert_eq!(root(&inputs), retargeter.fit(&pinch).unwrap().root);
    inputs
        .apply_hand_joints(&wire_joints(&moved, 2, 30 * MS))
        .expect("a hand");
    let (start, end) = (pinch.joints[0].position.x, moved.joints[0].position.x);
    let fitted = retargeter.fit(&moved).unwrap().root;
    let smoothed = root(&inputs);
    let travelled = smoothed.translation.x - retargeter.fit(&pinch).unwrap().root.translation.x;
    assert!(0.0 < travelled && travelled < end - start, "{travelled}");
    assert_ne!(smoothed, fitted);
    // Lost, then tracked again: the filter starts from the first tracked sample.
    let mut lost = wire_joints(&moved, 3, 50 * MS);
    lost.joints.iter_mut().for_each(|joint| joint.flags = 0);
    assert_eq!(
        inputs.apply_hand_joints(&lost),
        Ok(JointsOutcome::Untracked)
    );
    inputs
        .apply_hand_joints(&wire_joints(&moved, 4, 70 * MS))
        .expect("a hand");
    assert_eq!(root(&inputs), fitted);
    assert_eq!(inputs.filter_restarts(), 0);
}

#[test]
fn each_users_samples_drive_their_own_hand_and_cart() {
    let right = right_hand();
    let left = right.mirrored();
    // User 0 has a right hand, user 1 a right and a left one.
    let mut inputs = Inputs::for_hands(
        [(0, &right), (1, &right), (1, &left)],
        TrackingParams::default(),
    );
    let for_user = |user: u32, side: HandSide, sample: TrackerSample| TrackerSample {
        user,
        side: side as u32,
        ..sample
    };
    let first = tracker(1, at(0.1, 0.0, 0.0), at(0.0, 0.0, 1.0));
    let second = tracker(2, at(0.2, 0.0, 0.0), at(0.0, 0.0, 2.0));
    inputs
        .apply_tracker(&for_user(1, HandSide::Left, second))
        .expect("user 1 has a left hand");
    let glove = GloveSample {
        seq: 1,
        timestamp_ns: 1,
        flex: [0.3; FLEX_COUNT],
        user: 1,
        side: HandSide::Left as u32,
    };
    inputs.apply_glove(&glove).expect("valid");
    let frame = inputs.frame();
    let root = |hand: usize| frame.hands[hand].input.cart * frame.hands[hand].input.tracker;
    assert_eq!(frame.hands.len(), 3);
    assert_eq!(root(2).translation.vector, Vector3::new(0.2, 0.0, 2.0));
    assert_eq!(frame.hands[2].input.flex, [0.3; FLEX_COUNT]);
    assert!(frame.hands[2].tracked);
    // User 1's right hand rides on user 1's cart; user 0's hand is untouched.
    assert_eq!(root(1).translation.vector, Vector3::new(0.0, 0.0, 2.0));
    assert_eq!(root(0), Isometry3::identity());
    assert_eq!(frame.hands[0].input.flex, [0.0; FLEX_COUNT]);
    inputs
        .apply_tracker(&for_user(0, HandSide::Right, first))
        .expect("user 0 has a right hand");
    let frame = inputs.frame();
    let root = |hand: usize| frame.hands[hand].input.cart * frame.hands[hand].input.tracker;
    assert_eq!(root(0).translation.vector, Vector3::new(0.1, 0.0, 1.0));
    assert_eq!(root(2).translation.vector, Vector3::new(0.2, 0.0, 2.0));

    // A user or a side the scene does not have: rejected and counted, nothing moves.
    let before = inputs.frame();
    assert_eq!(
        inputs.apply_tracker(&for_user(2, HandSide::Right, first)),
        Err(InputRejection::NoSuchUser { user: 2 })
    );
    assert_eq!(
        inputs.apply_tracker(&for_user(0, HandSide::Left, first)),
        Err(InputRejection::NoSuchHand { user: 0, side: 1 })
    );
    assert_eq!(
        inputs.apply_glove(&GloveSample { side: 9, ..glove }),
        Err(InputRejection::NoSuchHand { user: 1, side: 9 })
    );
    let mut joints = pinch(3);
    joints.user = 7;
    assert_eq!(
        inputs.apply_hand_joints(&joints),
        Err(JointsRejection::Sample(InputRejection::NoSuchUser {
            user: 7
        }))
    );
    joints.user = 0;
    joints.side = HandSide::Left as u32;
    assert_eq!(
        inputs.apply_hand_joints(&joints),
        Err(JointsRejection::NoSuchHand { side: 1 })
    );
    assert_eq!(inputs.frame(), before);
    let stats = inputs.stats();
    assert_eq!(
        (stats.rejected_no_such_user, stats.rejected_no_such_hand),
        (2, 2)
    );
    assert_eq!(stats.joints_rejected_no_such_hand, 1);
    assert_eq!(stats.rejected(), 5);
}
