//! `vas-bench soak`: feeds the server tracker and glove samples at a steady rate for a long
//! time, counts the samples no hand frame answered, and samples the server's resident memory
//! every second to show whether it grows.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail};
use serde::Serialize;
use vas_client::{Client, Frame, Wake};
use vas_protocol::{HandFrame, InputStamp, wall_clock_ns};

use vas_client::latency::LatencySummary;

use crate::args::{OutputArgs, ServerArgs};
use crate::process::status_kib;
use crate::report::{LinePlot, Series};
use crate::slope::least_squares_slope;
use crate::synthetic;

/// How often the server's memory is sampled.
const RSS_PERIOD: Duration = Duration::from_secs(1);

/// How long to wait after the last sample for the answers still on their way.
const DRAIN: Duration = Duration::from_secs(1);

/// The most samples per stream one run may send (1 kHz for five and a half hours): the soak
/// keeps a timestamp and an answered flag per sample.
const MAX_SAMPLES_PER_STREAM: u64 = 20_000_000;

/// How often the threads look at each other's progress while waiting.
const DRAIN_CHECK: Duration = Duration::from_millis(10);

/// Arguments of `vas-bench soak`.
#[derive(Debug, clap::Args)]
pub struct SoakArgs {
    /// Samples per second of each input stream (tracker and glove).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    rate: u64,
    /// How long to feed the server, in seconds.
    #[arg(long, default_value_t = 600, value_parser = clap::value_parser!(u64).range(1..=604_800))]
    seconds: u64,
    /// The server's process id: its resident memory (VmRSS) is read every second.
    #[arg(long)]
    server_pid: u32,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    server: ServerArgs,
}

/// Samples sent and answered in one input stream.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct StreamCount {
    /// Samples sent.
    pub sent: u64,
    /// Samples whose stamp came back in a hand frame.
    pub answered: u64,
    /// Samples without an answer of their own but followed by an answered one: the server keeps
    /// only the latest target of a stream, so a sample that a newer one replaced before a frame
    /// took it up is merged into that frame (its target still takes effect: the latest wins).
    /// Seen from the client, a sample lost on the way and then replaced looks the same, and has
    /// the same effect.
    pub superseded: u64,
    /// Samples without an answer that no answered sample followed: lost on the way (or
    /// rejected), or answered only by frames this client missed.
    pub dropped: u64,
}

/// The server's resident memory over the run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MemoryReport {
    /// At the start, in KiB.
    pub start_kib: u64,
    /// At the end, in KiB.
    pub end_kib: u64,
    /// The largest sample, in KiB.
    pub max_kib: u64,
    /// Slope of the least-squares line through the samples, in KiB per minute; `None` when the
    /// run was too short for a line.
    pub growth_kib_per_min: Option<f64>,
    /// Every sample: seconds since the start and KiB.
    pub samples: Vec<(f64, u64)>,
}

/// Everything `soak` reports.
#[derive(Debug, Clone, Serialize)]
pub struct SoakReport {
    /// Samples per second of each stream.
    pub rate_hz: u64,
    /// How long the run lasted, in seconds (shorter than asked when interrupted).
    pub elapsed_s: f64,
    /// Whether SIGINT or SIGTERM ended the run early.
    pub interrupted: bool,
    /// The tracker stream.
    pub tracker: StreamCount,
    /// The glove stream.
    pub glove: StreamCount,
    /// Samples of both streams without an answer that no answered sample followed.
    pub dropped: u64,
    /// Hand frames the server published but this client never read (gaps in the frame
    /// numbers): its buffer overflowed while it was descheduled. A sample whose only answer
    /// was such a frame counts as dropped although the server answered it.
    pub frames_missed_by_client: u64,
    /// From a sample's timestamp to the arrival of the first frame carrying it.
    pub latency: Option<LatencySummary>,
    /// How late after its due time each tick's samples were sent.
    pub pacing_lateness: LatencySummary,
    /// The server's resident memory.
    pub memory: MemoryReport,
}

