//! The Unity and Unreal conversions against poses worked out by hand, through the C functions.

use vas_client::{
    VasStatus, vas_point_from_unity, vas_point_from_unreal, vas_point_to_unity,
    vas_point_to_unreal, vas_pose_from_unity, vas_pose_from_unreal, vas_pose_to_unity,
    vas_pose_to_unreal,
};
use vas_protocol::WirePose;

/// sin 45° = cos 45°: half of a 90° turn's quaternion.
const HALF: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The point (1, 2, 3) m turned 90° about vas's z (up): counter-clockwise seen from above, so
/// vas's x axis goes to its y axis. Its quaternion is (0, 0, sin 45°, cos 45°).
const VAS_POSE: WirePose = WirePose {
    position: [1.0, 2.0, 3.0],
    rotation: [0.0, 0.0, HALF, HALF],
};

type Convert<T> = unsafe extern "C" fn(*const T, *mut T) -> VasStatus;

fn call<T: Copy>(function: Convert<T>, from: T) -> T {
    let mut to = from;
    // SAFETY: both pointers are to live values of the right type.
    assert_eq!(unsafe { function(&from, &mut to) }, VasStatus::Ok);
    to
}

fn assert_close(actual: &[f64], expected: &[f64]) {
    assert_eq!(actual.len(), expected.len());
    for (a, e) in actual.iter().zip(expected) {
        assert!((a - e).abs() < 1e-12, "{actual:?} is not {expected:?}");
    }
}

/// Turns `v` by the unit quaternion `q` (x, y, z, w): v + 2w (u × v) + 2 u × (u × v).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let u = [q[0], q[1], q[2]];
    let uv = cross(u, v);
    let uuv = cross(u, uv);
    std::array::from_fn(|i| v[i] + 2.0 * q[3] * uv[i] + 2.0 * uuv[i])
}

/// Unity is y up, left-handed: vas's x stays x, vas's y (forward) is Unity's z, vas's z (up) is
/// Unity's y, so (1, 2, 3) is (1, 3, 2). The turn takes x to vas's y, which is Unity's z: in
/// Unity's own quaternion arithmetic that is −90° about y, (0, −sin 45°, 0, cos 45°) (a turn
/// about y by θ takes x to (cos θ, 0, −sin θ), and θ = −90° gives (0, 0, 1)).
#[test]
fn a_pose_in_unity() {
    let unity = call(vas_pose_to_unity, VAS_POSE);
    assert_close(&unity.position, &[1.0, 3.0, 2.0]);
    assert_close(&unity.rotation, &[0.0, -HALF, 0.0, HALF]);
    assert_close(&rotate(unity.rotation, [1.0, 0.0, 0.0]), &[0.0, 0.0, 1.0]);
    let back = call(vas_pose_from_unity, unity);
    assert_close(&back.position, &VAS_POSE.position);
    assert_close(&back.rotation, &VAS_POSE.rotation);
}

/// Unreal is z up, left-handed, x forward, y right, in centimetres: vas's y (left of x) is
/// Unreal's −y, so (1, 2, 3) m is (100, −200, 300) cm. The turn takes x to vas's y, Unreal's −y:
/// −90° about z in Unreal's arithmetic, (0, 0, −sin 45°, cos 45°) (a turn about z by θ takes x to
/// (cos θ, sin θ, 0), and θ = −90° gives (0, −1, 0)).
#[test]
fn a_pose_in_unreal() {
    let unreal = call(vas_pose_to_unreal, VAS_POSE);
    assert_close(&unreal.position, &[100.0, -200.0, 300.0]);
    assert_close(&unreal.rotation, &[0.0, 0.0, -HALF, HALF]);
    assert_close(&rotate(unreal.rotation, [1.0, 0.0, 0.0]), &[0.0, -1.0, 0.0]);
    let back = call(vas_pose_from_unreal, unreal);
    assert_close(&back.position, &VAS_POSE.position);
    assert_close(&back.rotation, &VAS_POSE.rotation);
}

/// A turn about a tilted axis: converting the pose and then turning a converted vector gives the
/// converted turned vector, in both engines, for every axis (the conjugation by the mirror the
/// header promises).
#[test]
fn a_converted_turn_turns_converted_vectors() {
    // 120° about (1, 1, 1)/√3: x → y → z → x.
    let half_sin = (60f64.to_radians()).sin() / 3f64.sqrt();
    let turn = [half_sin, half_sin, half_sin, 60f64.to_radians().cos()];
    let pose = WirePose {
        position: [0.0; 3],
        rotation: turn,
    };
    let engines: [(Convert<WirePose>, Convert<[f64; 3]>, f64); 2] = [
        (vas_pose_to_unity, vas_point_to_unity, 1.0),
        (vas_pose_to_unreal, vas_point_to_unreal, 100.0),
    ];
    for (pose_to, point_to, scale) in engines {
        let converted = call(pose_to, pose).rotation;
        for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            let turned_then_converted = call(point_to, rotate(turn, axis)).map(|v| v / scale);
            let converted_then_turned = rotate(converted, call(point_to, axis).map(|v| v / scale));
            assert_close(&converted_then_turned, &turned_then_converted);
        }
    }
}

#[test]
fn points_convert_and_come_back() {
    assert_close(&call(vas_point_to_unity, [1.0, 2.0, 3.0]), &[1.0, 3.0, 2.0]);
    assert_close(
        &call(vas_point_from_unity, [1.0, 3.0, 2.0]),
        &[1.0, 2.0, 3.0],
    );
    assert_close(
        &call(vas_point_to_unreal, [1.0, 2.0, 3.0]),
        &[100.0, -200.0, 300.0],
    );
    assert_close(
        &call(vas_point_from_unreal, [100.0, -200.0, 300.0]),
        &[1.0, 2.0, 3.0],
    );
}

#[test]
fn null_pointers_are_errors() {
    let mut out = VAS_POSE;
    // SAFETY: null pointers are what is tested; `out` is writable.
    let status = unsafe { vas_pose_to_unity(std::ptr::null(), &mut out) };
    assert_eq!(status, VasStatus::NullArgument);
    // SAFETY: as above.
    let status = unsafe { vas_point_to_unreal(&[0.0; 3], std::ptr::null_mut()) };
    assert_eq!(status, VasStatus::NullArgument);
}
