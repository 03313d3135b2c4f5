//! Conservative advancement: the first stage of contact approximation, before bisection.
//!
//! Between the last free pose and the first colliding one, the part at the free end is at some
//! distance `d` from every obstacle. Along the interpolation, no point of the part moves faster
//! than the interval's length per unit of its parameter (the pivot's travel plus the arc at the
//! part's radius, [`pose_distance`]), so the part can move `d` along it without touching
//! anything: the free end advances by that much for one distance query, however far the
//! colliding end lies. A head-on approach reaches the surface in one or two steps, where
//! bisection halves the whole interval down to the tolerance with one collision test a halving.
//!
//! The machine advances only when the scene asks for it (`conservative_advancement`: a distance
//! query near a close fit costs more than the collision tests it saves), and only a part that
//! arrives from free space: one pressed on the contacts it
//! remembers is within their release distance already, and a distance could not move it.
//! Advancement stops once the part is within the tolerance of an obstacle, or when a step
//! closed less than half the remaining gap (a grazing approach, where bisection does better);
//! bisection then goes on from the interval left. When advancement ended within the tolerance,
//! the contact most likely lies right ahead, so bisection's first cut is one tolerance ahead of
//! the free end instead of the middle.

use super::bisection::Bisection;
use super::motion::{Pose, interpolate, pose_distance};

/// More advancement steps than this go to bisection whatever they gain.
const MAX_STEPS: u32 = 16;

/// The share of the tolerance kept off the measured distance when advancing, so that the part
/// stops short of touching even with the distance rounded.
const MARGIN: f64 = 1e-3;

/// An interval of poses whose start is known free and whose end is known colliding, shortened
/// from its start by distance queries.
#[derive(Debug, Clone, PartialEq)]
pub struct Advance {
    valid: Pose,
    colliding: Pose,
    tolerance: f64,
    radius: f64,
    /// The distance measured at the previous step.
    last_distance: f64,
    steps: u32,
}

/// What comes after a distance query.
#[derive(Debug, Clone, PartialEq)]
pub enum Advanced {
    /// Another distance query, from a free end moved closer.
    Again(Advance),
    /// Bisection of the interval left.
    Bisect(Bisection),
}

impl Advance {
    /// Starts from a free pose and a colliding pose; `tolerance` in metres is measured with
    /// [`pose_distance`] at `radius` (the part's radius about its pivot: every point of the part
    /// lies within it).
    pub fn new(valid: Pose, colliding: Pose, tolerance: f64, radius: f64) -> Self {
        Advance {
            valid,
            colliding,
            tolerance,
            radius,
            last_distance: f64::INFINITY,
            steps: 0,
        }
    }

    /// The pose to measure (the free end) and the distance beyond which the measure does not
    /// matter: the most any point of the part moves over the rest of the interval.
    pub fn query(&self) -> (Pose, f64) {
        (self.valid, self.remaining())
    }

    /// Takes the distance from the free end to the obstacles (`None`: at least the bound of
    /// [`Advance::query`]) and advances the free end by it.
    pub fn record(mut self, distance: Option<f64>) -> Advanced {
        self.steps += 1;
        let remaining = self.remaining();
        let Some(distance) = distance.filter(|&d| d < remaining) else {
            // Nothing within the sweep, yet the end collides: only rounding does that.
            return Advanced::Bisect(self.bisection(false));
        };
        if distance <= self.tolerance {
            return Advanced::Bisect(self.bisection(true));
        }
        let step = distance - MARGIN * self.tolerance;
        self.valid = interpolate(&self.valid, &self.colliding, step / remaining);
        let converging = distance <= 0.5 * self.last_distance || self.steps == 1;
        self.last_distance = distance;
        if converging && self.steps < MAX_STEPS {
            Advanced::Again(self)
        } else {
            Advanced::Bisect(self.bisection(false))
        }
    }

    /// The length of the interval left.
    fn remaining(&self) -> f64 {
        pose_distance(&self.valid, &self.colliding, self.radius)
    }

    /// Bisection of the interval left; `near` when the free end is within the tolerance of an
    /// obstacle.
    fn bisection(&self, near: bool) -> Bisection {
        let bisection = Bisection::new(self.valid, self.colliding, self.tolerance, self.radius);
        if near {
            // Just inside the tolerance, so that a colliding cut ends the bisection.
            bisection.first_cut_at(0.99 * self.tolerance)
        } else {
            bisection
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn pose(t: [f64; 3], axis_angle: [f64; 3]) -> Pose {
        Pose::new(Vector3::from(t), Vector3::from(axis_angle))
    }

    /// The distance from a unit cube's corners (at `pose`) down to the plane z = 0, or `None`
    /// beyond `d_max`; zero when a corner is below.
    fn floor_distance(pose: &Pose, d_max: f64) -> Option<f64> {
        let lowest = (0..8)
            .map(|i| {
                let c = |bit: i32| if i & (1 << bit) != 0 { 0.5 } else { -0.5 };
                (pose * nalgebra::Point3::new(c(0), c(1), c(2))).z
            })
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        (lowest < d_max).then_some(lowest)
    }

    fn run(valid: Pose, colliding: Pose, tolerance: f64) -> (Bisection, u32) {
        let mut advance = Advance::new(valid, colliding, tolerance, 0.87);
        let mut queries = 0;
        loop {
            let (at, d_max) = advance.query();
            queries += 1;
            match advance.record(floor_distance(&at, d_max)) {
                Advanced::Again(next) => advance = next,
                Advanced::Bisect(bisection) => return (bisection, queries),
            }
        }
    }

    #[test]
    fn a_head_on_approach_gets_within_the_tolerance_in_a_few_queries() {
        let tolerance = 1e-4;
        let (bisection, queries) = run(
            pose([0.0, 0.0, 2.0], [0.0; 3]),
            pose([0.0, 0.0, -1.0], [0.0; 3]),
            tolerance,
        );
        assert!(queries <= 3, "{queries} queries");
        let gap = floor_distance(bisection.valid(), f64::INFINITY).unwrap();
        assert!(gap > 0.0 && gap <= tolerance, "{gap}");
        // The first cut is one tolerance ahead: it collides, and the interval is done.
        let trial = bisection.trial();
        assert!(floor_distance(&trial, f64::INFINITY) == Some(0.0));
    }

    #[test]
    fn advancing_never_passes_the_contact_even_turning() {
        let tolerance = 1e-5;
        for spin in [0.0, 0.3, 1.0, 2.5] {
            let (bisection, _) = run(
                pose([0.2, 0.0, 1.5], [0.0, 0.0, 0.0]),
                pose([0.9, 0.3, -0.4], [spin, 0.2, 0.1]),
                tolerance,
            );
            assert!(
                floor_distance(bisection.valid(), f64::INFINITY).unwrap() > 0.0,
                "spin {spin}"
            );
        }
    }

    #[test]
    fn a_grazing_approach_goes_to_bisection() {
        // Nearly level, 1 mm above the floor: each step closes far less than half the gap.
        let (bisection, queries) = run(
            pose([0.0, 0.0, 0.501], [0.0; 3]),
            pose([10.0, 0.0, 0.4], [0.0; 3]),
            1e-5,
        );
        assert!(queries <= 2, "{queries} queries");
        assert!(!bisection.is_done());
    }
}
