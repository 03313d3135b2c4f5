//! Driving the server along the scripted path at 1 kHz: each tick publishes the tracker sample
//! and times it to the hand frame that answers it (B7's procedure, [`round_trip`]), then
//! publishes the glove sample; the parts frames received meanwhile show where the bar is and
//! whether it is grasped and sliding.

use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use nalgebra::Isometry3;
use vas_client::recording::InputSample;
use vas_client::{ClearanceFrame, Client, Frame, Wake};
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
    /// What the clearance frames reported (none without a threshold).
    pub clearance: ClearanceSeen,
}

/// The clearance frames received over the drive.
#[derive(Debug, Clone, Copy, Default)]
pub struct ClearanceSeen {
    /// Clearance frames received.
    pub frames: u64,
    /// Frames that listed a pair.
    pub frames_with_pairs: u64,
    /// Pairs listed, summed over the frames.
    pub pairs: u64,
    /// The most pairs one frame listed.
    pub most_pairs: u32,
    /// Pairs listed stale (not measured on their frame's poses in time), summed.
    pub stale_pairs: u64,
    /// The least distance listed (metres); infinite when none was.
    pub closest_m: f64,
}

impl ClearanceSeen {
    fn observe(&mut self, frame: &ClearanceFrame) {
        let listed = frame.listed();
        if self.frames == 0 {
            self.closest_m = f64::INFINITY;
        }
        self.frames += 1;
        self.frames_with_pairs += u64::from(!listed.is_empty());
        self.pairs += listed.len() as u64;
        self.most_pairs = self.most_pairs.max(frame.pair_count);
        self.stale_pairs += listed.iter().filter(|pair| pair.is_stale()).count() as u64;
        self.closest_m = (listed.iter()).fold(self.closest_m, |m, pair| m.min(pair.distance));
    }
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
    fn observe(&mut self, frame: &Frame) {
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
/// as a round trip of at most `timeout`, and watches part `bar` and the clearance frames.
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
        let (bar, clearance) = (&mut drive.bar, &mut drive.clearance);
        let observe = |frame: Frame| match &frame {
            Frame::Clearance(listed) => clearance.observe(listed),
            _ => bar.observe(&frame),
        };
        match round_trip(client, sample, timeout, observe)? {
            Some(latency) => drive.latencies.push((key.time, latency)),
            None => drive.unanswered += 1,
        }
        client.send_glove(&GloveSample {
            seq,
            timestamp_ns: wall_clock_ns(),
            flex: key.input().flex,
            user: 0,
            side: 0,
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
        user: 0,
        side: 0,
        reserved: 0,
    }
}
