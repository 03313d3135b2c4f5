//! `vas-client send-tracker`, `send-glove` and `send-hand-joints`: single samples for scripts.

use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, bail};
use vas_client::recording::InputSample;
use vas_client::{Client, Frame};
use vas_protocol::{
    FLEX_COUNT, GloveSample, HandFrame, HandJointsSample, TrackerSample, WirePose, wall_clock_ns,
};

/// Arguments of `vas-client send-tracker`.
#[derive(Debug, clap::Args)]
pub struct TrackerArgs {
    /// Hand root position in metres: x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        default_value = "0,0,0"
    )]
    position: Vec<f64>,
    /// Hand root rotation as a unit quaternion: x,y,z,w.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        default_value = "0,0,0,1"
    )]
    rotation: Vec<f64>,
    /// Cart position in metres: x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        default_value = "0,0,0"
    )]
    cart_position: Vec<f64>,
    /// Cart rotation as a unit quaternion: x,y,z,w.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        default_value = "0,0,0,1"
    )]
    cart_rotation: Vec<f64>,
    /// Sequence number of the sample.
    #[arg(long, default_value_t = 1)]
    seq: u64,
    /// Tracker (sensor) number.
    #[arg(long, default_value_t = 0)]
    sensor: u32,
    #[command(flatten)]
    answer: AnswerArgs,
}

/// Arguments of `vas-client send-glove`.
#[derive(Debug, clap::Args)]
pub struct GloveArgs {
    /// The 22 joint angles in radians, CyberGlove order, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        required = true
    )]
    flex: Vec<f32>,
    /// Sequence number of the sample.
    #[arg(long, default_value_t = 1)]
    seq: u64,
    #[command(flatten)]
    answer: AnswerArgs,
}

/// Arguments of `vas-client send-hand-joints`.
#[derive(Debug, clap::Args)]
pub struct HandJointsArgs {
    /// The sample as JSON, as a recording's `hand_joints` lines hold it (`seq`, `timestamp_ns`,
    /// `joints`: 26 objects with `position`, `rotation`, `radius`, `flags`, and `side`: 0 right,
    /// 1 left); `-` reads it from stdin.
    sample: PathBuf,
    /// Sequence number of the sample (replaces the file's).
    #[arg(long, default_value_t = 1)]
    seq: u64,
    #[command(flatten)]
    answer: AnswerArgs,
}

/// Waiting for the hand frame that answers the sample.
#[derive(Debug, clap::Args)]
struct AnswerArgs {
    /// Wait for the answering hand frame and print it as JSON; fail if none comes in time.
    #[arg(long)]
    answer: bool,
    /// How long to wait for the answer, in milliseconds.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..=super::MAX_TIMEOUT_MS))]
    answer_timeout_ms: u64,
}

/// Sends one tracker sample, stamped now.
pub fn tracker(prefix: Option<&str>, args: &TrackerArgs) -> anyhow::Result<()> {
    let sample = TrackerSample {
        seq: args.seq,
        timestamp_ns: wall_clock_ns(),
        hand: pose(&args.position, &args.rotation).context("hand pose")?,
        cart: pose(&args.cart_position, &args.cart_rotation).context("cart pose")?,
        sensor_id: args.sensor,
    };
    let mut client = super::connect(prefix)?;
    client.send_tracker(&sample)?;
    client.flush_inputs(super::CONTROL_TIMEOUT)?;
    let stamp = sample.stamp();
    report_answer(&mut client, &args.answer, |frame| frame.tracker == stamp)
}

/// Sends one glove sample, stamped now.
pub fn glove(prefix: Option<&str>, args: &GloveArgs) -> anyhow::Result<()> {
    let flex: [f32; FLEX_COUNT] =
        args.flex.as_slice().try_into().with_context(|| {
            format!("--flex needs {FLEX_COUNT} values, got {}", args.flex.len())
        })?;
    let sample = GloveSample {
        seq: args.seq,
        timestamp_ns: wall_clock_ns(),
        flex,
    };
    let mut client = super::connect(prefix)?;
    client.send_glove(&sample)?;
    client.flush_inputs(super::CONTROL_TIMEOUT)?;
    let stamp = sample.stamp();
    report_answer(&mut client, &args.answer, |frame| frame.glove == stamp)
}

/// Sends one hand-joints sample read from JSON, numbered `--seq` and stamped now.
pub fn hand_joints(prefix: Option<&str>, args: &HandJointsArgs) -> anyhow::Result<()> {
    let text = if args.sample.as_os_str() == "-" {
        let mut text = String::new();
        std::io::stdin()
            .read_to_string(&mut text)
            .context("cannot read the sample from stdin")?;
        text
    } else {
        std::fs::read_to_string(&args.sample)
            .with_context(|| format!("cannot read {}", args.sample.display()))?
    };
    let read: HandJointsSample = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a hand-joints sample", args.sample.display()))?;
    let sample = InputSample::HandJoints(HandJointsSample {
        seq: args.seq,
        ..read
    })
    .with_timestamp(wall_clock_ns());
    let mut client = super::connect(prefix)?;
    client.send_input(&sample)?;
    client.flush_inputs(super::CONTROL_TIMEOUT)?;
    report_answer(&mut client, &args.answer, |frame| {
        sample.is_answered_by(frame)
    })
}

fn pose(position: &[f64], rotation: &[f64]) -> anyhow::Result<WirePose> {
    let Ok(position) = position.try_into() else {
        bail!("a position needs 3 values (x,y,z), got {}", position.len());
    };
    let Ok(rotation) = rotation.try_into() else {
        bail!(
            "a rotation needs 4 values (x,y,z,w), got {}",
            rotation.len()
        );
    };
    Ok(WirePose { position, rotation })
}

/// With `--answer`, waits for the hand frame `answers` accepts and prints it.
fn report_answer(
    client: &mut Client,
    args: &AnswerArgs,
    answers: impl Fn(&HandFrame) -> bool,
) -> anyhow::Result<()> {
    if !args.answer {
        return Ok(());
    }
    let timeout = Duration::from_millis(args.answer_timeout_ms);
    let frame = client
        .wait_for_hand_frame(timeout, answers, drop)?
        .with_context(|| format!("no hand frame answered the sample within {timeout:?}"))?;
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &Frame::Hand(frame))?;
    writeln!(out)?;
    Ok(())
}
