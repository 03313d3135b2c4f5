//! What `vas-bench assembly` reports: the figures as JSON, a table, and a plot of the input to
//! answer latency over the drive.

use std::time::Duration;

use serde::Serialize;

use crate::report::{LinePlot, Series, Table, format_number, median};

/// Everything `vas-bench assembly` measured.
#[derive(Debug, Clone, Serialize)]
pub struct AssemblyReport {
    /// Parts and triangles of the scene (as the server loaded it), and the grasped bar's.
    pub parts: usize,
    pub triangles: usize,
    pub bar_triangles: usize,
    pub seed: u64,
    /// Generating and writing the meshes and the scene.
    pub generate_s: f64,
    /// From starting the server to its answer to the first sample: with an empty tree cache
    /// (every tree built, then stored), and with the cache it filled.
    pub ready_s_cold: f64,
    pub ready_s_cached: f64,
    /// Files in the tree cache after the cold run (one a distinct mesh).
    pub tree_cache_files: usize,
    /// The server's peak resident memory (VmHWM), the larger of the two runs, in MiB.
    pub peak_rss_mb: f64,
    /// That peak over the triangles: all the server holds a triangle (meshes, trees, hulls,
    /// edge adjacency, the published geometry), not the trees alone.
    pub bytes_per_triangle: f64,
    /// The drive in the cached run: tracker samples sent, of which unanswered, and its time.
    pub samples: usize,
    pub unanswered: u64,
    pub drive_s: f64,
    /// Whether the bar was grasped; the parts frames that showed it sliding; how far it slid.
    pub grasped: bool,
    pub sliding_frames: u64,
    pub slid_m: f64,
    /// The bar's published poses checked by parry against the static parts near its path, and
    /// those found penetrating one (must be 0).
    pub checked_poses: usize,
    pub penetrations: usize,
    /// Each loop's frames a second over the drive, and its 99th-percentile and longest frame.
    pub grasping_hz: f64,
    pub grasping_p99_us: f64,
    pub grasping_max_us: f64,
    pub sliding_hz: f64,
    pub sliding_p99_us: f64,
    pub sliding_max_us: f64,
    pub collision_hz: f64,
    pub collision_p99_us: f64,
    pub collision_max_us: f64,
    /// From publishing a tracker sample to receiving the hand frame answering it (B7).
    pub e2e_p50_us: f64,
    pub e2e_p99_us: f64,
    pub e2e_max_us: f64,
    /// B12, with `--clearance`: the clearance watch's figures.
    pub clearance: Option<ClearanceFigures>,
}

/// B12: the clearance stage over the drive, and what the clearance frames listed.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ClearanceFigures {
    pub threshold_mm: f64,
    /// Frames the stage measured, and its median, 99th-percentile (each the largest of its
    /// log windows') and longest time per frame.
    pub stage_frames: u64,
    pub stage_p50_us: f64,
    pub stage_p99_us: f64,
    pub stage_max_us: f64,
    /// Clearance frames received, those listing a pair, the pairs listed in all, the most in
    /// one frame, the stale ones in all, and the least distance listed.
    pub frames: u64,
    pub frames_with_pairs: u64,
    pub pairs: u64,
    pub most_pairs: u32,
    pub stale_pairs: u64,
    pub closest_mm: f64,
}

