//! `vas-bench e2e`, benchmark B7: the latency from an input sample published by this
//! process to the hand frame that answers it, beside the bare iceoryx2 round trip measured in
//! the same run (and, with `--c-library`, that round trip through the C library).
//!
//! Both paths use the same client code: send a sample, then sleep on the client's WaitSet until
//! the hand frame carrying the sample's stamp arrives. The `vas` path goes through the server;
//! the `raw` path through an echo process ([`crate::echo`]) that this command starts on a private
//! prefix, which opens the same services and answers every tracker sample at once. The `c` path
//! ([`crate::c_library`]) sends the `raw` path's samples to the same echo through the C
//! library's calls. The paths alternate sample by sample, so that all see the same machine
//! load. The first `--warmup` exchanges of each path (page faults, connection set-up, cold
//! caches) are left out of the figures.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use serde::Serialize;

use crate::args::{OutputArgs, ServerArgs};
use crate::report::{LinePlot, Series};
use vas_client::recording::{InputSample, Recording};
use vas_client::{Client, Frame, Wake};
use vas_protocol::services::remove_prefix_segment;
use vas_protocol::wall_clock_ns;

use crate::c_library::CLibraryClient;
use crate::echo::READY_LINE;
use crate::process::stop_child;
use crate::synthetic;
use vas_client::latency::LatencySummary;
use vas_server::scene::Scene;
use vas_testkit::fixtures;
use vas_testkit::script::shove;

/// Arguments of `vas-bench e2e`.
#[derive(Debug, clap::Args)]
pub struct E2eArgs {
    /// Measured exchanges per path, after the warm-up.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(1..))]
    samples: u64,
    /// Exchanges per path before measuring, left out of the figures.
    #[arg(long, default_value_t = 200)]
    warmup: u64,
    /// Send this recording's samples (in order, repeated as needed) instead of the synthetic
    /// tracker stream; each is renumbered and stamped when sent.
    #[arg(long, conflicts_with = "hand_joints")]
    recording: Option<PathBuf>,
    /// Send violent shoves of the held peg against its block instead, made for this scene
    /// config (a `peg` and a `block`, as the peg insert scenes; the server must run the same
    /// scene): a power grasp, the peg lowered into the hole, then random shoves of up to 15 cm
    /// and 25 degrees. The grasp before the first shove is left out with the warm-up.
    #[arg(long, conflicts_with_all = ["hand_joints", "recording"])]
    shove: Option<PathBuf>,
    /// The seed of `--shove`'s shoves.
    #[arg(long, default_value_t = 1, requires = "shove")]
    shove_seed: u64,
    /// Send two hands' joints instead (the captured relaxed hand, right and left by turns,
    /// drifting in free space), on both paths; the server's scene needs both hands.
    #[arg(long)]
    hand_joints: bool,
    /// Measure the `c` path as well: the `raw` path's round trip through the C library's calls
    /// (send, wait, poll, read the hand frames), against the same echo.
    #[arg(long)]
    c_library: bool,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    server: ServerArgs,
    /// How long to wait for each answer before counting the sample unanswered, in ms.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=crate::args::MAX_TIMEOUT_MS))]
    answer_timeout_ms: u64,
}

/// One row of the results: the latency of one path.
#[derive(Debug, Clone, Serialize)]
pub struct PathRow {
    /// `raw`, `c` or `vas`.
    pub path: &'static str,
    /// Latency summary of the measured exchanges.
    #[serde(flatten)]
    pub latency: LatencySummary,
    /// Samples that got no answer within the timeout (after the warm-up).
    pub unanswered: u64,
}

/// The round trips of one path, as they are measured.
#[derive(Default)]
struct PathTimes {
    latencies: Vec<Duration>,
    unanswered: u64,
}

impl PathTimes {
    /// Records one exchange's outcome, if it is `measured` (not in the warm-up).
    fn record(&mut self, measured: bool, round_trip: Option<Duration>) {
        match round_trip {
            Some(latency) if measured => self.latencies.push(latency),
            None if measured => self.unanswered += 1,
            _ => {}
        }
    }

    /// The row of the path named `path`.
    fn row(&self, path: &'static str) -> anyhow::Result<PathRow> {
        let latency = LatencySummary::from_durations(&self.latencies)
            .with_context(|| format!("no {path} sample was answered"))?;
        let unanswered = self.unanswered;
        Ok(PathRow {
            path,
            latency,
            unanswered,
        })
    }
}

