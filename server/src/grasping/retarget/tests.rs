//! The retargeting against real captures (fingertips) and against the model's own poses
//! (angles), and the refusal of impossible samples and malformed captures.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::grasping::model::tests::hands_dir;
use crate::grasping::{FLEX_COUNT, FlexVector, HandModel};
use vas_protocol::HandSide;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures/hands")
        .join(name)
}

fn capture(name: &str) -> Capture {
    Capture::read(&fixture(name)).expect("the fixture is a valid capture")
}

fn retargeter(side: HandSide) -> Retargeter {
    let file = match side {
        HandSide::Left => "left.toml",
        HandSide::Right => "right.toml",
    };
    Retargeter::new(HandModel::load(&hands_dir().join(file)).unwrap()).unwrap()
}

#[test]
fn captures_are_left_hands_and_mirror_to_right_hands() {
    let pinch = capture("webxr_pinch.json");
    assert_eq!(pinch.joints.side, HandSide::Left);
    assert_eq!(pinch.pose.as_deref(), Some("pinch"));
    // WebXR has no palm: it is derived halfway along the middle finger's metacarpal.
    let palm = pinch.joints.get(Joint::Palm);
    let metacarpal = pinch.joints.get(Joint::MiddleMetacarpal);
    let knuckle = pinch.joints.get(Joint::MiddleProximal).position;
    assert_eq!(
        palm.position,
        nalgebra::center(&metacarpal.position, &knuckle)
    );
    assert_eq!(palm.orientation, metacarpal.orientation);
    let right = pinch.mirrored();
    assert_eq!(right.joints.side, HandSide::Right);
    right
        .joints
        .validate()
        .expect("the mirror image is a valid right hand");
    let tip = right.joints.get(Joint::IndexTip).position;
    let original = pinch.joints.get(Joint::IndexTip).position;
    assert_eq!(tip, Point3::new(-original.x, original.y, original.z));
    assert_eq!(right.mirrored(), pinch);
}

/// Calibrated on one capture and measured on the other, for the captured left hand and its
/// mirror image: the model's fingertips within 5 mm RMS and 10 mm of the captured tips.
#[test]
fn fingertips_of_real_captures_calibrated_on_the_other_capture() {
    let names = ["webxr_relaxed.json", "webxr_pinch.json"];
    for (calibration, measured) in [(names[0], names[1]), (names[1], names[0])] {
        for mirror in [false, true] {
            let load = |name| {
                let c = capture(name);
                if mirror { c.mirrored() } else { c }
            };
            let (calibration_capture, capture) = (load(calibration), load(measured));
            let side = capture.joints.side;
            let retargeter = retargeter(side)
                .calibrated(&calibration_capture.joints)
                .unwrap();
            let fit = retargeter.fit(&capture.joints).unwrap();
            let error = retargeter.fingertip_distances(&fit, &capture.joints);
            let (rms, max) = (error.rms() * 1e3, error.max() * 1e3);
            eprintln!(
                "{measured} ({side:?}) calibrated on {calibration}: fingertip RMS {rms:.2} mm, \
                 max {max:.2} mm, per digit {:.2?} mm",
                error.per_digit.map(|e| e * 1e3)
            );
            assert!(
                rms <= 5.0 && max <= 10.0,
                "{measured} {side:?}: {rms} {max}"
            );
        }
    }
}

fn random_flex(rng: &mut ChaCha8Rng, model: &HandModel) -> FlexVector {
    std::array::from_fn(|i| {
        let limit = &model.limits()[i];
        rng.random_range(limit.min..=limit.max)
    })
}

fn random_root(rng: &mut ChaCha8Rng) -> Isometry3<f64> {
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    Isometry3::from_parts(
        Translation3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(0.5..1.5),
            rng.random_range(-1.0..1.0),
        ),
        UnitQuaternion::from_scaled_axis(axis * 3.0),
    )
}

/// Random poses within the limits, through forward kinematics to OpenXR joints and back: every
/// angle but the wrist's (not seen: OpenXR's wrist turns with the palm) within a degree RMS, and
/// the palm where it was.
#[test]
fn model_generated_joints_give_back_their_angles() {
    const CASES: usize = 2000;
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    for side in [HandSide::Right, HandSide::Left] {
        for calibrated in [false, true] {
            let mut retargeter = retargeter(side);
            if calibrated {
                let mut c = capture("webxr_relaxed.json");
                if side == HandSide::Right {
                    c = c.mirrored();
                }
                retargeter = retargeter.calibrated(&c.joints).unwrap();
            }
            let model = retargeter.model().clone();
            let (mut squares, mut count, mut worst) = (0.0, 0, 0.0f64);
            for _ in 0..CASES {
                let flex = random_flex(&mut rng, &model);
                let root = random_root(&mut rng);
                let joints = retargeter.synthesize(&root, &flex);
                let fit = retargeter.fit(&joints).unwrap();
                // Every flex value but the last two, the wrist's.
                for (fitted, generated) in fit.flex.iter().zip(&flex).take(FLEX_COUNT - 2) {
                    let error = (fitted - generated).to_degrees();
                    squares += error * error;
                    worst = worst.max(error.abs());
                    count += 1;
                }
                let palm = root * model.segment_poses(&flex)[model.palm()];
                let fitted_palm = fit.root * model.segment_poses(&fit.flex)[model.palm()];
                assert!((palm.translation.vector - fitted_palm.translation.vector).norm() < 1e-9);
                assert!(palm.rotation.angle_to(&fitted_palm.rotation) < 1e-9);
            }
            let rms = (squares / count as f64).sqrt();
            eprintln!(
                "{side:?} (calibrated {calibrated}): {CASES} random poses, angle error RMS \
                 {rms:.2e} degrees, worst {worst:.2e}"
            );
            assert!(rms <= 1.0, "{side:?}: {rms} degrees");
        }
    }
}

