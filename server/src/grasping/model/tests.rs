use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

use super::*;
use crate::geometry::FileLimits;
use std::f64::consts::FRAC_PI_2;

pub(crate) fn hands_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands")
}

/// The project's right hand, for tests across the grasping module.
pub(crate) fn right_hand() -> HandModel {
    HandModel::load(&hands_dir().join("right.toml")).expect("right hand loads")
}

fn segment(model: &HandModel, name: &str) -> SegmentId {
    model
        .segments()
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no segment {name}"))
}

fn assert_pose(pose: &Isometry3<f64>, translation: [f64; 3], rotation: UnitQuaternion<f64>) {
    let t = Vector3::from(translation);
    assert!(
        (pose.translation.vector - t).norm() < 1e-12,
        "translation {} != {t}",
        pose.translation.vector
    );
    assert!(
        pose.rotation.angle_to(&rotation) < 1e-12,
        "rotation {:?} != {rotation:?}",
        pose.rotation
    );
}

#[test]
fn both_hands_load_with_sixteen_segments() {
    let right = right_hand();
    let left = HandModel::load(&hands_dir().join("left.toml")).unwrap();
    assert_eq!(right.segments().len(), 16);
    assert_eq!(left.side(), HandSide::Left);
    assert_eq!(left.name(), "left hand, 22 DOF");
    assert_eq!(right.limits()[4].name, "index inner (MCP)");
    assert!((right.limits()[4].max - 90f64.to_radians()).abs() < 1e-15);
}

#[test]
fn forward_kinematics_of_a_curled_index_finger() {
    let model = right_hand();
    let mut flex = [0.0; FLEX_COUNT];
    let rest = model.segment_poses(&flex);
    assert_pose(
        &rest[segment(&model, "index outer")],
        [-0.029, 0.165, 0.0],
        UnitQuaternion::identity(),
    );

    // MCP at 90 degrees turns the finger to point palmar (-z); PIP at 90 more points it back
    // toward the wrist.
    flex[4] = FRAC_PI_2;
    flex[5] = FRAC_PI_2;
    let poses = model.segment_poses(&flex);
    let about_minus_x = |a: f64| UnitQuaternion::from_axis_angle(&-Vector3::x_axis(), a);
    // A segment's frame includes its own joint: the middle segment is turned by MCP and PIP.
    assert_pose(
        &poses[segment(&model, "index inner")],
        [-0.029, 0.095, 0.0],
        about_minus_x(FRAC_PI_2),
    );
    assert_pose(
        &poses[segment(&model, "index middle")],
        [-0.029, 0.095, -0.044],
        about_minus_x(2.0 * FRAC_PI_2),
    );
    assert_pose(
        &poses[segment(&model, "index outer")],
        [-0.029, 0.095 - 0.026, -0.044],
        about_minus_x(2.0 * FRAC_PI_2),
    );
}

#[test]
fn forward_kinematics_of_wrist_spread_and_palm_arch() {
    let model = right_hand();
    let mut flex = [0.0; FLEX_COUNT];
    // Wrist flexion by 90 degrees turns the palm so that the fingers point palmar (-z).
    flex[20] = FRAC_PI_2;
    let poses = model.segment_poses(&flex);
    assert_pose(
        &poses[segment(&model, "middle inner")],
        [-0.0095, 0.0, -0.098],
        UnitQuaternion::from_axis_angle(&-Vector3::x_axis(), FRAC_PI_2),
    );

    // The palm arch swings the little finger about the palm's centre line x = 0: at 90
    // degrees its base is below the centre line.
    let mut flex = [0.0; FLEX_COUNT];
    flex[19] = FRAC_PI_2;
    let poses = model.segment_poses(&flex);
    let about_y = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2);
    assert_pose(
        &poses[segment(&model, "pinky inner")],
        [0.0, 0.088, -0.028],
        about_y,
    );
    // The ring finger gets half the arch.
    let half = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2 / 2.0);
    let s = (FRAC_PI_2 / 2.0).sin() * 0.0095;
    let c = (FRAC_PI_2 / 2.0).cos() * 0.0095;
    assert_pose(&poses[segment(&model, "ring inner")], [c, 0.095, -s], half);

    // Ring-middle spread (F14) plus pinky-ring spread (F18) turn the little finger about -z.
    let mut flex = [0.0; FLEX_COUNT];
    flex[14] = 0.1;
    flex[18] = 0.2;
    let poses = model.segment_poses(&flex);
    let spread = UnitQuaternion::from_axis_angle(&-Vector3::z_axis(), 0.3);
    assert_pose(
        &poses[segment(&model, "pinky inner")],
        [0.028, 0.088, 0.0],
        spread,
    );
    let tip = poses[segment(&model, "pinky middle")].translation.vector;
    let expected = Vector3::new(
        0.028 + 0.036 * 0.3f64.sin(),
        0.088 + 0.036 * 0.3f64.cos(),
        0.0,
    );
    assert!((tip - expected).norm() < 1e-12);
}

