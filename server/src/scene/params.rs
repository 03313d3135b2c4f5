//! Algorithm parameters and loop rates of a scene, with the defaults used when a config leaves
//! them out and the checks applied when it gives them.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A config value that is out of range: the key (as written in the config) and the reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Problem {
    pub key: String,
    pub reason: String,
}

/// The DOP orientation counts the collision module provides: the axes (6), axes and diagonals
/// (14), axes and edge diagonals (18), the paper's optimum (24) and all three families (26).
pub const DOP_ORIENTATION_COUNTS: [usize; 5] = [6, 14, 18, 24, 26];

/// Parameters of the paper's algorithms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AlgorithmParams {
    /// k, the number of DOP orientations (one of [`DOP_ORIENTATION_COUNTS`]); 24 by default, the
    /// paper's optimum.
    pub dop_orientations: usize,
    /// Sliding contact.
    pub sliding: SlidingParams,
    /// Natural grasping (clasp minimisation).
    pub clasp: ClaspParams,
}

impl Default for AlgorithmParams {
    fn default() -> Self {
        AlgorithmParams {
            dop_orientations: 24,
            sliding: SlidingParams::default(),
            clasp: ClaspParams::default(),
        }
    }
}

/// How a grasped part follows the hand (the paper's three grasp metaphors).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SlidingMetaphor {
    /// The position is pulled towards the ghost; the orientation comes from the simulation.
    RubberBand,
    /// Position and orientation are both pulled towards the ghost.
    SpiralSpring,
    /// The part repeats each motion increment of the ghost.
    Incremental,
}

impl fmt::Display for SlidingMetaphor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SlidingMetaphor::RubberBand => "rubber-band",
            SlidingMetaphor::SpiralSpring => "spiral-spring",
            SlidingMetaphor::Incremental => "incremental",
        })
    }
}

/// Parameters of sliding contact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlidingParams {
    /// The grasp metaphor; rubber band by default.
    pub metaphor: SlidingMetaphor,
    /// Contact approximation (bisection) stops when the bracketed translation is shorter than
    /// this, in metres; 0.1 mm by default.
    pub contact_tolerance: f64,
    /// The same for the bracketed rotation, in radians; 1 mrad by default.
    pub angle_tolerance: f64,
    /// At most this many bisection steps per contact; 24 by default.
    pub max_bisection_steps: u32,
    /// At most this many slide iterations (move, find contact, classify, new direction) per
    /// frame, the stopping criterion; 8 by default.
    pub max_iterations: u32,
}

impl Default for SlidingParams {
    fn default() -> Self {
        SlidingParams {
            metaphor: SlidingMetaphor::RubberBand,
            contact_tolerance: 1e-4,
            angle_tolerance: 1e-3,
            max_bisection_steps: 24,
            max_iterations: 8,
        }
    }
}

/// Parameters of the clasp minimisation of natural grasping.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClaspParams {
    /// A flex value is fixed once its interval between valid and colliding is narrower than this,
    /// in radians; 0.01 (about 0.6°) by default.
    pub flex_tolerance: f64,
    /// The hand root is fixed once its interval is shorter than this, in metres; 1 mm by default.
    pub root_tolerance: f64,
    /// At most this many interpolation steps per new target; 16 by default.
    pub max_iterations: u32,
}

impl Default for ClaspParams {
    fn default() -> Self {
        ClaspParams {
            flex_tolerance: 0.01,
            root_tolerance: 1e-3,
            max_iterations: 16,
        }
    }
}

/// Rates of the runtime loops, in hertz (each loop runs at most this often).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Rates {
    /// Output frames published per second; 60 by default.
    pub publish_hz: f64,
    /// Collision detection loop; 500 by default.
    pub collision_hz: f64,
    /// Sliding loop; 500 by default.
    pub sliding_hz: f64,
    /// Grasping loop; 100 by default.
    pub grasping_hz: f64,
}

impl Default for Rates {
    fn default() -> Self {
        Rates {
            publish_hz: 60.0,
            collision_hz: 500.0,
            sliding_hz: 500.0,
            grasping_hz: 100.0,
        }
    }
}

