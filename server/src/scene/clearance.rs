//! A scene's `[params.clearance]`: which part pairs the server watches for coming closer than a
//! threshold, and that threshold.

use serde::{Deserialize, Serialize};

use super::params::Problem;

/// The largest threshold accepted (metres): beyond a metre, "clearance" is the whole scene.
const MAX_THRESHOLD_M: f64 = 1.0;

/// The clearance watch: off unless a threshold is given.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClearanceParams {
    /// Pairs closer than this many metres are reported (e.g. 0.005); `None`, the default, turns
    /// the watch off.
    pub threshold: Option<f64>,
    /// Which pairs are watched.
    pub parts: ClearanceParts,
}

/// Which part pairs the clearance watch measures.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClearanceParts {
    /// Every grasped part against every other part: what the user is fitting (the default).
    #[default]
    Held,
    /// Every movable part against every other part, grasped or not.
    Movable,
}

impl ClearanceParams {
    /// Checks the threshold: positive, finite, at most a metre. Keys are named within
    /// `[params.clearance]`.
    pub(crate) fn validate(&self) -> Result<(), Problem> {
        match self.threshold {
            Some(threshold) if !(threshold > 0.0 && threshold <= MAX_THRESHOLD_M) => Err(Problem {
                key: "threshold".to_owned(),
                reason: format!(
                    "must be a distance above 0 and at most {MAX_THRESHOLD_M} m, not {}",
                    vas_protocol::Readable(threshold)
                ),
            }),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_must_be_positive_finite_distances() {
        for threshold in [None, Some(0.005), Some(1e-6), Some(1.0)] {
            let params = ClearanceParams {
                threshold,
                parts: ClearanceParts::Movable,
            };
            assert_eq!(params.validate(), Ok(()), "{threshold:?}");
        }
        for bad in [0.0, -0.001, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1.5] {
            let params = ClearanceParams {
                threshold: Some(bad),
                parts: ClearanceParts::Held,
            };
            let problem = params.validate().expect_err("refused");
            assert_eq!(problem.key, "threshold");
            assert!(problem.reason.contains("above 0"), "{}", problem.reason);
        }
    }

    #[test]
    fn the_table_reads_from_toml() {
        let params: ClearanceParams =
            toml::from_str("threshold = 0.005\nparts = \"movable\"").expect("reads");
        assert_eq!(params.threshold, Some(0.005));
        assert_eq!(params.parts, ClearanceParts::Movable);
        assert_eq!(
            toml::from_str::<ClearanceParams>("").expect("reads"),
            ClearanceParams::default()
        );
        assert!(toml::from_str::<ClearanceParams>("parts = \"all\"").is_err());
        assert!(toml::from_str::<ClearanceParams>("treshold = 0.005").is_err());
    }
}