#[test]
fn the_left_hand_is_the_mirror_image_of_the_right() {
    let right = right_hand();
    let left = HandModel::load(&hands_dir().join("left.toml")).unwrap();
    let mirror = Vector3::new(-1.0, 1.0, 1.0);
    let flex: FlexVector =
        std::array::from_fn(|i| 0.05 * (i as f64 + 1.0) * if i % 2 == 0 { 1.0 } else { -1.0 });
    let rp = right.segment_poses(&flex);
    let lp = left.segment_poses(&flex);
    for (r, l) in rp.iter().zip(&lp) {
        assert!(
            (l.translation.vector - r.translation.vector.component_mul(&mirror)).norm() < 1e-12
        );
        // S R S for S = diag(-1, 1, 1)
        let s = nalgebra::Matrix3::from_diagonal(&mirror);
        let expected = s * r.rotation.to_rotation_matrix().matrix() * s;
        assert!((l.rotation.to_rotation_matrix().matrix() - expected).norm() < 1e-12);
    }
}

#[test]
fn variable_sets_follow_the_chain() {
    let model = right_hand();
    let tip = &model.segments()[segment(&model, "pinky outer")];
    for v in [ROOT_VARIABLE, 20, 21, 19, 14, 18, 15, 16, 17] {
        assert!(tip.variables.contains(v), "pinky tip depends on {v}");
    }
    assert!(!tip.variables.contains(4));
    assert_eq!(tip.own_variables, VariableSet::single(17));
    let palm = &model.segments()[model.palm()];
    assert_eq!(
        palm.own_variables.iter().collect::<Vec<_>>(),
        vec![20, 21, ROOT_VARIABLE]
    );
    // Every variable moves something, and the root's lever is the hand's reach (about 20 cm).
    for v in 0..VARIABLE_COUNT {
        assert!(model.lever(v) > 0.01, "variable {v}");
    }
    assert!(
        (0.15..0.3).contains(&model.lever(ROOT_VARIABLE)),
        "{}",
        model.lever(ROOT_VARIABLE)
    );
}

fn refusal(text: &str) -> String {
    HandModel::from_toml(Path::new("hand.toml"), text, &FileLimits::default())
        .unwrap_err()
        .to_string()
}

fn right_text() -> String {
    std::fs::read_to_string(hands_dir().join("right.toml")).unwrap()
}

#[test]
fn bad_configs_are_refused_naming_file_key_and_reason() {
    let text = right_text();
    let cases = [
        (
            text.replacen(
                "[[flex]]\nname = \"thumb roll\"\nmin_deg = -30\nmax_deg = 70\n",
                "",
                1,
            ),
            "hand.toml: flex: expected 22 entries",
        ),
        (
            text.replacen("max_deg = 70", "max_deg = -40", 1),
            "hand.toml: flex[0] (thumb roll): need finite min_deg < max_deg",
        ),
        (
            text.replacen("parent = \"index inner\"", "parent = \"indx inner\"", 1),
            "segment[5] (index middle).parent: no segment named \"indx inner\"",
        ),
        (
            text.replacen(
                "axis = [-1.0, 0.0, 0.0], flex = [5]",
                "axis = [0.0, 0.0, 0.0], flex = [5]",
                1,
            ),
            "segment[5] (index middle).dofs[0].axis: must be finite and non-zero",
        ),
        (
            text.replacen("flex = [5]", "flex = [22]", 1),
            "segment[5] (index middle).dofs[0].flex: flex index 22 is not below 22",
        ),
        (
            text.replacen(
                "flex = [19], gains = [0.5]",
                "flex = [19], gains = [0.5, 1.0]",
                1,
            ),
            "segment[10] (ring inner).dofs[0].gains",
        ),
        (
            text.replacen("radius = 0.0088, centres", "radius = -0.0088, centres", 1),
            "segment[5] (index middle).shape.radius",
        ),
        (
            text.replacen("name = \"index outer\"", "name = \"index middle\"", 1),
            "segment[6] (index middle).name: names must be unique",
        ),
        (
            text.replacen(
                "finger = \"pinky\"\njoint = \"outer\"",
                "finger = \"pinky\"\njoint = \"middle\"",
                1,
            ),
            "segment[15] (pinky outer).parent: a Middle segment of the Pinky must hang from its Inner segment",
        ),
        (
            text.replacen(
                "origin = [0.0, 0.048, 0.0]",
                "origin = [0.0, 0.048, nan]",
                1,
            ),
            "segment[2] (thumb middle).origin: must be finite and within 10 m",
        ),
        (
            text.replacen("side = \"right\"", "side = \"right\"\nhandedness = 1", 1),
            "unknown field `handedness`",
        ),
    ];
    for (config, expected) in cases {
        let message = refusal(&config);
        assert!(
            message.contains(expected),
            "expected {expected:?} in {message:?}"
        );
        assert!(message.starts_with("hand.toml"), "{message}");
    }
}

