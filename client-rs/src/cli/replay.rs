//! `vas-client replay`: a recording into the server, in real time or in lockstep (paced at the
//! recording's timing or as fast as the server answers).

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;
use vas_client::recording::{RecordedSample, Recording};
use vas_client::{Client, Frame, Roles, SceneWords, Wake};
use vas_protocol::wall_clock_ns;

use vas_client::latency::LatencySummary;

/// Arguments of `vas-client replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The recording to play (JSON Lines, as `vas-client record` writes).
    file: PathBuf,
    /// Send one sample, wait for the hand frame answering it, then send the next, regardless of
    /// the recorded times; prints the events each sample caused and then its answer as JSON
    /// lines, the same every time but for the timestamps.
    #[arg(long)]
    lockstep: bool,
    /// In lockstep, how long to wait for each answer before going on without it, in ms. The
    /// first answer may take seconds on a busy machine: the loops build the parts' trees on
    /// first use.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(1..=super::MAX_TIMEOUT_MS))]
    answer_timeout_ms: u64,
    /// In lockstep, send no sample before its recorded time since the replay started (and then
    /// wait for its answer), so that the replay plays at the recording's pace for a person to
    /// watch; a sample whose turn came while the previous answer was awaited goes at once.
    #[arg(long, requires = "lockstep")]
    pace: bool,
}

/// How far before the replay starts a lockstep replay's last sample is stamped, when it is not
/// paced: its stamps lie in the past whatever its pace, and so far in it that a renderer does
/// not take them for live input (vas-viewer shows latency only for answers published within a
/// second of their sample's stamp).
const UNPACED_STAMPS_BEFORE: Duration = Duration::from_secs(1);

/// Plays the recording. Samples keep their sequence numbers and are stamped with the replay's
/// start plus their recorded time, so that they keep their recorded spacing in every mode (a
/// server counts sample times); the latencies are measured from when each was sent.
pub fn run(prefix: Option<&str>, args: &ReplayArgs) -> anyhow::Result<()> {
    let recording = Recording::load(&args.file)?;
    // In lockstep the replay reads the answer to each sample; in real time it only sends.
    let roles = if args.lockstep {
        Roles::INPUT | Roles::RENDER
    } else {
        Roles::INPUT
    };
    let mut client = super::connect(prefix, roles)?;
    let scene = client.scene_info(super::CONTROL_TIMEOUT)?;
    if scene.name != recording.header.scene {
        tracing::warn!(
            recorded = recording.header.scene,
            server = scene.name,
            "the recording was made against another scene"
        );
    }
    tracing::info!(
        file = %args.file.display(),
        samples = recording.samples.len(),
        lockstep = args.lockstep,
        paced = args.pace,
        "replaying"
    );
    if args.lockstep {
        lockstep(
            &mut client,
            &recording,
            &SceneWords::new(&scene),
            Duration::from_millis(args.answer_timeout_ms),
            args.pace,
        )?;
    } else {
        real_time(&client, &recording)?;
    }
    // The last samples, unanswered yet, would go with this process.
    client.flush_inputs(super::CONTROL_TIMEOUT)?;
    Ok(())
}

fn real_time(client: &Client, recording: &Recording) -> anyhow::Result<()> {
    let start_ns = wall_clock_ns();
    let start = Instant::now();
    for (sent, recorded) in recording.samples.iter().enumerate() {
        if !wait_for_turn(client, start, sent, recorded)? {
            return Ok(());
        }
        client.send_input(&recorded.stamped(start_ns))?;
    }
    tracing::info!(sent = recording.samples.len(), "replay finished");
    Ok(())
}

/// Waits until `recorded` (the replay's sample number `sent`, from 0) is due: its recorded time
/// after `start`. False when the replay was told to stop meanwhile.
fn wait_for_turn(
    client: &Client,
    start: Instant,
    sent: usize,
    recorded: &RecordedSample,
) -> anyhow::Result<bool> {
    let due = Duration::try_from_secs_f64(recorded.time)
        .ok()
        .and_then(|offset| start.checked_add(offset))
        .with_context(|| format!("sample {sent}: time {} s is out of range", recorded.time))?;
    if client.sleep(due.saturating_duration_since(Instant::now())) == Wake::Terminated {
        tracing::info!(sent, "replay interrupted");
        return Ok(false);
    }
    Ok(true)
}

fn lockstep(
    client: &mut Client,
    recording: &Recording,
    words: &SceneWords,
    timeout: Duration,
    paced: bool,
) -> anyhow::Result<()> {
    let mut round_trips = Vec::with_capacity(recording.samples.len());
    let mut server_latencies = Vec::with_capacity(recording.samples.len());
    let mut unanswered = 0usize;
    let mut out = std::io::stdout().lock();
    // Paced, samples are stamped as in real time. Not paced, the stamps keep the recorded
    // spacing and end before the replay starts (`UNPACED_STAMPS_BEFORE`), so that they lie in
    // the past whatever pace the replay takes; this replay measures its own latencies from when
    // it sends.
    // The clock read before the instant: no paced sample is stamped later than it is sent.
    let start_ns = if paced {
        wall_clock_ns()
    } else {
        let before = recording.duration_ns() + UNPACED_STAMPS_BEFORE.as_nanos() as u64;
        wall_clock_ns().saturating_sub(before)
    };
    let start = Instant::now();
    for (sent, recorded) in recording.samples.iter().enumerate() {
        if paced && !wait_for_turn(client, start, sent, recorded)? {
            break;
        }
        let input = recorded.stamped(start_ns);
        let stamp = input.stamp();
        let sent_at = Instant::now();
        let sent_ns = wall_clock_ns();
        client.send_input(&input)?;
        let mut events = Vec::new();
        let answer = client.wait_for_hand_frame(
            timeout,
            |frame| input.is_answered_by(frame),
            |frame| {
                if let Frame::Event(_) = frame {
                    events.push(frame);
                }
            },
        )?;
        for event in &events {
            serde_json::to_writer(&mut out, &super::named::named(event, words)?)?;
            writeln!(out)?;
        }
        match answer {
            Some(frame) => {
                serde_json::to_writer(&mut out, &super::named::named(&Frame::Hand(frame), words)?)?;
                writeln!(out)?;
                round_trips.push(sent_at.elapsed());
                server_latencies.push(Duration::from_nanos(
                    frame.timestamp_ns.saturating_sub(sent_ns),
                ));
            }
            None => {
                // A server that went away answers nothing more: say so instead of waiting out
                // every remaining sample.
                if client.scene_info(super::CONTROL_TIMEOUT).is_err() {
                    anyhow::bail!(
                        "no vas server answers on this prefix any more; stopped at the \
                         recording's sample {} of {} (its stream's sample {})",
                        sent + 1,
                        recording.samples.len(),
                        stamp.seq
                    );
                }
                tracing::warn!(
                    sample = sent + 1,
                    seq = stamp.seq,
                    "no answer within the timeout"
                );
                unanswered += 1;
            }
        }
    }
    tracing::info!(
        sent = recording.samples.len(),
        answered = round_trips.len(),
        unanswered,
        round_trip = %summary(&round_trips),
        input_to_publish = %summary(&server_latencies),
        "lockstep replay finished"
    );
    out.flush()?;
    Ok(())
}

/// The latencies' nearest-rank summary, or "none".
fn summary(latencies: &[Duration]) -> String {
    LatencySummary::from_durations(latencies)
        .map_or_else(|_| "none".to_owned(), |summary| summary.to_string())
}