/// Everything `vas-bench e2e` reports.
#[derive(Debug, Clone, Serialize)]
pub struct E2eReport {
    /// The server's scene.
    pub scene: String,
    /// What was sent: `synthetic tracker`, `synthetic hand joints, two hands`, the recording's
    /// path or `shoves, seed N`.
    pub input: String,
    /// Exchanges per path left out before measuring.
    pub warmup: u64,
    /// The `raw`, `c` (with `--c-library`) and `vas` rows.
    pub rows: Vec<PathRow>,
    /// With `--c-library`: how much the C library adds to the round trip at the 99th
    /// percentile, the `c` row's p99 less the `raw` row's, in microseconds.
    pub c_library_p99_added_us: Option<f64>,
    /// Samples per second the server answers when each sample is sent as soon as the previous
    /// one is answered: measured `vas` exchanges divided by their total time.
    pub vas_samples_per_s: f64,
    /// With `--shove`: how many measured samples' answers found the peg held.
    pub held_samples: Option<usize>,
}

/// Runs the benchmark against the server on `prefix`.
pub fn run(args: &E2eArgs) -> anyhow::Result<()> {
    let prefix = args.server.prefix.as_deref();
    let mut warmup = args.warmup;
    let (inputs, input) = match (&args.recording, &args.shove) {
        (Some(path), _) => (InputStream::recording(path)?, path.display().to_string()),
        (None, Some(scene)) => {
            let (samples, lead_in) =
                shove_samples(scene, args.shove_seed, args.warmup + args.samples)?;
            warmup = warmup.max(lead_in);
            let input = format!("shoves, seed {}", args.shove_seed);
            (InputStream::Recording(samples), input)
        }
        (None, None) if args.hand_joints => (
            InputStream::HandJoints,
            "synthetic hand joints, two hands".to_owned(),
        ),
        (None, None) => (InputStream::Synthetic, "synthetic tracker".to_owned()),
    };
    let mut server = crate::args::connect(prefix)?;
    let scene = server
        .scene_info(crate::args::CONTROL_TIMEOUT)
        .context("no vas server answers on this prefix")?
        .name;
    let echo_prefix = format!("{}raw{}_", prefix.unwrap_or("vas_"), std::process::id());
    let _echo = EchoProcess::spawn(&echo_prefix)?;
    let mut echo = crate::args::connect(Some(&echo_prefix))?;
    let mut c_echo = (args.c_library)
        .then(|| CLibraryClient::connect(&echo_prefix))
        .transpose()?;
    tracing::info!(
        scene,
        samples = args.samples,
        warmup,
        "measuring the raw and vas round trips"
    );

    let timeout = Duration::from_millis(args.answer_timeout_ms);
    let [mut raw, mut c, mut vas]: [PathTimes; 3] = Default::default();
    // Measured samples whose answer found a part held: shoves of an empty hand measure nothing.
    let mut held = 0usize;
    let mut inputs = inputs.numbered();
    for index in 0..warmup + args.samples {
        let measured = index >= warmup;
        let sample = inputs.raw_sample(index + 1);
        // The raw and c paths take turns at going first, so that neither alone follows the
        // server's exchange, whose work may still be settling.
        let c_first = index % 2 == 1;
        for c_turn in [c_first, !c_first] {
            match &mut c_echo {
                Some(c_echo) if c_turn => c.record(measured, c_echo.round_trip(sample, timeout)?),
                _ if !c_turn => raw.record(measured, round_trip(&mut echo, sample, timeout, drop)?),
                _ => {}
            }
        }
        let sample = inputs.next_sample();
        let mut holds = false;
        let note_held = |frame: Frame| {
            if let Frame::Parts(parts) = frame {
                holds = parts.parts.iter().any(|part| part.is_grasped());
            }
        };
        vas.record(
            measured,
            round_trip(&mut server, sample, timeout, note_held)?,
        );
        held += usize::from(measured && holds);
    }
    if args.shove.is_some() && held == 0 {
        bail!(
            "the peg was never held while shoved: the grasp before the shoves failed on the \
             server's scene (is its tracking filter on? It makes the scripted hand trail its glove)"
        );
    }
    // The C library's client goes before the echo's prefix is removed.
    drop(c_echo);

    let raw_row = raw.row("raw")?;
    let c_row = (args.c_library).then(|| c.row("c")).transpose()?;
    let c_library_p99_added_us =
        (c_row.as_ref()).map(|c| c.latency.p99_us - raw_row.latency.p99_us);
    let rows = [Some(raw_row), c_row, Some(vas.row("vas")?)];
    let report = E2eReport {
        scene,
        input,
        warmup,
        vas_samples_per_s: vas.latencies.len() as f64
            / vas.latencies.iter().sum::<Duration>().as_secs_f64(),
        rows: rows.into_iter().flatten().collect(),
        c_library_p99_added_us,
        held_samples: args.shove.is_some().then_some(held),
    };
    print!("{}", render(&report));
    args.output.write(&report, || plot(&report))
}

