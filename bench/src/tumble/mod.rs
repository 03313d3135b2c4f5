//! B1, the tumbling pair (the paper's Figure 3), and the machinery it shares with B2: a set of
//! exact colliders built over two meshes, run on the same poses, timed per query, with their
//! answers compared at every pose.
//!
//! Procedure: both meshes are centred on their bounding-box centre and scaled to fit [-1, 1]^3.
//! A stays at the identity; B is at translation (d, 0, 0) with rotation Rz(a)·Rx(a),
//! a = 2π s / steps, for s = 0 .. steps-1, at every distance d. One first-hit query per step and
//! algorithm; each algorithm runs the whole sequence in its turn, and the turns rotate over
//! several rounds so that machine noise hits them alike (see [`run_poses`]).

use anyhow::{Result, bail};
use serde::Serialize;

use crate::args::OutputArgs;
use crate::report::{LinePlot, Series, Table, format_number};
use vas_server::collision::OrientationSet;
use vas_server::geometry::shapes::{self, ShapeKind};
use vas_server::geometry::{TriMesh, parse_mesh_spec};
use vas_testkit::tumble::tumble_pose;

mod colliders;
#[cfg(test)]
mod tests;

use colliders::HarnessFloor;
pub use colliders::{
    Algo, AlgoResult, BuildResult, BuiltCollider, build_results, build_table, print_disagreements,
    results_table, run_poses,
};

/// The default distances of B1.
pub const DEFAULT_DISTANCES: [f64; 9] = [3.0, 2.5, 2.0, 1.75, 1.5, 1.25, 1.0, 0.75, 0.5];

/// The default number of steps per distance.
pub const DEFAULT_STEPS: usize = 5000;

/// Parameters of B1.
#[derive(Debug, Clone)]
pub struct TumbleConfig {
    /// Steps per distance.
    pub steps: usize,
    /// Distances d of B's centre from A's.
    pub distances: Vec<f64>,
    /// Algorithms to compare.
    pub algos: Vec<Algo>,
    /// Orientation set of the DOP-based algorithms.
    pub orientations: OrientationSet,
    /// Passes over the poses; each query's time is its fastest pass (see [`run_poses`]).
    pub rounds: usize,
}

/// The JSON document of B1.
#[derive(Debug, Clone, Serialize)]
pub struct TumbleReport {
    /// Always "tumble".
    pub benchmark: &'static str,
    /// Steps per distance.
    pub steps: usize,
    /// Triangles of A.
    pub triangles_a: usize,
    /// Triangles of B.
    pub triangles_b: usize,
    /// DOP orientations used.
    pub k: usize,
    /// Passes over the poses (each query's time is its fastest pass).
    pub rounds: usize,
    /// Steps (over all distances) where the algorithms disagreed.
    pub mismatches: usize,
    /// One entry per algorithm and distance.
    pub results: Vec<AlgoResult>,
    /// Build time and memory per algorithm.
    pub build: Vec<BuildResult>,
    /// The harness's own cost per query, on the first distance's poses.
    pub floor: HarnessFloor,
}

/// Runs B1 on meshes `a` and `b` (normalised here).
pub fn run_tumble(a: &TriMesh, b: &TriMesh, config: &TumbleConfig) -> Result<TumbleReport> {
    if config.steps == 0 || config.distances.is_empty() || config.algos.is_empty() {
        bail!("the tumbling benchmark needs at least one step, one distance and one algorithm");
    }
    if let Some(d) = config.distances.iter().find(|d| !d.is_finite()) {
        bail!("the tumbling benchmark's distances must be finite, not {d}");
    }
    let (a, b) = (a.normalized_to_unit_box(), b.normalized_to_unit_box());
    let colliders: Vec<BuiltCollider> = config
        .algos
        .iter()
        .map(|&algo| BuiltCollider::new(algo, &a, &b, &config.orientations))
        .collect();
    let poses_at = |d: f64| -> Vec<_> {
        (0..config.steps)
            .map(|s| tumble_pose(d, s, config.steps))
            .collect()
    };
    let mut results = Vec::new();
    let mut mismatches = 0;
    for &d in &config.distances {
        let (mut r, m) = run_poses(&colliders, &poses_at(d), Some(d), config.rounds);
        results.append(&mut r);
        mismatches += m;
    }
    let floor = HarnessFloor::measure(&a, &b, &poses_at(config.distances[0]), config.rounds);
    Ok(TumbleReport {
        benchmark: "tumble",
        steps: config.steps,
        triangles_a: a.triangles().len(),
        triangles_b: b.triangles().len(),
        k: config.orientations.k(),
        rounds: config.rounds,
        mismatches,
        results,
        build: build_results(&colliders),
        floor,
    })
}

