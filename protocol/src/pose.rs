//! Rigid poses on the wire and their nalgebra counterparts.

use iceoryx2::prelude::ZeroCopySend;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// A rigid pose: position in metres and a unit quaternion `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
pub struct WirePose {
    /// Position in metres.
    pub position: [f64; 3],
    /// Rotation as a unit quaternion in x, y, z, w order.
    pub rotation: [f64; 4],
}

impl WirePose {
    /// The identity pose: at the origin, not rotated.
    pub const IDENTITY: Self = Self {
        position: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };

    /// The wire form of an isometry.
    pub fn from_isometry(pose: &Isometry3<f64>) -> Self {
        let t = pose.translation.vector;
        let q = pose.rotation.quaternion();
        Self {
            position: [t.x, t.y, t.z],
            rotation: [q.i, q.j, q.k, q.w],
        }
    }

    /// The isometry this pose describes, renormalising the quaternion.
    ///
    /// Meant for poses that passed validation (see [`crate::TrackerSample::validate`]); a zero or
    /// non-finite quaternion gives a non-finite rotation rather than a panic.
    pub fn to_isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            self.translation(),
            UnitQuaternion::new_normalize(self.quaternion()),
        )
    }

    /// The position as a nalgebra translation.
    pub fn translation(&self) -> Translation3<f64> {
        let [x, y, z] = self.position;
        Translation3::new(x, y, z)
    }

    /// The rotation as a (not necessarily unit) nalgebra quaternion.
    pub fn quaternion(&self) -> Quaternion<f64> {
        let [x, y, z, w] = self.rotation;
        Quaternion::new(w, x, y, z)
    }

    /// Whether every coordinate is finite.
    pub fn is_finite(&self) -> bool {
        self.position
            .iter()
            .chain(&self.rotation)
            .all(|v| v.is_finite())
    }
}

impl Default for WirePose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl From<&Isometry3<f64>> for WirePose {
    fn from(pose: &Isometry3<f64>) -> Self {
        Self::from_isometry(pose)
    }
}

impl From<Isometry3<f64>> for WirePose {
    fn from(pose: Isometry3<f64>) -> Self {
        Self::from_isometry(&pose)
    }
}

impl From<&WirePose> for Isometry3<f64> {
    fn from(pose: &WirePose) -> Self {
        pose.to_isometry()
    }
}

impl From<WirePose> for Isometry3<f64> {
    fn from(pose: WirePose) -> Self {
        pose.to_isometry()
    }
}
