//! Conversions between wire types and nalgebra, and the input validation rules.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use vas_protocol::*;

fn pose(position: [f64; 3], rotation: [f64; 4]) -> WirePose {
    WirePose { position, rotation }
}

fn tracker(hand: WirePose, cart: WirePose) -> TrackerSample {
    TrackerSample {
        seq: 7,
        timestamp_ns: 1_000,
        hand,
        cart,
        sensor_id: 2,
        user: 1,
        side: HandSide::Left as u32,
        reserved: 0,
    }
}

fn glove(flex: [f32; FLEX_COUNT]) -> GloveSample {
    GloveSample {
        seq: 3,
        timestamp_ns: 2_000,
        flex,
        user: 1,
        side: HandSide::Left as u32,
    }
}

fn arbitrary_isometry() -> impl Strategy<Value = Isometry3<f64>> {
    (
        prop::array::uniform3(-10.0..10.0f64),
        prop::array::uniform3(-std::f64::consts::PI..std::f64::consts::PI),
    )
        .prop_map(|([x, y, z], [roll, pitch, yaw])| {
            Isometry3::from_parts(
                Translation3::new(x, y, z),
                UnitQuaternion::from_euler_angles(roll, pitch, yaw),
            )
        })
}

proptest! {
    #[test]
    fn isometry_survives_the_wire(iso in arbitrary_isometry()) {
        let wire = WirePose::from(iso);
        let back: Isometry3<f64> = wire.into();
        prop_assert!((back.translation.vector - iso.translation.vector).norm() < 1e-12);
        prop_assert!(back.rotation.angle_to(&iso.rotation) < 1e-9);
        // The wire order is x, y, z, w.
        prop_assert_eq!(wire.rotation[3], iso.rotation.quaternion().w);
        prop_assert_eq!(wire.rotation[0], iso.rotation.quaternion().i);
    }

    #[test]
    fn valid_tracker_samples_are_accepted_unchanged(hand in arbitrary_isometry(), cart in arbitrary_isometry()) {
        let target = tracker(hand.into(), cart.into()).validate().expect("valid sample");
        prop_assert_eq!(target.stamp, InputStamp { seq: 7, timestamp_ns: 1_000 });
        prop_assert_eq!(target.sensor_id, 2);
        prop_assert!(target.hand.rotation.angle_to(&hand.rotation) < 1e-9);
        prop_assert!((target.cart.translation.vector - cart.translation.vector).norm() < 1e-12);
    }

    #[test]
    fn flex_values_inside_the_limits_are_untouched(fractions in prop::array::uniform22(0.0..=1.0f32)) {
        let mut flex = [0.0; FLEX_COUNT];
        for ((value, fraction), (low, high)) in flex.iter_mut().zip(fractions).zip(FLEX_LIMITS_RAD) {
            *value = low + (high - low) * fraction;
            *value = value.clamp(low, high);
        }
        let target = glove(flex).validate().expect("finite sample");
        prop_assert_eq!(target.clamped, 0);
        prop_assert_eq!(target.flex, flex);
    }
}