/// Runs the soak against the server on `prefix`.
///
/// This thread paces and sends the samples (sleeping with nanosleep between ticks) and samples
/// the memory; a second thread, with its own connection, sleeps on its WaitSet for the hand
/// frames and marks the samples they answer, so that neither job delays the other.
pub fn run(args: &SoakArgs) -> anyhow::Result<()> {
    let prefix = args.server.prefix.as_deref();
    let ticks = args.rate * args.seconds;
    if ticks > MAX_SAMPLES_PER_STREAM {
        bail!(
            "--rate {} for --seconds {} is {ticks} samples per stream; at most \
             {MAX_SAMPLES_PER_STREAM} fit one run",
            args.rate,
            args.seconds
        );
    }
    let client = crate::args::connect(prefix)?;
    client
        .scene_info(crate::args::CONTROL_TIMEOUT)
        .context("no vas server answers on this prefix")?;
    let sent = SentStamps::new(ticks);
    let done = AtomicBool::new(false);
    let answered = AtomicU64::new(0);
    tracing::info!(
        rate = args.rate,
        seconds = args.seconds,
        pid = args.server_pid,
        "soaking"
    );
    let (pacing, answers) = std::thread::scope(|scope| {
        let (ready_tx, ready_rx) = mpsc::channel();
        let receiver = scope.spawn(|| receive_answers(prefix, &sent, &done, &answered, ready_tx));
        let pacing = match ready_rx.recv() {
            Ok(()) => pace(&client, args, &sent, &answered).map(Some),
            // The receiver failed to connect; its error is the one to report.
            Err(_) => Ok(None),
        };
        done.store(true, Ordering::Release);
        let answers = receiver
            .join()
            .map_err(|_| anyhow!("the receiving thread panicked"))?;
        anyhow::Ok((pacing?, answers?))
    })?;
    let pacing = pacing.context("the receiving thread ended before the run")?;

    let tracker = answers.tracker.count(pacing.ticks_sent);
    let glove = answers.glove.count(pacing.ticks_sent);
    let report = SoakReport {
        rate_hz: args.rate,
        elapsed_s: pacing.elapsed_s,
        interrupted: pacing.interrupted,
        tracker,
        glove,
        dropped: tracker.dropped + glove.dropped,
        frames_missed_by_client: answers.frames_missed,
        latency: LatencySummary::from_durations(&answers.latencies).ok(),
        pacing_lateness: LatencySummary::from_durations(&pacing.lateness)
            .context("the run ended before its first sample")?,
        memory: memory_report(pacing.memory),
    };
    print!("{}", render(&report));
    args.output.write(&report, || plot(&report))
}

/// What the pacing thread measured.
struct Pacing {
    /// Ticks whose two samples were sent.
    ticks_sent: u64,
    elapsed_s: f64,
    interrupted: bool,
    /// How late each tick was sent.
    lateness: Vec<Duration>,
    /// Seconds since the start and the server's resident KiB.
    memory: Vec<(f64, u64)>,
}

