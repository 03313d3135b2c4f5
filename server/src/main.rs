//! The `vas-server` command line.

use std::io::IsTerminal;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use tracing_subscriber::EnvFilter;
use vas_server::geometry::shapes::{self, ShapeKind};
use vas_server::geometry::write_obj;
use vas_server::runtime;
use vas_server::scene::{Scene, default_scene_path};

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
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();
    let result =
        match Cli::parse().command {
            Command::Run {
                scene,
                scenes,
                prefix,
                lockstep,
            } => runtime::run(&runtime::RunOptions {
                scene: scene.unwrap_or_else(default_scene_path),
                scenes,
                prefix,
                lockstep,
            })
            .map_err(Into::into),
            Command::Shape {
                kind,
                triangles,
                out,
            } => write_shape(kind, triangles, &out),
            Command::CheckScene { file } => Scene::load(&file)
                .map_err(anyhow::Error::from)
                .and_then(|scene| {
                    match writeln!(std::io::stdout().lock(), "{}", scene.summary()) {
                        // The reader went away (`check-scene ... | head`): nothing is wrong.
                        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
                        written => written.map_err(Into::into),
                    }
                }),
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

/// clap's parser of a procedural shape's triangle count: from 1 to
/// [`MAX_TRIANGLES`](shapes::MAX_TRIANGLES), as a scene config allows.
fn triangle_count() -> impl TypedValueParser<Value = usize> {
    clap::value_parser!(u64)
        .range(1..=shapes::MAX_TRIANGLES as u64)
        .map(|count| count as usize)
}