/// The figure: each path's latency at the median, the 99th percentile and the maximum.
fn plot(report: &E2eReport) -> LinePlot {
    LinePlot {
        title: format!("B7: input to answer, {} ({})", report.scene, report.input),
        x_label: "percentile".into(),
        y_label: "latency (us)".into(),
        log_x: false,
        log_y: true,
        series: report
            .rows
            .iter()
            .map(|row| Series {
                name: row.path.into(),
                points: vec![
                    (50.0, row.latency.p50_us),
                    (99.0, row.latency.p99_us),
                    (100.0, row.latency.max_us),
                ],
            })
            .collect(),
    }
}

/// The shoves of `--shove` for the scene config at `path`, at least `count` samples of them
/// after the grasp, and how many samples the grasp before the first shove takes.
fn shove_samples(path: &Path, seed: u64, count: u64) -> anyhow::Result<(Vec<InputSample>, u64)> {
    let scene = Scene::load(path)?;
    let part = |name: &str| {
        scene
            .parts
            .iter()
            .find(|part| part.name == name)
            .with_context(|| format!("{}: no part named {name}", path.display()))
    };
    // One tracker and one glove sample per tick.
    let samples_per_second = 2.0 * fixtures::RATE_HZ;
    let per_shove = (samples_per_second * shove::PERIOD).round() as u64;
    let count = usize::try_from(count.div_ceil(per_shove)).context("too many samples")?;
    let shoves = shove::shoves(part("peg")?, part("block")?, seed, count);
    let lead_in = (shoves.first_shove * samples_per_second).round() as u64;
    Ok((fixtures::input_samples(&shoves.keys), lead_in))
}

/// Sends `input` stamped now and waits for the hand frame answering it; its round trip, or
/// `None` if none came within `timeout`. Every other frame received meanwhile goes to `others`
/// (`drop` ignores them). SIGINT or SIGTERM ends the benchmark.
pub fn round_trip(
    client: &mut Client,
    input: InputSample,
    timeout: Duration,
    others: impl FnMut(Frame),
) -> anyhow::Result<Option<Duration>> {
    let input = input.with_timestamp(wall_clock_ns());
    let sent_at = Instant::now();
    client.send_input(&input)?;
    let answer =
        client.wait_for_hand_frame(timeout, |frame| input.is_answered_by(frame), others)?;
    let round_trip = sent_at.elapsed();
    if answer.is_none() && client.sleep(Duration::ZERO) == Wake::Terminated {
        bail!("interrupted");
    }
    Ok(answer.map(|_| round_trip))
}

/// The results as a table.
fn render(report: &E2eReport) -> String {
    let mut text = format!(
        "B7 end to end ({}, scene {}, {} warm-up exchanges left out)\n\
         path    p50_us    p99_us    max_us  samples  unanswered\n",
        report.input, report.scene, report.warmup
    );
    for row in &report.rows {
        let latency = &row.latency;
        text += &format!(
            "{:<4}  {:>8.1}  {:>8.1}  {:>8.1}  {:>7}  {:>10}\n",
            row.path,
            latency.p50_us,
            latency.p99_us,
            latency.max_us,
            latency.samples,
            row.unanswered
        );
    }
    if let Some(added) = report.c_library_p99_added_us {
        text += &format!("c p99 - raw p99 = {added:.1} us (what the C library adds)\n");
    }
    if let Some(held) = report.held_samples {
        text += &format!("the peg held in {held} of the measured samples' answers\n");
    }
    text += &format!(
        "vas sustains {:.0} samples/s, each sent once the one before was answered\n",
        report.vas_samples_per_s
    );
    text
}

