//! B6, grasping: time per clasp minimisation of the 22-DOF hand against parts of 1k to 50k
//! triangles.
//!
//! Procedure: each scripted grasp (approach, close, carry, open; see
//! [`ScriptedGrasp`]) is sampled at 1 kHz and fed to a fresh hand, the part's mesh built with
//! each triangle count. Every input sample is one frame; the clasp minimisation of every frame
//! is timed (inside the frame), and so is the whole frame (clasp, contacts, analysis, hold).
//! Each run is repeated; the table shows the median over the repeats of each run's mean, 99th
//! percentile and maximum, and the grasp the hand recognised.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::args::OutputArgs;
use crate::report::{LinePlot, Series, Table, format_number, median, timer_overhead};
use vas_server::grasping::clasp::HandPose;
use vas_server::grasping::collider::{Obstacle, PartGeometry};
use vas_server::grasping::hand::{GraspEvent, GraspParams, GraspingHand};
use vas_server::grasping::model::{FLEX_COUNT, HandModel};
use vas_testkit::script::{ScriptedGrasp, sample};

/// The default triangle counts of the parts.
pub const DEFAULT_TRIANGLES: [usize; 5] = [1_000, 5_000, 10_000, 20_000, 50_000];

/// Input samples per second: a tracker and glove at 1 kHz.
pub const RATE_HZ: f64 = 1000.0;

/// Parameters of B6.
#[derive(Debug, Clone)]
pub struct GraspBenchConfig {
    /// The scripted grasps to run.
    pub scripts: Vec<ScriptedGrasp>,
    /// Triangle counts of the parts.
    pub triangles: Vec<usize>,
    /// Runs per script and triangle count.
    pub repeats: usize,
    /// The grasping parameters.
    pub params: GraspParams,
}

/// One row of B6: a part at one triangle count.
#[derive(Debug, Clone, Serialize)]
pub struct GraspRow {
    /// The part's name.
    pub part: String,
    /// Its triangle count.
    pub triangles: usize,
    /// Mean time per clasp minimisation (median over repeats), microseconds.
    pub mean_clasp_us: f64,
    /// 99th percentile of the time per clasp minimisation (median over repeats).
    pub p99_clasp_us: f64,
    /// Largest time per clasp minimisation (median over repeats).
    pub max_clasp_us: f64,
    /// The grasp the hand recognised ("none" if it grasped nothing).
    pub grasp: String,
    /// The grasp the script expects.
    pub expected: String,
    /// Mean time per whole frame (clasp, contacts, analysis), microseconds.
    pub mean_frame_us: f64,
    /// 99th percentile of the time per whole frame.
    pub p99_frame_us: f64,
    /// Mean clasp iteration steps per frame.
    pub mean_steps: f64,
    /// Mean segment collision checks per frame.
    pub mean_checks: f64,
    /// Frames in which the clasp ran, per run.
    pub clasps: usize,
}

/// The JSON document of B6.
#[derive(Debug, Clone, Serialize)]
pub struct GraspReport {
    /// Always "grasp".
    pub benchmark: &'static str,
    /// The hand model's name.
    pub hand: String,
    /// Input samples per second.
    pub rate_hz: f64,
    /// Runs per row.
    pub repeats: usize,
    /// One row per part and triangle count.
    pub rows: Vec<GraspRow>,
}

/// What one run of a script measured.
struct RunTimes {
    clasp_us: Vec<f64>,
    frame_us: Vec<f64>,
    steps: u64,
    checks: u64,
    grasp: Option<String>,
}

