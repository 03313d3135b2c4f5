//! `vas-client soak`: feeds the server tracker and glove samples at a steady rate for a long
//! time, counts the samples no hand frame answered, and samples the server's resident memory
//! every second to show whether it grows.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;
use serde::Serialize;
use vas_client::{Client, Frame, Wake};
use vas_protocol::{HandFrame, InputStamp, wall_clock_ns};

use super::stats::{LatencySummary, least_squares_slope};
use super::synthetic;

/// How often the server's memory is sampled.
const RSS_PERIOD: Duration = Duration::from_secs(1);

/// How long to wait after the last sample for the answers still on their way.
const DRAIN: Duration = Duration::from_secs(1);

/// Arguments of `vas-client soak`.
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
    /// Write the results as JSON to this file.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Samples sent and answered in one input stream.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct StreamCount {
    /// Samples sent.
    pub sent: u64,
    /// Samples whose stamp came back in a hand frame.
    pub answered: u64,
    /// Samples whose stamp never came back: dropped (or rejected) on the way.
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
    /// Samples of both streams without an answer.
    pub dropped: u64,
    /// From a sample's timestamp to the arrival of the first frame carrying it.
    pub latency: Option<LatencySummary>,
    /// How late after its due time each tick's samples were sent.
    pub pacing_lateness: LatencySummary,
    /// The server's resident memory.
    pub memory: MemoryReport,
}

/// Runs the soak against the server on `prefix`.
pub fn run(prefix: Option<&str>, args: &SoakArgs) -> anyhow::Result<()> {
    let mut client = super::connect(prefix)?;
    client
        .scene_info(super::CONTROL_TIMEOUT)
        .context("no vas server answers on this prefix")?;
    let pid = args.server_pid;
    let ticks = args.rate * args.seconds;
    let tick_time = |tick: u64| Duration::from_nanos(tick * 1_000_000_000 / args.rate);
    tracing::info!(rate = args.rate, seconds = args.seconds, pid, "soaking");

    let mut answers = Answers::with_capacity(ticks);
    let mut lateness = Vec::with_capacity(usize::try_from(ticks).unwrap_or_default());
    let start = Instant::now();
    let mut memory = vec![(0.0, resident_kib(pid)?)];
    let mut next_memory_sample = start + RSS_PERIOD;
    let mut interrupted = false;
    'ticks: for tick in 0..ticks {
        let due = start + tick_time(tick);
        loop {
            answers.take_frames(&mut client)?;
            let now = Instant::now();
            if now >= next_memory_sample {
                memory.push((start.elapsed().as_secs_f64(), resident_kib(pid)?));
                next_memory_sample += RSS_PERIOD;
            }
            if now >= due {
                break;
            }
            let nap = (due - now).min(next_memory_sample.saturating_duration_since(now));
            if client.wait(nap)? == Wake::Terminated {
                interrupted = true;
                break 'ticks;
            }
        }
        lateness.push(due.elapsed());
        let seq = tick + 1;
        let tracker = synthetic::tracker(seq);
        client.send_tracker(&tracker)?;
        answers
            .tracker
            .sent(stamp(tracker.seq, tracker.timestamp_ns));
        let glove = synthetic::glove(seq);
        client.send_glove(&glove)?;
        answers.glove.sent(stamp(glove.seq, glove.timestamp_ns));
    }
    let elapsed_s = start.elapsed().as_secs_f64();
    let drain_until = Instant::now() + DRAIN;
    while !interrupted && !answers.all_answered() {
        let remaining = drain_until.saturating_duration_since(Instant::now());
        if remaining.is_zero() || client.wait(remaining)? != Wake::Ready {
            break;
        }
        answers.take_frames(&mut client)?;
    }
    memory.push((start.elapsed().as_secs_f64(), resident_kib(pid)?));

    let (tracker, glove) = (answers.tracker.count(), answers.glove.count());
    let report = SoakReport {
        rate_hz: args.rate,
        elapsed_s,
        interrupted,
        tracker,
        glove,
        dropped: tracker.dropped + glove.dropped,
        latency: LatencySummary::from_durations(&answers.latencies).ok(),
        pacing_lateness: LatencySummary::from_durations(&lateness)
            .context("the run ended before its first sample")?,
        memory: memory_report(memory),
    };
    print!("{}", render(&report));
    if let Some(out) = &args.out {
        super::write_json(out, &report)?;
    }
    Ok(())
}

