//! How long each frame of a loop (or the clearance stage) took, logged as a "loop rate" line per
//! window: what `vas-bench` reads the loops' figures from.

use std::time::{Duration, Instant};

/// How often a loop logs its rate.
const RATE_LOG_PERIOD: Duration = Duration::from_secs(10);

/// The time a loop spent on each frame of the current window: the rate it sustains is frames per
/// busy second, whatever rate its input comes at. A window ends every [`RATE_LOG_PERIOD`], at a
/// restart (so that one scene's figures are not mixed with the next's) and when the loop ends.
pub(super) struct LoopMeter {
    name: &'static str,
    /// Each frame's processing time since the window began.
    frames: Vec<Duration>,
    since: Instant,
}

impl LoopMeter {
    /// A meter whose lines name the loop `name`.
    pub(super) fn new(name: &'static str) -> LoopMeter {
        LoopMeter {
            name,
            frames: Vec::new(),
            since: Instant::now(),
        }
    }

    /// Counts a frame whose processing started at `started`, and logs the window now and then.
    pub(super) fn frame_done(&mut self, started: Instant) {
        self.frames.push(started.elapsed());
        if self.since.elapsed() >= RATE_LOG_PERIOD {
            self.log();
        }
    }

    /// Logs the window's frames, their rate, mean, median, 99th percentile (nearest rank) and
    /// longest time, and starts a new window.
    pub(super) fn log(&mut self) {
        let window = self.since.elapsed().as_secs_f64();
        let count = self.frames.len();
        if let (Some(p50), Some(p99)) = (
            percentile(&mut self.frames, 50),
            percentile(&mut self.frames, 99),
        ) {
            let busy = self.frames.iter().sum::<Duration>().as_secs_f64();
            let longest = self.frames.iter().max().copied().unwrap_or(p99);
            tracing::info!(
                loop_name = self.name,
                frames = count,
                frames_per_s = format_args!("{:.0}", count as f64 / window),
                busy_percent = format_args!("{:.1}", 100.0 * busy / window),
                mean_us = format_args!("{:.1}", busy * 1e6 / count as f64),
                p50_us = format_args!("{:.1}", p50.as_secs_f64() * 1e6),
                p99_us = format_args!("{:.1}", p99.as_secs_f64() * 1e6),
                max_us = format_args!("{:.1}", longest.as_secs_f64() * 1e6),
                sustains_per_s = format_args!("{:.0}", count as f64 / busy),
                "loop rate"
            );
        }
        self.frames.clear();
        self.since = Instant::now();
    }
}

/// The `percent`th percentile of `times` by nearest rank (reordering them); `None` for no
/// times.
fn percentile(times: &mut [Duration], percent: usize) -> Option<Duration> {
    let rank = (times.len() * percent).div_ceil(100).checked_sub(1)?;
    Some(*times.select_nth_unstable(rank).1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_the_nearest_rank() {
        let micros = |range: std::ops::RangeInclusive<u64>| -> Vec<Duration> {
            range.rev().map(Duration::from_micros).collect()
        };
        let p99 = |times: &mut [Duration]| percentile(times, 99);
        assert_eq!(p99(&mut []), None);
        assert_eq!(p99(&mut micros(7..=7)), Some(Duration::from_micros(7)));
        assert_eq!(p99(&mut micros(1..=100)), Some(Duration::from_micros(99)));
        assert_eq!(p99(&mut micros(1..=1000)), Some(Duration::from_micros(990)));
        assert_eq!(p99(&mut micros(1..=50)), Some(Duration::from_micros(50)));
        assert_eq!(
            percentile(&mut micros(1..=100), 50),
            Some(Duration::from_micros(50))
        );
        assert_eq!(
            percentile(&mut micros(1..=7), 50),
            Some(Duration::from_micros(4))
        );
    }
}
