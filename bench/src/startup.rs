//! B0, start-up: for one movable part of N triangles, the time of each stage that stands between
//! a scene config and the first answered input (shape generation and welding, edge adjacency,
//! convex hull, DOP-tree), each timed in this process, and the time from starting a real
//! `vas-server` on a scene of that part to its answer to one input sample. The log-log slope of
//! each from 100k triangles up says how it grows.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use serde::Serialize;
use vas_protocol::{TrackerSample, WirePose, wall_clock_ns};
use vas_server::collision::{DopTree, MeshCollider};
use vas_server::geometry::shapes::{ShapeKind, ShapeSpec};
use vas_server::geometry::{ConvexHull, EdgeAdjacency};

use crate::args::OutputArgs;
use crate::process::{ServerProcess, server_binary};
use crate::report::{LinePlot, Series, Table, format_number};
use crate::slope::least_squares_slope;

/// Command line of `vas-bench startup`.
#[derive(Debug, clap::Args)]
pub struct StartupArgs {
    /// Triangle counts of the part, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_values_t = [1_000, 10_000, 100_000, 1_000_000, 2_000_000]
    )]
    triangles: Vec<usize>,
    /// The part's shape.
    #[arg(long, default_value = "sphere")]
    shape: ShapeKind,
    /// The server binary; default: `vas-server` beside this program.
    #[arg(long, value_name = "PATH")]
    server: Option<PathBuf>,
    /// How long the server may take to answer, in seconds.
    #[arg(long, default_value_t = 600)]
    timeout_s: u64,
    #[command(flatten)]
    output: OutputArgs,
}

/// One part size: each stage's time and the server's.
#[derive(Debug, Clone, Serialize)]
pub struct StartupRow {
    pub triangles: usize,
    pub shape_s: f64,
    pub adjacency_s: f64,
    pub hull_s: f64,
    pub tree_s: f64,
    /// From starting the server to its answer to the first input sample.
    pub ready_s: f64,
}

/// Everything `vas-bench startup` measured.
#[derive(Debug, Clone, Serialize)]
pub struct StartupReport {
    pub shape: String,
    pub rows: Vec<StartupRow>,
    /// Log-log slope of each column over the rows of at least 100k triangles (1 is linear).
    pub slopes: Vec<(String, f64)>,
}

/// A column of a row: its name and how to read it.
type Column = (&'static str, fn(&StartupRow) -> f64);

/// The columns of a row, for the table, the slopes and the plot.
const COLUMNS: [Column; 5] = [
    ("shape_s", |r| r.shape_s),
    ("adjacency_s", |r| r.adjacency_s),
    ("hull_s", |r| r.hull_s),
    ("tree_s", |r| r.tree_s),
    ("ready_s", |r| r.ready_s),
];

/// Triangles from which the slopes are fitted: below, fixed costs hide the growth.
const SLOPE_FROM_TRIANGLES: usize = 100_000;

pub fn run(args: &StartupArgs) -> Result<()> {
    let server = server_binary(args.server.as_deref())?;
    let mut rows = Vec::new();
    for &triangles in &args.triangles {
        let mut row = stages(args.shape, triangles)?;
        row.ready_s = ready(&server, args.shape, triangles, args.timeout_s)?.as_secs_f64();
        println!(
            "{triangles} triangles: ready after {} s",
            format_number(row.ready_s)
        );
        rows.push(row);
    }
    let slopes = COLUMNS
        .iter()
        .filter_map(|(name, value)| {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.triangles >= SLOPE_FROM_TRIANGLES)
                .map(|r| ((r.triangles as f64).ln(), value(r).max(1e-9).ln()))
                .collect();
            Some((name.to_string(), least_squares_slope(&points).ok()?))
        })
        .collect();
    let report = StartupReport {
        shape: args.shape.to_string(),
        rows,
        slopes,
    };
    print!("{}", render(&report));
    args.output.write(&report, || plot(&report))
}

