//! The DOP-tree build against FCL's OBB-tree build on the same meshes: each built `--runs` times,
//! the median taken; the DOP-tree on all of rayon's threads (the ratio's figure: the build is
//! parallel, FCL's is not) and on one; bytes a triangle of everything each tree holds. FCL's
//! build runs in its own process, the harness `bench/fcl/obb_build.cpp` compiled when FCL was
//! found at build time; without it the ratios are against a reference time.

use std::io::Write;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use vas_server::collision::DopTree;
use vas_server::collision::orientation::{DEFAULT_K, OrientationSet};
use vas_server::geometry::{TriMesh, parse_mesh_spec};

use crate::args::OutputArgs;
use crate::report::{LinePlot, Series, Table, format_number, median};

/// FCL's harness, if it was built with this program.
const FCL_HARNESS: Option<&str> = option_env!("VAS_FCL_OBB_BUILD");

/// FCL's OBB-tree build of the 1M-triangle torus on this kind of machine, for the ratio when the
/// harness is missing.
const FCL_REFERENCE_S: f64 = 2.5;

/// Command line of `vas-bench tree-build`.
#[derive(Debug, clap::Args)]
pub struct TreeBuildArgs {
    /// Meshes: files or shape:KIND:TRIANGLES, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "shape:torus:1000000")]
    meshes: Vec<String>,
    /// Builds of each tree; the median counts.
    #[arg(long, default_value_t = 3, value_parser = crate::args::pass_count())]
    runs: usize,
    #[command(flatten)]
    output: OutputArgs,
}

/// One mesh's builds.
#[derive(Debug, Clone, Serialize)]
pub struct BuildRow {
    pub mesh: String,
    pub triangles: usize,
    /// Median DOP-tree build (k = 18) on one thread.
    pub dop_1_thread_s: f64,
    /// Median DOP-tree build on all of rayon's threads.
    pub dop_all_threads_s: f64,
    pub threads: usize,
    pub dop_bytes_per_triangle: f64,
    /// Median FCL OBB-tree build, or `None` without the harness.
    pub fcl_obb_s: Option<f64>,
    pub fcl_bytes_per_triangle: Option<f64>,
    /// `dop_all_threads_s` over FCL's median (or over the reference time without the harness).
    pub ratio: f64,
    /// `dop_1_thread_s` over the same.
    pub ratio_1_thread: f64,
    /// Whether the ratios are against FCL measured in this run.
    pub ratio_measured: bool,
}

/// What the FCL harness prints.
#[derive(Debug, Deserialize)]
struct FclBuilds {
    seconds: Vec<f64>,
    bytes: u64,
}

pub fn run(args: &TreeBuildArgs) -> Result<()> {
    if FCL_HARNESS.is_none() {
        println!(
            "FCL was not found when vas-bench was built (Debian: libfcl-dev); ratios are against \
             {FCL_REFERENCE_S} s"
        );
    }
    let set = OrientationSet::new(DEFAULT_K).expect("the default orientations");
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut rows = Vec::new();
    for spec in &args.meshes {
        let mesh = parse_mesh_spec(spec).with_context(|| format!("mesh {spec}"))?;
        let triangles = mesh.triangles().len();
        let mut bytes = 0;
        let mut build = || {
            let started = Instant::now();
            let tree = DopTree::with_orientations(&mesh, &set);
            bytes = tree.bytes();
            started.elapsed().as_secs_f64()
        };
        let mut one: Vec<f64> = (0..args.runs)
            .map(|_| one_thread.install(&mut build))
            .collect();
        let mut all: Vec<f64> = (0..args.runs).map(|_| build()).collect();
        let (dop_1_thread_s, dop_all_threads_s) = (median(&mut one), median(&mut all));
        let mut fcl = match FCL_HARNESS {
            Some(harness) => Some(fcl_builds(Path::new(harness), &mesh, args.runs)?),
            None => None,
        };
        let fcl_obb_s = fcl.as_mut().map(|f| median(&mut f.seconds));
        let against = fcl_obb_s.unwrap_or(FCL_REFERENCE_S);
        let row = BuildRow {
            mesh: spec.clone(),
            triangles,
            dop_1_thread_s,
            dop_all_threads_s,
            threads: rayon::current_num_threads(),
            dop_bytes_per_triangle: bytes as f64 / triangles as f64,
            fcl_obb_s,
            fcl_bytes_per_triangle: fcl.map(|f| f.bytes as f64 / triangles as f64),
            ratio: dop_all_threads_s / against,
            ratio_1_thread: dop_1_thread_s / against,
            ratio_measured: fcl_obb_s.is_some(),
        };
        println!(
            "{spec}: DOP-tree {} s, FCL {} s",
            format_number(row.dop_all_threads_s),
            row.fcl_obb_s.map_or("-".to_owned(), format_number)
        );
        rows.push(row);
    }
    print!("{}", render(&rows));
    args.output.write(&rows, || plot(&rows))
}

