//! `vas-client send-tracker`, `send-glove` and `send-hand-joints`: single samples for scripts.

use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, bail};
use vas_client::recording::InputSample;
use vas_client::{Frame, Roles};
use vas_protocol::{
    FLEX_COUNT, GloveSample, HandJointsSample, HandSide, InputStats, TrackerSample, WirePose,
    wall_clock_ns,
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
    hand: HandArgs,
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
    hand: HandArgs,
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
    user: UserArgs,
    #[command(flatten)]
    answer: AnswerArgs,
}

/// Whose hand a sample drives.
#[derive(Debug, clap::Args)]
struct UserArgs {
    /// The user whose hand the sample drives, by name, as the scene info lists the users
    /// (`vas-client info`); default the scene's first user.
    #[arg(long)]
    user: Option<String>,
}

/// Which hand a tracker or glove sample drives.
#[derive(Debug, clap::Args)]
struct HandArgs {
    #[command(flatten)]
    user: UserArgs,
    /// Which of the user's hands: right or left.
    #[arg(long, default_value = "right", value_parser = ["right", "left"])]
    side: String,
}

impl HandArgs {
    /// The side's code.
    fn side_code(&self) -> u32 {
        let side = if self.side == "left" {
            HandSide::Left
        } else {
            HandSide::Right
        };
        side as u32
    }
}

/// Waiting for the hand frame that answers the sample.
#[derive(Debug, clap::Args)]
struct AnswerArgs {
    /// Wait for the answering hand frame and print it as JSON; fail with the reason if the
    /// server rejects the sample, or if no frame comes in time.
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
        user: 0,
        side: args.hand.side_code(),
        reserved: 0,
    };
    send(
        prefix,
        InputSample::Tracker(sample),
        &args.hand.user,
        &args.answer,
    )
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
        user: 0,
        side: args.hand.side_code(),
    };
    send(
        prefix,
        InputSample::Glove(sample),
        &args.hand.user,
        &args.answer,
    )
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
    send(prefix, sample, &args.user, &args.answer)
}

/// Sends `sample` and waits until the server has taken it in; with `--answer`, prints the hand
/// frame that answers it, or fails with its rejection and the reason.
///
/// A rejected sample has no answering frame: the server only counts it (`vas-client info`). So
/// the input counters are read before the send and again by the round trip that flushes it (the
/// server takes in input before it answers a control request), and a rejection counter that
/// moved is this sample's. The counters exist for every stream and need nothing new on the
/// wire, where an event per rejection would let a broken sender flood every reader's events; a
/// sample rejected for another sender between the two reads would be taken for this one's,
/// which a script sending one sample at a time does not meet.
fn send(
    prefix: Option<&str>,
    sample: InputSample,
    user: &UserArgs,
    args: &AnswerArgs,
) -> anyhow::Result<()> {
    // Only a sender that waits for its answer reads frames.
    let roles = if args.answer {
        Roles::INPUT | Roles::RENDER
    } else {
        Roles::INPUT
    };
    let mut client = super::connect(prefix, roles)?;
    let sample = match &user.user {
        None => sample,
        Some(name) => {
            let scene = client.scene_info(super::CONTROL_TIMEOUT)?;
            let index = scene.user_index(name).with_context(|| {
                format!(
                    "the scene has no user {name:?} (its users: {})",
                    scene.users.join(", ")
                )
            })?;
            sample.with_user(index)
        }
    };
    let sample = &sample;
    if !args.answer {
        client.send_input(sample)?;
        return Ok(client.flush_inputs(super::CONTROL_TIMEOUT)?);
    }
    let before = client.input_stats(super::CONTROL_TIMEOUT)?;
    client.send_input(sample)?;
    let after = client.input_stats(super::CONTROL_TIMEOUT)?;
    if after.rejected() > before.rejected() {
        bail!(
            "the server rejected the sample: {}",
            rejection(sample, &before, &after)?
        );
    }
    let timeout = Duration::from_millis(args.answer_timeout_ms);
    let frame = client
        .wait_for_hand_frame(timeout, |frame| sample.is_answered_by(frame), drop)?
        .with_context(|| format!("no hand frame answered the sample within {timeout:?}"))?;
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &Frame::Hand(frame))?;
    writeln!(out)?;
    Ok(())
}

/// Why `sample` was rejected: the protocol's own check of a tracker or glove sample (the one
/// the server runs) where it fails, and the counters that moved from `before` to `after`.
fn rejection(
    sample: &InputSample,
    before: &InputStats,
    after: &InputStats,
) -> anyhow::Result<String> {
    let (before, after) = (serde_json::to_value(before)?, serde_json::to_value(after)?);
    let moved: Vec<&str> = (after.as_object().into_iter().flatten())
        .filter(|(name, count)| name.contains("rejected") && before[name.as_str()] != **count)
        .map(|(name, _)| name.as_str())
        .collect();
    let reason = match sample {
        InputSample::Tracker(sample) => sample.validate().err().map(|e| e.to_string()),
        InputSample::Glove(sample) => sample.validate().err().map(|e| e.to_string()),
        InputSample::HandJoints(_) => None,
    };
    let counted = format!("counted in {}", moved.join(", "));
    Ok(match reason {
        Some(reason) => format!("{reason} ({counted})"),
        None => counted,
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
