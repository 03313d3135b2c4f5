use super::*;

fn touch(
    finger: Finger,
    level: JointLevel,
    side: ContactSide,
    normal: [f64; 3],
    points: &[[f64; 3]],
) -> Touch {
    Touch {
        segment: 0,
        finger,
        level,
        contact: Contact {
            points: points.iter().map(|&p| Point3::from(p)).collect(),
            normal: Unit::new_normalize(Vector3::from(normal)),
            side,
        },
    }
}

use ContactSide::{Dorsal, Lateral, Palmar, Tip};
use Finger::{Index, Middle, Palm, Pinky, Ring, Thumb};
use JointLevel::{Inner, Middle as Mid, Outer};

/// The palm's palmar face touching a part above it, around the origin, 8 cm square.
fn palm_under() -> Touch {
    touch(
        Palm,
        JointLevel::Palm,
        Palmar,
        [0., 0., 1.],
        &[
            [-0.04, -0.04, 0.],
            [0.04, -0.04, 0.],
            [0.04, 0.04, 0.],
            [-0.04, 0.04, 0.],
        ],
    )
}

fn flat_finger_under(finger: Finger, level: JointLevel, x: f64) -> Touch {
    touch(
        finger,
        level,
        Palmar,
        [0., 0.1, 1.],
        &[[x, 0.06, 0.], [x, 0.09, 0.]],
    )
}

fn classify_default(touches: &[Touch], com: [f64; 3]) -> Option<GraspClass> {
    classify(touches, &Point3::from(com), &AnalysisParams::default())
}

#[test]
fn nothing_touching_is_no_grasp_and_the_back_of_the_hand_only_pushes() {
    assert_eq!(classify_default(&[], [0.; 3]), None);
    let back = touch(
        Palm,
        JointLevel::Palm,
        Dorsal,
        [0., 0., 1.],
        &[[0., 0., 0.]],
    );
    assert_eq!(
        classify_default(std::slice::from_ref(&back), [0., 0., 0.05]),
        Some(GraspClass::Push)
    );
    // Even with fingers wrapped around the other side.
    let wrap = touch(Index, Outer, Palmar, [0., 0., -1.], &[[0., 0.05, 0.05]]);
    assert_eq!(
        classify_default(&[back, wrap], [0., 0., 0.05]),
        Some(GraspClass::Push)
    );
}

#[test]
fn a_part_resting_on_the_open_hand_is_a_gravity_grasp() {
    let hand = [
        palm_under(),
        flat_finger_under(Index, Mid, -0.03),
        flat_finger_under(Middle, Outer, -0.01),
    ];
    assert_eq!(
        classify_default(&hand, [0.0, 0.02, 0.05]),
        Some(GraspClass::Gravity)
    );
    assert_eq!(
        classify_default(&hand[..1], [0.01, -0.01, 0.03]),
        Some(GraspClass::Gravity)
    );
    // Centre of mass beyond the hand's edge: it would tip off; the flat hand only pushes.
    assert_eq!(
        classify_default(&hand, [0.0, 0.2, 0.05]),
        Some(GraspClass::Push)
    );
    assert_eq!(
        classify_default(&hand[..1], [0.1, 0.0, 0.05]),
        Some(GraspClass::Push)
    );
    // A palm pressed on the side of a part pushes it.
    let side = touch(
        Palm,
        JointLevel::Palm,
        Palmar,
        [1., 0., 0.],
        &[[0., -0.04, -0.04], [0., 0.04, 0.04], [0., 0.04, -0.04]],
    );
    assert_eq!(
        classify_default(&[side], [0.05, 0.0, 0.0]),
        Some(GraspClass::Push)
    );
    // With the thumb holding on it is no longer resting.
    let thumb = touch(Thumb, Outer, Palmar, [1., 0., 0.], &[[-0.05, 0.0, 0.02]]);
    assert_eq!(
        classify_default(&[palm_under(), thumb], [0., 0., 0.05]),
        Some(GraspClass::Power)
    );
}

