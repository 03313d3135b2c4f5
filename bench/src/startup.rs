//! B0, start-up: for one movable part of N triangles, the time of each stage that stands between
//! a scene config and the first answered input (shape generation and welding, edge adjacency,
//! convex hull, DOP-tree), each timed in this process, and the time from starting a real
//! `vas-server` on a scene of that part to its answer to one input sample. The log-log slope of
//! each from 100k triangles up says how it grows.

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde::Serialize;
use vas_client::Client;
use vas_client::recording::InputSample;
use vas_protocol::services::remove_prefix_segment;
use vas_protocol::{TrackerSample, WirePose, wall_clock_ns};
use vas_server::collision::{DopTree, MeshCollider};
use vas_server::geometry::shapes::{ShapeKind, ShapeSpec};
use vas_server::geometry::{ConvexHull, EdgeAdjacency};

use crate::args::OutputArgs;
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
    let server = match &args.server {
        Some(path) => path.clone(),
        None => std::env::current_exe()
            .context("locating vas-bench")?
            .with_file_name("vas-server"),
    };
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

/// Starts `server` in lockstep on a scene of a floor and one movable part, sends one tracker
/// sample once it answers control requests, and returns the time from its start to the answer.
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
    let timeout = Duration::from_secs(timeout_s);
    let started = Instant::now();
    let child = Command::new(server)
        .args(["run", "--lockstep", "--prefix", &prefix, "--scene"])
        .arg(&scene)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(
            std::fs::File::create(folder.path().join("server.log")).context("the server's log")?,
        )
        .spawn()
        .with_context(|| format!("starting {}", server.display()))?;
    let mut server = ServerProcess(child);
    let mut client = crate::args::connect(Some(&prefix))?;
    // Asked again each second, so that a server that exits (a bad scene) is noticed at once.
    while let Err(error) = client.scene_info(Duration::from_secs(1)) {
        let exited = !matches!(server.0.try_wait(), Ok(None));
        if exited || started.elapsed() > timeout {
            let log = std::fs::read_to_string(folder.path().join("server.log")).unwrap_or_default();
            bail!("the server does not answer control requests ({error}); its log:\n{log}");
        }
    }
    let answered = first_answer(&mut client, timeout)?;
    let ready = started.elapsed();
    drop(client);
    server.stop();
    // SAFETY: the server has ended (killed if SIGINT did not end it) and this client is gone.
    if let Err(error) = unsafe { remove_prefix_segment(&prefix) } {
        tracing::warn!(%error, "the server's prefix stays in shared memory");
    }
    if !answered {
        bail!("no answer to the first sample within {timeout_s} s");
    }
    Ok(ready)
}

/// Sends one tracker sample and waits for the hand frame answering it.
fn first_answer(client: &mut Client, timeout: Duration) -> Result<bool> {
    let sample = InputSample::Tracker(TrackerSample {
        seq: 1,
        timestamp_ns: wall_clock_ns(),
        hand: WirePose {
            position: [0.0, 0.3, 0.5],
            rotation: [0.0, 0.0, 0.0, 1.0],
        },
        cart: WirePose::IDENTITY,
        sensor_id: 0,
    });
    client.send_input(&sample)?;
    let answer = client.wait_for_hand_frame(timeout, |frame| sample.is_answered_by(frame), drop)?;
    Ok(answer.is_some())
}

/// The server process, stopped with SIGINT (by its pid) when done or dropped.
struct ServerProcess(Child);

impl ServerProcess {
    /// How long a stopped server may take to exit before it is killed.
    const EXIT_PATIENCE: Duration = Duration::from_secs(5);

    fn stop(&mut self) {
        let pid = self.0.id();
        // SAFETY: kill(2) only sends a signal; `pid` is our child, not yet reaped (we own its
        // `Child` and wait for it only below), so the id names no other process.
        let signalled = libc::pid_t::try_from(pid)
            .is_ok_and(|pid| unsafe { libc::kill(pid, libc::SIGINT) } == 0);
        let deadline = Instant::now() + Self::EXIT_PATIENCE;
        while signalled && Instant::now() < deadline {
            match self.0.try_wait() {
                Ok(Some(_)) => return,
                Ok(None) => std::thread::sleep(Duration::from_millis(10)),
                Err(_) => break,
            }
        }
        tracing::warn!(pid, "the server did not stop on SIGINT; killing it");
        let _ = self.0.kill().and_then(|()| self.0.wait().map(drop));
    }
}

impl Drop for ServerProcess {
    fn drop(&mut self) {
        if matches!(self.0.try_wait(), Ok(None)) {
            self.stop();
        }
    }
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