fn stamp(seq: u64, timestamp_ns: u64) -> InputStamp {
    InputStamp { seq, timestamp_ns }
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

/// The results as text.
fn render(report: &SoakReport) -> String {
    let memory = &report.memory;
    let stream = |name: &str, count: &StreamCount| {
        format!(
            "{name:<7}  sent {:>9}  answered {:>9}  dropped {:>7}\n",
            count.sent, count.answered, count.dropped
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
        report.pacing_lateness,
        memory.start_kib,
        memory.end_kib,
        memory.max_kib,
    )
}

/// Which samples of the two streams have been answered, and how fast.
struct Answers {
    tracker: AnswerBook,
    glove: AnswerBook,
    /// From each answered sample's timestamp to the arrival of its answer.
    latencies: Vec<Duration>,
}

impl Answers {
    fn with_capacity(per_stream: u64) -> Self {
        Self {
            tracker: AnswerBook::with_capacity(per_stream),
            glove: AnswerBook::with_capacity(per_stream),
            latencies: Vec::new(),
        }
    }

    /// Receives every queued frame and marks the samples its stamps answer.
    fn take_frames(&mut self, client: &mut Client) -> anyhow::Result<()> {
        for frame in client.receive()? {
            if let Frame::Hand(frame) = frame {
                self.mark(&frame, wall_clock_ns());
            }
        }
        Ok(())
    }

    fn mark(&mut self, frame: &HandFrame, now_ns: u64) {
        for (book, stamp) in [
            (&mut self.tracker, frame.tracker),
            (&mut self.glove, frame.glove),
        ] {
            if book.answer(stamp) {
                self.latencies.push(Duration::from_nanos(
                    now_ns.saturating_sub(stamp.timestamp_ns),
                ));
            }
        }
    }

    fn all_answered(&self) -> bool {
        self.tracker.count().dropped == 0 && self.glove.count().dropped == 0
    }
}

/// The samples sent in one stream (numbered from 1) and which of them were answered.
#[derive(Debug, Default)]
struct AnswerBook {
    /// Timestamp of sample `seq` at index `seq - 1`.
    sent_timestamps: Vec<u64>,
    answered: Vec<bool>,
    answered_count: u64,
}

impl AnswerBook {
    fn with_capacity(samples: u64) -> Self {
        let capacity = usize::try_from(samples).unwrap_or_default();
        Self {
            sent_timestamps: Vec::with_capacity(capacity),
            answered: Vec::with_capacity(capacity),
            answered_count: 0,
        }
    }

    /// Notes the next sample sent; its sequence number must follow the previous one.
    fn sent(&mut self, stamp: InputStamp) {
        debug_assert_eq!(stamp.seq, self.sent_timestamps.len() as u64 + 1);
        self.sent_timestamps.push(stamp.timestamp_ns);
        self.answered.push(false);
    }

    /// Marks the sample `stamp` names as answered; true the first time. Stamps of samples this
    /// book did not send (another sender's, or none yet) are ignored.
    fn answer(&mut self, stamp: InputStamp) -> bool {
        let Some(index) = usize::try_from(stamp.seq)
            .ok()
            .and_then(|seq| seq.checked_sub(1))
        else {
            return false;
        };
        let ours = self.sent_timestamps.get(index) == Some(&stamp.timestamp_ns);
        if !ours || self.answered[index] {
            return false;
        }
        self.answered[index] = true;
        self.answered_count += 1;
        true
    }

    fn count(&self) -> StreamCount {
        let sent = self.sent_timestamps.len() as u64;
        StreamCount {
            sent,
            answered: self.answered_count,
            dropped: sent - self.answered_count,
        }
    }
}

/// The resident memory of process `pid` in KiB, from `/proc/<pid>/status`.
fn resident_kib(pid: u32) -> anyhow::Result<u64> {
    let path = format!("/proc/{pid}/status");
    let status = std::fs::read_to_string(&path)
        .with_context(|| format!("reading {path}: is process {pid} (the server) running?"))?;
    parse_vm_rss(&status).with_context(|| format!("{path} has no readable VmRSS line"))
}

/// The `VmRSS` value of a `/proc/<pid>/status` text, in KiB.
fn parse_vm_rss(status: &str) -> Option<u64> {
    let line = status
        .lines()
        .find_map(|line| line.strip_prefix("VmRSS:"))?;
    let mut fields = line.split_whitespace();
    let kib = fields.next()?.parse().ok()?;
    (fields.next() == Some("kB")).then_some(kib)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_resident_set_is_read_from_a_status_text() {
        let status = "Name:\tvas-server\nVmPeak:\t  900 kB\nVmRSS:\t   12345 kB\nThreads:\t4\n";
        assert_eq!(parse_vm_rss(status), Some(12345));
        assert_eq!(parse_vm_rss("Name:\tx\n"), None);
        assert_eq!(parse_vm_rss("VmRSS:\tlots kB\n"), None);
        assert_eq!(parse_vm_rss("VmRSS:\t12 MB\n"), None);
    }

    #[test]
    fn this_process_has_resident_memory() {
        let kib = resident_kib(std::process::id()).expect("our own status");
        assert!(kib > 0);
    }

    #[test]
    fn a_missing_process_is_a_clear_error() {
        // Process ids are below 2^22 on Linux.
        let error = resident_kib(u32::MAX).expect_err("no such process");
        assert!(error.to_string().contains("is process"), "{error}");
    }

    #[test]
    fn each_sample_is_answered_once_and_only_with_its_own_stamp() {
        let mut book = AnswerBook::default();
        for seq in 1..=4 {
            book.sent(stamp(seq, 100 + seq));
        }
        assert!(book.answer(stamp(2, 102)));
        assert!(!book.answer(stamp(2, 102)), "a second frame with the stamp");
        assert!(!book.answer(stamp(3, 999)), "another sender's sample 3");
        assert!(!book.answer(stamp(0, 0)), "no sample yet");
        assert!(!book.answer(stamp(9, 109)), "never sent");
        assert!(book.answer(stamp(4, 104)));
        assert_eq!(
            book.count(),
            StreamCount {
                sent: 4,
                answered: 2,
                dropped: 2
            }
        );
    }

    #[test]
    fn a_frame_answers_the_samples_of_both_streams_it_carries() {
        let mut answers = Answers::with_capacity(2);
        answers.tracker.sent(stamp(1, 1_000));
        answers.glove.sent(stamp(1, 1_500));
        let frame = HandFrame {
            frame: 1,
            tracker: stamp(1, 1_000),
            glove: stamp(1, 1_500),
            timestamp_ns: 0,
            root: vas_protocol::WirePose::IDENTITY,
            flex: [0.0; vas_protocol::FLEX_COUNT],
            touching: 0,
            grasp_type: 0,
        };
        answers.mark(&frame, 3_000);
        answers.mark(&frame, 9_000);
        assert!(answers.all_answered());
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