#[test]
fn the_paper_rules_for_push_and_power() {
    // Rule 1: a single segment.
    let tip = touch(Index, Outer, Tip, [0., 1., 0.], &[[0., 0.15, 0.]]);
    assert_eq!(
        classify_default(&[tip], [0., 0.2, 0.]),
        Some(GraspClass::Push)
    );
    // Rule 2: fingers, no thumb, no palm, on one face.
    let fingers = [
        touch(Index, Outer, Tip, [0., 1., 0.], &[[-0.03, 0.15, 0.]]),
        touch(Middle, Outer, Tip, [0., 1., 0.], &[[-0.01, 0.16, 0.]]),
        touch(Ring, Outer, Tip, [0., 1., 0.], &[[0.01, 0.15, 0.]]),
    ];
    assert_eq!(
        classify_default(&fingers, [0., 0.2, 0.]),
        Some(GraspClass::Push)
    );
    // Rule 4: the palm and wrapping outer segments (a handle below the palm, axis along x).
    let palm = touch(
        Palm,
        JointLevel::Palm,
        Palmar,
        [0., 0., -1.],
        &[[0., 0.06, -0.0125]],
    );
    let wrap = [
        palm.clone(),
        touch(Index, Mid, Palmar, [0., -0.7, 0.7], &[[-0.03, 0.1, -0.05]]),
        touch(
            Middle,
            Outer,
            Palmar,
            [0., -1., 0.3],
            &[[-0.01, 0.07, -0.04]],
        ),
        touch(
            Thumb,
            Outer,
            Palmar,
            [0.3, 0.6, 0.7],
            &[[-0.05, 0.04, -0.05]],
        ),
    ];
    assert_eq!(
        classify_default(&wrap, [0., 0.06, -0.03]),
        Some(GraspClass::Power)
    );
    // Rule 5: the palm and inner segments only.
    let inner = [
        palm.clone(),
        touch(
            Index,
            Inner,
            Palmar,
            [0., -0.7, 0.7],
            &[[-0.03, 0.1, -0.03]],
        ),
    ];
    assert_eq!(
        classify_default(&inner, [0., 0.06, -0.03]),
        Some(GraspClass::Push)
    );
    // A flat hand pressed down on a face: outer segments touch but nothing opposes the palm.
    let flat = [
        palm,
        touch(
            Middle,
            Outer,
            Palmar,
            [0., 0.1, -1.],
            &[[-0.01, 0.17, -0.01]],
        ),
    ];
    assert_eq!(
        classify_default(&flat, [0., 0.1, -0.05]),
        Some(GraspClass::Push)
    );
}

#[test]
fn precision_grasps_and_their_kinds() {
    let thumb_tip = touch(Thumb, Outer, Tip, [0.8, 0.6, 0.], &[[-0.02, 0.12, -0.03]]);
    let index_tip = touch(
        Index,
        Outer,
        Palmar,
        [-0.8, -0.6, 0.],
        &[[-0.01, 0.13, -0.03]],
    );
    let middle_tip = touch(
        Middle,
        Outer,
        Palmar,
        [-0.6, -0.8, 0.],
        &[[0.0, 0.135, -0.03]],
    );
    let com = [-0.015, 0.125, -0.03];
    assert_eq!(
        classify_default(&[thumb_tip.clone(), index_tip.clone()], com),
        Some(GraspClass::Precision(PrecisionKind::TipPinch))
    );
    assert_eq!(
        classify_default(
            &[thumb_tip.clone(), index_tip.clone(), middle_tip.clone()],
            com
        ),
        Some(GraspClass::Precision(PrecisionKind::ThreeJawChuck))
    );
    // The middle finger's side instead of its tip: a 3-point pinch.
    let middle_side = touch(Middle, Mid, Lateral, [-1., 0., 0.], &[[0.0, 0.12, -0.03]]);
    assert_eq!(
        classify_default(&[thumb_tip.clone(), index_tip.clone(), middle_side], com),
        Some(GraspClass::ThreePointPinch)
    );
    // The thumb pad on the side of the index's middle segment: a key grasp.
    let index_side = touch(Index, Mid, Lateral, [-1., 0., 0.], &[[-0.035, 0.14, 0.0]]);
    let thumb_pad = touch(Thumb, Outer, Palmar, [1., 0., 0.], &[[-0.045, 0.14, 0.0]]);
    assert_eq!(
        classify_default(&[thumb_pad, index_side], [-0.04, 0.14, 0.0]),
        Some(GraspClass::Precision(PrecisionKind::Key))
    );
    // Thumb and four fingers around a disc.
    let all = [
        thumb_tip.clone(),
        index_tip.clone(),
        middle_tip,
        touch(
            Ring,
            Outer,
            Palmar,
            [-0.5, -0.8, 0.],
            &[[0.01, 0.13, -0.03]],
        ),
        touch(
            Pinky,
            Outer,
            Palmar,
            [-0.3, -0.9, 0.],
            &[[0.03, 0.12, -0.03]],
        ),
    ];
    assert_eq!(
        classify_default(&all, com),
        Some(GraspClass::Precision(PrecisionKind::Other))
    );
    // Thumb and index both pressing on one face, side by side: no opposition, a push.
    let same_way = touch(Thumb, Outer, Tip, [-0.8, -0.6, 0.], &[[-0.02, 0.12, -0.03]]);
    assert_eq!(
        classify_default(&[same_way, index_tip], com),
        Some(GraspClass::Push)
    );
}