/// Sends a tracker and a glove sample every tick, samples the server's memory every second,
/// then waits (at most [`DRAIN`]) for the last answers.
fn pace(
    client: &Client,
    args: &SoakArgs,
    sent: &SentStamps,
    answered: &AtomicU64,
) -> anyhow::Result<Pacing> {
    let pid = args.server_pid;
    let ticks = sent.tracker.len() as u64;
    let tick_time = |tick: u64| Duration::from_nanos(tick * 1_000_000_000 / args.rate);
    let mut pacing = Pacing {
        ticks_sent: 0,
        elapsed_s: 0.0,
        interrupted: false,
        lateness: Vec::with_capacity(sent.tracker.len()),
        memory: vec![(0.0, status_kib(pid, "VmRSS")?)],
    };
    let start = Instant::now();
    let mut next_memory_sample = start + RSS_PERIOD;
    for tick in 0..ticks {
        let due = start + tick_time(tick);
        let early = due.saturating_duration_since(Instant::now());
        if !early.is_zero() && client.sleep(early) == Wake::Terminated {
            pacing.interrupted = true;
            break;
        }
        pacing.lateness.push(due.elapsed());
        let seq = tick + 1;
        let tracker = synthetic::tracker(seq);
        sent.record(&sent.tracker, seq, tracker.timestamp_ns);
        client.send_tracker(&tracker)?;
        let glove = synthetic::glove(seq);
        sent.record(&sent.glove, seq, glove.timestamp_ns);
        client.send_glove(&glove)?;
        pacing.ticks_sent = seq;
        if Instant::now() >= next_memory_sample {
            pacing
                .memory
                .push((start.elapsed().as_secs_f64(), status_kib(pid, "VmRSS")?));
            next_memory_sample += RSS_PERIOD;
        }
    }
    pacing.elapsed_s = start.elapsed().as_secs_f64();
    let drain_until = Instant::now() + DRAIN;
    while !pacing.interrupted
        && answered.load(Ordering::Acquire) < 2 * pacing.ticks_sent
        && Instant::now() < drain_until
    {
        if client.sleep(DRAIN_CHECK) == Wake::Terminated {
            break;
        }
    }
    pacing
        .memory
        .push((start.elapsed().as_secs_f64(), status_kib(pid, "VmRSS")?));
    Ok(pacing)
}

/// The receiving thread: connects, says it is ready, then marks the samples every hand frame
/// answers until `done`.
fn receive_answers(
    prefix: Option<&str>,
    sent: &SentStamps,
    done: &AtomicBool,
    answered: &AtomicU64,
    ready: mpsc::Sender<()>,
) -> anyhow::Result<Answers> {
    let mut client = crate::args::connect(prefix)?;
    let mut answers = Answers::new(sent.tracker.len());
    // The pacing thread may have ended already; then `done` ends this loop at once.
    let _ = ready.send(());
    while !done.load(Ordering::Acquire) {
        if client.wait(DRAIN_CHECK)? == Wake::Terminated {
            break;
        }
        for frame in client.receive()? {
            if let Frame::Hand(frame) = frame {
                answers.mark(&frame, sent, wall_clock_ns());
            }
        }
        answered.store(answers.answered(), Ordering::Release);
    }
    Ok(answers)
}

/// The summary of a memory series (at least one sample).
fn memory_report(samples: Vec<(f64, u64)>) -> MemoryReport {
    let per_minute: Vec<(f64, f64)> = samples
        .iter()
        .map(|&(seconds, kib)| (seconds / 60.0, kib as f64))
        .collect();
    MemoryReport {
        start_kib: samples.first().map_or(0, |sample| sample.1),
        end_kib: samples.last().map_or(0, |sample| sample.1),
        max_kib: samples.iter().map(|sample| sample.1).max().unwrap_or(0),
        growth_kib_per_min: least_squares_slope(&per_minute).ok(),
        samples,
    }
}

/// The figure: the server's resident memory over the run.
fn plot(report: &SoakReport) -> LinePlot {
    LinePlot {
        title: format!(
            "soak at {} Hz per stream: the server's memory",
            report.rate_hz
        ),
        x_label: "time (s)".into(),
        y_label: "resident memory (MiB)".into(),
        log_x: false,
        log_y: false,
        series: vec![Series {
            name: "resident memory".into(),
            points: report
                .memory
                .samples
                .iter()
                .map(|&(seconds, kib)| (seconds, kib as f64 / 1024.0))
                .collect(),
        }],
    }
}