/// Times the stages in this process, each on the part the stage before made.
fn stages(shape: ShapeKind, triangles: usize) -> Result<StartupRow> {
    let started = Instant::now();
    let mesh = ShapeSpec::unit(shape, triangles)
        .build()
        .with_context(|| format!("building a {shape} of {triangles} triangles"))?;
    let shape_s = started.elapsed().as_secs_f64();
    let timed = |stage: &dyn Fn()| {
        let started = Instant::now();
        stage();
        started.elapsed().as_secs_f64()
    };
    Ok(StartupRow {
        triangles: mesh.triangles().len(),
        shape_s,
        adjacency_s: timed(&|| drop(EdgeAdjacency::new(&mesh))),
        hull_s: timed(&|| drop(ConvexHull::of(&mesh))),
        tree_s: timed(&|| drop(DopTree::build(&mesh))),
        ready_s: f64::NAN,
    })
}

/// Starts `server` in lockstep on a scene of a floor and one movable part and returns the time
/// from its start to its answer to one tracker sample.
fn ready(
    server: &std::path::Path,
    shape: ShapeKind,
    triangles: usize,
    timeout_s: u64,
) -> Result<Duration> {
    let folder = tempfile::tempdir().context("a scratch folder for the scene")?;
    let scene = folder.path().join("startup.toml");
    // The unit shape fits in [-1, 1]^3: 1.1 m up, it clears the floor.
    let part = toml::to_string(&ShapeSpec::unit(shape, triangles)).context("the part's shape")?;
    std::fs::write(
        &scene,
        format!(
            "name = \"start-up\"\n\n\
             [[parts]]\nname = \"floor\"\nposition = [0.0, 0.0, -0.01]\n\
             shape = {{ kind = \"box\", size = [4.0, 4.0, 0.02], triangles = 12 }}\n\n\
             [[parts]]\nname = \"part\"\nmovable = true\nposition = [0.0, 0.0, 1.1]\n\
             [parts.shape]\n{part}"
        ),
    )
    .context("writing the scene")?;
    let prefix = format!("vas_b0_{}_{triangles}_", std::process::id());
    let first = TrackerSample {
        seq: 1,
        timestamp_ns: wall_clock_ns(),
        hand: WirePose {
            position: [0.0, 0.3, 0.5],
            rotation: [0.0, 0.0, 0.0, 1.0],
        },
        cart: WirePose::IDENTITY,
        sensor_id: 0,
        user: 0,
        side: 0,
        reserved: 0,
    };
    let started = ServerProcess::start_ready(
        server,
        &prefix,
        &["--lockstep".as_ref(), "--scene".as_ref(), scene.as_os_str()],
        &folder.path().join("server.log"),
        first,
        Duration::from_secs(timeout_s),
    )?;
    started.server.stop(started.client);
    Ok(started.ready)
}

/// The results as a table, with the slopes under it.
fn render(report: &StartupReport) -> String {
    let mut table =
        Table::new(std::iter::once("triangles").chain(COLUMNS.iter().map(|(name, _)| *name)));
    for row in &report.rows {
        table.push_row(
            std::iter::once(row.triangles.to_string())
                .chain(COLUMNS.iter().map(|(_, value)| format_number(value(row)))),
        );
    }
    let mut text = format!(
        "start-up of one movable {}, stage by stage\n{}",
        report.shape,
        table.render()
    );
    text.push_str("log-log slope from 100k triangles:");
    for (name, slope) in &report.slopes {
        text.push_str(&format!(" {name} {slope:.2}"));
    }
    text.push('\n');
    text
}

/// Each stage's time and the time to ready against the triangles, log-log.
fn plot(report: &StartupReport) -> LinePlot {
    LinePlot {
        title: format!("B0: start-up of one movable {}", report.shape),
        x_label: "triangles".into(),
        y_label: "seconds".into(),
        log_x: true,
        log_y: true,
        series: COLUMNS
            .iter()
            .map(|(name, value)| Series {
                name: name.to_string(),
                points: report
                    .rows
                    .iter()
                    .map(|r| (r.triangles as f64, value(r).max(1e-6)))
                    .collect(),
            })
            .collect(),
    }
}