/// One object of the Figure 3 sweep: its family (curve) name and mesh.
pub struct FigureObject {
    /// Curve the object belongs to ("sphere", "torus", ..., or "real").
    pub family: String,
    /// Label of the object (for the table).
    pub label: String,
    /// The mesh, used as both A and B.
    pub mesh: TriMesh,
}

/// One point of Figure 3: mean time per query of one algorithm on one object, over all distances.
#[derive(Debug, Clone, Serialize)]
pub struct FigurePoint {
    /// Curve family of the object.
    pub family: String,
    /// Object label.
    pub label: String,
    /// Triangles of the object.
    pub triangles: usize,
    /// Algorithm name.
    pub algo: String,
    /// Mean time per query over every distance and step, microseconds.
    pub mean_us: f64,
    /// Steps where the algorithms disagreed.
    pub mismatches: usize,
}

/// Runs B1 on every object (both copies the same mesh) and averages over distances.
pub fn figure3(objects: &[FigureObject], config: &TumbleConfig) -> Result<Vec<FigurePoint>> {
    let mut points = Vec::new();
    for object in objects {
        let report = run_tumble(&object.mesh, &object.mesh, config)?;
        for algo in &config.algos {
            let rows: Vec<&AlgoResult> = report
                .results
                .iter()
                .filter(|r| r.algo == algo.name())
                .collect();
            let mean_us = rows.iter().map(|r| r.mean_us).sum::<f64>() / rows.len() as f64;
            points.push(FigurePoint {
                family: object.family.clone(),
                label: object.label.clone(),
                triangles: report.triangles_a,
                algo: algo.name().to_string(),
                mean_us,
                mismatches: report.mismatches,
            });
        }
    }
    Ok(points)
}