/// FCL's builds of `mesh`, `runs` of them, by the harness in its own process.
fn fcl_builds(harness: &Path, mesh: &TriMesh, runs: usize) -> Result<FclBuilds> {
    let folder = tempfile::tempdir()?;
    let file = folder.path().join("mesh.bin");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&file)?);
    out.write_all(&(mesh.vertices().len() as u64).to_le_bytes())?;
    out.write_all(&(mesh.triangles().len() as u64).to_le_bytes())?;
    for vertex in mesh.vertices() {
        for x in vertex.coords.iter() {
            out.write_all(&x.to_le_bytes())?;
        }
    }
    for index in mesh.triangles().iter().flatten() {
        out.write_all(&index.to_le_bytes())?;
    }
    out.flush()?;
    drop(out);
    let output = Command::new(harness)
        .arg(&file)
        .arg(runs.to_string())
        .output()
        .with_context(|| format!("running {}", harness.display()))?;
    if !output.status.success() {
        bail!(
            "{} failed: {}",
            harness.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    serde_json::from_slice(&output.stdout).context("reading the FCL harness's output")
}

fn render(rows: &[BuildRow]) -> String {
    let mut table = Table::new([
        "mesh",
        "triangles",
        "dop_1_thread_s",
        "dop_all_threads_s",
        "dop_bytes_per_tri",
        "fcl_obb_s",
        "fcl_bytes_per_tri",
        "ratio_1_thread",
        "ratio",
    ]);
    let optional = |value: Option<f64>| value.map_or("-".to_owned(), format_number);
    let ratio = |value: f64, measured: bool| {
        format!(
            "{}{}",
            format_number(value),
            if measured { "" } else { " (ref)" }
        )
    };
    for row in rows {
        table.push_row([
            row.mesh.clone(),
            row.triangles.to_string(),
            format_number(row.dop_1_thread_s),
            format_number(row.dop_all_threads_s),
            format_number(row.dop_bytes_per_triangle),
            optional(row.fcl_obb_s),
            optional(row.fcl_bytes_per_triangle),
            ratio(row.ratio_1_thread, row.ratio_measured),
            ratio(row.ratio, row.ratio_measured),
        ]);
    }
    table.render()
}

/// Build seconds against triangles, one series per builder.
fn plot(rows: &[BuildRow]) -> LinePlot {
    let series = |name: &str, value: fn(&BuildRow) -> Option<f64>| Series {
        name: name.to_owned(),
        points: rows
            .iter()
            .filter_map(|r| Some((r.triangles as f64, value(r)?)))
            .collect(),
    };
    LinePlot {
        title: "Tree build".to_owned(),
        x_label: "triangles".to_owned(),
        y_label: "seconds".to_owned(),
        log_x: true,
        log_y: true,
        series: vec![
            series("DOP-tree, 1 thread", |r| Some(r.dop_1_thread_s)),
            series("DOP-tree, all threads", |r| Some(r.dop_all_threads_s)),
            series("FCL OBB-tree", |r| r.fcl_obb_s),
        ],
    }
}
