//! The `vas-client` tool: watch a server's frames, record and replay input, send samples from
//! scripts, print the scene, and reset, load scenes or set the sliding metaphor. (The latency benchmark and the soak are `vas-bench e2e` and `soak`.)

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Talks to a vas server over iceoryx2 shared memory.
#[derive(Debug, Parser)]
#[command(name = "vas-client", version, about)]
struct Args {
    /// iceoryx2 prefix of the server (its `--prefix`); default: the iceoryx2 configuration's.
    #[arg(long, global = true)]
    prefix: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print every frame as a JSON line on stdout, codes also in words.
    Watch {
        /// Stop after this many frames.
        #[arg(long)]
        count: Option<u64>,
    },
    /// Print the server's scene (parts, meshes, ids) and input counters as JSON.
    Info,
    /// Record the tracker, glove and hand-joints input that reaches the server, as JSON Lines.
    Record(cli::record::RecordArgs),
    /// Play a recording into the server.
    Replay(cli::replay::ReplayArgs),
    /// Send one tracker sample.
    SendTracker(cli::send::TrackerArgs),
    /// Send one glove sample.
    SendGlove(cli::send::GloveArgs),
    /// Send one hand-joints sample (26 OpenXR joints of one hand) read from JSON.
    SendHandJoints(cli::send::HandJointsArgs),
    /// Put the scene back to its initial state.
    Reset,
    /// Replace the served scene by a scene file, or by a scene the server offers by name.
    LoadScene(cli::control::LoadSceneArgs),
    /// List the scenes the server offers by name.
    Scenes,
    /// Choose how grasped parts follow the hand.
    SetMetaphor {
        /// The sliding metaphor.
        #[arg(value_parser = cli::control::metaphor_parser())]
        metaphor: vas_client::SlidingMetaphor,
    },
}

fn main() -> ExitCode {
    let args = Args::parse();
    cli::init_logging();
    let prefix = args.prefix.as_deref();
    let outcome = match args.command {
        Command::Watch { count } => cli::watch::run(prefix, count),
        Command::Info => cli::info(prefix),
        Command::Record(record) => cli::record::run(prefix, &record),
        Command::Replay(replay) => cli::replay::run(prefix, &replay),
        Command::SendTracker(tracker) => cli::send::tracker(prefix, &tracker),
        Command::SendGlove(glove) => cli::send::glove(prefix, &glove),
        Command::SendHandJoints(joints) => cli::send::hand_joints(prefix, &joints),
        Command::Reset => cli::control::reset(prefix),
        Command::LoadScene(load) => cli::control::load_scene(prefix, &load),
        Command::Scenes => cli::control::scenes(prefix),
        Command::SetMetaphor { metaphor } => cli::control::set_metaphor(prefix, metaphor),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`watch | head`): nothing is wrong.
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            tracing::error!("{error:#}");
            ExitCode::FAILURE
        }
    }
}

/// True when `error` comes from writing to a pipe whose reader has exited.
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