/// Figure 3 as a log-log line plot: one curve per algorithm and object family.
pub fn figure3_plot(points: &[FigurePoint]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for p in points {
        let name = format!("{} / {}", p.algo, p.family);
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push((p.triangles as f64, p.mean_us)),
            None => series.push(Series {
                name,
                points: vec![(p.triangles as f64, p.mean_us)],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    LinePlot {
        title: "Tumbling pair: mean time per query".into(),
        x_label: "triangles per object".into(),
        y_label: "microseconds per query".into(),
        log_x: true,
        log_y: true,
        series,
    }
}

/// Command-line arguments of `vas-bench tumble`.
#[derive(Debug, Clone, clap::Args)]
pub struct TumbleArgs {
    /// Mesh A (and B unless --mesh-b): a file or shape:KIND:TRIANGLES. With --figure, real
    /// meshes to add to the sweep (repeatable).
    #[arg(long, required_unless_present = "figure")]
    pub mesh: Vec<String>,
    /// Mesh B (default: a copy of A).
    #[arg(long)]
    pub mesh_b: Option<String>,
    /// Steps per distance (default 5000, or 300 with --figure).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Distances d, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_DISTANCES,
          value_parser = crate::args::finite_number)]
    pub distances: Vec<f64>,
    /// Algorithms to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = Algo::DEFAULT)]
    pub algos: Vec<Algo>,
    /// Number of DOP orientations (6, 14, 18, 24 or 26).
    #[arg(long, default_value_t = vas_server::collision::orientation::DEFAULT_K)]
    pub k: usize,
    /// Passes over the poses; each query's time is its fastest pass (robust to preemption).
    #[arg(long, default_value_t = 3, value_parser = crate::args::pass_count())]
    pub rounds: usize,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Run the Figure 3 sweep: sphere, hyperboloid and torus at each of --figure-sizes
    /// triangles, plus the --mesh files.
    #[arg(long)]
    pub figure: bool,
    /// Triangle counts of the procedural objects in the Figure 3 sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [1_000usize, 5_000, 10_000, 50_000, 100_000])]
    pub figure_sizes: Vec<usize>,
}

/// `vas-bench tumble`: runs B1 (or the Figure 3 sweep), prints the table, writes files.
pub fn run_cli(args: &TumbleArgs) -> Result<()> {
    let orientations = OrientationSet::new(args.k)?;
    if args.figure {
        return run_figure_cli(args, orientations);
    }
    let a = parse_mesh_spec(&args.mesh[0])?;
    let b = match &args.mesh_b {
        Some(spec) => parse_mesh_spec(spec)?,
        None => a.clone(),
    };
    let config = TumbleConfig {
        steps: args.steps.unwrap_or(DEFAULT_STEPS),
        distances: args.distances.clone(),
        algos: args.algos.clone(),
        orientations,
        rounds: args.rounds,
    };
    let report = run_tumble(&a, &b, &config)?;
    println!(
        "tumbling pair: {} x {} triangles, {} steps per distance, k = {}, fastest of {} rounds",
        report.triangles_a, report.triangles_b, report.steps, report.k, report.rounds
    );
    print!("{}", results_table(&report.results).render());
    print!("{}", build_table(&report.build).render());
    println!("mismatches: {}", report.mismatches);
    print_disagreements(&report.results);
    let floor = &report.floor;
    println!(
        "harness floor, mean / pass per query: a query that answers at once {:.1} / {:.1} ns, \
         a bounding-sphere test {:.1} / {:.1} ns",
        floor.empty_query.mean_us * 1e3,
        floor.empty_query.pass_mean_us * 1e3,
        floor.sphere_test.mean_us * 1e3,
        floor.sphere_test.pass_mean_us * 1e3,
    );
    args.output
        .write(&report, || distance_plot(&report.results))
}

/// The Figure 3 sweep from the command line.
fn run_figure_cli(args: &TumbleArgs, orientations: OrientationSet) -> Result<()> {
    let mut objects = Vec::new();
    for kind in [ShapeKind::Sphere, ShapeKind::Hyperboloid, ShapeKind::Torus] {
        for &n in &args.figure_sizes {
            objects.push(FigureObject {
                family: kind.name().to_string(),
                label: format!("{kind} {n}"),
                mesh: shapes::build(kind, n),
            });
        }
    }
    for spec in &args.mesh {
        objects.push(FigureObject {
            family: "real".to_string(),
            label: spec.clone(),
            mesh: parse_mesh_spec(spec)?,
        });
    }
    let config = TumbleConfig {
        steps: args.steps.unwrap_or(300),
        distances: args.distances.clone(),
        algos: args.algos.clone(),
        orientations,
        rounds: args.rounds,
    };
    let points = figure3(&objects, &config)?;
    let mut table = Table::new(["object", "triangles", "algo", "mean_us", "mismatches"]);
    for p in &points {
        table.push_row([
            p.label.clone(),
            p.triangles.to_string(),
            p.algo.clone(),
            format_number(p.mean_us),
            p.mismatches.to_string(),
        ]);
    }
    print!("{}", table.render());
    args.output.write(&points, || figure3_plot(&points))
}

/// Mean time per query against distance, one curve per algorithm (log time axis).
fn distance_plot(results: &[AlgoResult]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for r in results {
        let point = (r.distance.unwrap_or_default(), r.mean_us.max(1e-3));
        match series.iter_mut().find(|s| s.name == r.algo) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name: r.algo.clone(),
                points: vec![point],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    LinePlot {
        title: "Tumbling pair: mean time per query".into(),
        x_label: "distance d".into(),
        y_label: "microseconds per query".into(),
        log_x: false,
        log_y: true,
        series,
    }
}