/// The results as text.
fn render(report: &SoakReport) -> String {
    let memory = &report.memory;
    let stream = |name: &str, count: &StreamCount| {
        format!(
            "{name:<7}  sent {:>9}  answered {:>9}  superseded {:>7}  dropped {:>7}\n",
            count.sent, count.answered, count.superseded, count.dropped
        )
    };
    let latency = report
        .latency
        .map_or_else(|| "none".to_owned(), |latency| latency.to_string());
    let growth = memory
        .growth_kib_per_min
        .map_or_else(|| "n/a".to_owned(), |slope| format!("{slope:.1}"));
    format!(
        "soak at {} Hz per stream for {:.1} s{}\n{}{}\
         hand frames missed by this client {}\n\
         latency         {latency}\n\
         pacing lateness {}\n\
         server RSS      start {} KiB, end {} KiB, max {} KiB, growth {growth} KiB/min\n",
        report.rate_hz,
        report.elapsed_s,
        if report.interrupted {
            " (interrupted)"
        } else {
            ""
        },
        stream("tracker", &report.tracker),
        stream("glove", &report.glove),
        report.frames_missed_by_client,
        report.pacing_lateness,
        memory.start_kib,
        memory.end_kib,
        memory.max_kib,
    )
}

/// The timestamp of every sample the pacing thread sent (index `seq - 1`; 0 until sent), so
/// that the receiving thread recognises this run's samples in the frames.
struct SentStamps {
    tracker: Vec<AtomicU64>,
    glove: Vec<AtomicU64>,
}

impl SentStamps {
    fn new(per_stream: u64) -> Self {
        let stamps = || (0..per_stream).map(|_| AtomicU64::new(0)).collect();
        Self {
            tracker: stamps(),
            glove: stamps(),
        }
    }

    /// Notes sample `seq` (from 1) of `stream` before it is sent.
    fn record(&self, stream: &[AtomicU64], seq: u64, timestamp_ns: u64) {
        if let Some(slot) = index_of(seq).and_then(|index| stream.get(index)) {
            slot.store(timestamp_ns, Ordering::Release);
        }
    }
}

/// The index of sample `seq` (numbered from 1).
fn index_of(seq: u64) -> Option<usize> {
    usize::try_from(seq).ok()?.checked_sub(1)
}

/// Which samples of the two streams have been answered, and how fast.
struct Answers {
    tracker: AnswerBook,
    glove: AnswerBook,
    /// From each answered sample's timestamp to the arrival of its answer.
    latencies: Vec<Duration>,
    /// The number of the last hand frame received.
    last_frame: Option<u64>,
    /// Hand frames skipped in the numbering: published, but lost before this client read them.
    frames_missed: u64,
}

impl Answers {
    fn new(per_stream: usize) -> Self {
        Self {
            tracker: AnswerBook::new(per_stream),
            glove: AnswerBook::new(per_stream),
            latencies: Vec::new(),
            last_frame: None,
            frames_missed: 0,
        }
    }

    /// Marks the samples whose stamps `frame` carries, as received at `now_ns`, and counts the
    /// frames missed since the previous one.
    fn mark(&mut self, frame: &HandFrame, sent: &SentStamps, now_ns: u64) {
        if let Some(last) = self.last_frame {
            self.frames_missed += frame.frame.saturating_sub(last + 1);
        }
        self.last_frame = Some(frame.frame);
        for (book, stream, stamp) in [
            (&mut self.tracker, &sent.tracker, frame.tracker),
            (&mut self.glove, &sent.glove, frame.glove),
        ] {
            if book.answer(stamp, stream) {
                self.latencies.push(Duration::from_nanos(
                    now_ns.saturating_sub(stamp.timestamp_ns),
                ));
            }
        }
    }

    /// Samples of both streams answered so far.
    fn answered(&self) -> u64 {
        self.tracker.answered_count + self.glove.answered_count
    }
}

/// Which samples of one stream were answered.
struct AnswerBook {
    answered: Vec<bool>,
    answered_count: u64,
}

impl AnswerBook {
    fn new(samples: usize) -> Self {
        Self {
            answered: vec![false; samples],
            answered_count: 0,
        }
    }

    /// Marks the sample `stamp` names as answered; true the first time. Stamps of samples not
    /// in `sent` (another sender's, or none yet) are ignored.
    fn answer(&mut self, stamp: InputStamp, sent: &[AtomicU64]) -> bool {
        let Some(index) = index_of(stamp.seq) else {
            return false;
        };
        let ours = sent
            .get(index)
            .is_some_and(|sent| sent.load(Ordering::Acquire) == stamp.timestamp_ns);
        if !ours || self.answered[index] {
            return false;
        }
        self.answered[index] = true;
        self.answered_count += 1;
        true
    }

