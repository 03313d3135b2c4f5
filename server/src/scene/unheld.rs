//! What happens to movable parts no hand holds: the `[params.push]` and `[params.release]`
//! tables, and the `push` and `release` keys a part may set to differ from them.

use serde::{Deserialize, Serialize};

use super::params::Problem;

/// Pushing, the `[params.push]` table: a hand touching a movable part without holding it moves
/// the part by its motion into it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PushParams {
    /// Whether hands push the scene's movable parts (a part's own `push` key overrides it);
    /// true by default.
    pub enabled: bool,
}

impl Default for PushParams {
    fn default() -> Self {
        PushParams { enabled: true }
    }
}

impl PushParams {
    /// Whether hands push a part that is `movable` and says `own` (its `push` key).
    pub fn pushes(&self, movable: bool, own: Option<bool>) -> bool {
        movable && own.unwrap_or(self.enabled)
    }
}

/// What a released part does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReleaseMode {
    /// It stays where the hand let go of it, as if held in a fixture.
    Stay,
    /// It moves down until it rests on what is below it, or on the floor.
    Settle,
}

/// Setting down, the `[params.release]` table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReleaseParams {
    /// What a released part does (a part's own `release` key overrides it); `settle` by default.
    pub mode: ReleaseMode,
    /// The scene's up direction (any length but zero); parts settle against it. `[0, 0, 1]` by
    /// default.
    pub up: [f64; 3],
    /// The height along `up` (metres) a settling part with nothing below stops at: its lowest
    /// point rests there. 0 by default.
    pub floor: f64,
    /// How fast a settling part moves down (metres per second of sliding frames); 1 m/s by
    /// default, a fall of 5 cm in 50 ms.
    pub speed: f64,
    /// The steepest surface (degrees from level) a settling part comes to rest on, as friction
    /// holds a part on a shelf; on steeper ones it goes on down along the surface. 30 by
    /// default.
    pub max_slope_degrees: f64,
}

impl Default for ReleaseParams {
    fn default() -> Self {
        ReleaseParams {
            mode: ReleaseMode::Settle,
            up: [0.0, 0.0, 1.0],
            floor: 0.0,
            speed: 1.0,
            max_slope_degrees: 30.0,
        }
    }
}

/// The push and release tables together: what the simulation does with movable parts no hand
/// holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnheldParams {
    /// Pushing.
    pub push: PushParams,
    /// Setting down.
    pub release: ReleaseParams,
}

impl UnheldParams {
    /// No pushing, and released parts stay: parts move only while held.
    pub fn held_only() -> UnheldParams {
        UnheldParams {
            push: PushParams { enabled: false },
            release: ReleaseParams {
                mode: ReleaseMode::Stay,
                ..ReleaseParams::default()
            },
        }
    }
}

/// The largest floor height accepted (metres), as for positions of parts.
const MAX_FLOOR_M: f64 = vas_protocol::MAX_POSITION_M;

impl ReleaseParams {
    /// Checks every value; keys as in the config, below `params.release`.
    pub(crate) fn validate(&self) -> Result<(), Problem> {
        let problem = |key: &str, reason: String| Problem {
            key: format!("params.release.{key}"),
            reason,
        };
        let length = self.up.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !length.is_finite() || length < 1e-9 {
            return Err(problem("up", "must be a finite direction, not zero".into()));
        }
        if !self.floor.is_finite() || self.floor.abs() > MAX_FLOOR_M {
            return Err(problem(
                "floor",
                format!("must be finite and at most {MAX_FLOOR_M} m from 0"),
            ));
        }
        if !self.speed.is_finite() || self.speed <= 0.0 || self.speed > 100.0 {
            return Err(problem(
                "speed",
                "must be above 0 and at most 100 m/s".into(),
            ));
        }
        if !(0.0..=89.0).contains(&self.max_slope_degrees) {
            return Err(problem(
                "max_slope_degrees",
                "must be between 0 and 89 degrees".into(),
            ));
        }
        Ok(())
    }

    /// What a released part that is `movable` and says `own` (its `release` key) does; a
    /// static part stays.
    pub fn mode_of(&self, movable: bool, own: Option<ReleaseMode>) -> ReleaseMode {
        match own {
            _ if !movable => ReleaseMode::Stay,
            Some(mode) => mode,
            None => self.mode,
        }
    }

    /// The unit up direction.
    pub fn up_direction(&self) -> nalgebra::Unit<nalgebra::Vector3<f64>> {
        nalgebra::Unit::new_normalize(nalgebra::Vector3::from(self.up))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_their_key() {
        assert_eq!(ReleaseParams::default().validate(), Ok(()));
        let bad = [
            ReleaseParams {
                up: [0.0; 3],
                ..ReleaseParams::default()
            },
            ReleaseParams {
                floor: f64::NAN,
                ..ReleaseParams::default()
            },
            ReleaseParams {
                speed: 0.0,
                ..ReleaseParams::default()
            },
            ReleaseParams {
                max_slope_degrees: 90.0,
                ..ReleaseParams::default()
            },
        ];
        let keys: Vec<String> = (bad.iter())
            .map(|params| params.validate().expect_err("refused").key)
            .collect();
        assert_eq!(
            keys,
            [
                "params.release.up",
                "params.release.floor",
                "params.release.speed",
                "params.release.max_slope_degrees"
            ]
        );
    }
}