/// Where the `vas` path's samples come from.
enum InputStream {
    /// [`synthetic::tracker`].
    Synthetic,
    /// [`synthetic::hand_joints`]: two hands by turns.
    HandJoints,
    /// A recording's samples, in order, repeated.
    Recording(Vec<InputSample>),
}

impl InputStream {
    fn recording(path: &Path) -> anyhow::Result<Self> {
        let recording = Recording::load(path)?;
        if recording.samples.is_empty() {
            bail!("{}: the recording has no samples", path.display());
        }
        Ok(Self::Recording(
            recording
                .samples
                .iter()
                .map(|sample| sample.input)
                .collect(),
        ))
    }

    /// The stream with fresh sequence numbers: from 1 in each input stream.
    fn numbered(self) -> NumberedInputs {
        NumberedInputs {
            stream: self,
            sent: 0,
            tracker_seq: 0,
            glove_seq: 0,
            joints_seq: 0,
        }
    }
}

/// An [`InputStream`] renumbered per input stream as it is sent.
struct NumberedInputs {
    stream: InputStream,
    sent: usize,
    tracker_seq: u64,
    glove_seq: u64,
    joints_seq: u64,
}

impl NumberedInputs {
    /// Sample `seq` of the raw path: the synthetic stream of the same kind as the `vas`
    /// path's (a recording's, the tracker's).
    fn raw_sample(&self, seq: u64) -> InputSample {
        match self.stream {
            InputStream::HandJoints => InputSample::HandJoints(synthetic::hand_joints(seq)),
            InputStream::Synthetic | InputStream::Recording(_) => {
                InputSample::Tracker(synthetic::tracker(seq))
            }
        }
    }

    fn next_sample(&mut self) -> InputSample {
        let recorded = match &self.stream {
            InputStream::Synthetic => None,
            InputStream::HandJoints => {
                self.joints_seq += 1;
                return InputSample::HandJoints(synthetic::hand_joints(self.joints_seq));
            }
            InputStream::Recording(samples) => Some(samples[self.sent % samples.len()]),
        };
        self.sent += 1;
        match recorded {
            None => {
                self.tracker_seq += 1;
                InputSample::Tracker(synthetic::tracker(self.tracker_seq))
            }
            Some(InputSample::Tracker(mut sample)) => {
                self.tracker_seq += 1;
                sample.seq = self.tracker_seq;
                InputSample::Tracker(sample)
            }
            Some(InputSample::Glove(mut sample)) => {
                self.glove_seq += 1;
                sample.seq = self.glove_seq;
                InputSample::Glove(sample)
            }
            Some(InputSample::HandJoints(mut sample)) => {
                self.joints_seq += 1;
                sample.seq = self.joints_seq;
                InputSample::HandJoints(sample)
            }
        }
    }
}

/// The echo child process; stopped with SIGTERM (by its pid) when dropped, and its private
/// prefix then removed from shared memory (drop this process's client on it first).
struct EchoProcess {
    child: Child,
    prefix: String,
}

impl EchoProcess {
    /// How long a stopped echo may take to exit before it is killed.
    const EXIT_PATIENCE: Duration = Duration::from_secs(2);

    /// Starts `vas-bench echo` on `prefix` and waits until it is ready.
    fn spawn(prefix: &str) -> anyhow::Result<Self> {
        let exe = std::env::current_exe().context("locating the vas-client executable")?;
        let child = Command::new(&exe)
            .args(["echo", "--prefix", prefix])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .with_context(|| format!("starting {} echo", exe.display()))?;
        let mut echo = Self {
            child,
            prefix: prefix.to_owned(),
        };
        let stdout = echo.child.stdout.take().context("the echo's stdout")?;
        let mut line = String::new();
        BufReader::new(stdout)
            .read_line(&mut line)
            .context("reading the echo's readiness")?;
        if line.trim_end() != READY_LINE {
            bail!("the echo process did not start (it said {line:?})");
        }
        tracing::debug!(pid = echo.child.id(), prefix, "echo ready");
        Ok(echo)
    }
}

impl Drop for EchoProcess {
    fn drop(&mut self) {
        stop_child(&mut self.child, libc::SIGTERM, Self::EXIT_PATIENCE, "echo");
        // SAFETY: the echo has ended (killed if SIGTERM did not end it), and the
        // client on its prefix is dropped before it (declared after it in `run`).
        if let Err(error) = unsafe { remove_prefix_segment(&self.prefix) } {
            tracing::warn!(%error, "the echo's prefix stays in shared memory");
        }
    }
}
