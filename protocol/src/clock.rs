//! The clock every timestamp on the wire is read from.

use std::time::{SystemTime, UNIX_EPOCH};

/// Nanoseconds since the Unix epoch: the clock of every `timestamp_ns` field.
///
/// A wall clock rather than a monotonic one, because timestamps are compared between processes
/// (and, over a bridge, between hosts). Returns 0 if the system clock is set before 1970.
pub fn wall_clock_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |elapsed| {
            u64::try_from(elapsed.as_nanos()).unwrap_or(u64::MAX)
        })
}
