//! The `vas-server` command line.

use std::io::IsTerminal;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use tracing_subscriber::EnvFilter;
use vas_client::recording::{InputSample, Recording};
use vas_protocol::HandSide;
use vas_server::collision::dop_tree::{Provenance, TreeCache};
use vas_server::geometry::shapes::{self, ShapeKind};
use vas_server::geometry::{FileLimits, write_obj};
use vas_server::grasping::HandModel;
use vas_server::grasping::retarget::{Capture, HandJoints, Retargeter};
use vas_server::replay::{Outcome, Replay};
use vas_server::report::{Session, html};
use vas_server::runtime;
use vas_server::runtime::priority::RealtimePriority;
use vas_server::scene::{LoadOptions, Scene, default_scene_path};

/// vas: headless virtual-assembly simulation server.
#[derive(Debug, Parser)]
#[command(name = "vas-server", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Serve a scene over iceoryx2 until SIGINT or SIGTERM.
    Run {
        /// The scene config (default: configs/default.toml).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// The folder of the scenes clients may load by name, as a viewer's page offers them
        /// (default: the scene file's folder).
        #[arg(long)]
        scenes: Option<PathBuf>,
        /// iceoryx2 prefix of every resource, so that servers on different prefixes never meet.
        #[arg(long)]
        prefix: Option<String>,
        /// One frame per input sample, each after the previous one was verified, and no loop
        /// stepping on its own: replays give the same output every time.
        #[arg(long)]
        lockstep: bool,
        /// Run the I/O thread and the three loops under SCHED_FIFO at this priority (1-99), so
        /// that a renderer busy on the same cores does not delay them; needs CAP_SYS_NICE or an
        /// rtprio limit (`ulimit -r`). Threads they start (scene loading) keep the normal policy.
        #[arg(long, value_name = "PRIORITY", value_parser = parse_realtime)]
        realtime: Option<RealtimePriority>,
        /// Hold every core's wake-up latency within US microseconds while serving (Linux's
        /// /dev/cpu_dma_latency; 0: idle cores poll, never sleeping), so that no sample waits
        /// for a core to leave a deep idle state. Costs power; needs root.
        #[arg(long, value_name = "US", value_parser = clap::value_parser!(u32).range(0..=1_000_000))]
        cpu_latency: Option<u32>,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Write a procedural test object (unit size, centred at the origin) as an OBJ file.
    Shape {
        /// Which object.
        #[arg(value_parser = shape_kind())]
        kind: ShapeKind,
        /// About how many triangles.
        #[arg(long, default_value_t = 10_000, value_parser = triangle_count())]
        triangles: usize,
        /// The OBJ file to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Validate a scene config and print its summary; exits non-zero if it is invalid.
    CheckScene {
        /// The scene file.
        file: PathBuf,
        /// Also build every part's DOP-tree, convex hull and edge adjacency, as a server does
        /// before it answers input, with a progress bar, and say how long that took.
        #[arg(long)]
        prepare: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Retarget a captured hand pose (WebXR joints, JSON) onto the hand model: print the flex
    /// angles and each fingertip's distance from the captured tip.
    Retarget(RetargetArgs),
    /// Replay a recording in-process, one frame per sample as in lockstep, and report per part
    /// pair the minimum clearance, the contacts and the clashes (text, JSON, an HTML page).
    Report(ReportArgs),
}

/// How scenes are loaded: the largest files read (larger ones are refused with their size), the
/// most triangles taken, and where built trees are kept.
#[derive(Debug, Args)]
struct LoadArgs {
    /// The largest mesh file, in bytes or with a unit (KiB, MiB, GiB).
    #[arg(long, value_name = "SIZE", default_value = "4GiB", value_parser = parse_size)]
    max_mesh_file: u64,
    /// The largest scene or hand config file, in bytes or with a unit (KiB, MiB, GiB).
    #[arg(long, value_name = "SIZE", default_value = "16MiB", value_parser = parse_size)]
    max_config_file: u64,
    /// The most triangles of a scene's parts together (shapes and files alike).
    #[arg(long, value_name = "N", default_value_t = FileLimits::default().scene_triangles)]
    max_scene_triangles: u64,
    /// A folder (made if missing) where the parts' DOP-trees are kept once built, so that the
    /// next start reads them; a file that is stale, corrupt or not a valid tree of its mesh is
    /// built again.
    #[arg(long, value_name = "DIR")]
    tree_cache: Option<PathBuf>,
}

impl LoadArgs {
    fn options(&self) -> anyhow::Result<LoadOptions> {
        let tree_cache = match &self.tree_cache {
            Some(folder) => Some(Arc::new(TreeCache::open(folder).map_err(|error| {
                anyhow::anyhow!("cannot use {} as the tree cache: {error}", folder.display())
            })?)),
            None => None,
        };
        Ok(LoadOptions {
            limits: FileLimits {
                mesh_bytes: self.max_mesh_file,
                config_bytes: self.max_config_file,
                scene_triangles: self.max_scene_triangles,
            },
            tree_cache,
        })
    }
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();
    let result = match Cli::parse().command {
        Command::Run {
            scene,
            scenes,
            prefix,
            lockstep,
            realtime,
            cpu_latency,
            load,
        } => load.options().and_then(|load| {
            runtime::run(&runtime::RunOptions {
                scene: scene.unwrap_or_else(default_scene_path),
                scenes,
                prefix,
                lockstep,
                load,
                realtime,
                cpu_latency,
            })
            .map_err(Into::into)
        }),
        Command::Shape {
            kind,
            triangles,
            out,
        } => write_shape(kind, triangles, &out),
        Command::CheckScene {
            file,
            prepare,
            load,
        } => load
            .options()
            .and_then(|load| check_scene(&file, prepare, &load)),
        Command::Retarget(args) => retarget(&args),
        Command::Report(args) => report(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // Our errors name the file and the reason in their message; the chain would repeat it.
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}

/// `vas-server check-scene`: loads the scene, prints its summary and, with `prepare`, builds
/// its parts' trees, hulls and adjacency with a progress bar (on a terminal), prints the time,
/// and names the pairs of parts that collide where the scene places them.
fn check_scene(file: &Path, prepare: bool, load: &LoadOptions) -> anyhow::Result<()> {
    let scene = Scene::load_with(file, load)?;
    let mut report = scene.summary();
    if prepare {
        let started = std::time::Instant::now();
        let bar = indicatif::ProgressBar::new(scene.triangle_count() as u64).with_style(
            indicatif::ProgressStyle::with_template(
                "preparing {bar:40} {percent}% of the triangles, last ready: {msg}",
            )?,
        );
        Scene::prepare_parts(&scene.parts, &|part, _| {
            bar.set_message(part.name.clone());
            bar.inc(part.mesh.triangles().len() as u64);
        });
        bar.finish_and_clear();
        report.push_str(&format!(
            "\nprepared (DOP-trees, convex hulls and edge adjacency of {} parts) in {:.2} s",
            scene.parts.len(),
            started.elapsed().as_secs_f64()
        ));
        let colliding = scene.colliding_as_placed();
        report.push_str(&if colliding.is_empty() {
            "\nno parts collide as the scene places them".to_owned()
        } else {
            format!(
                "\nparts collide as the scene places them (not checked until they part): {}",
                scene.pair_names(&colliding)
            )
        });
        if let Some(cache) = &load.tree_cache {
            let read = (scene.parts.iter())
                .filter(|part| part.tree.provenance() == Some(Provenance::Read))
                .count();
            report.push_str(&format!(
                "\ntrees of {read} of {} parts read from the tree cache {}",
                scene.parts.len(),
                cache.folder().display()
            ));
        }
    }
    match writeln!(std::io::stdout().lock(), "{report}") {
        // The reader went away (`check-scene ... | head`): nothing is wrong.
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        written => written.map_err(Into::into),
    }
}

/// What `vas-server retarget` is asked.
#[derive(Debug, Args)]
struct RetargetArgs {
    /// The capture to retarget.
    capture: PathBuf,
    /// Calibrate the model on this capture of the same hand first.
    #[arg(long, value_name = "CAPTURE")]
    calibrate: Option<PathBuf>,
    /// The hand model (default: configs/hands/left.toml or right.toml, by the capture's side).
    #[arg(long)]
    hand: Option<PathBuf>,
    /// Mirror the captures first: a left hand becomes a right hand, and the reverse.
    #[arg(long)]
    mirror: bool,
    /// Also write the result as JSON to this file.
    #[arg(long, value_name = "OUT")]
    json: Option<PathBuf>,
    /// Retarget this many times and print the mean time per sample.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
}

/// `vas-server retarget`: retargets a capture, optionally on a model calibrated on another, and
/// prints the angles and the fingertip error (and writes them as JSON).
fn retarget(args: &RetargetArgs) -> anyhow::Result<()> {
    let read = |path: &Path| -> anyhow::Result<HandJoints> {
        let capture = Capture::read(path)?;
        Ok(if args.mirror {
            capture.mirrored()
        } else {
            capture
        }
        .joints)
    };
    let joints = read(&args.capture)?;
    let hand = args.hand.clone().unwrap_or_else(|| {
        let file = match joints.side {
            HandSide::Left => "left.toml",
            HandSide::Right => "right.toml",
        };
        default_scene_path().with_file_name("hands").join(file)
    });
    let mut retargeter = Retargeter::new(HandModel::load(&hand)?)?;
    if let Some(path) = &args.calibrate {
        retargeter = retargeter.calibrated(&read(path)?)?;
    }
    let started = std::time::Instant::now();
    let mut fit = retargeter.fit(&joints)?;
    for _ in 1..args.repeat {
        fit = retargeter.fit(std::hint::black_box(&joints))?;
    }
    let per_sample_us = started.elapsed().as_secs_f64() * 1e6 / f64::from(args.repeat);
    let error = retargeter.fingertip_distances(&fit, &joints);

    let mut text = format!(
        "{}: {:?} hand, model {}{}\nangles (degrees):\n",
        args.capture.display(),
        joints.side,
        hand.display(),
        match &args.calibrate {
            Some(path) => format!(", calibrated on {}", path.display()),
            None => String::new(),
        }
    );
    let limits = retargeter.model().limits();
    for (limit, value) in limits.iter().zip(fit.flex) {
        text.push_str(&format!(
            "  {:<24} {:>7.2}\n",
            limit.name,
            value.to_degrees()
        ));
    }
    text.push_str("fingertip error (mm):");
    for (finger, distance) in error.digits() {
        text.push_str(&format!(" {finger:?} {:.2}", distance * 1e3));
    }
    text.push_str(&format!(
        "; rms {:.2}, max {:.2}\nretargeted {} times, {:.2} us per sample\n",
        error.rms() * 1e3,
        error.max() * 1e3,
        args.repeat,
        per_sample_us
    ));
    print!("{text}");

    if let Some(out) = &args.json {
        let angles: serde_json::Map<String, serde_json::Value> = limits
            .iter()
            .zip(fit.flex)
            .map(|(limit, value)| (limit.name.clone(), value.to_degrees().into()))
            .collect();
        let fingertips: serde_json::Map<String, serde_json::Value> = error
            .digits()
            .map(|(finger, distance)| {
                (
                    format!("{finger:?}").to_lowercase(),
                    (distance * 1e3).into(),
                )
            })
            .collect();
        let report = serde_json::json!({
            "capture": args.capture,
            "side": format!("{:?}", joints.side).to_lowercase(),
            "hand": hand,
            "calibration": args.calibrate,
            "angles_deg": angles,
            "root": {
                "position": fit.root.translation.vector.as_slice(),
                "rotation": fit.root.rotation.coords.as_slice(),
            },
            "fingertip_mm": fingertips,
            "fingertip_rms_mm": error.rms() * 1e3,
            "fingertip_max_mm": error.max() * 1e3,
            "repeat": args.repeat,
            "us_per_sample": per_sample_us,
        });
        std::fs::write(out, serde_json::to_string_pretty(&report)? + "\n")
            .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", out.display()))?;
    }
    Ok(())
}

/// The clearance threshold when neither `--clearance` nor the scene gives one, metres.
const DEFAULT_CLEARANCE: f64 = 0.005;

/// What `vas-server report` is asked.
#[derive(Debug, Args)]
struct ReportArgs {
    /// The scene the recording was made in.
    #[arg(long)]
    scene: PathBuf,
    /// The recording (JSON Lines, as `vas-client record` writes it).
    recording: PathBuf,
    /// The clearance threshold in metres (default: the scene's `[params.clearance] threshold`,
    /// else 0.005).
    #[arg(long, value_name = "M", value_parser = parse_clearance)]
    clearance: Option<f64>,
    /// Also write the report as JSON to this file.
    #[arg(long, value_name = "OUT")]
    json: Option<PathBuf>,
    /// Also write the report as one self-contained HTML page to this file.
    #[arg(long, value_name = "OUT")]
    html: Option<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
}

/// `vas-server report`: replays the recording in the scene, measures every pair of parts with
/// a movable one, prints the pairs that came within the threshold and writes the JSON and HTML.
fn report(args: &ReportArgs) -> anyhow::Result<()> {
    let scene = Scene::load_with(&args.scene, &args.load.options()?)?;
    let recording = Recording::load(&args.recording)?;
    if recording.header.scene != scene.name {
        anyhow::bail!(
            "{} was recorded in scene {:?}, but {} is scene {:?}",
            args.recording.display(),
            recording.header.scene,
            args.scene.display(),
            scene.name
        );
    }
    // The outputs are created first, so that a path that cannot be written fails at once.
    let create = |path: &Path| {
        std::fs::File::create(path)
            .map_err(|error| anyhow::anyhow!("{}: cannot write: {error}", path.display()))
    };
    let json_out = args.json.as_deref().map(create).transpose()?;
    let html_out = args.html.as_deref().map(create).transpose()?;
    let threshold = (args.clearance)
        .or(scene.params.clearance.threshold)
        .unwrap_or(DEFAULT_CLEARANCE);
    let mut replay = Replay::new(&scene)?;
    let mut session = Session::new(&scene, threshold);
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(recording.samples.len() as u64).with_style(
            indicatif::ProgressStyle::with_template(
                "replaying {bar:40} {pos}/{len} samples, {eta} left",
            )?,
        )
    } else {
        indicatif::ProgressBar::hidden()
    };
    // Stamped as `vas-client replay --lockstep` stamps them: the recording's times, ending now.
    let start_ns = vas_protocol::wall_clock_ns().saturating_sub(recording.duration_ns());
    for (index, recorded) in recording.samples.iter().enumerate() {
        let outcome = match recorded.stamped(start_ns) {
            InputSample::Tracker(sample) => replay.tracker(&sample)?,
            InputSample::Glove(sample) => replay.glove(&sample)?,
            InputSample::HandJoints(sample) => replay.hand_joints(&sample)?,
        };
        if let (Outcome::Stepped(_), Some(interaction)) = (outcome, replay.interaction()) {
            let poses: Vec<_> = interaction.part_poses().collect();
            session.observe(index, recorded.time, &poses);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if replay.frames() == 0 {
        anyhow::bail!(
            "{}: no valid tracker or hand-joints sample places the hand",
            args.recording.display()
        );
    }
    let name = (args.recording.file_name()).map_or_else(
        || args.recording.display().to_string(),
        |name| name.to_string_lossy().into_owned(),
    );
    let report = session.finish(name, recording.samples.len(), replay.rejected());
    let mut text = format!(
        "{}: {} samples, {} frames, {} refused; threshold {:.3} mm; {} of {} pairs within it\n",
        report.recording,
        report.samples,
        report.frames,
        report.rejected,
        threshold * 1e3,
        report.pairs.len(),
        report.pairs_measured
    );
    for pair in &report.pairs {
        let minimum = (pair.minimum.as_ref()).map_or_else(
            || "no distance".to_owned(),
            |m| format!("min {:.4} mm at sample {}", m.clearance_m * 1e3, m.sample),
        );
        text.push_str(&format!(
            "  {} – {}: {}, {minimum}, {:.3} s below, {} contacts, {} clash frames\n",
            pair.a,
            pair.b,
            pair.status.name(),
            pair.seconds_below,
            pair.contacts.len(),
            pair.clash_frames
        ));
    }
    print!("{text}");
    let write = |file: Option<std::fs::File>, path: &Option<PathBuf>, content: String| {
        let (Some(mut file), Some(path)) = (file, path) else {
            return Ok(());
        };
        file.write_all(content.as_bytes())
            .map_err(|error| anyhow::anyhow!("{}: cannot write: {error}", path.display()))
    };
    write(json_out, &args.json, report.json() + "\n")?;
    write(html_out, &args.html, html::page(&report))
}

/// clap's parser of a clearance threshold: a distance in metres above 0, at most a metre.
fn parse_clearance(text: &str) -> Result<f64, String> {
    let metres: f64 = (text.trim().parse())
        .map_err(|_| format!("a clearance is a distance in metres, such as 0.005, not {text:?}"))?;
    if metres > 0.0 && metres <= 1.0 {
        Ok(metres)
    } else {
        Err(format!(
            "a clearance must be above 0 and at most 1 m, not {text}"
        ))
    }
}

/// `vas-server shape`: builds the object and writes it as OBJ.
fn write_shape(kind: ShapeKind, triangles: usize, out: &Path) -> anyhow::Result<()> {
    let mesh = shapes::build(kind, triangles);
    write_obj(&mesh, out)?;
    println!(
        "wrote {kind} with {} triangles and {} vertices to {}",
        mesh.triangles().len(),
        mesh.vertices().len(),
        out.display()
    );
    Ok(())
}

/// clap's parser of a shape's name, listing the names in `--help`.
fn shape_kind() -> impl TypedValueParser<Value = ShapeKind> {
    PossibleValuesParser::new(ShapeKind::names()).map(|name| {
        name.parse()
            .expect("the possible values are the kinds' own names")
    })
}

/// clap's parser of a realtime priority.
fn parse_realtime(text: &str) -> Result<RealtimePriority, String> {
    let number = text
        .trim()
        .parse::<u64>()
        .map_err(|_| format!("a realtime priority is a whole number, 1 to 99, not {text:?}"))?;
    RealtimePriority::new(number).map_err(|error| error.to_string())
}

/// clap's parser of a file size: a whole number of bytes, or of KiB, MiB or GiB (`512MiB`).
fn parse_size(text: &str) -> Result<u64, String> {
    let text = text.trim();
    let split = text
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let shift = match unit.trim() {
        "" | "B" => 0,
        "KiB" => 10,
        "MiB" => 20,
        "GiB" => 30,
        other => return Err(format!("unknown unit {other:?}; use B, KiB, MiB or GiB")),
    };
    let number: u64 = number
        .parse()
        .map_err(|_| format!("{text:?} is not a size such as 4096 or 64MiB"))?;
    number
        .checked_mul(1 << shift)
        .filter(|&bytes| bytes > 0)
        .ok_or_else(|| format!("{text:?} must be at least 1 byte and at most 2^64 - 1 bytes"))
}

/// clap's parser of a procedural shape's triangle count: from 1 to
/// [`MAX_TRIANGLES`](shapes::MAX_TRIANGLES), as a scene config allows.
fn triangle_count() -> impl TypedValueParser<Value = usize> {
    clap::value_parser!(u64)
        .range(1..=shapes::MAX_TRIANGLES as u64)
        .map(|count| count as usize)
}
