//! Driving the server along the scripted path at 1 kHz: each tick publishes the tracker sample
//! and times it to the hand frame that answers it (B7's procedure, [`round_trip`]), then
//! publishes the glove sample; the parts frames received meanwhile show where the bar is and
//! whether it is grasped and sliding.

use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use nalgebra::Isometry3;
use vas_client::recording::InputSample;
use vas_client::{Client, Frame, Wake};
use vas_protocol::{GloveSample, PART_GRASPED, PART_SLIDING, TrackerSample, wall_clock_ns};
use vas_testkit::script::Keyframe;

use crate::e2e::round_trip;

/// Input samples per second of each stream.
pub const RATE_HZ: f64 = 1000.0;

/// What one drive along the path saw.
#[derive(Debug, Clone, Default)]
pub struct Drive {
    /// Each answered tracker sample: its time in the script, and its round trip.
    pub latencies: Vec<(f64, Duration)>,
    /// Tracker samples without an answer within the timeout.
    pub unanswered: u64,
    /// Seconds from the first sample to the answer to the last.
    pub seconds: f64,
    /// What the parts frames said of the bar.
    pub bar: BarWatch,
}

/// The bar as the published parts frames show it.
#[derive(Debug, Clone, Default)]
pub struct BarWatch {
    id: usize,
    /// Its published poses, each differing from the one before.
    pub poses: Vec<Isometry3<f64>>,
    /// Whether a frame showed it grasped.
    pub grasped: bool,
    /// Frames that showed it sliding along a contact.
    pub sliding_frames: u64,
    /// How far its middle moved from one sliding frame to the next, in all (metres).
    pub slid_m: f64,
}

impl BarWatch {
    fn observe(&mut self, frame: Frame) {
        let Frame::Parts(frame) = frame else {
            return;
        };
        let Some(state) = frame.parts.get(self.id) else {
            return;
        };
        let pose: Isometry3<f64> = state.pose().into();
        self.grasped |= state.flags & PART_GRASPED != 0;
        if state.flags & PART_SLIDING != 0 {
            if let Some(last) = self.poses.last() {
                self.slid_m += (pose.translation.vector - last.translation.vector).norm();
            }
            self.sliding_frames += 1;
        }
        if self.poses.last() != Some(&pose) {
            self.poses.push(pose);
        }
    }
}

/// Sends `samples` ([`RATE_HZ`] apart, numbered from `first_seq`) to the server, each tracker sample
/// as a round trip of at most `timeout`, and watches part `bar`.
pub fn along(
    client: &mut Client,
    samples: &[Keyframe],
    first_seq: u64,
    bar: u32,
    timeout: Duration,
) -> Result<Drive> {
    let mut drive = Drive {
        bar: BarWatch {
            id: bar as usize,
            ..BarWatch::default()
        },
        ..Drive::default()
    };
    let start = Instant::now();
    for (seq, key) in (first_seq..).zip(samples) {
        let due = start + Duration::from_secs_f64((seq - first_seq) as f64 / RATE_HZ);
        let early = due.saturating_duration_since(Instant::now());
        if !early.is_zero() && client.sleep(early) == Wake::Terminated {
            bail!("interrupted");
        }
        let sample = InputSample::Tracker(tracker(key, seq));
        match round_trip(client, sample, timeout, |frame| drive.bar.observe(frame))? {
            Some(latency) => drive.latencies.push((key.time, latency)),
            None => drive.unanswered += 1,
        }
        client.send_glove(&GloveSample {
            seq,
            timestamp_ns: wall_clock_ns(),
            flex: key.input().flex,
        })?;
    }
    drive.seconds = start.elapsed().as_secs_f64();
    Ok(drive)
}

/// Tracker sample `seq` of `key` (stamped when sent).
pub fn tracker(key: &Keyframe, seq: u64) -> TrackerSample {
    let input = key.input();
    TrackerSample {
        seq,
        timestamp_ns: 0,
        hand: input.tracker.into(),
        cart: input.cart.into(),
        sensor_id: 0,
    }
}
