//! A synthetic input stream for the benchmarks: the hand moves on a slow ellipse in free space,
//! 25 cm above the demo scene's table, while the fingers open and close a little. For hand-joints
//! input, two captured hands drift on the same ellipse side by side.

use std::path::Path;
use std::sync::OnceLock;

use nalgebra::{Isometry3, Vector3};
use vas_protocol::HandSide;
use vas_protocol::{
    FLEX_COUNT, GloveSample, HandJointsSample, TrackerSample, WirePose, wall_clock_ns,
};
use vas_server::grasping::retarget::{Capture, HandJoints, Joint};
use vas_server::runtime::hand_joints::wire_joints;

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
        user: 0,
        side: 0,
        reserved: 0,
    }
}

/// Glove sample `seq`, stamped now.
pub fn glove(seq: u64) -> GloveSample {
    let closing = (0.5 - 0.5 * phase(seq).cos()) as f32;
    GloveSample {
        seq,
        timestamp_ns: wall_clock_ns(),
        flex: [MAX_FLEX * closing; FLEX_COUNT],
        user: 0,
        side: 0,
    }
}

/// The captured relaxed hand (`tests/fixtures/hands/`), built into the benchmark so that it runs
/// from any folder.
const RELAXED: &str = include_str!("../../tests/fixtures/hands/webxr_relaxed.json");

/// Where the two hands' wrists drift, in the world (metres, z up): 20 cm either side of the
/// middle, 45 cm up, clear of `configs/two_hand_handover.toml`'s handle.
const WRISTS: [[f64; 3]; 2] = [[0.2, 0.0, 0.45], [-0.2, 0.0, 0.45]];

/// The captured relaxed hand as a right and as a left hand, each with its wrist at the origin.
fn hands() -> &'static [HandJoints; 2] {
    static HANDS: OnceLock<[HandJoints; 2]> = OnceLock::new();
    HANDS.get_or_init(|| {
        let capture = Capture::from_json(Path::new("webxr_relaxed.json"), RELAXED)
            .expect("the built-in capture is a hand");
        [HandSide::Right, HandSide::Left].map(|side| {
            let joints = capture.joints_of(side);
            let wrist = joints.joints[Joint::Wrist.index()].position.coords;
            joints.transformed(&Isometry3::translation(-wrist.x, -wrist.y, -wrist.z))
        })
    })
}

/// Hand-joints sample `seq`, stamped now: the captured relaxed hand, right for odd `seq` and
/// left for even, its wrist drifting on the tracker stream's ellipse around its place.
pub fn hand_joints(seq: u64) -> HandJointsSample {
    let phase = phase(seq);
    let hand = usize::from(seq.is_multiple_of(2));
    let drift = Vector3::new(0.1 * phase.cos(), 0.05 * phase.sin(), 0.0);
    let wrist = Vector3::from(WRISTS[hand]) + drift;
    let joints = hands()[hand].transformed(&Isometry3::translation(wrist.x, wrist.y, wrist.z));
    wire_joints(&joints, seq, wall_clock_ns())
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

    #[test]
    fn the_hands_alternate_and_are_valid_hands_that_drift() {
        use vas_protocol::HandSide;
        use vas_server::grasping::retarget::Retargeter;
        use vas_server::runtime::hand_joints::read_joints;
        let model = |name: &str| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../configs/hands")
                .join(name);
            vas_server::grasping::HandModel::load(&path).expect("a hand model")
        };
        let retargeters = [model("right.toml"), model("left.toml")]
            .map(|model| Retargeter::new(model).expect("retargets"));
        let mut roots = Vec::new();
        for seq in (1..4_000).step_by(333) {
            let sample = hand_joints(seq);
            let (side, expected) = if !seq.is_multiple_of(2) {
                (HandSide::Right, HandSide::Right)
            } else {
                (HandSide::Left, HandSide::Left)
            };
            assert_eq!(sample.side, expected as u32);
            let fit = retargeters[usize::from(side == HandSide::Left)]
                .fit(&read_joints(&sample, side))
                .expect("a valid, tracked hand");
            roots.push(fit.root.translation.vector);
        }
        assert!((roots[0] - roots[2]).norm() > 0.01, "the hands drift");
    }
}