#[test]
fn values_that_would_make_poses_non_finite_are_refused() {
    // Each was accepted, and gave infinite levers or NaN segment poses.
    let text = right_text();
    let cases = [
        (
            text.replacen(
                "origin = [0.0, 0.048, 0.0]",
                "origin = [0.0, 1e308, 0.0]",
                1,
            ),
            "segment[2] (thumb middle).origin: must be finite and within 10 m",
        ),
        (
            text.replacen(
                "pivot = [-0.0095, 0.0, 0.0]",
                "pivot = [-1e300, 0.0, 0.0]",
                1,
            ),
            "segment[10] (ring inner).dofs[0].pivot: must be finite and within 10 m",
        ),
        (
            text.replacen("[0.0, 0.026, 0.0]] }", "[0.0, 1e300, 0.0]] }", 1),
            "segment[5] (index middle).shape.centres: must be finite and within 10 m",
        ),
        (
            text.replacen("radius = 0.0088, centres", "radius = 1e300, centres", 1),
            "segment[5] (index middle).shape.radius",
        ),
        (
            text.replacen("gains = [0.5]", "gains = [1e300]", 1),
            "segment[10] (ring inner).dofs[0].gains: needs one finite gain per flex index, \
             each within ±100",
        ),
        (
            text.replacen(
                "name = \"palm arch\"\nmin_deg = -10\nmax_deg = 40",
                "name = \"palm arch\"\nmin_deg = -10\nmax_deg = 1e300",
                1,
            ),
            "flex[19] (palm arch): need finite min_deg < max_deg within ±360",
        ),
    ];
    for (config, expected) in cases {
        let message = refusal(&config);
        assert!(
            message.contains(expected),
            "expected {expected:?} in {message:?}"
        );
    }
}

#[test]
fn a_long_joint_axis_is_normalised_without_overflow() {
    // The square of its length overflowed, and the axis became the zero vector.
    let text = right_text().replacen(
        "axis = [-1.0, 0.0, 0.0], flex = [5]",
        "axis = [-1e308, -1e308, 0.0], flex = [5]",
        1,
    );
    let model =
        HandModel::from_toml(Path::new("hand.toml"), &text, &FileLimits::default()).expect("loads");
    let axis = model.segments()[segment(&model, "index middle")].dofs[0].axis;
    let expected = Vector3::new(-1.0, -1.0, 0.0).normalize();
    assert!((axis.into_inner() - expected).norm() < 1e-12, "{axis:?}");
}

#[test]
fn a_mirror_must_name_a_full_hand_of_the_other_side() {
    let dir = std::env::temp_dir().join(format!("vas-hand-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("right.toml"), right_text()).unwrap();
    std::fs::write(
        dir.join("wrong.toml"),
        "name = \"x\"\nside = \"right\"\nmirror_of = \"right.toml\"\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("chain.toml"),
        "name = \"x\"\nside = \"right\"\nmirror_of = \"left.toml\"\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("left.toml"),
        "name = \"x\"\nside = \"left\"\nmirror_of = \"right.toml\"\n",
    )
    .unwrap();
    let wrong = HandModel::load(&dir.join("wrong.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        wrong.contains("wrong.toml: side: a mirror of a Right hand is a Left hand"),
        "{wrong}"
    );
    let chain = HandModel::load(&dir.join("chain.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        chain.contains("chain.toml: mirror_of:") && chain.contains("is itself a mirror"),
        "{chain}"
    );
    let missing = HandModel::load(&dir.join("absent.toml"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("absent.toml: cannot read"), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}
