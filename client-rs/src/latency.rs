//! Latency statistics: nearest-rank percentiles of input-to-answer times, as `vas-client replay`
//! and the benchmarks report them.

use std::time::Duration;

use serde::Serialize;

/// A summary was asked of no samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("no samples to summarise")]
pub struct NoSamples;

/// The `percent` percentile of ascending `sorted` values by the nearest-rank method: the
/// smallest value such that at least `percent` % of the values are at most it (rank
/// `ceil(percent / 100 * n)`, at least 1). `None` for no values.
pub fn nearest_rank<T: Copy>(sorted: &[T], percent: f64) -> Option<T> {
    let count = sorted.len();
    if count == 0 {
        return None;
    }
    let rank = (percent.clamp(0.0, 100.0) / 100.0 * count as f64).ceil() as usize;
    Some(sorted[rank.clamp(1, count) - 1])
}

/// Median, 99th percentile (both nearest-rank) and maximum of a set of latencies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LatencySummary {
    /// Median, in microseconds.
    pub p50_us: f64,
    /// 99th percentile, in microseconds.
    pub p99_us: f64,
    /// Largest value, in microseconds.
    pub max_us: f64,
    /// How many latencies were summarised.
    pub samples: usize,
}

impl LatencySummary {
    /// Summarises `latencies` (in any order).
    pub fn from_durations(latencies: &[Duration]) -> Result<Self, NoSamples> {
        let mut sorted = latencies.to_vec();
        sorted.sort_unstable();
        let micros = |percent| {
            nearest_rank(&sorted, percent)
                .map(|latency: Duration| latency.as_secs_f64() * 1e6)
                .ok_or(NoSamples)
        };
        Ok(Self {
            p50_us: micros(50.0)?,
            p99_us: micros(99.0)?,
            max_us: micros(100.0)?,
            samples: sorted.len(),
        })
    }
}

impl std::fmt::Display for LatencySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "p50 {:.1} us, p99 {:.1} us, max {:.1} us over {} samples",
            self.p50_us, self.p99_us, self.max_us, self.samples
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn micros(values: impl IntoIterator<Item = u64>) -> Vec<Duration> {
        values.into_iter().map(Duration::from_micros).collect()
    }

    #[test]
    fn nearest_rank_picks_the_ranked_value() {
        let values: Vec<u32> = (1..=100).collect();
        assert_eq!(nearest_rank(&values, 50.0), Some(50));
        assert_eq!(nearest_rank(&values, 99.0), Some(99));
        assert_eq!(nearest_rank(&values, 99.5), Some(100));
        assert_eq!(nearest_rank(&values, 100.0), Some(100));
        assert_eq!(nearest_rank(&values, 0.0), Some(1));
        // Five values: the median is the third, any percentile above 80 the fifth.
        let five = [10, 20, 30, 40, 50];
        assert_eq!(nearest_rank(&five, 50.0), Some(30));
        assert_eq!(nearest_rank(&five, 40.0), Some(20));
        assert_eq!(nearest_rank(&five, 41.0), Some(30));
        assert_eq!(nearest_rank(&five, 81.0), Some(50));
        assert_eq!(nearest_rank(&[7], 99.0), Some(7));
        assert_eq!(nearest_rank::<u32>(&[], 50.0), None);
    }

    #[test]
    fn summaries_sort_their_input() {
        // 1..=200 us, shuffled by a stride coprime with the length.
        let latencies = micros((0..200).map(|i| (i * 77) % 200 + 1));
        let summary = LatencySummary::from_durations(&latencies).expect("summary");
        assert_eq!(summary.samples, 200);
        assert_eq!(summary.p50_us, 100.0);
        assert_eq!(summary.p99_us, 198.0);
        assert_eq!(summary.max_us, 200.0);
    }

    #[test]
    fn a_single_outlier_shows_in_the_maximum_only() {
        let mut latencies = micros(std::iter::repeat_n(20, 999));
        latencies.push(Duration::from_millis(5));
        let summary = LatencySummary::from_durations(&latencies).expect("summary");
        assert_eq!((summary.p50_us, summary.p99_us), (20.0, 20.0));
        assert_eq!(summary.max_us, 5000.0);
    }

    #[test]
    fn summarising_nothing_is_an_error() {
        assert_eq!(LatencySummary::from_durations(&[]), Err(NoSamples));
        assert_eq!(NoSamples.to_string(), "no samples to summarise");
    }
}
