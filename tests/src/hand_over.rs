//! The two-handed hand-over recording: the scripted hand-over (`vas_server::scene::hand_over`)
//! as the right hand's tracker and glove samples and the left hand's hand-joints samples, at
//! [`RATE_HZ`]. The left hand's joints are those of the scene's left hand model posed by its
//! script ([`Retargeter::synthesize`]): what a headset would report for that hand.
//!
//! Per tick one tracker, one glove and one hand-joints sample, each numbered by the tick (from
//! 1), stamped at the tick, 5 ms and 10 ms later, counting from zero; the joints'
//! values [rounded](crate::hands::rounded). Two runs write identical files.

use anyhow::{Context, bail};
use vas_client::recording::InputSample;
use vas_protocol::{GloveSample, TrackerSample};
use vas_server::grasping::Side;
use vas_server::grasping::retarget::Retargeter;
use vas_server::runtime::hand_joints::wire_joints;
use vas_server::scene::Scene;
use vas_server::scene::hand_over::{block_pose, handle_pose, keyframes};
use vas_server::scene::script::keyframe_at;

use crate::hands::rounded;

/// Ticks per second.
pub const RATE_HZ: f64 = 50.0;

/// Nanoseconds between ticks.
const PERIOD_NS: u64 = 20_000_000;

/// The part handed over.
pub const HANDLE: &str = "handle";

/// The part the handle goes into.
pub const BLOCK: &str = "block";

/// What the recording shows, for its header.
pub const DESCRIPTION: &str = "the right hand (tracker and glove) power-grasps one end of a long \
    handle, the left hand (hand joints) grasps the other end and takes it over, the right hand \
    opens and withdraws, the left pushes the handle's other end 3 cm into a block's hole and lets \
    go";

/// The hand-over's samples in `scene`: its hands the right and then the left one, its parts
/// [`HANDLE`] and [`BLOCK`] where the script puts them.
pub fn samples(scene: &Scene) -> anyhow::Result<Vec<InputSample>> {
    let sides: Vec<Side> = scene.hands.iter().map(|hand| hand.model.side()).collect();
    if sides != [Side::Right, Side::Left] {
        bail!("the hand-over needs a right and then a left hand, not {sides:?}");
    }
    for (name, expected) in [(HANDLE, handle_pose()), (BLOCK, block_pose())] {
        let part = (scene.parts.iter())
            .find(|part| part.name == name)
            .with_context(|| format!("the scene has no part {name:?}"))?;
        if (part.pose.translation.vector - expected.translation.vector).norm() > 1e-9
            || part.pose.rotation.angle_to(&expected.rotation) > 1e-9
        {
            bail!("the {name} must lie where the script puts it, at {expected}");
        }
    }
    let left = Retargeter::new(scene.hands[1].model.as_ref().clone())?;
    let [right_keys, left_keys] = keyframes();
    let end = right_keys.last().context("keyframes")?.time;
    let ticks = (end * RATE_HZ).round() as u64;
    let mut samples = Vec::new();
    for tick in 0..=ticks {
        let time = tick as f64 / RATE_HZ;
        let right = keyframe_at(&right_keys, time).context("keyframes")?.input();
        let left_key = keyframe_at(&left_keys, time).context("keyframes")?;
        let seq = tick + 1;
        let tick_ns = tick * PERIOD_NS;
        let joints = rounded(&left.synthesize(&(left_key.cart * left_key.tracker), &left_key.flex));
        joints
            .validate()
            .with_context(|| format!("the left hand's joints at tick {seq}"))?;
        samples.extend([
            InputSample::Tracker(TrackerSample {
                seq,
                timestamp_ns: tick_ns,
                hand: right.tracker.into(),
                cart: right.cart.into(),
                sensor_id: 0,
            }),
            InputSample::Glove(GloveSample {
                seq,
                timestamp_ns: tick_ns + PERIOD_NS / 4,
                flex: right.flex,
            }),
            InputSample::HandJoints(wire_joints(&joints, seq, tick_ns + PERIOD_NS / 2)),
        ]);
    }
    Ok(samples)
}
