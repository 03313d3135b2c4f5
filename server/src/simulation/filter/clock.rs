//! The time between a stream's samples, from their own timestamps.

/// Why a sample's timestamp cannot be filtered against the previous one.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TimeFault {
    /// The timestamp is NaN or infinite.
    #[error("the sample's timestamp {0} s is not a finite number")]
    NonFinite(f64),
    /// The timestamp is not after the previous sample's (a repeated or reordered sample, or a
    /// clock that jumped back).
    #[error("the sample's timestamp {at_s} s is not after the previous one's, {previous_s} s")]
    NotAfter {
        /// The sample's timestamp (seconds).
        at_s: f64,
        /// The previous accepted sample's (seconds).
        previous_s: f64,
    },
}

/// The latest timestamp of a stream, which gives the step to the next sample.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SampleClock {
    latest_s: Option<f64>,
}

impl SampleClock {
    /// The seconds from the previous sample to one stamped `at_s` (`None` for the first), and
    /// the clock moved on to it; a fault leaves the clock as it was.
    pub fn advance(&mut self, at_s: f64) -> Result<Option<f64>, TimeFault> {
        if !at_s.is_finite() {
            return Err(TimeFault::NonFinite(at_s));
        }
        let step = match self.latest_s {
            Some(previous_s) if at_s <= previous_s => {
                return Err(TimeFault::NotAfter { at_s, previous_s });
            }
            Some(previous_s) => Some(at_s - previous_s),
            None => None,
        };
        self.latest_s = Some(at_s);
        Ok(step)
    }

    /// Forgets the latest timestamp: the next sample is a first one.
    pub fn restart(&mut self) {
        self.latest_s = None;
    }
}
