//! `vas-bench browser` (B9): how soon the viewer's pages have what the server publishes.
//!
//! Against a running server and viewer, each case opens the viewer's page in a number of pages
//! of one headless Chromium (one shown and drawing, the others in tabs not shown, which receive
//! every frame but draw none: a software renderer per page would starve the machine's cores,
//! where each real renderer has a GPU of its own), feeds the server a tracker stream at a steady
//! rate, and then reads each page's own timing of the frames it got: from the server's publish
//! stamp to the page's receipt (transport), and from the receipt to the end of the animation
//! frame that drew it (draw). The viewer's CPU time over the same span gives its share of a core.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};
use vas_client::Wake;
use vas_client::latency::LatencySummary;
use vas_testkit::browser::Browser;

use crate::args::{OutputArgs, ServerArgs};
use crate::report::{LinePlot, Series, Table, format_number};
use crate::synthetic;

/// How long the pages run before their timing is reset and the measured span starts: the scene
/// arrives and is drawn once, and the viewer's and Chromium's caches warm.
const WARMUP: Duration = Duration::from_secs(3);

/// The JavaScript that estimates how far the page's high-resolution wall clock
/// (`performance.timeOrigin + performance.now()`, which the page's timing uses) is from the
/// system's (`Date.now()`, which reads it each call, as the server's stamps do), in ms.
/// `Date.now()` truncates to whole milliseconds, half a millisecond on average.
const CLOCK_SKEW_JS: &str = "(() => { let sum = 0; const n = 20000; \
     for (let i = 0; i < n; i++) sum += performance.timeOrigin + performance.now() - Date.now(); \
     return sum / n - 0.5; })()";

/// Arguments of `vas-bench browser`.
#[derive(Debug, clap::Args)]
pub struct BrowserArgs {
    /// The viewer's page, as `vas-viewer` printed it.
    #[arg(long, default_value = "http://127.0.0.1:8080/")]
    url: String,
    /// The viewer's process id: its CPU time (user and system) is read before and after each
    /// case.
    #[arg(long)]
    viewer_pid: u32,
    /// Page counts, one case each: one page shown and drawing, the others in tabs not shown.
    #[arg(long, value_delimiter = ',', default_value = "1,16",
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pages: Vec<u32>,
    /// How long each case is measured, in seconds (after a warm-up of 3 s).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=3600))]
    seconds: u64,
    /// Tracker samples sent to the server per second.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=10_000))]
    rate: u64,
    /// Each window's width and height in CSS pixels.
    #[arg(long, default_value = "640x480", value_parser = window_size)]
    window: (u32, u32),
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    server: ServerArgs,
}

/// One case's results.
#[derive(Debug, Clone, Serialize)]
pub struct CaseReport {
    /// Pages open at once.
    pub pages: u32,
    /// The measured span, in seconds.
    pub seconds: f64,
    /// Tracker samples sent in it.
    pub samples_sent: u64,
    /// Frames the pages received, all pages together.
    pub frames_received: usize,
    /// Frames one page received per second, on average.
    pub frames_per_page_per_s: f64,
    /// From the server's publish stamp to a page's receipt, over every page's frames.
    pub transport: LatencySummary,
    /// From a page's receipt of a frame to the end of the animation frame that drew it (the
    /// shown page).
    pub draw: LatencySummary,
    /// Drawn frames that were late, as a share of those drawn: an animation frame began after
    /// the frame arrived and did not draw it.
    pub late_share: f64,
    /// Frames a newer frame replaced before they were drawn, as a share of those received (a
    /// page draws only the newest at each animation frame).
    pub superseded_share: f64,
    /// Animation frames per second of the shown page.
    pub fps: f64,
    /// The viewer's CPU time over the span, in percent of one core.
    pub viewer_cpu_percent: f64,
    /// The first page's high-resolution wall clock minus the system's, in milliseconds: how far
    /// the transport figures can be off.
    pub clock_skew_ms: f64,
}

/// The timing one page kept (see the viewer's `main.js`).
#[derive(Debug, Deserialize)]
struct PageTiming {
    transport: Vec<f64>,
    draw: Vec<f64>,
    superseded: u64,
    late: u64,
}

/// Runs every case against the viewer at `--url` and the server on `--prefix`.
pub fn run(args: &BrowserArgs) -> anyhow::Result<()> {
    let client = crate::args::connect(args.server.prefix.as_deref())?;
    client
        .scene_info(crate::args::CONTROL_TIMEOUT)
        .context("no vas server answers on this prefix")?;
    drop(client);
    cpu_seconds(args.viewer_pid)?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("a runtime for the WebDriver session")?;
    let mut cases = Vec::new();
    for &pages in &args.pages {
        tracing::info!(pages, "measuring");
        cases.push(measure(&runtime, args, pages)?);
    }
    print!("{}", render(&cases));
    args.output.write(&cases, || plot(&cases))
}

