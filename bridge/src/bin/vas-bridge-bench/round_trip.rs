//! B13's round trip: a hand-joints sample put on zenoh to the hand frame that answers it
//! (`remote`), against the bare zenoh round trip of payloads of the same sizes, a sample's out
//! and a hand frame's back, to an echo peer in another process (`bare`). The paths take turns,
//! each sample sent once the one before was answered, the first of each turn alternating; both
//! receive through zenoh's default FIFO handler and time on this process's monotonic clock.

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::Context;
use serde::Serialize;
use vas_bridge::keys::{Input, Keys};
use vas_bridge::wire;
use vas_client::recording::{InputSample, Recording};
use vas_protocol::{HandFrame, HandJointsSample, services, wall_clock_ns};
use zenoh::Wait;
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::sample::Sample;

use crate::{micros, open_session, percentile, zenoh_error};

/// Options of `round-trip`.
#[derive(Debug, clap::Args)]
pub struct RoundTripArgs {
    /// Measured round trips of each path.
    #[arg(long, default_value_t = 10_000)]
    samples: usize,
    /// Round trips of each path left out first.
    #[arg(long, default_value_t = 200)]
    warmup: usize,
    /// A recording whose first hand-joints sample is the hand sent, its wrist drifting on an
    /// ellipse.
    #[arg(long)]
    recording: PathBuf,
    /// How far the hand is raised above where it was recorded, metres: clear of every part.
    #[arg(long, default_value_t = 0.2)]
    lift: f64,
    /// A round trip not answered within this is counted, not measured.
    #[arg(long, default_value_t = 1000)]
    answer_timeout_ms: u64,
    /// Write the figures as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One path's figures.
#[derive(Debug, Serialize)]
struct PathFigures {
    measured: usize,
    unanswered: usize,
    p50_us: f64,
    p99_us: f64,
    max_us: f64,
}

fn figures(mut times: Vec<Duration>, unanswered: usize) -> PathFigures {
    times.sort();
    PathFigures {
        measured: times.len(),
        unanswered,
        p50_us: micros(percentile(&times, 50.0)),
        p99_us: micros(percentile(&times, 99.0)),
        max_us: micros(times.last().copied().unwrap_or_default()),
    }
}

/// The echo child, killed when dropped.
struct Echo(Child);

impl Drop for Echo {
    fn drop(&mut self) {
        // It may have died already; nothing else to do then.
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One path: where samples go and where answers come from.
struct Path {
    out: Publisher<'static>,
    back: Subscriber<FifoChannelHandler<Sample>>,
    times: Vec<Duration>,
    unanswered: usize,
}

impl Path {
    /// Puts `payload`, waits for the answer `answers` accepts; the round trip, or `None`.
    fn exchange(
        &mut self,
        payload: Vec<u8>,
        timeout: Duration,
        answers: impl Fn(&[u8]) -> bool,
    ) -> anyhow::Result<Option<Duration>> {
        let start = Instant::now();
        self.out
            .put(payload)
            .wait()
            .map_err(|error| anyhow::anyhow!("{error}"))?;
        let deadline = start + timeout;
        loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            match self.back.recv_timeout(remaining) {
                Ok(Some(sample)) if answers(&sample.payload().to_bytes()) => {
                    return Ok(Some(start.elapsed()));
                }
                Ok(Some(_)) => {}
                Ok(None) => return Ok(None),
                Err(error) => anyhow::bail!("the answers' subscriber closed: {error}"),
            }
        }
    }

    fn record(&mut self, measured: bool, time: Option<Duration>) {
        match (measured, time) {
            (true, Some(time)) => self.times.push(time),
            (true, None) => self.unanswered += 1,
            (false, _) => {}
        }
    }
}

/// The recording's first hand-joints sample.
fn recorded_hand(path: &std::path::Path) -> anyhow::Result<HandJointsSample> {
    let recording = Recording::load(path)?;
    (recording.samples.iter())
        .find_map(|recorded| match recorded.input {
            InputSample::HandJoints(sample) => Some(sample),
            _ => None,
        })
        .with_context(|| format!("{} has no hand-joints sample", path.display()))
}

/// The hand of sample `index`: raised by `lift`, its wrist on an ellipse (10 cm by 6 cm).
fn drifting(hand: &HandJointsSample, index: usize, lift: f64) -> HandJointsSample {
    let angle = index as f64 * 0.01;
    let offset = [0.05 * angle.cos(), 0.03 * angle.sin(), lift];
    let mut sample = *hand;
    for joint in &mut sample.joints {
        for (coordinate, shift) in joint.position.iter_mut().zip(offset) {
            *coordinate += shift;
        }
    }
    sample.seq = index as u64 + 1;
    sample.timestamp_ns = wall_clock_ns();
    sample
}

/// Runs the round trips and prints the table (and JSON).
pub fn run(endpoint: &str, session_name: &str, args: &RoundTripArgs) -> anyhow::Result<()> {
    let hand = recorded_hand(&args.recording)?;
    let keys = Keys::new(session_name)?;
    let session = open_session(endpoint)?;
    let echo_key = format!("vas-bridge-bench/{}", std::process::id());
    let _echo = Echo(
        Command::new(std::env::current_exe()?)
            .args(["--connect", endpoint, "echo", "--key", &echo_key])
            .stdin(Stdio::null())
            .spawn()
            .context("cannot start the echo")?,
    );
    let publisher = |key: String| session.declare_publisher(key).express(true).wait();
    let subscriber = |key: String| session.declare_subscriber(key).wait();
    let mut remote = Path {
        out: publisher(keys.input(Input::HandJoints)).map_err(zenoh_error)?,
        back: subscriber(keys.service(services::HAND)).map_err(zenoh_error)?,
        times: Vec::new(),
        unanswered: 0,
    };
    let mut bare = Path {
        out: publisher(format!("{echo_key}/ping")).map_err(zenoh_error)?,
        back: subscriber(format!("{echo_key}/pong")).map_err(zenoh_error)?,
        times: Vec::new(),
        unanswered: 0,
    };
    let timeout = Duration::from_millis(args.answer_timeout_ms);
    let ping_bytes = wire::ENVELOPE_BYTES + size_of::<HandJointsSample>();
    let ping = |seq: u64| {
        let mut bytes = vec![0; ping_bytes];
        bytes[..8].copy_from_slice(&seq.to_le_bytes());
        bytes
    };
    let is_pong = |seq: u64| {
        move |bytes: &[u8]| {
            bytes.len() == crate::echo::PONG_BYTES && bytes[..8] == seq.to_le_bytes()
        }
    };
    // The echo is up once it answers.
    let started = Instant::now();
    while bare
        .exchange(ping(0), Duration::from_millis(100), is_pong(0))?
        .is_none()
    {
        anyhow::ensure!(
            started.elapsed() < Duration::from_secs(30),
            "the echo never answered"
        );
    }
    let rounds = args.warmup + args.samples;
    for index in 0..rounds {
        let measured = index >= args.warmup;
        let seq = index as u64 + 1;
        let sample = drifting(&hand, index, args.lift);
        let answers = move |bytes: &[u8]| {
            wire::decode::<HandFrame>(bytes).is_ok_and(|frame| frame.joints.seq == seq)
        };
        for remote_first in [index % 2 == 0, index % 2 != 0] {
            if remote_first {
                let time = remote.exchange(wire::encode(&sample), timeout, answers)?;
                remote.record(measured, time);
            } else {
                let time = bare.exchange(ping(seq), timeout, is_pong(seq))?;
                bare.record(measured, time);
            }
        }
    }
    let (bare, remote) = (
        figures(bare.times, bare.unanswered),
        figures(remote.times, remote.unanswered),
    );
    let bar = 2.0 * bare.p99_us + 100.0;
    println!("| path | measured | unanswered | p50 | p99 | max |");
    println!("|---|---|---|---|---|---|");
    for (name, path) in [("bare zenoh", &bare), ("remote (bridge)", &remote)] {
        println!(
            "| {name} | {} | {} | {:.1} us | {:.1} us | {:.1} us |",
            path.measured, path.unanswered, path.p50_us, path.p99_us, path.max_us
        );
    }
    let met = remote.p99_us <= bar && remote.unanswered == 0;
    println!(
        "bar: remote p99 {:.1} us <= 2 x bare p99 + 100 us = {bar:.1} us: {}",
        remote.p99_us,
        if met { "met" } else { "not met" }
    );
    if let Some(path) = &args.json {
        let json = serde_json::json!({ "bare": bare, "remote": remote, "bar_us": bar, "met": met });
        std::fs::write(path, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