#[test]
fn calibration_takes_the_measured_bone_lengths() {
    let relaxed = capture("webxr_relaxed.json");
    let retargeter = retargeter(HandSide::Left)
        .calibrated(&relaxed.joints)
        .unwrap();
    let rest = retargeter.synthesize(&Isometry3::identity(), &[0.0; FLEX_COUNT]);
    let length = |joints: &HandJoints, from: Joint, to: Joint| {
        (joints.get(to).position - joints.get(from).position).norm()
    };
    // The thumb's base is halfway between the wrist and its metacarpal joint, and its inner
    // segment reaches the proximal joint.
    let wrist = relaxed.joints.get(Joint::Wrist).position;
    let base = nalgebra::center(&wrist, &relaxed.joints.get(Joint::ThumbMetacarpal).position);
    let inner = (relaxed.joints.get(Joint::ThumbProximal).position - base).norm();
    assert!((length(&rest, Joint::ThumbMetacarpal, Joint::ThumbProximal) - inner).abs() < 1e-9);
    for chain in Joint::digit_chains() {
        let bones = &chain[chain.len() - 4..];
        let skip = usize::from(chain[0] == Joint::ThumbMetacarpal);
        for pair in bones.windows(2).skip(skip) {
            let measured = length(&relaxed.joints, pair[0], pair[1]);
            let model = length(&rest, pair[0], pair[1]);
            assert!(
                (measured - model).abs() < 1e-9,
                "{}: {measured} {model}",
                pair[0]
            );
        }
    }
}

#[test]
fn a_hand_moved_rigidly_retargets_to_the_moved_root_and_the_same_angles() {
    let joints = capture("webxr_pinch.json").joints;
    let retargeter = retargeter(HandSide::Left);
    let pose = Isometry3::from_parts(
        Translation3::new(0.3, -0.2, 1.1),
        UnitQuaternion::from_euler_angles(0.4, -1.1, 2.0),
    );
    let fit = retargeter.fit(&joints).unwrap();
    let moved = retargeter.fit(&joints.transformed(&pose)).unwrap();
    let expected = pose * fit.root;
    assert!((moved.root.translation.vector - expected.translation.vector).norm() < 1e-12);
    assert!(moved.root.rotation.angle_to(&expected.rotation) < 1e-12);
    for (moved, fitted) in moved.flex.iter().zip(&fit.flex) {
        assert!((moved - fitted).abs() < 1e-6, "{moved} {fitted}");
    }
}

#[test]
fn quaternions_a_little_off_unit_length_give_a_unit_root() {
    let mut joints = capture("webxr_relaxed.json").joints;
    for joint in &mut joints.joints {
        joint.orientation *= 1.0 + 5e-4;
    }
    let fit = retargeter(HandSide::Left)
        .fit(&joints)
        .expect("within the tolerance");
    assert!((fit.root.rotation.quaternion().norm() - 1.0).abs() < 1e-12);
}