#[test]
fn parts_state_pose_matches_its_fields() {
    let state = PartState {
        id: 1,
        flags: PART_GRASPED | PART_SLIDING,
        position: [1.0, 2.0, 3.0],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    let iso = state.pose().to_isometry();
    assert_eq!(iso.translation.vector, Vector3::new(1.0, 2.0, 3.0));
    assert_eq!(iso.rotation, UnitQuaternion::identity());
}

#[test]
fn typed_accessors_read_each_flag_and_code() {
    let flags = [PART_GRASPED, PART_TOUCHING, PART_SLIDING, PART_PUSHED];
    for (index, &flag) in flags.iter().enumerate() {
        let state = PartState {
            flags: flag,
            ..PartState::default()
        };
        let read = [
            state.is_grasped(),
            state.is_touching(),
            state.is_sliding(),
            state.is_pushed(),
        ];
        let expected: Vec<bool> = (0..flags.len()).map(|i| i == index).collect();
        assert_eq!(read.to_vec(), expected, "flag {flag:#x}");
    }

    let mut hand = HandFrame {
        hand: HandSide::Left as u32,
        grasp_type: GraspType::TipPinch as u32,
        touching: HandSegment::IndexDistal.bit(),
        tracked: 1,
        ..HandFrame::default()
    };
    assert_eq!(hand.side(), Some(HandSide::Left));
    assert_eq!(hand.grasp(), Some(GraspType::TipPinch));
    assert!(hand.is_tracked());
    assert!(hand.is_touching(HandSegment::IndexDistal));
    assert!(!hand.is_touching(HandSegment::ThumbDistal));
    (hand.hand, hand.grasp_type) = (2, 99);
    assert_eq!((hand.side(), hand.grasp()), (None, None));

    let mut event = SimEvent {
        frame: 1,
        tracker: InputStamp::default(),
        glove: InputStamp::default(),
        joints: InputStamp::default(),
        timestamp_ns: 0,
        kind: EventKind::Grasp as u32,
        grasp_type: GraspType::Power as u32,
        part: 0,
        other: HAND_PART_ID,
        hand: HandSide::Left as u32,
        segment: 0,
        user: 0,
        reserved: 0,
        point: [0.0; 3],
        normal: [0.0; 3],
        other_point: [0.0; 3],
        distance: 0.0,
    };
    assert_eq!(event.kind(), Some(EventKind::Grasp));
    assert_eq!(event.side(), Some(HandSide::Left));
    assert_eq!(event.grasp(), Some(GraspType::Power));
    (event.kind, event.hand) = (EventKind::ClearanceBelow as u32, 0);
    assert_eq!(event.side(), None, "a clearance event is about no hand");
    event.kind = 0;
    assert_eq!(event.kind(), None);
}

#[test]
fn non_finite_tracker_values_are_rejected_naming_the_field() {
    let nan_hand = tracker(
        pose([f64::NAN, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
        WirePose::IDENTITY,
    );
    assert_eq!(
        nan_hand.validate(),
        Err(InputRejection::NonFinite {
            field: "hand.position"
        })
    );
    let infinite_cart = tracker(
        WirePose::IDENTITY,
        pose([0.0; 3], [0.0, f64::INFINITY, 0.0, 1.0]),
    );
    assert_eq!(
        infinite_cart.validate(),
        Err(InputRejection::NonFinite {
            field: "cart.rotation"
        })
    );
}

#[test]
fn quaternions_must_be_unit_within_the_tolerance() {
    let scaled = tracker(pose([0.0; 3], [0.0, 0.0, 0.0, 2.0]), WirePose::IDENTITY);
    assert!(matches!(
        scaled.validate(),
        Err(InputRejection::NotUnitQuaternion { field: "hand.rotation", norm }) if norm == 2.0
    ));
    let zero = tracker(WirePose::IDENTITY, pose([0.0; 3], [0.0; 4]));
    assert!(matches!(
        zero.validate(),
        Err(InputRejection::NotUnitQuaternion {
            field: "cart.rotation",
            ..
        })
    ));
    // Slightly off unit is accepted and renormalised.
    let w = 1.0 + UNIT_QUATERNION_TOLERANCE / 2.0;
    let target = tracker(pose([0.0; 3], [0.0, 0.0, 0.0, w]), WirePose::IDENTITY)
        .validate()
        .expect("within tolerance");
    assert!((target.hand.rotation.quaternion().norm() - 1.0).abs() < 1e-12);
    let just_outside = 1.0 + UNIT_QUATERNION_TOLERANCE * 1.5;
    assert!(
        tracker(
            pose([0.0; 3], [0.0, 0.0, 0.0, just_outside]),
            WirePose::IDENTITY
        )
        .validate()
        .is_err()
    );
}

#[test]
fn out_of_range_flex_values_are_clamped_and_reported() {
    let mut flex = [0.0f32; FLEX_COUNT];
    flex[0] = 3.0; // thumb roll above 60 degrees
    flex[5] = -0.5; // index middle joint below 0
    flex[21] = 0.1; // inside the wrist abduction range
    let target = glove(flex).validate().expect("finite sample");
    assert_eq!(target.clamped, (1 << 0) | (1 << 5));
    assert_eq!(target.clamped_count(), 2);
    assert_eq!(target.flex[0], FLEX_LIMITS_RAD[0].1);
    assert_eq!(target.flex[5], 0.0);
    assert_eq!(target.flex[21], 0.1);
    assert_eq!(
        target.stamp,
        InputStamp {
            seq: 3,
            timestamp_ns: 2_000
        }
    );
}

#[test]
fn non_finite_flex_values_are_rejected_naming_the_index() {
    let mut flex = [0.0f32; FLEX_COUNT];
    flex[13] = f32::NEG_INFINITY;
    assert_eq!(
        glove(flex).validate(),
        Err(InputRejection::NonFinite { field: "flex[13]" })
    );
}

#[test]
fn joint_limits_are_ordered_and_named() {
    for ((low, high), name) in FLEX_LIMITS_RAD.iter().zip(FLEX_JOINT_NAMES) {
        assert!(low < high, "{name}: {low} < {high}");
        assert!(
            high.abs() <= std::f32::consts::PI / 2.0 + 1e-6,
            "{name} within 90 degrees"
        );
    }
}

#[test]
fn enumeration_codes_round_trip_and_unknown_codes_are_errors() {
    for code in 0..=9 {
        let grasp = GraspType::try_from(code).expect("known grasp code");
        assert_eq!(grasp as u32, code);
    }
    assert_eq!(
        GraspType::try_from(10),
        Err(UnknownCode {
            type_name: "GraspType",
            code: 10
        })
    );
    for code in 1..=9 {
        assert_eq!(EventKind::try_from(code).map(|k| k as u32), Ok(code));
    }
    for code in 1..=5 {
        assert_eq!(
            ControlRequestKind::try_from(code).map(|k| k as u32),
            Ok(code)
        );
    }
    for code in 0..=4 {
        assert_eq!(ControlStatus::try_from(code).map(|k| k as u32), Ok(code));
    }
    for code in 1..=3 {
        assert_eq!(SlidingMetaphor::try_from(code).map(|k| k as u32), Ok(code));
    }
    assert!(EventKind::try_from(0).is_err());
    assert!(ControlRequestKind::try_from(99).is_err());
}

#[test]
fn hand_segment_bits_are_distinct_and_cover_sixteen_bits() {
    let all = HandSegment::ALL.iter().fold(0u32, |bits, segment| {
        assert_eq!(bits & segment.bit(), 0, "{segment:?} shares a bit");
        bits | segment.bit()
    });
    assert_eq!(all, 0xFFFF);
}

#[test]
fn wire_text_round_trips_and_truncates_at_character_boundaries() {
    let text = WireText::<8>::new("gear").expect("fits");
    assert_eq!(text.as_str(), Ok("gear"));
    assert_eq!(
        WireText::<4>::new("gearbox"),
        Err(WireTextError::TooLong {
            len: 7,
            capacity: 4
        })
    );
    // "Zahnräder": the 'ä' spans bytes 5 and 6; a cut at 6 must back off to 5.
    let (cut, truncated) = WireText::<6>::truncated("Zahnräder");
    assert!(truncated);
    assert_eq!(cut.as_str(), Ok("Zahnr"));
    let (whole, truncated) = WireText::<16>::truncated("Zahnräder");
    assert!(!truncated);
    assert_eq!(whole.as_str(), Ok("Zahnräder"));
}

#[test]
fn control_requests_carry_their_kind_and_argument() {
    let request = ControlRequest::part_info(12);
    assert_eq!(
        ControlRequestKind::try_from(request.kind),
        Ok(ControlRequestKind::PartInfo)
    );
    assert_eq!(request.argument, 12);
    let metaphor = ControlRequest::set_metaphor(SlidingMetaphor::Incremental);
    assert_eq!(
        SlidingMetaphor::try_from(metaphor.argument),
        Ok(SlidingMetaphor::Incremental)
    );
    let path = WireText::new("configs/demo.toml").expect("fits");
    assert_eq!(
        ControlRequest::load_scene(path).path.as_str(),
        Ok("configs/demo.toml")
    );
}

#[test]
fn samples_round_trip_through_json() {
    let sample = tracker(
        pose([0.1, 0.2, 0.3], [0.0, 0.0, 0.6, 0.8]),
        WirePose::IDENTITY,
    );
    let json = serde_json::to_string(&sample).expect("serialises");
    let back: TrackerSample = serde_json::from_str(&json).expect("parses");
    assert_eq!(back, sample);
    let mut flex = [0.0; FLEX_COUNT];
    flex[4] = 0.75;
    let glove_sample = glove(flex);
    let back: GloveSample =
        serde_json::from_str(&serde_json::to_string(&glove_sample).expect("serialises"))
            .expect("parses");
    assert_eq!(back, glove_sample);
}

#[test]
fn samples_recorded_before_users_drive_the_first_users_right_hand() {
    let mut json =
        serde_json::to_value(tracker(WirePose::IDENTITY, WirePose::IDENTITY)).expect("serialises");
    let fields = json.as_object_mut().expect("an object");
    assert!(!fields.contains_key("reserved"), "padding is not recorded");
    fields.remove("user");
    fields.remove("side");
    let old: TrackerSample = serde_json::from_value(json).expect("parses");
    assert_eq!((old.user, old.side), (0, HandSide::Right as u32));
}

#[test]
fn users_are_looked_up_by_index_and_by_name() {
    let mut response = ControlResponse {
        user_count: 2,
        ..zeroed_response()
    };
    response.users[0] = WireText::new("anna").expect("fits");
    response.users[1] = WireText::new("ben").expect("fits");
    response.users[2] = WireText::new("beyond the count").expect("fits");
    assert_eq!(response.user_names().collect::<Vec<_>>(), ["anna", "ben"]);
    assert_eq!(response.user_name(1), Some("ben"));
    assert_eq!(response.user_name(2), None);
    assert_eq!(response.user_index("ben"), Some(1));
    assert_eq!(response.user_index("beyond the count"), None);
}

/// A response of zeros, as a request that fills nothing would leave it.
fn zeroed_response() -> ControlResponse {
    ControlResponse {
        status: 0,
        kind: 0,
        part_count: 0,
        scene_truncated: 0,
        scene_name: WireText::EMPTY,
        scene_source: WireText::EMPTY,
        part: PartDescription::default(),
        stats: InputStats::default(),
        message: WireText::EMPTY,
        up: [0.0; 3],
        metres_per_unit: 1.0,
        hand_count: 0,
        listed_count: 0,
        hands: [HandDescription::default(); MAX_HANDS],
        listed: WireText::EMPTY,
        generation: 0,
        metaphor: 0,
        user_count: 0,
        users: [WireText::EMPTY; MAX_USERS],
    }
}

#[test]
fn wall_clock_is_after_2020() {
    const JAN_2020_NS: u64 = 1_577_836_800_000_000_000;
    assert!(wall_clock_ns() > JAN_2020_NS);
}

#[test]
fn the_cart_carries_the_hand_into_the_world() {
    let quarter_turn = std::f64::consts::FRAC_1_SQRT_2;
    let sample = tracker(
        pose([1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
        pose([0.0, 0.0, 5.0], [0.0, 0.0, quarter_turn, quarter_turn]),
    );
    let world = sample.validate().expect("valid").hand_in_world();
    // The cart turns a quarter about z, so the hand's offset along x ends up along y.
    assert!((world.translation.vector - Vector3::new(0.0, 1.0, 5.0)).norm() < 1e-12);
}
