//! The `vas-server` command line.

use std::io::IsTerminal;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use tracing_subscriber::EnvFilter;
use vas_server::collision::dop_tree::{Provenance, TreeCache};
use vas_server::geometry::shapes::{self, ShapeKind};
use vas_server::geometry::{FileLimits, write_obj};
use vas_server::runtime;
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
        /// Also build every part's DOP-tree and convex hull, as a server does before it
        /// answers input, with a progress bar, and say how long that took.
        #[arg(long)]
        prepare: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
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
            load,
        } => load.options().and_then(|load| {
            runtime::run(&runtime::RunOptions {
                scene: scene.unwrap_or_else(default_scene_path),
                scenes,
                prefix,
                lockstep,
                load,
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
/// its parts' trees and hulls with a progress bar (on a terminal) and prints the time.
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
            "\nprepared (DOP-trees and convex hulls of {} parts) in {:.2} s",
            scene.parts.len(),
            started.elapsed().as_secs_f64()
        ));
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
