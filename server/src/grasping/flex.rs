//! Turning raw glove samples into a trusted flex vector: joint limits, clamped and counted.

use super::model::{FLEX_COUNT, FlexVector, HandModel};

/// What [`sanitize_flex`] had to change in one sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FlexReport {
    /// Values outside their joint limits, clamped to the nearest limit.
    pub clamped: u32,
    /// Values that were not finite; the previous value was kept.
    pub rejected: u32,
}

impl FlexReport {
    /// Adds another report's counts to this one (for running totals).
    pub fn accumulate(&mut self, other: FlexReport) {
        self.clamped += other.clamped;
        self.rejected += other.rejected;
    }
}

/// The flex vector for a raw glove sample (radians, CyberGlove order): each value clamped to its
/// joint limits; a value that is not a number (a broken sensor, a bad packet) is replaced by the
/// previous trusted value. Nothing is trusted blindly, and everything changed is counted.
pub fn sanitize_flex(
    model: &HandModel,
    raw: &[f32; FLEX_COUNT],
    previous: &FlexVector,
) -> (FlexVector, FlexReport) {
    let mut report = FlexReport::default();
    let flex = std::array::from_fn(|i| {
        let value = f64::from(raw[i]);
        let limit = &model.limits()[i];
        if !value.is_finite() {
            report.rejected += 1;
            previous[i]
        } else if value < limit.min || value > limit.max {
            report.clamped += 1;
            value.clamp(limit.min, limit.max)
        } else {
            value
        }
    });
    (flex, report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasping::model::tests::right_hand;

    #[test]
    fn values_outside_the_limits_are_clamped_and_counted() {
        let model = right_hand();
        let mut raw = [0.1f32; FLEX_COUNT];
        raw[4] = 2.0; // index MCP beyond 90 degrees
        raw[20] = -1.5; // wrist flexion below -70 degrees
        raw[7] = f32::NAN;
        raw[8] = f32::INFINITY;
        let previous = [0.25; FLEX_COUNT];
        let (flex, report) = sanitize_flex(&model, &raw, &previous);
        assert_eq!(
            report,
            FlexReport {
                clamped: 2,
                rejected: 2
            }
        );
        assert_eq!(flex[4], model.limits()[4].max);
        assert_eq!(flex[20], model.limits()[20].min);
        assert_eq!(flex[7], 0.25);
        assert_eq!(flex[8], 0.25);
        assert_eq!(flex[0], f64::from(0.1f32));
        let mut total = report;
        total.accumulate(report);
        assert_eq!(
            total,
            FlexReport {
                clamped: 4,
                rejected: 4
            }
        );
    }
}