/// Plays `script` once against `part` and times every frame.
fn run_once(
    model: &Arc<HandModel>,
    script: ScriptedGrasp,
    part: &PartGeometry,
    params: &GraspParams,
    overhead: Duration,
) -> Result<RunTimes> {
    let keys = script.keyframes();
    let initial = HandPose {
        root: keys[0].tracker,
        flex: [0.0; FLEX_COUNT],
    };
    let mut hand = GraspingHand::new(model.clone(), *params, initial)
        .context("building the hand's collision geometry")?;
    let mut part_pose = script.part_pose();
    let mut times = RunTimes {
        clasp_us: Vec::new(),
        frame_us: Vec::new(),
        steps: 0,
        checks: 0,
        grasp: None,
    };
    let micros = |d: Duration| d.saturating_sub(overhead).as_secs_f64() * 1e6;
    for key in sample(&keys, RATE_HZ) {
        let obstacles = [Obstacle {
            part: 0,
            geometry: part,
            pose: part_pose,
        }];
        let input = key.input();
        let started = Instant::now();
        let frame = hand.step(&input, &obstacles);
        let elapsed = started.elapsed();
        times.frame_us.push(micros(elapsed));
        if let Some(clasp) = frame.clasp {
            times.clasp_us.push(micros(clasp.time));
            times.steps += u64::from(clasp.steps);
            times.checks += u64::from(frame.segment_checks);
        }
        for event in &frame.events {
            match event {
                GraspEvent::Grasp { grasp, .. } => {
                    times.grasp.get_or_insert_with(|| grasp.to_string());
                }
                GraspEvent::Release { pose, .. } => part_pose = *pose,
            }
        }
        if let Some((_, pose)) = frame.held {
            part_pose = pose;
        }
    }
    Ok(times)
}

/// The `q` quantile (0..1) of `values`, by the nearest-rank method; NaN when empty.
fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

/// Runs B6.
pub fn run_grasp(model: Arc<HandModel>, config: &GraspBenchConfig) -> Result<GraspReport> {
    if config.scripts.is_empty() || config.triangles.is_empty() || config.repeats == 0 {
        bail!("the grasp benchmark needs at least one part, one triangle count and one repeat");
    }
    let overhead = timer_overhead();
    let mut rows = Vec::new();
    for &script in &config.scripts {
        for &triangles in &config.triangles {
            let mesh = script.part_mesh(triangles);
            let actual = mesh.triangles().len();
            let part = PartGeometry::new(mesh);
            let runs = (0..config.repeats)
                .map(|_| run_once(&model, script, &part, &config.params, overhead))
                .collect::<Result<Vec<RunTimes>>>()?;
            let across = |f: &dyn Fn(&RunTimes) -> f64| {
                median(&mut runs.iter().map(f).collect::<Vec<f64>>())
            };
            let first = &runs[0];
            let clasps = first.clasp_us.len();
            rows.push(GraspRow {
                part: script.part_name().to_string(),
                triangles: actual,
                mean_clasp_us: across(&|r| mean(&r.clasp_us)),
                p99_clasp_us: across(&|r| quantile(&r.clasp_us, 0.99)),
                max_clasp_us: across(&|r| quantile(&r.clasp_us, 1.0)),
                grasp: first.grasp.clone().unwrap_or_else(|| "none".into()),
                expected: script.expected().to_string(),
                mean_frame_us: across(&|r| mean(&r.frame_us)),
                p99_frame_us: across(&|r| quantile(&r.frame_us, 0.99)),
                mean_steps: first.steps as f64 / clasps.max(1) as f64,
                mean_checks: first.checks as f64 / clasps.max(1) as f64,
                clasps,
            });
        }
    }
    Ok(GraspReport {
        benchmark: "grasp",
        hand: model.name().to_string(),
        rate_hz: RATE_HZ,
        repeats: config.repeats,
        rows,
    })
}

/// The table of B6.
pub fn grasp_table(rows: &[GraspRow]) -> Table {
    let mut table = Table::new([
        "part",
        "triangles",
        "mean clasp us",
        "p99 clasp us",
        "max clasp us",
        "mean frame us",
        "p99 frame us",
        "steps",
        "checks",
        "grasp",
    ]);
    for r in rows {
        table.push_row([
            r.part.clone(),
            r.triangles.to_string(),
            format_number(r.mean_clasp_us),
            format_number(r.p99_clasp_us),
            format_number(r.max_clasp_us),
            format_number(r.mean_frame_us),
            format_number(r.p99_frame_us),
            format_number(r.mean_steps),
            format_number(r.mean_checks),
            r.grasp.clone(),
        ]);
    }
    table
}