/// The report as a table of figures.
pub fn render(report: &AssemblyReport) -> String {
    let rows: [(&str, String); 16] = [
        ("ready_s_cold", format_number(report.ready_s_cold)),
        ("ready_s_cached", format_number(report.ready_s_cached)),
        ("tree_cache_files", report.tree_cache_files.to_string()),
        ("peak_rss_mb", format_number(report.peak_rss_mb)),
        (
            "bytes_per_triangle (peak RSS)",
            format_number(report.bytes_per_triangle),
        ),
        ("drive_s", format_number(report.drive_s)),
        ("samples", report.samples.to_string()),
        ("unanswered", report.unanswered.to_string()),
        ("grasped", report.grasped.to_string()),
        ("sliding_frames", report.sliding_frames.to_string()),
        ("slid_m", format_number(report.slid_m)),
        ("checked_poses", report.checked_poses.to_string()),
        ("penetrations", report.penetrations.to_string()),
        ("e2e_p50_us", format_number(report.e2e_p50_us)),
        ("e2e_p99_us", format_number(report.e2e_p99_us)),
        ("e2e_max_us", format_number(report.e2e_max_us)),
    ];
    let mut figures = Table::new(["figure", "value"]);
    for (name, value) in rows {
        figures.push_row([name.to_owned(), value]);
    }
    let mut loops = Table::new(["loop", "hz", "p99_us", "max_us"]);
    for (name, hz, p99, max) in [
        (
            "grasping",
            report.grasping_hz,
            report.grasping_p99_us,
            report.grasping_max_us,
        ),
        (
            "sliding",
            report.sliding_hz,
            report.sliding_p99_us,
            report.sliding_max_us,
        ),
        (
            "collision",
            report.collision_hz,
            report.collision_p99_us,
            report.collision_max_us,
        ),
    ] {
        loops.push_row([
            name.to_owned(),
            format_number(hz),
            format_number(p99),
            format_number(max),
        ]);
    }
    let clearance = report.clearance.map_or_else(String::new, |c| {
        let mut table = Table::new(["clearance", "value"]);
        for (name, value) in [
            ("threshold_mm", format_number(c.threshold_mm)),
            ("stage_frames", c.stage_frames.to_string()),
            ("stage_p50_us", format_number(c.stage_p50_us)),
            ("stage_p99_us", format_number(c.stage_p99_us)),
            ("stage_max_us", format_number(c.stage_max_us)),
            ("frames", c.frames.to_string()),
            ("frames_with_pairs", c.frames_with_pairs.to_string()),
            ("pairs", c.pairs.to_string()),
            ("most_pairs", c.most_pairs.to_string()),
            ("stale_pairs", c.stale_pairs.to_string()),
            ("closest_mm", format_number(c.closest_mm)),
        ] {
            table.push_row([name.to_owned(), value]);
        }
        format!("\n{}", table.render())
    });
    format!(
        "B8 big assembly: {} parts, {} triangles (the grasped bar {}), seed {}, generated in {} s\n{}\n{}{clearance}",
        report.parts,
        report.triangles,
        report.bar_triangles,
        report.seed,
        format_number(report.generate_s),
        figures.render(),
        loops.render()
    )
}

/// Seconds of the drive whose latencies make one point of the plot.
const PLOT_BIN_S: f64 = 0.05;

/// The input to answer latency over the drive: the median and the longest of every 50 ms, with
/// the script's grasp and the start of the slide marked (`marks`: name and script time).
pub fn plot(
    report: &AssemblyReport,
    latencies: &[(f64, Duration)],
    marks: [(&str, f64); 2],
) -> LinePlot {
    let mut bins: Vec<(f64, Vec<f64>)> = Vec::new();
    for &(time, latency) in latencies {
        let start = (time / PLOT_BIN_S).floor() * PLOT_BIN_S;
        let micros = latency.as_secs_f64() * 1e6;
        match bins.last_mut() {
            Some((bin, values)) if *bin == start => values.push(micros),
            _ => bins.push((start, vec![micros])),
        }
    }
    let series = |name: &str, of: fn(&mut Vec<f64>) -> f64| Series {
        name: name.into(),
        points: bins
            .iter()
            .map(|(start, values)| (start + PLOT_BIN_S / 2.0, of(&mut values.clone())))
            .collect(),
    };
    let micros = latencies
        .iter()
        .map(|(_, latency)| latency.as_secs_f64() * 1e6);
    let (lo, hi) = micros.fold((f64::MAX, 0.0_f64), |(lo, hi), us| (lo.min(us), hi.max(us)));
    let mut series = vec![
        series("median of 50 ms", |values| median(values)),
        series("longest of 50 ms", |values| {
            values.iter().copied().fold(0.0, f64::max)
        }),
    ];
    series.extend(marks.map(|(name, time)| Series {
        name: name.into(),
        points: vec![(time, lo), (time, hi)],
    }));
    LinePlot {
        title: format!(
            "B8: input to answer along the path, {} parts, {} triangles",
            report.parts, report.triangles
        ),
        x_label: "seconds into the script".into(),
        y_label: "latency (us)".into(),
        log_x: false,
        log_y: true,
        series,
    }
}
