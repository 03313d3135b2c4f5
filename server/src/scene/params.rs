//! Algorithm parameters and loop rates of a scene, with the defaults used when a config leaves
//! them out and the checks applied when it gives them.

use serde::{Deserialize, Serialize};

use super::clearance::ClearanceParams;
use super::unheld::{PushParams, ReleaseParams, UnheldParams};
use crate::collision::orientation::DEFAULT_K;
use crate::grasping::{ClaspParams, GraspParams};
use crate::sliding::SlideParams;

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
    /// k, the number of DOP orientations of every tree in the scene (one of
    /// [`DOP_ORIENTATION_COUNTS`]); by default the fastest in the tumbling benchmark,
    /// [`DEFAULT_K`] (the paper found 24).
    pub dop_orientations: usize,
    /// Sliding contact, the `[params.sliding]` table.
    pub sliding: SlideParams,
    /// Natural grasping's clasp minimisation, the `[params.clasp]` table.
    pub clasp: ClaspParams,
    /// What a hand does when its tracking drops, the `[params.tracking]` table.
    pub tracking: TrackingParams,
    /// The clearance watch, the `[params.clearance]` table (off by default).
    pub clearance: ClearanceParams,
    /// Pushing of movable parts no hand holds, the `[params.push]` table (on by default).
    pub push: PushParams,
    /// What released parts do, the `[params.release]` table (they settle by default).
    pub release: ReleaseParams,
}

impl Default for AlgorithmParams {
    fn default() -> Self {
        AlgorithmParams {
            dop_orientations: DEFAULT_K,
            sliding: SlideParams::default(),
            clasp: ClaspParams::default(),
            tracking: TrackingParams::default(),
            clearance: ClearanceParams::default(),
            push: PushParams::default(),
            release: ReleaseParams::default(),
        }
    }
}

/// How a hand driven by hand-joints samples rides out a loss of tracking, in seconds of sample
/// time (the samples' timestamps, so that a lockstep replay gives the same outcome every time),
/// and how tracked input is smoothed: the One Euro filter
/// ([`simulation::filter`](crate::simulation::filter)) of the tracker's hand root and of each
/// joints-driven hand's retargeted root and flex values.
///
/// The filter's defaults suit a headset's hand tracking (about 1-2 mm and 1° of noise at 50 to
/// 90 Hz): at rest a cut-off of 0.2 Hz, which takes the jitter of a still hand down more than
/// fivefold; moving, the cut-off rises by `beta` per m/s so that at 1 m/s the root trails by
/// about 10 ms (`vas-bench filter`, BENCHMARKS.md). A rotation's and the flex values' cut-off
/// rises more slowly with their speed (`beta_angular`), as retargeting turns the joints'
/// noise into more jitter of angles than of the root's position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingParams {
    /// A hand whose latest sample is this much older than the newest sample of any input is
    /// untracked, as one whose latest sample says so; 0.1 s by default (a few frames of a
    /// headset's hand tracking).
    pub lost_after: f64,
    /// A hand untracked this long after its last tracked sample lets go of the part it holds
    /// (where the part is); until then the part stays held. 0.5 s by default, as users of
    /// hand-tracking SDKs ask for.
    pub grace: f64,
    /// Whether tracked input is smoothed (true by default); false passes it on as it comes.
    pub filter: bool,
    /// The filter's cut-off frequency at rest, Hz (0.2 by default).
    pub min_cutoff: f64,
    /// How much the cut-off rises with the root's speed, Hz per m/s (20 by default).
    pub beta: f64,
    /// How much the cut-off rises with the speed of the root's rotation and of each flex value,
    /// Hz per rad/s (0.5 by default).
    pub beta_angular: f64,
    /// The cut-off frequency of the filter's speed estimate, Hz (1 by default).
    pub d_cutoff: f64,
}

impl Default for TrackingParams {
    fn default() -> Self {
        TrackingParams {
            lost_after: 0.1,
            grace: 0.5,
            filter: true,
            min_cutoff: 0.2,
            beta: 20.0,
            beta_angular: 0.5,
            d_cutoff: 1.0,
        }
    }
}

/// The longest tracking time accepted (seconds).
const MAX_TRACKING_S: f64 = 60.0;

/// The range of the filter's cut-off frequencies (Hz): positive, and at most far beyond any
/// tracker's rate (where the filter passes samples on all but unchanged).
const FILTER_CUTOFF_HZ: (f64, f64) = (1e-3, 1e3);

/// The range of the filter's speed coefficients (Hz per m/s or per rad/s); 0 makes the filter a
/// plain low-pass at `min_cutoff`.
const FILTER_BETA: (f64, f64) = (0.0, 1e4);