/// One case: `pages` windows open while the input streams from a thread of its own.
fn measure(
    runtime: &tokio::runtime::Runtime,
    args: &BrowserArgs,
    pages: u32,
) -> anyhow::Result<CaseReport> {
    let stop = AtomicBool::new(false);
    let sent = AtomicU64::new(0);
    std::thread::scope(|scope| {
        let feeder = scope.spawn(|| feed(args, &stop, &sent));
        let measured = {
            // The input stops however the measurement ends, a panic included.
            let _stop = StopOnDrop(&stop);
            runtime.block_on(measure_pages(args, pages, &sent))
        };
        feeder
            .join()
            .map_err(|_| anyhow::anyhow!("the input thread panicked"))??;
        measured
    })
}

async fn measure_pages(
    args: &BrowserArgs,
    pages: u32,
    sent: &AtomicU64,
) -> anyhow::Result<CaseReport> {
    let (width, height) = args.window;
    let browser = Browser::start(width, height).await;
    let mut windows = browser.open_windows(&args.url, 1).await;
    windows.extend(browser.open_tabs(&args.url, pages as usize - 1).await);
    for window in &windows {
        browser.switch_to(window).await;
        browser
            .wait_for("window.vasViewer?.scene && window.vasViewer.received.frames > 0")
            .await;
    }
    browser.switch_to(&windows[0]).await;
    browser.wait_for("window.vasViewer.drawn.frames > 0").await;
    tokio::time::sleep(WARMUP).await;
    for window in &windows {
        browser.switch_to(window).await;
        browser.eval::<()>("window.vasViewer.resetTiming()").await;
    }
    let cpu_before = cpu_seconds(args.viewer_pid)?;
    let sent_before = sent.load(Ordering::Acquire);
    let start = Instant::now();
    tokio::time::sleep(Duration::from_secs(args.seconds)).await;
    let seconds = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds(args.viewer_pid)? - cpu_before;
    let samples_sent = sent.load(Ordering::Acquire) - sent_before;

    // The shown page first, before a switch shows another.
    let fps = browser.eval::<f64>("window.vasViewer.fps").await;
    let clock_skew_ms = browser.eval::<f64>(CLOCK_SKEW_JS).await;
    let mut timings = Vec::new();
    for window in &windows {
        browser.switch_to(window).await;
        timings.push(browser.eval::<PageTiming>("window.vasViewer.timing").await);
    }
    browser.close().await;

    let transport: Vec<f64> = timings.iter().flat_map(|t| t.transport.clone()).collect();
    let draw: Vec<f64> = timings.iter().flat_map(|t| t.draw.clone()).collect();
    let superseded: u64 = timings.iter().map(|t| t.superseded).sum();
    let late: u64 = timings.iter().map(|t| t.late).sum();
    if transport.is_empty() || draw.is_empty() {
        bail!(
            "the pages received or drew no frame in {seconds:.1} s: is input reaching the server?"
        );
    }
    Ok(CaseReport {
        pages,
        seconds,
        samples_sent,
        frames_received: transport.len(),
        frames_per_page_per_s: transport.len() as f64 / f64::from(pages) / seconds,
        transport: summary(&transport)?,
        draw: summary(&draw)?,
        late_share: late as f64 / draw.len() as f64,
        superseded_share: superseded as f64 / transport.len() as f64,
        fps,
        viewer_cpu_percent: 100.0 * cpu / seconds,
        clock_skew_ms,
    })
}

/// Sets its flag when dropped.
struct StopOnDrop<'a>(&'a AtomicBool);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// Sends tracker samples at `--rate` until `stop`, counting them in `sent`.
fn feed(args: &BrowserArgs, stop: &AtomicBool, sent: &AtomicU64) -> anyhow::Result<()> {
    let client = crate::args::connect(args.server.prefix.as_deref())?;
    let start = Instant::now();
    let mut seq = 0;
    while !stop.load(Ordering::Acquire) {
        seq += 1;
        let due = start + Duration::from_nanos(seq * 1_000_000_000 / args.rate);
        let early = due.saturating_duration_since(Instant::now());
        if !early.is_zero() && client.sleep(early) == Wake::Terminated {
            bail!("interrupted");
        }
        client.send_tracker(&synthetic::tracker(seq))?;
        sent.store(seq, Ordering::Release);
    }
    Ok(())
}