    /// The counts once `sent` samples were sent.
    fn count(&self, sent: u64) -> StreamCount {
        let sent_flags = &self.answered[..(sent as usize).min(self.answered.len())];
        // The unanswered samples after the last answered one.
        let trailing = sent_flags
            .iter()
            .rev()
            .take_while(|&&answered| !answered)
            .count() as u64;
        let unanswered = sent.saturating_sub(self.answered_count);
        StreamCount {
            sent,
            answered: self.answered_count,
            superseded: unanswered.saturating_sub(trailing),
            dropped: trailing.min(unanswered),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamp(seq: u64, timestamp_ns: u64) -> InputStamp {
        InputStamp { seq, timestamp_ns }
    }

    #[test]
    fn each_sample_is_answered_once_and_only_with_its_own_stamp() {
        let sent = SentStamps::new(5);
        for seq in 1..=4 {
            sent.record(&sent.tracker, seq, 100 + seq);
        }
        let mut book = AnswerBook::new(5);
        assert!(book.answer(stamp(2, 102), &sent.tracker));
        assert!(!book.answer(stamp(2, 102), &sent.tracker), "a second frame");
        assert!(
            !book.answer(stamp(3, 999), &sent.tracker),
            "another sender's 3"
        );
        assert!(!book.answer(stamp(0, 0), &sent.tracker), "no sample yet");
        assert!(!book.answer(stamp(5, 105), &sent.tracker), "not sent yet");
        assert!(!book.answer(stamp(9, 109), &sent.tracker), "beyond the run");
        assert!(book.answer(stamp(4, 104), &sent.tracker));
        // 1 and 3 were followed by answered samples.
        assert_eq!(
            book.count(4),
            StreamCount {
                sent: 4,
                answered: 2,
                superseded: 2,
                dropped: 0
            }
        );
        // 5 was sent but never answered, nor anything after it.
        sent.record(&sent.tracker, 5, 105);
        assert_eq!(
            book.count(5),
            StreamCount {
                sent: 5,
                answered: 2,
                superseded: 2,
                dropped: 1
            }
        );
    }

    #[test]
    fn a_frame_answers_the_samples_of_both_streams_it_carries() {
        let sent = SentStamps::new(2);
        sent.record(&sent.tracker, 1, 1_000);
        sent.record(&sent.glove, 1, 1_500);
        let mut answers = Answers::new(2);
        let frame = HandFrame {
            frame: 1,
            tracker: stamp(1, 1_000),
            glove: stamp(1, 1_500),
            ..HandFrame::default()
        };
        answers.mark(&frame, &sent, 3_000);
        let later = HandFrame { frame: 4, ..frame };
        answers.mark(&later, &sent, 9_000);
        assert_eq!(answers.answered(), 2);
        assert_eq!(answers.frames_missed, 2, "frames 2 and 3");
        assert_eq!(
            answers.latencies,
            [Duration::from_nanos(2_000), Duration::from_nanos(1_500)]
        );
    }

    #[test]
    fn memory_growth_is_the_slope_per_minute() {
        // 60 KiB more every 30 s: 120 KiB per minute.
        let samples: Vec<(f64, u64)> = (0..11).map(|i| (30.0 * i as f64, 5_000 + 60 * i)).collect();
        let report = memory_report(samples);
        assert_eq!(report.start_kib, 5_000);
        assert_eq!(report.end_kib, 5_600);
        assert_eq!(report.max_kib, 5_600);
        let growth = report.growth_kib_per_min.expect("a line");
        assert!((growth - 120.0).abs() < 1e-9, "growth {growth}");
        assert_eq!(memory_report(vec![(0.0, 7)]).growth_kib_per_min, None);
    }
}
