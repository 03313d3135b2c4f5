//! Force output for force-feedback devices: a spring-damper between the visible part and its ghost.
//!
//! The ghost is where the hand holds the part; the visible part is where the simulation lets it be.
//! A device that renders the returned wrench on the hand pulls the hand back towards the visible
//! part, so that the user feels the contacts that keep the part from penetrating.

use nalgebra::Vector3;

use super::motion::{Motion, Pose};

/// Stiffness, damping and limits of the spring-damper, from the scene's sliding parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ForceParams {
    /// Translational stiffness, N/m.
    pub stiffness: f64,
    /// Translational damping, N·s/m.
    pub damping: f64,
    /// Rotational stiffness, N·m/rad.
    pub angular_stiffness: f64,
    /// Rotational damping, N·m·s/rad.
    pub angular_damping: f64,
    /// Largest force magnitude sent to a device, N (devices saturate; this keeps them stable).
    pub max_force: f64,
    /// Largest torque magnitude sent to a device, N·m.
    pub max_torque: f64,
}

impl Default for ForceParams {
    /// Values a desktop haptic arm renders comfortably.
    fn default() -> Self {
        ForceParams {
            stiffness: 500.0,
            damping: 5.0,
            angular_stiffness: 2.0,
            angular_damping: 0.02,
            max_force: 20.0,
            max_torque: 1.0,
        }
    }
}

/// A force and a torque (about the part's pivot), in the world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force, N.
    pub force: Vector3<f64>,
    /// Torque, N·m.
    pub torque: Vector3<f64>,
}

/// The spring-damper, remembering the previous offset to differentiate it.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceModel {
    params: ForceParams,
    previous_offset: Option<Motion>,
}

impl ForceModel {
    /// A spring-damper with the given parameters and no history.
    pub fn new(params: ForceParams) -> Self {
        ForceModel {
            params,
            previous_offset: None,
        }
    }

    /// The wrench to render on the hand, given the visible part's and the ghost's pivot poses and
    /// the time since the previous call (seconds; the damping term is skipped when it is not
    /// positive and finite, or on the first call).
    pub fn update(&mut self, visible: &Pose, ghost: &Pose, dt: f64) -> Wrench {
        // The offset that takes the ghost to the visible part: the spring pulls along it.
        let offset = Motion::between(ghost, visible);
        let rate = match self.previous_offset {
            Some(previous) if dt > 0.0 && dt.is_finite() => Motion {
                translation: (offset.translation - previous.translation) / dt,
                rotation: (offset.rotation - previous.rotation) / dt,
            },
            _ => Motion::default(),
        };
        self.previous_offset = Some(offset);
        let p = &self.params;
        Wrench {
            force: clamp_norm(
                offset.translation * p.stiffness + rate.translation * p.damping,
                p.max_force,
            ),
            torque: clamp_norm(
                offset.rotation * p.angular_stiffness + rate.rotation * p.angular_damping,
                p.max_torque,
            ),
        }
    }

    /// Forgets the history (on grasp and release).
    pub fn reset(&mut self) {
        self.previous_offset = None;
    }
}

/// `v` shortened to at most `limit` long.
fn clamp_norm(v: Vector3<f64>, limit: f64) -> Vector3<f64> {
    let norm = v.norm();
    if norm > limit { v * (limit / norm) } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64) -> Pose {
        Pose::translation(x, 0.0, 0.0)
    }

    #[test]
    fn the_spring_pulls_the_hand_towards_the_visible_part() {
        let mut model = ForceModel::new(ForceParams::default());
        let w = model.update(&at(0.0), &at(0.01), 0.001);
        assert!((w.force - Vector3::new(-5.0, 0.0, 0.0)).norm() < 1e-9);
        assert_eq!(w.torque, Vector3::zeros());
    }

    #[test]
    fn the_damper_opposes_a_growing_offset_and_forces_are_clamped() {
        let params = ForceParams {
            damping: 10.0,
            ..ForceParams::default()
        };
        let mut model = ForceModel::new(params);
        model.update(&at(0.0), &at(0.01), 0.001);
        // The offset grows by 1 mm in 1 ms: 1 m/s, so damping adds 10 N to the spring's 5.5 N.
        let w = model.update(&at(0.0), &at(0.011), 0.001);
        assert!((w.force.x + 15.5).abs() < 1e-9, "{}", w.force);
        let far = model.update(&at(0.0), &at(1.0), 0.001);
        assert!((far.force.norm() - params.max_force).abs() < 1e-9);
    }

    #[test]
    fn a_twisted_ghost_gives_a_restoring_torque() {
        let mut model = ForceModel::new(ForceParams::default());
        let ghost = Pose::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 0.1));
        let w = model.update(&Pose::identity(), &ghost, 0.0);
        assert!((w.torque - Vector3::new(0.0, 0.0, -0.2)).norm() < 1e-9);
        assert_eq!(w.force, Vector3::zeros());
    }
}
