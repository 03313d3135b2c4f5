//! B8, a big assembly: a car-like assembly of 1,000 parts and 5M triangles ([`generate`]) is
//! written as STL files and a scene before the server starts. `vas-server run` starts on it
//! twice with a tree cache: cold (the cache empty, so every tree is built and stored), then
//! cached (every tree read). Each run is timed from its start to the answer to its first input
//! sample. In the cached run the scene is reset (a restart closes the loops' rate windows, so
//! that start-up stays out of their figures) and the hand is driven at 1 kHz along the scripted
//! path ([`path`]): it grasps the bar, presses its end onto the right side panel and slides it
//! along. Each tracker sample is timed to its answer (B7's procedure), the loops' rates and
//! 99th percentiles come from the server's log ([`loop_log`]), and every published pose of the
//! bar is checked against the static parts near its path with parry.
//!
//! B12 is the same run with `--clearance 0.005`: the scene watches the held bar against every
//! other part for pairs closer than 5 mm, and the report adds the clearance stage's time per
//! frame (its "loop rate" lines) and the pairs the clearance frames listed.

mod drive;
mod generate;
mod loop_log;
mod meshes;
mod path;
mod report;

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use vas_client::latency::LatencySummary;
use vas_client::recording::InputSample;
use vas_server::geometry::load_mesh;
use vas_testkit::script::Keyframe;

use crate::args::{CONTROL_TIMEOUT, MAX_TIMEOUT_MS, OutputArgs};
use crate::e2e::round_trip;
use crate::oracle::PenetrationOracle;
use crate::process::{ReadyServer, ServerProcess, server_binary, status_kib};
use crate::report::format_number;
use drive::{Drive, RATE_HZ};
use generate::{Assembly, AssemblySpec, BAR_ID};
use loop_log::LoopFigures;
use path::ScriptedPath;
use report::{AssemblyReport, ClearanceFigures};

/// Command line of `vas-bench assembly`.
#[derive(Debug, clap::Args)]
pub struct AssemblyArgs {
    /// Parts in all: the grasped bar, six body panels and small fittings.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(AssemblySpec::FIXED_PARTS as u64..=100_000))]
    parts: u64,
    /// Triangles in all.
    #[arg(long, default_value_t = 5_000_000, value_parser = clap::value_parser!(u64).range(10_000..=50_000_000))]
    triangles: u64,
    /// Seconds the bar slides along the panel (after about 1.3 s of grasping and carrying).
    #[arg(long, default_value_t = 5.0, value_parser = slide_seconds)]
    seconds: f64,
    /// Seed of the fittings' kinds, sizes and places.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// B12: watch the clearance of the held bar against every other part, reporting pairs
    /// closer than this many metres (the scene's `[params.clearance] threshold`).
    #[arg(long, value_name = "METRES", value_parser = clearance_threshold)]
    clearance: Option<f64>,
    /// Where to write the meshes, the scene, the tree cache and the servers' logs (kept);
    /// default: a temporary folder, removed at the end.
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// The right hand's model.
    #[arg(long, default_value = "configs/hands/right.toml")]
    hand: PathBuf,
    /// The server binary; default: `vas-server` beside this program.
    #[arg(long, value_name = "PATH")]
    server: Option<PathBuf>,
    /// How long the server may take to answer its first sample, in seconds.
    #[arg(long, default_value_t = 600)]
    timeout_s: u64,
    /// How long to wait for the answer to each sample of the drive before counting it
    /// unanswered, in ms.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=MAX_TIMEOUT_MS))]
    answer_timeout_ms: u64,
    #[command(flatten)]
    output: OutputArgs,
}

/// clap's parser of the slide's duration: from a tenth of a second to an hour.
fn slide_seconds(text: &str) -> Result<f64, String> {
    let seconds = crate::args::finite_number(text)?;
    if (0.1..=3600.0).contains(&seconds) {
        Ok(seconds)
    } else {
        Err(format!("{seconds} is not between 0.1 and 3600 seconds"))
    }
}

/// clap's parser of the clearance threshold: above 0 and at most a metre, as scenes take it.
fn clearance_threshold(text: &str) -> Result<f64, String> {
    let metres = crate::args::finite_number(text)?;
    if metres > 0.0 && metres <= 1.0 {
        Ok(metres)
    } else {
        Err(format!("{metres} is not above 0 and at most 1 metre"))
    }
}

/// Adds the clearance watch of the held part at `threshold` metres to the scene file `scene`.
fn watch_clearance(scene: &Path, threshold: f64) -> Result<()> {
    use std::io::Write;
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(scene)
        .with_context(|| format!("opening {}", scene.display()))?;
    write!(
        file,
        "\n[params.clearance]\nthreshold = {threshold:?}\nparts = \"held\"\n"
    )
    .with_context(|| format!("writing {}", scene.display()))
}

