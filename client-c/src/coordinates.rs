//! Poses and points between vas's frame and the frames of Unity and Unreal.
//!
//! vas is right-handed, z up, in metres. Unity is left-handed, y up, in metres; Unreal is
//! left-handed, z up (x forward, y right), in centimetres. Each engine's frame is vas's under a
//! signed permutation of the axes and a scale:
//!
//! * Unity `(x, y, z) = (x, z, y)` of vas: vas's y (forward) becomes Unity's z, vas's up its y.
//! * Unreal `(x, y, z) = 100 (x, −y, z)` of vas: vas's y (left) becomes Unreal's −y (right).
//!
//! Both are reflections (determinant −1), which is what turns right-handed into left-handed. A
//! rotation `R` becomes `M R Mᵀ`; its quaternion's vector part turns with `M` times the
//! determinant (an axis is a pseudo-vector), its scalar part stays: a point and a quaternion
//! convert by a few sign changes and swaps, no trigonometry. A reflection also reverses the
//! winding of triangles, so an engine that culls back faces swaps two indices of each triangle.

use vas_protocol::WirePose;

use crate::pointers::{input, output};
use crate::status::{VasStatus, guard};

/// An engine's frame: its coordinate `i` is `sign[i] × scale ×` vas's coordinate `axis[i]`.
struct EngineFrame {
    axis: [usize; 3],
    sign: [f64; 3],
    /// Engine units per metre.
    scale: f64,
}

/// Unity: left-handed, y up, metres.
const UNITY: EngineFrame = EngineFrame {
    axis: [0, 2, 1],
    sign: [1.0, 1.0, 1.0],
    scale: 1.0,
};

/// Unreal: left-handed, z up, x forward, y right, centimetres.
const UNREAL: EngineFrame = EngineFrame {
    axis: [0, 1, 2],
    sign: [1.0, -1.0, 1.0],
    scale: 100.0,
};

impl EngineFrame {
    /// The determinant of the axis map: the parity of the permutation times the signs.
    fn determinant(&self) -> f64 {
        let [a, b, c] = self.axis;
        let even = (a + 1) % 3 == b && (b + 1) % 3 == c;
        let parity = if even { 1.0 } else { -1.0 };
        parity * self.sign.iter().product::<f64>()
    }

    /// A direction of vas in this frame (no scale).
    fn direction_to(&self, vas: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.sign[i] * vas[self.axis[i]])
    }

    /// A direction of this frame in vas's (no scale).
    fn direction_from(&self, engine: [f64; 3]) -> [f64; 3] {
        let mut vas = [0.0; 3];
        for i in 0..3 {
            vas[self.axis[i]] = self.sign[i] * engine[i];
        }
        vas
    }

    fn point_to(&self, vas: [f64; 3]) -> [f64; 3] {
        self.direction_to(vas).map(|value| value * self.scale)
    }

    fn point_from(&self, engine: [f64; 3]) -> [f64; 3] {
        self.direction_from(engine).map(|value| value / self.scale)
    }

    fn rotation_to(&self, [x, y, z, w]: [f64; 4]) -> [f64; 4] {
        let [x, y, z] = self.direction_to([x, y, z]).map(|v| v * self.determinant());
        [x, y, z, w]
    }

    fn rotation_from(&self, [x, y, z, w]: [f64; 4]) -> [f64; 4] {
        let [x, y, z] = self
            .direction_from([x, y, z])
            .map(|v| v * self.determinant());
        [x, y, z, w]
    }

    fn pose_to(&self, pose: &WirePose) -> WirePose {
        WirePose {
            position: self.point_to(pose.position),
            rotation: self.rotation_to(pose.rotation),
        }
    }

    fn pose_from(&self, pose: &WirePose) -> WirePose {
        WirePose {
            position: self.point_from(pose.position),
            rotation: self.rotation_from(pose.rotation),
        }
    }
}

/// Converts `*from` with `convert` into `*to`; `from` and `to` may be the same.
///
/// # Safety
/// `from` points to a readable `T`, `to` to a writable `T`.
unsafe fn convert<T: Copy>(from: *const T, to: *mut T, convert: impl FnOnce(T) -> T) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees; the value is copied before `to` is written.
        let value = *unsafe { input(from, "from") }?;
        // SAFETY: as the caller guarantees.
        *unsafe { output(to, "to") }? = convert(value);
        Ok(VasStatus::Ok)
    })
}

/// Converts a pose of vas (metres, right-handed, z up) into Unity's (metres, left-handed, y up):
/// position `(x, z, y)`, rotation `(−qx, −qz, −qy, qw)`. `to` may be `from`.
///
/// # Safety
/// `from` points to a readable pose, `to` to a writable one.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_pose_to_unity(from: *const WirePose, to: *mut WirePose) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |pose| UNITY.pose_to(&pose)) }
}

/// Converts a pose of Unity into vas's: the inverse of [`vas_pose_to_unity`] (the same swaps).
///
/// # Safety
/// `from` points to a readable pose, `to` to a writable one.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_pose_from_unity(
    from: *const WirePose,
    to: *mut WirePose,
) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |pose| UNITY.pose_from(&pose)) }
}

/// Converts a pose of vas into Unreal's (centimetres, left-handed, z up, x forward, y right):
/// position `100 (x, −y, z)`, rotation `(−qx, qy, −qz, qw)`. `to` may be `from`.
///
/// # Safety
/// `from` points to a readable pose, `to` to a writable one.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_pose_to_unreal(from: *const WirePose, to: *mut WirePose) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |pose| UNREAL.pose_to(&pose)) }
}

/// Converts a pose of Unreal into vas's: the inverse of [`vas_pose_to_unreal`].
///
/// # Safety
/// `from` points to a readable pose, `to` to a writable one.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_pose_from_unreal(
    from: *const WirePose,
    to: *mut WirePose,
) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |pose| UNREAL.pose_from(&pose)) }
}

/// Converts a point of vas (3 doubles, metres) into Unity's: `(x, z, y)`. Normals and
/// directions convert the same way. `to` may be `from`.
///
/// # Safety
/// `from` points to 3 readable doubles, `to` to 3 writable ones.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_point_to_unity(from: *const [f64; 3], to: *mut [f64; 3]) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |point| UNITY.point_to(point)) }
}

/// Converts a point of Unity into vas's: the inverse of [`vas_point_to_unity`].
///
/// # Safety
/// `from` points to 3 readable doubles, `to` to 3 writable ones.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_point_from_unity(
    from: *const [f64; 3],
    to: *mut [f64; 3],
) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |point| UNITY.point_from(point)) }
}

/// Converts a point of vas (metres) into Unreal's (centimetres): `100 (x, −y, z)`. A direction
/// or normal converts as `(x, −y, z)`, without the scale. `to` may be `from`.
///
/// # Safety
/// `from` points to 3 readable doubles, `to` to 3 writable ones.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_point_to_unreal(
    from: *const [f64; 3],
    to: *mut [f64; 3],
) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |point| UNREAL.point_to(point)) }
}

/// Converts a point of Unreal (centimetres) into vas's (metres): the inverse of
/// [`vas_point_to_unreal`].
///
/// # Safety
/// `from` points to 3 readable doubles, `to` to 3 writable ones.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_point_from_unreal(
    from: *const [f64; 3],
    to: *mut [f64; 3],
) -> VasStatus {
    // SAFETY: as the caller guarantees.
    unsafe { convert(from, to, |point| UNREAL.point_from(point)) }
}
