//! Contact approximation by interval bisection (the paper's §3.1): between the last valid pose and
//! the first colliding one, halve the interval with static collision checks until it is shorter
//! than the contact tolerance.
//!
//! [`Bisection`] performs one check per call so that the state machine can hand each check to the
//! collision loop. It usually follows conservative advancement (`advance`), which may ask for
//! the first cut near the free end, where the contact is expected.

use super::motion::{Pose, interpolate, pose_distance};

/// More halvings than this cannot shrink any finite interval further in `f64`.
const MAX_HALVINGS: u32 = 64;

/// An interval of poses whose start is known free and whose end is known colliding.
#[derive(Debug, Clone, PartialEq)]
pub struct Bisection {
    valid: Pose,
    colliding: Pose,
    tolerance: f64,
    radius: f64,
    halvings: u32,
    /// Where the next cut goes, as a fraction of the interval from its free end.
    cut: f64,
}

impl Bisection {
    /// Starts from a free pose and a colliding pose; `tolerance` in metres is measured with
    /// [`pose_distance`] at `radius` (the part's radius).
    pub fn new(valid: Pose, colliding: Pose, tolerance: f64, radius: f64) -> Self {
        Bisection {
            valid,
            colliding,
            tolerance,
            radius,
            halvings: 0,
            cut: 0.5,
        }
    }

    /// The same interval with its first cut `length` metres from the free end (if that is
    /// before the middle), where a contact is expected.
    pub fn first_cut_at(mut self, length: f64) -> Self {
        let whole = pose_distance(&self.valid, &self.colliding, self.radius);
        if whole > 0.0 {
            self.cut = (length / whole).min(0.5);
        }
        self
    }

    /// True when the interval is within tolerance (or cannot be halved any further).
    pub fn is_done(&self) -> bool {
        self.halvings >= MAX_HALVINGS
            || pose_distance(&self.valid, &self.colliding, self.radius) <= self.tolerance
    }

    /// The pose to check next: the middle of the interval, or the first cut asked for.
    pub fn trial(&self) -> Pose {
        interpolate(&self.valid, &self.colliding, self.cut)
    }

    /// Records whether the part collides at `trial` (a pose returned by [`Bisection::trial`]).
    pub fn record(&mut self, trial: Pose, collides: bool) {
        if collides {
            self.colliding = trial;
        } else {
            self.valid = trial;
        }
        self.halvings += 1;
        self.cut = 0.5;
    }

    /// The last pose known to be free.
    pub fn valid(&self) -> &Pose {
        &self.valid
    }

    /// The first pose known to collide.
    pub fn colliding(&self) -> &Pose {
        &self.colliding
    }

    /// How many checks were recorded.
    pub fn checks(&self) -> u32 {
        self.halvings
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proptest::prelude::*;

    /// Runs a [`Bisection`] to the end with `collides` as the static check; returns it finished.
    fn bisect(
        valid: Pose,
        colliding: Pose,
        tolerance: f64,
        radius: f64,
        mut collides: impl FnMut(&Pose) -> bool,
    ) -> Bisection {
        let mut bisection = Bisection::new(valid, colliding, tolerance, radius);
        while !bisection.is_done() {
            let trial = bisection.trial();
            let hit = collides(&trial);
            bisection.record(trial, hit);
        }
        bisection
    }

    fn pose(t: [f64; 3], axis_angle: [f64; 3]) -> Pose {
        Pose::new(Vector3::from(t), Vector3::from(axis_angle))
    }

    proptest! {
        /// Against a half-space obstacle (a point of the part must stay above a plane), the
        /// bisection brackets the exact contact parameter within the tolerance.
        #[test]
        fn brackets_the_contact_within_tolerance(
            start in prop::array::uniform3(-1.0f64..1.0),
            rot in prop::array::uniform3(-1.0f64..1.0),
            drop in 0.5f64..3.0,
            tolerance in 1e-6f64..1e-2,
        ) {
            let valid = pose([start[0], start[1], 1.0 + start[2].abs()], rot);
            let colliding = pose([start[0] + 0.3, start[1] - 0.2, -drop], [0.0; 3]);
            let probe = nalgebra::Point3::new(0.2, 0.1, -0.3);
            let collides = |p: &Pose| (p * probe).z < 0.0;
            prop_assume!(!collides(&valid) && collides(&colliding));
            let done = bisect(valid, colliding, tolerance, 0.5, collides);
            prop_assert!(!collides(done.valid()));
            prop_assert!(collides(done.colliding()));
            prop_assert!(pose_distance(done.valid(), done.colliding(), 0.5) <= tolerance);
            // Both ends lie on the interpolation path from the original ends.
            let start_to_valid = pose_distance(&valid, done.valid(), 0.5);
            let valid_to_end = pose_distance(done.valid(), &colliding, 0.5);
            prop_assert!(
                (start_to_valid + valid_to_end - pose_distance(&valid, &colliding, 0.5)).abs() < 1e-9
            );
        }
    }

    #[test]
    fn a_zero_tolerance_still_terminates() {
        let done = bisect(
            pose([0.0, 0.0, 1.0], [0.0; 3]),
            pose([0.0, 0.0, -1.0], [0.0; 3]),
            0.0,
            1.0,
            |p| p.translation.vector.z < 0.25,
        );
        assert_eq!(done.checks(), MAX_HALVINGS);
        assert!((done.valid().translation.vector.z - 0.25).abs() < 1e-12);
    }
}