impl TrackingParams {
    /// Checks every value; keys are named as in the config.
    fn validate(&self) -> Result<(), Problem> {
        let tracking = (0.0, MAX_TRACKING_S);
        within("params.tracking.lost_after", self.lost_after, tracking, "s")?;
        within("params.tracking.grace", self.grace, tracking, "s")?;
        within(
            "params.tracking.min_cutoff",
            self.min_cutoff,
            FILTER_CUTOFF_HZ,
            "Hz",
        )?;
        within(
            "params.tracking.d_cutoff",
            self.d_cutoff,
            FILTER_CUTOFF_HZ,
            "Hz",
        )?;
        within("params.tracking.beta", self.beta, FILTER_BETA, "Hz per m/s")?;
        within(
            "params.tracking.beta_angular",
            self.beta_angular,
            FILTER_BETA,
            "Hz per rad/s",
        )
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

/// Lowest accepted loop rate: a frame every ten seconds (a rate whose period no timer can
/// hold, such as 1e-300 Hz, would pass a mere positivity check and fail when the loops start).
const MIN_RATE_HZ: f64 = 0.1;

/// Checks that a value is a finite number in `[min, max]`.
fn within(key: &str, value: f64, (min, max): (f64, f64), unit: &str) -> Result<(), Problem> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(Problem {
            key: key.to_owned(),
            reason: format!(
                "must be between {min} and {max} {unit}, not {}",
                vas_protocol::Readable(value)
            ),
        })
    }
}

impl AlgorithmParams {
    /// What the simulation does with movable parts no hand holds: the push and release tables.
    pub fn unheld(&self) -> UnheldParams {
        UnheldParams {
            push: self.push,
            release: self.release,
        }
    }

    /// The grasping hand's tuning for this scene: its clasp parameters, and segment trees with
    /// its parts' orientations.
    pub fn grasp(&self) -> GraspParams {
        GraspParams {
            clasp: self.clasp,
            dop_orientations: self.dop_orientations,
            ..GraspParams::default()
        }
    }

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
        self.sliding.validate().map_err(|e| Problem {
            key: format!("params.sliding.{}", e.key),
            reason: e.reason,
        })?;
        self.clasp.validate().map_err(|e| Problem {
            key: format!("params.clasp.{}", e.key),
            reason: e.reason,
        })?;
        self.clearance.validate().map_err(|e| Problem {
            key: format!("params.clearance.{}", e.key),
            reason: e.reason,
        })?;
        self.release.validate()?;
        self.tracking.validate()
    }
}

impl Rates {
    /// Checks that every rate is finite, at least 0.1 Hz and at most 10 kHz.
    pub(crate) fn validate(&self) -> Result<(), Problem> {
        [
            ("rates.publish_hz", self.publish_hz),
            ("rates.collision_hz", self.collision_hz),
            ("rates.sliding_hz", self.sliding_hz),
            ("rates.grasping_hz", self.grasping_hz),
        ]
        .into_iter()
        .try_for_each(|(key, value)| within(key, value, (MIN_RATE_HZ, MAX_RATE_HZ), "Hz"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(AlgorithmParams::default().validate(), Ok(()));
        assert_eq!(Rates::default().validate(), Ok(()));
        assert_eq!(AlgorithmParams::default().dop_orientations, DEFAULT_K);
    }

    #[test]
    fn out_of_range_values_name_their_key() {
        let mut params = AlgorithmParams::default();
        params.sliding.cluster_angle = f64::INFINITY;
        assert_eq!(
            params.validate().unwrap_err().key,
            "params.sliding.cluster_angle"
        );
        let mut params = AlgorithmParams::default();
        params.clasp.max_steps = 0;
        assert_eq!(params.validate().unwrap_err().key, "params.clasp.max_steps");
        let mut params = AlgorithmParams::default();
        params.tracking.grace = -0.5;
        assert_eq!(params.validate().unwrap_err().key, "params.tracking.grace");
        params.tracking = TrackingParams {
            lost_after: f64::NAN,
            grace: 0.5,
            ..TrackingParams::default()
        };
        assert_eq!(
            params.validate().unwrap_err().key,
            "params.tracking.lost_after"
        );
        for (key, edit) in [
            (
                "min_cutoff",
                (|t| t.min_cutoff = 0.0) as fn(&mut TrackingParams),
            ),
            ("d_cutoff", |t| t.d_cutoff = f64::INFINITY),
            ("beta", |t| t.beta = -1.0),
            ("beta_angular", |t| t.beta_angular = f64::NAN),
        ] {
            let mut params = AlgorithmParams::default();
            edit(&mut params.tracking);
            let problem = params.validate().unwrap_err();
            assert_eq!(problem.key, format!("params.tracking.{key}"));
            assert!(
                problem.reason.starts_with("must be between"),
                "{}",
                problem.reason
            );
        }
        let mut params = AlgorithmParams::default();
        params.clearance.threshold = Some(-0.005);
        assert_eq!(
            params.validate().unwrap_err().key,
            "params.clearance.threshold"
        );
        let rates = Rates {
            grasping_hz: 0.0,
            ..Rates::default()
        };
        assert_eq!(rates.validate().unwrap_err().key, "rates.grasping_hz");
    }
}
