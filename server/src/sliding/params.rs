//! The sliding parameters a scene sets: metaphor, tolerances, stopping criterion, force output and
//! slide-in allowances.

use serde::{Deserialize, Serialize};

use super::force::ForceParams;
use vas_protocol::SlidingMetaphor;

/// A slide-in unit: two parts that may overlap by design, up to `depth` metres.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Allowance {
    /// The names of the two parts.
    pub parts: [String; 2],
    /// The largest interference depth tolerated between them, in metres.
    pub depth: f64,
}

/// Sliding parameters, read from a scene's `[sliding]` table; every field has a default.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SlideParams {
    /// The grasping metaphor; it can also be switched at run time.
    pub metaphor: SlidingMetaphor,
    /// Contact tolerance in metres: bisection stops when the interval between the free and the
    /// colliding pose is shorter, and a target nearer than it counts as reached. Unset: 1e-4 of
    /// the grasped part's size.
    pub contact_tolerance: Option<f64>,
    /// Whether contact approximation starts with conservative advancement (distance queries)
    /// before bisecting. Off by default: near a close fit, such as a peg in its hole, one
    /// distance query costs more than the dozen collision tests it saves.
    pub conservative_advancement: bool,
    /// Clearance, as a fraction of the tolerance, that the part regains from the surfaces it has
    /// just hit (if that lift is free), so that it glides instead of scraping and the visible
    /// pose is not left arbitrarily close to a surface.
    pub lift: f64,
    /// Most sliding iterations (move, contact, classification, new direction) per frame: the
    /// stopping criterion's iteration count.
    pub max_iterations: u32,
    /// Consecutive cycles with no progress (less than a tenth of the tolerance) that end a frame.
    pub stall_cycles: u32,
    /// Contacts whose normals differ by less than this angle (radians) form one cluster, reduced
    /// to its extreme points.
    pub cluster_angle: f64,
    /// The spring-damper that gives force-feedback devices their force.
    pub force: ForceParams,
    /// Slide-in units and their allowances.
    pub allowances: Vec<Allowance>,
}

impl Default for SlideParams {
    fn default() -> Self {
        SlideParams {
            metaphor: SlidingMetaphor::default(),
            contact_tolerance: None,
            conservative_advancement: false,
            lift: 0.5,
            max_iterations: 24,
            stall_cycles: 3,
            cluster_angle: 0.02,
            force: ForceParams::default(),
            allowances: Vec::new(),
        }
    }
}

/// A parameter outside its valid range: the key and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("sliding.{key}: {reason}")]
pub struct ParamError {
    /// The offending key, relative to the `[sliding]` table.
    pub key: String,
    /// Why its value is refused.
    pub reason: String,
}

impl SlideParams {
    /// Checks every value's range, so that a scene with bad sliding parameters is refused at load.
    pub fn validate(&self) -> Result<(), ParamError> {
        let fail = |key: &str, reason: String| {
            Err(ParamError {
                key: key.to_owned(),
                reason,
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if let Some(t) = self.contact_tolerance
            && !positive(t)
        {
            return fail(
                "contact_tolerance",
                format!("must be a positive length in metres, got {t}"),
            );
        }
        if !non_negative(self.lift) || self.lift > 10.0 {
            return fail(
                "lift",
                format!("must be between 0 and 10, got {}", self.lift),
            );
        }
        if self.max_iterations == 0 {
            return fail("max_iterations", "must be at least 1".into());
        }
        if self.stall_cycles == 0 {
            return fail("stall_cycles", "must be at least 1".into());
        }
        if !positive(self.cluster_angle) || self.cluster_angle > 0.5 {
            return fail(
                "cluster_angle",
                format!("must be in (0, 0.5] radians, got {}", self.cluster_angle),
            );
        }
        let f = &self.force;
        for (key, value) in [
            ("force.stiffness", f.stiffness),
            ("force.damping", f.damping),
            ("force.angular_stiffness", f.angular_stiffness),
            ("force.angular_damping", f.angular_damping),
            ("force.max_force", f.max_force),
            ("force.max_torque", f.max_torque),
        ] {
            if !non_negative(value) {
                return fail(
                    key,
                    format!(
                        "must be finite and not negative, got {}",
                        vas_protocol::Readable(value)
                    ),
                );
            }
        }
        for (i, a) in self.allowances.iter().enumerate() {
            if !positive(a.depth) {
                return fail(
                    &format!("allowances[{i}].depth"),
                    format!("must be a positive length in metres, got {}", a.depth),
                );
            }
            if a.parts[0] == a.parts[1] {
                return fail(
                    &format!("allowances[{i}].parts"),
                    format!("names the same part twice ({})", a.parts[0]),
                );
            }
        }
        Ok(())
    }

    /// The contact tolerance for a part of the given size (its bounding-box diagonal), metres.
    pub fn tolerance_for(&self, part_size: f64) -> f64 {
        self.contact_tolerance.unwrap_or(1e-4 * part_size)
    }

    /// The allowance between two named parts, if they form a slide-in unit.
    pub fn allowance_between(&self, a: &str, b: &str) -> Option<f64> {
        self.allowances
            .iter()
            .find(|x| (x.parts[0] == a && x.parts[1] == b) || (x.parts[0] == b && x.parts[1] == a))
            .map(|x| x.depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_with_some_keys_fills_the_rest_with_defaults() {
        let params: SlideParams = toml::from_str(
            r#"
            metaphor = "incremental"
            contact_tolerance = 1e-5
            conservative_advancement = true
            [force]
            stiffness = 800.0
            [[allowances]]
            parts = ["radio", "console"]
            depth = 0.0015
            "#,
        )
        .unwrap();
        params.validate().unwrap();
        assert_eq!(params.metaphor, SlidingMetaphor::Incremental);
        assert_eq!(params.tolerance_for(1.0), 1e-5);
        assert!(params.conservative_advancement);
        assert!(!SlideParams::default().conservative_advancement);
        assert_eq!(params.force.stiffness, 800.0);
        assert_eq!(params.force.damping, ForceParams::default().damping);
        assert_eq!(params.allowance_between("console", "radio"), Some(0.0015));
        assert_eq!(params.allowance_between("console", "door"), None);
        assert_eq!(SlideParams::default().tolerance_for(0.5), 5e-5);
    }

    #[test]
    fn bad_values_are_refused_with_their_key() {
        let unknown = toml::from_str::<SlideParams>("contact_tolerence = 1e-5").unwrap_err();
        assert!(
            unknown.to_string().contains("contact_tolerence"),
            "{unknown}"
        );
        let negative: SlideParams = toml::from_str("contact_tolerance = -1.0").unwrap();
        assert_eq!(negative.validate().unwrap_err().key, "contact_tolerance");
        let same: SlideParams =
            toml::from_str("[[allowances]]\nparts = [\"a\", \"a\"]\ndepth = 0.001").unwrap();
        assert_eq!(same.validate().unwrap_err().key, "allowances[0].parts");
        let stiff: SlideParams = toml::from_str("[force]\nstiffness = -3.0").unwrap();
        assert_eq!(stiff.validate().unwrap_err().key, "force.stiffness");
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