/// Mean and 99th-percentile clasp time against triangle count, one pair of curves per part.
fn grasp_plot(rows: &[GraspRow]) -> LinePlot {
    let mut series = Vec::new();
    let mut parts: Vec<&str> = rows.iter().map(|r| r.part.as_str()).collect();
    parts.dedup();
    for part in parts {
        let mine: Vec<&GraspRow> = rows.iter().filter(|r| r.part == part).collect();
        series.push(Series {
            name: format!("{part}, mean"),
            points: mine
                .iter()
                .map(|r| (r.triangles as f64, r.mean_clasp_us))
                .collect(),
        });
        series.push(Series {
            name: format!("{part}, p99"),
            points: mine
                .iter()
                .map(|r| (r.triangles as f64, r.p99_clasp_us))
                .collect(),
        });
    }
    LinePlot {
        title: "B6: time per clasp minimisation".into(),
        x_label: "part triangles".into(),
        y_label: "microseconds per clasp".into(),
        log_x: true,
        log_y: true,
        series,
    }
}

/// Arguments of `vas-bench grasp`.
#[derive(Debug, Clone, clap::Args)]
pub struct GraspArgs {
    /// The hand model.
    #[arg(long, default_value = "configs/hands/right.toml")]
    pub hand: PathBuf,
    /// The scripted grasps to run, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = ScriptedGrasp::ALL,
          value_parser = scripted_grasp())]
    pub parts: Vec<ScriptedGrasp>,
    /// Triangle counts of the parts, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_TRIANGLES,
          value_parser = crate::args::triangle_count())]
    pub triangles: Vec<usize>,
    /// Runs per part and triangle count (the table shows medians).
    #[arg(long, default_value_t = 5, value_parser = crate::args::pass_count())]
    pub repeats: usize,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// clap's parser of a scripted grasp by its part's name, listing the names in `--help`.
fn scripted_grasp() -> impl clap::builder::TypedValueParser<Value = ScriptedGrasp> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(ScriptedGrasp::ALL.map(ScriptedGrasp::part_name)).map(
        |name| {
            ScriptedGrasp::ALL
                .into_iter()
                .find(|grasp| grasp.part_name() == name)
                .expect("the possible values are the grasps' own names")
        },
    )
}

/// `vas-bench grasp`: runs B6, prints the table, writes files.
pub fn run_cli(args: &GraspArgs) -> Result<()> {
    let model = Arc::new(HandModel::load(Path::new(&args.hand))?);
    let config = GraspBenchConfig {
        scripts: args.parts.clone(),
        triangles: args.triangles.clone(),
        repeats: args.repeats,
        params: GraspParams::default(),
    };
    let report = run_grasp(model, &config)?;
    println!(
        "grasp: {}, input at {} Hz, median of {} runs",
        report.hand, report.rate_hz, report.repeats
    );
    print!("{}", grasp_table(&report.rows).render());
    for r in report.rows.iter().filter(|r| r.grasp != r.expected) {
        println!(
            "warning: {} with {} triangles: grasp {}, expected {}",
            r.part, r.triangles, r.grasp, r.expected
        );
    }
    args.output.write(&report, || grasp_plot(&report.rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped right hand model.
    fn right_hand() -> HandModel {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands/right.toml");
        HandModel::load(&path).expect("the right hand model loads")
    }

    #[test]
    fn the_benchmark_times_clasps_and_reports_the_grasp() {
        let config = GraspBenchConfig {
            scripts: vec![ScriptedGrasp::PowerOnHandle],
            triangles: vec![1_000],
            repeats: 1,
            params: GraspParams::default(),
        };
        let report = run_grasp(Arc::new(right_hand()), &config).unwrap();
        let row = &report.rows[0];
        assert_eq!((row.part.as_str(), row.grasp.as_str()), ("handle", "power"));
        assert_eq!(row.expected, "power");
        // Every frame of the 1.2 s script clasps (the first frame only places the hand).
        assert_eq!(row.clasps, 1200);
        // One slow clasp can lift the mean above p99; neither passes the slowest.
        assert!(row.mean_clasp_us > 0.0 && row.p99_clasp_us > 0.0);
        assert!(row.max_clasp_us >= row.p99_clasp_us && row.max_clasp_us >= row.mean_clasp_us);
        assert!(row.p99_frame_us > 0.0);
        assert!(row.mean_steps >= 1.0 && row.mean_checks >= 16.0);
        assert!(grasp_table(&report.rows).render().contains("handle"));
    }

    #[test]
    fn quantiles_by_nearest_rank() {
        let values: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(quantile(&values, 0.99), 99.0);
        assert_eq!(quantile(&values, 1.0), 100.0);
        assert_eq!(quantile(&values, 0.0), 1.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