#[test]
fn impossible_samples_are_rejected() {
    let good = capture("webxr_pinch.json").joints;
    let retargeter = retargeter(HandSide::Left);
    let reject = |edit: &dyn Fn(&mut HandJoints)| {
        let mut joints = good.clone();
        edit(&mut joints);
        retargeter.fit(&joints).unwrap_err()
    };
    let at = |joint: Joint| joint.index();
    assert_eq!(
        reject(&|j| j.joints[at(Joint::RingDistal)].position.y = f64::NAN),
        RetargetError::Joints(JointsError::NonFinite {
            joint: Joint::RingDistal
        })
    );
    assert_eq!(
        reject(&|j| j.joints[at(Joint::Wrist)].position.x = 2e6),
        RetargetError::Joints(JointsError::OutOfRange {
            joint: Joint::Wrist
        })
    );
    assert!(matches!(
        reject(&|j| j.joints[at(Joint::ThumbDistal)].orientation *= 1.1),
        RetargetError::Joints(JointsError::NotUnit {
            joint: Joint::ThumbDistal,
            ..
        })
    ));
    assert_eq!(
        reject(&|j| j.joints[at(Joint::Wrist)].flags = JointFlags::POSITION_VALID),
        RetargetError::Joints(JointsError::NotValid {
            joint: Joint::Wrist
        })
    );
    // The index tip and distal joint swapped.
    assert_eq!(
        reject(&|j| j.joints.swap(at(Joint::IndexDistal), at(Joint::IndexTip))),
        RetargetError::Joints(JointsError::OutOfOrder {
            joint: Joint::IndexTip,
            reason: "behind the joint before it (against its -Z)"
        })
    );
    // The middle finger's tip 20 cm beyond its distal joint.
    assert!(matches!(
        reject(&|j| {
            let distal = j.joints[at(Joint::MiddleDistal)];
            let forward = distal.rotation() * -Vector3::z();
            j.joints[at(Joint::MiddleTip)].position = distal.position + forward * 0.2;
        }),
        RetargetError::Joints(JointsError::BoneLength {
            from: Joint::MiddleDistal,
            to: Joint::MiddleTip,
            ..
        })
    ));
    // A left hand's joints called a right hand: the knuckles are in the wrong order.
    let mut called_right = good.clone();
    called_right.side = HandSide::Right;
    assert!(matches!(
        called_right.validate(),
        Err(JointsError::OutOfOrder { .. })
    ));
    assert_eq!(
        self::retargeter(HandSide::Right)
            .fit(&good)
            .unwrap_err()
            .to_string(),
        "a Left hand sample cannot drive a Right hand model"
    );
    // A zero quaternion is not a rotation.
    assert!(matches!(
        reject(
            &|j| j.joints[at(Joint::LittleTip)].orientation = Quaternion::new(0.0, 0.0, 0.0, 0.0)
        ),
        RetargetError::Joints(JointsError::NotUnit { .. })
    ));
}

#[test]
fn malformed_captures_are_refused_with_the_reason() {
    let text = std::fs::read_to_string(fixture("webxr_relaxed.json")).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let refusal = |value: &serde_json::Value| {
        Capture::from_json(Path::new("hand.json"), &value.to_string())
            .unwrap_err()
            .to_string()
    };
    let edited = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = value.clone();
        edit(&mut v);
        refusal(&v)
    };
    let cases = [
        (
            edited(&|v| {
                v["joints"].as_array_mut().unwrap().pop();
            }),
            "hand.json: joints: expected 25 joints (WebXR's, wrist first), found 24",
        ),
        (
            edited(&|v| v["joints"][3]["name"] = "thumb-phalanx-middle".into()),
            "hand.json: joints[3]: expected joint \"thumb-phalanx-distal\"",
        ),
        (
            edited(&|v| v["joints"][7]["matrix"][0] = 2.0.into()),
            "hand.json: joints[7]: matrix: the upper 3x3 is not a rotation",
        ),
        (
            edited(&|v| v["joints"][7]["matrix"][15] = 0.0.into()),
            "hand.json: joints[7]: matrix: the last row must be 0 0 0 1",
        ),
        (
            edited(&|v| {
                v["joints"][7]["matrix"].as_array_mut().unwrap().pop();
            }),
            "hand.json: joints[7]: matrix: expected 16 numbers, found 15",
        ),
        (
            edited(&|v| v["joints"][7]["radius"] = (-1.0).into()),
            "hand.json: joints[7]: radius: -1 is not a length",
        ),
        (
            edited(&|v| v["joints"][7]["colour"] = "red".into()),
            "unknown field `colour`",
        ),
        (
            edited(&|v| v["side"] = "middle".into()),
            "unknown variant `middle`",
        ),
        (
            // The index finger's proximal joint moved 30 cm: two impossible bones.
            edited(&|v| v["joints"][6]["matrix"][13] = 0.3.into()),
            "hand.json: bone index-finger-metacarpal -> index-finger-phalanx-proximal",
        ),
    ];
    for (message, expected) in cases {
        assert!(
            message.contains(expected),
            "expected {expected:?} in {message:?}"
        );
    }
    let missing = Capture::read(Path::new("/nonexistent/hand.json"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("hand.json: cannot read"), "{missing}");
}

#[test]
fn a_joint_of_three_axes_through_it_is_not_supported() {
    let text = std::fs::read_to_string(hands_dir().join("right.toml"))
        .unwrap()
        .replacen(
            "    { axis = [0.0, 0.0, 1.0], flex = [10] },\n",
            "    { axis = [0.0, 0.0, 1.0], flex = [10] },\n    { axis = [0.0, 1.0, 0.0], flex = [10] },\n",
            1,
        );
    let model = HandModel::from_toml(
        Path::new("hand.toml"),
        &text,
        &crate::geometry::FileLimits::default(),
    )
    .unwrap();
    assert_eq!(
        Retargeter::new(model).unwrap_err().to_string(),
        "segment \"index inner\": more than two degrees of freedom about axes through the joint"
    );
}
