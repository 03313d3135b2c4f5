//! A synthetic input stream for the benchmarks: the hand moves on a slow ellipse in free space,
//! 25 cm above the demo scene's table, while the fingers open and close a little.

use vas_protocol::{FLEX_COUNT, GloveSample, TrackerSample, WirePose, wall_clock_ns};

/// Radians the motion advances per sample: a full turn every ~3,100 samples (~3 s at 1 kHz).
const PHASE_STEP: f64 = 0.002;

/// The largest flex angle of the stream, in radians: inside every joint's limits.
const MAX_FLEX: f32 = 0.2;

fn phase(seq: u64) -> f64 {
    seq as f64 * PHASE_STEP
}

/// Tracker sample `seq`, stamped now.
pub fn tracker(seq: u64) -> TrackerSample {
    let phase = phase(seq);
    TrackerSample {
        seq,
        timestamp_ns: wall_clock_ns(),
        hand: WirePose {
            position: [0.1 * phase.cos(), -0.3 + 0.05 * phase.sin(), 1.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        },
        cart: WirePose::IDENTITY,
        sensor_id: 0,
    }
}

/// Glove sample `seq`, stamped now.
pub fn glove(seq: u64) -> GloveSample {
    let closing = (0.5 - 0.5 * phase(seq).cos()) as f32;
    GloveSample {
        seq,
        timestamp_ns: wall_clock_ns(),
        flex: [MAX_FLEX * closing; FLEX_COUNT],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stream_is_valid_input_without_clamping() {
        for seq in (1..20_000).step_by(7) {
            tracker(seq).validate().expect("valid tracker sample");
            let glove = glove(seq).validate().expect("valid glove sample");
            assert_eq!(glove.clamped, 0, "seq {seq}: flex within the joint limits");
        }
    }
}