#[test]
fn a_cigarette_is_held_between_the_sides_of_neighbouring_fingers() {
    let index = touch(Index, Mid, Lateral, [1., 0., 0.], &[[-0.021, 0.15, 0.0]]);
    let middle = touch(Middle, Mid, Lateral, [-1., 0., 0.], &[[-0.019, 0.15, 0.0]]);
    assert_eq!(
        classify_default(&[index.clone(), middle], [-0.02, 0.15, 0.03]),
        Some(GraspClass::Cigarette)
    );
    // Pressing apart (the part outside the pair) is no cigarette grasp.
    let out_index = touch(Index, Mid, Lateral, [-1., 0., 0.], &[[-0.04, 0.15, 0.0]]);
    let out_middle = touch(Middle, Mid, Lateral, [1., 0., 0.], &[[0.0, 0.15, 0.0]]);
    assert_eq!(
        classify_default(&[out_index, out_middle], [-0.02, 0.15, 0.0]),
        Some(GraspClass::Push)
    );
    // Fingers that are not neighbours.
    let ring = touch(Ring, Mid, Lateral, [-1., 0., 0.], &[[0.0, 0.15, 0.0]]);
    assert_eq!(
        classify_default(&[index.clone(), ring], [-0.01, 0.15, 0.0]),
        Some(GraspClass::Push)
    );
    // Pads instead of sides.
    let pad = touch(Middle, Mid, Palmar, [-1., 0., 0.], &[[-0.019, 0.15, 0.0]]);
    assert_eq!(
        classify_default(&[index, pad], [-0.02, 0.15, 0.0]),
        Some(GraspClass::Push)
    );
}

#[test]
fn a_held_part_keeps_its_grasp_with_relaxed_thresholds() {
    // Palm and thumb 55 degrees apart: not opposed enough to take the part, enough to keep it.
    let palm = touch(
        Palm,
        JointLevel::Palm,
        Palmar,
        [0., 0., -1.],
        &[[0., 0.06, -0.0125]],
    );
    let (s, c) = 55f64.to_radians().sin_cos();
    let thumb = touch(Thumb, Mid, Palmar, [s, 0., -c], &[[-0.04, 0.05, -0.03]]);
    let params = AnalysisParams::default();
    let com = Point3::new(0., 0.06, -0.03);
    assert_eq!(
        classify(&[palm.clone(), thumb.clone()], &com, &params),
        Some(GraspClass::Push)
    );
    assert_eq!(
        classify(&[palm, thumb], &com, &params.for_held()),
        Some(GraspClass::Power)
    );
    // Resting tilted 50 degrees: kept but not taken.
    let (s, c) = 50f64.to_radians().sin_cos();
    let tilted = touch(
        Palm,
        JointLevel::Palm,
        Palmar,
        [s, 0., c],
        &[[-0.03, -0.03, 0.0], [0.03, -0.03, 0.0], [0.0, 0.03, 0.0]],
    );
    let above = Point3::new(0.0, 0.0, 0.02);
    assert_eq!(
        classify(std::slice::from_ref(&tilted), &above, &params),
        Some(GraspClass::Push)
    );
    assert_eq!(
        classify(&[tilted], &above, &params.for_held()),
        Some(GraspClass::Gravity)
    );
}

#[test]
fn firmness_ranks_the_holding_types() {
    let order = [
        GraspClass::Push,
        GraspClass::Gravity,
        GraspClass::Cigarette,
        GraspClass::Precision(PrecisionKind::TipPinch),
        GraspClass::ThreePointPinch,
        GraspClass::Power,
    ];
    for pair in order.windows(2) {
        assert!(pair[0].firmness() < pair[1].firmness());
    }
    assert!(!GraspClass::Push.holds());
    assert!(order[1..].iter().all(|g| g.holds()));
}