/// Milliseconds (negative ones, from clock skew, as zero) summarised.
fn summary(milliseconds: &[f64]) -> anyhow::Result<LatencySummary> {
    let durations: Vec<Duration> = milliseconds
        .iter()
        .map(|&ms| Duration::from_secs_f64(ms.max(0.0) / 1e3))
        .collect();
    Ok(LatencySummary::from_durations(&durations)?)
}

/// The process's CPU time so far (user and system), in seconds, from `/proc/PID/stat`.
fn cpu_seconds(pid: u32) -> anyhow::Result<f64> {
    let path = format!("/proc/{pid}/stat");
    let stat = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {path}: is --viewer-pid the viewer's?"))?;
    let ticks = parse_cpu_ticks(&stat).with_context(|| format!("{path} has no CPU times"))?;
    // SAFETY: sysconf only reads a configuration value.
    let per_second = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    if per_second <= 0 {
        bail!("the system does not say how long a clock tick is");
    }
    Ok(ticks as f64 / per_second as f64)
}

/// utime + stime (fields 14 and 15) of a `/proc/PID/stat` line, in clock ticks. The command
/// name (field 2) is in parentheses and may hold spaces, so fields are counted after its `)`.
fn parse_cpu_ticks(stat: &str) -> Option<u64> {
    let after_name = &stat[stat.rfind(')')? + 1..];
    let mut fields = after_name.split_whitespace().skip(11);
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    Some(user + system)
}

/// Parses `WIDTHxHEIGHT`.
fn window_size(text: &str) -> Result<(u32, u32), String> {
    let parse = |part: Option<&str>| {
        part.and_then(|part| part.parse::<u32>().ok())
            .filter(|pixels| (100..=4096).contains(pixels))
    };
    let mut parts = text.split('x');
    match (parse(parts.next()), parse(parts.next()), parts.next()) {
        (Some(width), Some(height), None) => Ok((width, height)),
        _ => Err(format!(
            "{text:?} is not WIDTHxHEIGHT with each 100 to 4096 pixels"
        )),
    }
}

/// The results as a table.
fn render(cases: &[CaseReport]) -> String {
    let mut table = Table::new([
        "pages",
        "frames_per_page_per_s",
        "transport_p50_ms",
        "transport_p99_ms",
        "transport_max_ms",
        "draw_p50_ms",
        "draw_p99_ms",
        "late_%",
        "fps",
        "superseded_%",
        "viewer_cpu_%",
        "clock_skew_ms",
    ]);
    let ms = |us: f64| format_number(us / 1e3);
    for case in cases {
        table.push_row([
            case.pages.to_string(),
            format_number(case.frames_per_page_per_s),
            ms(case.transport.p50_us),
            ms(case.transport.p99_us),
            ms(case.transport.max_us),
            ms(case.draw.p50_us),
            ms(case.draw.p99_us),
            format_number(100.0 * case.late_share),
            format_number(case.fps),
            format_number(100.0 * case.superseded_share),
            format_number(case.viewer_cpu_percent),
            format!("{:.3}", case.clock_skew_ms),
        ]);
    }
    table.render()
}

/// The figure: the transport and draw percentiles against the number of pages.
fn plot(cases: &[CaseReport]) -> LinePlot {
    let series = |name: &str, value: fn(&CaseReport) -> f64| Series {
        name: name.into(),
        points: cases
            .iter()
            .map(|case| (f64::from(case.pages), value(case) / 1e3))
            .collect(),
    };
    LinePlot {
        title: "B9: from the server's publish to the page, and to the drawn frame".into(),
        x_label: "pages open".into(),
        y_label: "milliseconds".into(),
        log_x: true,
        log_y: true,
        series: vec![
            series("transport p50", |case| case.transport.p50_us),
            series("transport p99", |case| case.transport.p99_us),
            series("draw p50", |case| case.draw.p50_us),
            series("draw p99", |case| case.draw.p99_us),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_times_are_read_after_the_command_name() {
        let stat = "4242 (a (strange) name) S 1 4242 4242 0 -1 4194560 500 0 0 0 \
                    1234 567 0 0 20 0 3 0 100 0 0";
        assert_eq!(parse_cpu_ticks(stat), Some(1234 + 567));
        assert_eq!(parse_cpu_ticks("4242 (cut) S 1 2"), None);
    }

    #[test]
    fn this_process_has_cpu_time() {
        let spent = cpu_seconds(std::process::id()).expect("own CPU time");
        assert!(spent.is_finite() && spent >= 0.0, "{spent}");
    }

    #[test]
    fn window_sizes_are_width_by_height() {
        assert_eq!(window_size("640x480"), Ok((640, 480)));
        for bad in [
            "640",
            "640x",
            "x480",
            "640x480x2",
            "10x10",
            "640x99999",
            "axb",
        ] {
            assert!(window_size(bad).is_err(), "{bad}");
        }
    }
}