/// Highest accepted loop rate (10 kHz, well above haptic rates of 1 kHz).
const MAX_RATE_HZ: f64 = 10_000.0;

/// Highest accepted iteration or step count of a loop.
const MAX_STEPS: u32 = 10_000;

/// Checks that a tolerance is a positive finite number of at most `max`.
fn tolerance(key: &str, value: f64, max: f64, unit: &str) -> Result<(), Problem> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(())
    } else {
        Err(Problem {
            key: key.to_owned(),
            reason: format!("must be positive and at most {max} {unit}, not {value}"),
        })
    }
}

/// Checks that a step count is between 1 and [`MAX_STEPS`].
fn step_count(key: &str, value: u32) -> Result<(), Problem> {
    if (1..=MAX_STEPS).contains(&value) {
        Ok(())
    } else {
        Err(Problem {
            key: key.to_owned(),
            reason: format!("must be between 1 and {MAX_STEPS}, not {value}"),
        })
    }
}

impl AlgorithmParams {
    /// Checks every value; keys are named as in the config (`params.sliding.contact_tolerance`).
    pub(crate) fn validate(&self) -> Result<(), Problem> {
        if !DOP_ORIENTATION_COUNTS.contains(&self.dop_orientations) {
            return Err(Problem {
                key: "params.dop_orientations".to_owned(),
                reason: format!(
                    "must be one of {DOP_ORIENTATION_COUNTS:?}, not {}",
                    self.dop_orientations
                ),
            });
        }
        let s = &self.sliding;
        tolerance(
            "params.sliding.contact_tolerance",
            s.contact_tolerance,
            0.1,
            "m",
        )?;
        tolerance(
            "params.sliding.angle_tolerance",
            s.angle_tolerance,
            0.1,
            "rad",
        )?;
        step_count("params.sliding.max_bisection_steps", s.max_bisection_steps)?;
        step_count("params.sliding.max_iterations", s.max_iterations)?;
        let c = &self.clasp;
        tolerance("params.clasp.flex_tolerance", c.flex_tolerance, 0.5, "rad")?;
        tolerance("params.clasp.root_tolerance", c.root_tolerance, 0.1, "m")?;
        step_count("params.clasp.max_iterations", c.max_iterations)
    }
}

impl Rates {
    /// Checks that every rate is positive, finite and at most 10 kHz.
    pub(crate) fn validate(&self) -> Result<(), Problem> {
        [
            ("rates.publish_hz", self.publish_hz),
            ("rates.collision_hz", self.collision_hz),
            ("rates.sliding_hz", self.sliding_hz),
            ("rates.grasping_hz", self.grasping_hz),
        ]
        .into_iter()
        .try_for_each(|(key, value)| tolerance(key, value, MAX_RATE_HZ, "Hz"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(AlgorithmParams::default().validate(), Ok(()));
        assert_eq!(Rates::default().validate(), Ok(()));
        assert_eq!(AlgorithmParams::default().dop_orientations, 24);
    }

    #[test]
    fn out_of_range_values_name_their_key() {
        let mut params = AlgorithmParams::default();
        params.sliding.angle_tolerance = f64::INFINITY;
        assert_eq!(
            params.validate().unwrap_err().key,
            "params.sliding.angle_tolerance"
        );
        let mut params = AlgorithmParams::default();
        params.clasp.max_iterations = 0;
        assert_eq!(
            params.validate().unwrap_err().key,
            "params.clasp.max_iterations"
        );
        let rates = Rates {
            grasping_hz: 0.0,
            ..Rates::default()
        };
        assert_eq!(rates.validate().unwrap_err().key, "rates.grasping_hz");
    }

    #[test]
    fn metaphor_names_match_the_config_spelling() {
        for metaphor in [
            SlidingMetaphor::RubberBand,
            SlidingMetaphor::SpiralSpring,
            SlidingMetaphor::Incremental,
        ] {
            let quoted = serde_json::to_string(&metaphor).unwrap();
            assert_eq!(quoted, format!("\"{metaphor}\""));
        }
    }
}