pub fn run(args: &AssemblyArgs) -> Result<()> {
    let scratch = match &args.dir {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("making {}", dir.display()))?;
            None
        }
        None => Some(tempfile::tempdir().context("a scratch folder for the assembly")?),
    };
    let dir = match (&scratch, &args.dir) {
        (Some(scratch), _) => scratch.path(),
        (None, dir) => dir.as_deref().expect("a folder was given"),
    };
    let spec = AssemblySpec {
        parts: args.parts as usize,
        triangles: args.triangles as usize,
        seed: args.seed,
    };
    let path = ScriptedPath::new(args.seconds);
    let started = Instant::now();
    let assembly = generate::generate(dir, &spec, &args.hand, &path)?;
    if let Some(threshold) = args.clearance {
        watch_clearance(&assembly.scene, threshold)?;
    }
    let generate_s = started.elapsed().as_secs_f64();
    println!(
        "generated {} parts, {} triangles, in {} s",
        assembly.parts,
        assembly.triangles,
        format_number(generate_s)
    );
    let runs = Runs {
        binary: server_binary(args.server.as_deref())?,
        dir,
        scene: &assembly.scene,
        cache: dir.join("tree-cache"),
        samples: path.samples(RATE_HZ),
        timeout: Duration::from_secs(args.timeout_s),
        answer_timeout: Duration::from_millis(args.answer_timeout_ms),
    };
    let cold = runs.cold()?;
    if cold.served_triangles != assembly.triangles {
        bail!(
            "the server serves {} triangles of the {} written",
            cold.served_triangles,
            assembly.triangles
        );
    }
    let cached = runs.cached()?;
    let drive = &cached.drive;
    println!(
        "checking {} poses of the bar with parry",
        drive.bar.poses.len()
    );
    let penetrations = penetrations(&assembly, drive)?;
    let latencies: Vec<Duration> = drive
        .latencies
        .iter()
        .map(|(_, latency)| *latency)
        .collect();
    let latency = LatencySummary::from_durations(&latencies)
        .context("no sample of the drive was answered")?;
    let loop_figures = |name: &str| {
        let figures = cached.loops.get(name).copied().unwrap_or_default();
        let hz = figures.frames as f64 / drive.seconds;
        (hz, figures.p99_us, figures.max_us)
    };
    let (grasping_hz, grasping_p99_us, grasping_max_us) = loop_figures("grasping");
    let (sliding_hz, sliding_p99_us, sliding_max_us) = loop_figures("sliding");
    let (collision_hz, collision_p99_us, collision_max_us) = loop_figures("collision");
    let peak_bytes = cold.peak_kib.max(cached.peak_kib) as f64 * 1024.0;
    let report = AssemblyReport {
        parts: assembly.parts,
        triangles: cold.served_triangles,
        bar_triangles: assembly.bar_triangles,
        seed: args.seed,
        generate_s,
        ready_s_cold: cold.ready_s,
        ready_s_cached: cached.ready_s,
        tree_cache_files: cold.tree_cache_files,
        peak_rss_mb: peak_bytes / (1024.0 * 1024.0),
        bytes_per_triangle: peak_bytes / cold.served_triangles as f64,
        samples: runs.samples.len(),
        unanswered: drive.unanswered,
        drive_s: drive.seconds,
        grasped: drive.bar.grasped,
        sliding_frames: drive.bar.sliding_frames,
        slid_m: drive.bar.slid_m,
        checked_poses: drive.bar.poses.len(),
        penetrations,
        grasping_hz,
        grasping_p99_us,
        grasping_max_us,
        sliding_hz,
        sliding_p99_us,
        sliding_max_us,
        collision_hz,
        collision_p99_us,
        collision_max_us,
        e2e_p50_us: latency.p50_us,
        e2e_p99_us: latency.p99_us,
        e2e_max_us: latency.max_us,
        clearance: args.clearance.map(|threshold| {
            let stage = cached.loops.get("clearance").copied().unwrap_or_default();
            let seen = drive.clearance;
            ClearanceFigures {
                threshold_mm: threshold * 1e3,
                stage_frames: stage.frames,
                stage_p50_us: stage.p50_us,
                stage_p99_us: stage.p99_us,
                stage_max_us: stage.max_us,
                frames: seen.frames,
                frames_with_pairs: seen.frames_with_pairs,
                pairs: seen.pairs,
                most_pairs: seen.most_pairs,
                stale_pairs: seen.stale_pairs,
                closest_mm: seen.closest_m * 1e3,
            }
        }),
    };
    print!("{}", report::render(&report));
    let marks = [
        ("grasped", path.grasp_s()),
        ("slide starts", path.slide_s()),
    ];
    args.output
        .write(&report, || report::plot(&report, &drive.latencies, marks))
}

