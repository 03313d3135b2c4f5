//! The fixture generator: each recorded scenario's motion written as a recording. A scripted
//! motion is sampled at a fixed rate into tracker and glove samples, as below; the captured hands
//! make hand-joints samples ([`crate::captured`]).
//!
//! Per tick of [`RATE_HZ`] one tracker sample and then one glove sample, both with the tick's
//! number as their sequence number (from 1); the tracker is stamped at the tick, the glove half a
//! period later. Stamps count from zero (a replay stamps samples anew when it sends them), so the
//! output depends on nothing but the scripts and the scenes: generating twice gives identical
//! files.

use std::path::{Path, PathBuf};

use vas_client::recording::{InputSample, RecordingHeader, RecordingWriter};
use vas_protocol::{GloveSample, TrackerSample};
use vas_server::scene::Scene;
use vas_server::scene::script::{Keyframe, sample};

use crate::scenarios::{Motion, Scenario};

/// Ticks per second of the recordings: one tracker and one glove sample each.
pub const RATE_HZ: f64 = 100.0;

/// Nanoseconds between ticks.
const PERIOD_NS: u64 = 10_000_000;

/// The input samples of a trajectory sampled at [`RATE_HZ`], tracker and glove interleaved.
pub fn input_samples(keys: &[Keyframe]) -> Vec<InputSample> {
    sample(keys, RATE_HZ)
        .iter()
        .zip(1u64..)
        .flat_map(|(key, seq)| {
            let input = key.input();
            let tick_ns = (seq - 1) * PERIOD_NS;
            [
                InputSample::Tracker(TrackerSample {
                    seq,
                    timestamp_ns: tick_ns,
                    hand: input.tracker.into(),
                    cart: input.cart.into(),
                    sensor_id: 0,
                }),
                InputSample::Glove(GloveSample {
                    seq,
                    timestamp_ns: tick_ns + PERIOD_NS / 2,
                    flex: input.flex,
                }),
            ]
        })
        .collect()
}

/// Writes the recording of `scenario` (its scene read from `configs`) into the folder `out`;
/// returns the file written.
pub fn write_fixture(scenario: &Scenario, configs: &Path, out: &Path) -> anyhow::Result<PathBuf> {
    let scene = Scene::load(&configs.join(scenario.scene))?;
    let (samples, description) = match scenario.motion {
        Motion::Script(script) => (
            input_samples(&script.keyframes(&scene)?),
            script.description(),
        ),
        Motion::Captured(captured) => (captured.samples(&scene)?, captured.description()),
        Motion::HandOver => (
            crate::hand_over::samples(&scene)?,
            crate::hand_over::DESCRIPTION,
        ),
    };
    let path = out.join(scenario.fixture_file());
    let header = RecordingHeader::new(scene.name, description);
    let mut writer = RecordingWriter::create(&path, &header)?;
    for input in &samples {
        writer.write(input)?;
    }
    Ok(path)
}