/// The two runs of the server on the generated scene, each with the tree cache.
struct Runs<'a> {
    binary: PathBuf,
    /// Where the servers' logs go.
    dir: &'a Path,
    scene: &'a Path,
    cache: PathBuf,
    /// The path, sampled at [`RATE_HZ`].
    samples: Vec<Keyframe>,
    /// How long a server may take to answer its first sample.
    timeout: Duration,
    /// How long a sample of the drive may wait for its answer.
    answer_timeout: Duration,
}

/// What the cold run measured.
struct ColdRun {
    ready_s: f64,
    /// The server's VmHWM.
    peak_kib: u64,
    /// The triangles of the geometry the server published.
    served_triangles: usize,
    /// The files the run left in the tree cache.
    tree_cache_files: usize,
}

/// What the cached run measured.
struct CachedRun {
    ready_s: f64,
    peak_kib: u64,
    drive: Drive,
    /// Each loop's figures over the drive, by name.
    loops: BTreeMap<String, LoopFigures>,
}

impl Runs<'_> {
    /// Starts the server of `run` (`cold`, `cached`) on a prefix and a log of its own, and
    /// waits for its answer to the first sample of the path.
    fn start(&self, run: &str) -> Result<ReadyServer> {
        let prefix = format!("vas_b8_{}_{run}_", std::process::id());
        let args: [&OsStr; 4] = [
            "--scene".as_ref(),
            self.scene.as_os_str(),
            "--tree-cache".as_ref(),
            self.cache.as_os_str(),
        ];
        let log = self.dir.join(format!("server-{run}.log"));
        let first = drive::tracker(&self.samples[0], 1);
        let started =
            ServerProcess::start_ready(&self.binary, &prefix, &args, &log, first, self.timeout)?;
        println!(
            "{run}: ready after {} s",
            format_number(started.ready.as_secs_f64())
        );
        Ok(started)
    }

    /// The server with the tree cache emptied: it builds and stores every tree.
    fn cold(&self) -> Result<ColdRun> {
        if self.cache.exists() {
            std::fs::remove_dir_all(&self.cache)
                .with_context(|| format!("emptying the tree cache {}", self.cache.display()))?;
        }
        let cold = self.start("cold")?;
        let geometry = (cold.client.geometry()).context("the server published no geometry")?;
        let served_triangles = geometry.parts.iter().map(|mesh| mesh.triangles.len()).sum();
        let peak_kib = status_kib(cold.server.pid(), "VmHWM")?;
        cold.server.stop(cold.client);
        let tree_cache_files = std::fs::read_dir(&self.cache)
            .with_context(|| format!("listing {}", self.cache.display()))?
            .count();
        Ok(ColdRun {
            ready_s: cold.ready.as_secs_f64(),
            peak_kib,
            served_triangles,
            tree_cache_files,
        })
    }

    /// The server with the trees the cold run stored: once it has answered, the scene is reset
    /// (which starts the loops' windows anew) and the hand driven along the path; the loops'
    /// figures are the windows they log from then on.
    fn cached(&self) -> Result<CachedRun> {
        let ReadyServer {
            server,
            mut client,
            ready,
        } = self.start("cached")?;
        client
            .reset(CONTROL_TIMEOUT)
            .context("resetting the scene")?;
        // Answered once every loop has taken the restart, and logged the window before it.
        let after_reset = InputSample::Tracker(drive::tracker(&self.samples[0], 2));
        round_trip(&mut client, after_reset, self.timeout, drop)?
            .context("no answer to the first sample after the reset")?;
        let log = server.log().to_owned();
        let windows_from = std::fs::metadata(&log).context("the server's log")?.len() as usize;
        println!("driving {} samples at {RATE_HZ} Hz", self.samples.len());
        let drive = drive::along(&mut client, &self.samples, 3, BAR_ID, self.answer_timeout)?;
        let peak_kib = status_kib(server.pid(), "VmHWM")?;
        // The loops log their last windows as the server ends.
        server.stop(client);
        let log_text = std::fs::read_to_string(&log).context("the server's log")?;
        let windows = loop_log::windows(log_text.get(windows_from..).unwrap_or_default())?;
        Ok(CachedRun {
            ready_s: ready.as_secs_f64(),
            peak_kib,
            drive,
            loops: loop_log::figures(&windows),
        })
    }
}

/// How many of the bar's published poses parry finds penetrating a static part near its path,
/// each mesh read from its file as the server read it.
fn penetrations(assembly: &Assembly, drive: &Drive) -> Result<usize> {
    let read = |file: &Path| load_mesh(file).with_context(|| format!("reading {}", file.display()));
    let bar = read(&assembly.bar_file)?;
    let near: Vec<_> = (assembly.near_path.iter())
        .map(|(file, pose)| Ok((read(file)?, *pose)))
        .collect::<Result<_>>()?;
    let oracle = PenetrationOracle::new(&bar, near.iter().map(|(mesh, pose)| (mesh, *pose)));
    Ok(drive
        .bar
        .poses
        .par_iter()
        .filter(|pose| oracle.penetrates(pose))
        .count())
}
