//! The runtime: the iceoryx2 ports, the three loops and their rendezvous, clean start and stop.
//!
//! This is the only module that knows about threads and IPC. The interaction manager (`io_thread`)
//! owns every port on the main thread: it validates input, hands targets to the grasping loop,
//! publishes what the collision loop verified and answers control requests. The grasping,
//! sliding and collision loops (`loops`) each run on their own thread and meet only at the
//! hand-offs of `rendezvous`.
//!
//! Input services: `vas/input/tracker`, `vas/input/glove` and `vas/input/hand_joints`, each
//! validated and counted on the I/O thread ([`inputs`]); hand-joints samples are retargeted
//! there onto the scene's hand ([`hand_joints`]), so that the loops see one kind of hand input.
//!
//! Output services: every verified frame publishes `vas/output/hand` (answering the input sample
//! it carries the stamp of), `vas/output/parts` when a part changed (and at the scene's
//! `rates.publish_hz` regardless), `vas/output/events` and, while a part is held,
//! `vas/output/force`; a scene with a clearance threshold also has each published frame measured
//! on a thread beside the loops (`clearance`) and its pairs published on `vas/output/clearance`
//! (with their events on `vas/output/events`) as soon as they are measured. The input counters (rejected, clamped) are logged and returned in every
//! `vas/control` response (`stats`).

mod clearance;
pub mod control;
pub mod cpu_latency;
mod geometry;
pub mod hand_joints;
pub mod inputs;
mod io_thread;
mod loader;
pub(crate) mod loops;
mod meter;
mod owners;
mod ports;
pub mod priority;
pub(crate) mod rendezvous;
pub(crate) mod wakeup;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crossbeam_channel::RecvTimeoutError;

use iceoryx2::prelude::*;
use vas_protocol::services::{PrefixError, ServiceOpenError, config_with_prefix};

use crate::scene::{LoadOptions, Scene, SceneError, log_prepared};
use crate::simulation::restart::HandSetupError;
use control::Session;
use cpu_latency::{CpuLatencyError, CpuLatencyRequest};
use loops::{Links, Loops};
use priority::{PriorityError, RealtimePriority};

/// What `vas-server run` serves, and where.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The scene file to load.
    pub scene: PathBuf,
    /// The folder of the scenes that clients may load by name (a renderer's page offers
    /// them); `None` takes the scene file's folder.
    pub scenes: Option<PathBuf>,
    /// iceoryx2 prefix of every resource, so that servers (and tests) on different prefixes
    /// never meet; `None` uses the iceoryx2 configuration's.
    pub prefix: Option<String>,
    /// One frame per input sample, each handed over when the previous one was verified, and no
    /// loop steps on its own: a replay gives the same output every time.
    pub lockstep: bool,
    /// How scenes are loaded (the largest files read, the tree cache), at start-up and for a
    /// load-scene request alike.
    pub load: LoadOptions,
    /// Runs the I/O thread and the loops under `SCHED_FIFO` at this priority, so that a busy
    /// renderer on the same cores does not delay them ([`priority`]); `None` keeps the normal
    /// policy.
    pub realtime: Option<RealtimePriority>,
    /// Holds every core's wake-up latency within this many microseconds while serving (0: idle
    /// cores poll), so that no sample or frame waits for a core to leave a deep idle state
    /// ([`cpu_latency`]); `None` leaves the cores' idle states to the system.
    pub cpu_latency: Option<u32>,
}

/// Why the server could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene's hand could not be set up.
    #[error(transparent)]
    Hand(#[from] HandSetupError),
    /// A loop thread could not be started.
    #[error("cannot start the loop threads: {0}")]
    Thread(#[from] std::io::Error),
    /// The realtime priority asked for cannot be had.
    #[error(transparent)]
    Priority(#[from] PriorityError),
    /// The CPU latency asked for cannot be requested.
    #[error(transparent)]
    CpuLatency(#[from] CpuLatencyError),
    /// The thread loading the scene to serve ended without a scene (it panicked; the log says
    /// where).
    #[error("the scene loader failed; the log says where")]
    LoaderFailed,
    /// A loop thread ended unexpectedly (it panicked; the log says where).
    #[error("a simulation loop ended unexpectedly")]
    LoopEnded,
    /// The prefix is not usable by iceoryx2.
    #[error(transparent)]
    Prefix(#[from] PrefixError),
    /// A service could not be opened (its settings or types do not match).
    #[error(transparent)]
    Service(#[from] ServiceOpenError),
    /// A port could not be created (for instance a second publisher on an output service: another
    /// server already runs on this prefix).
    #[error("cannot create a port on {service}: {reason}")]
    Port {
        /// The service.
        service: &'static str,
        /// What iceoryx2 reported.
        reason: String,
    },
    /// Another server already serves the prefix (each output service takes one publisher).
    #[error(
        "another vas server already serves this prefix: stop it, or start this one with another \
         --prefix"
    )]
    PrefixInUse,
    /// An iceoryx2 operation failed.
    #[error("cannot {action}: {reason}")]
    Ipc {
        /// What the server was doing.
        action: &'static str,
        /// What iceoryx2 reported.
        reason: String,
    },
    /// The scene's publish rate cannot drive a loop.
    #[error(
        "the publish rate must be positive, finite and below 1 GHz, not {} Hz",
        vas_protocol::Readable(*hz)
    )]
    PublishRate {
        /// The configured rate.
        hz: f64,
    },
}

impl RuntimeError {
    /// A [`RuntimeError::Ipc`] for `action` from any iceoryx2 error.
    fn ipc(action: &'static str, error: impl std::fmt::Debug) -> Self {
        Self::Ipc {
            action,
            reason: format!("{error:?}"),
        }
    }
}

/// Runs the server until SIGINT or SIGTERM: cleans up the resources of dead nodes, loads the
/// scene, opens the services, serves. Returns `Ok` on a clean shutdown.
pub fn run(options: &RunOptions) -> Result<(), RuntimeError> {
    // First of all, so that a server that cannot have the priority or latency asked for says so
    // at once.
    if let Some(priority) = options.realtime {
        priority.raise_this_thread()?;
        tracing::info!(
            priority = priority.get(),
            "the I/O thread and the loops run under SCHED_FIFO"
        );
    }
    // Held until the server returns.
    let _cpu_latency = match options.cpu_latency {
        Some(microseconds) => {
            let request = CpuLatencyRequest::hold(microseconds)?;
            tracing::info!(microseconds, "holding the cores' wake-up latency");
            Some(request)
        }
        None => None,
    };
    let config = config_with_prefix(options.prefix.as_deref())?;
    let name =
        NodeName::new("vas-server").map_err(|error| RuntimeError::ipc("name the node", error))?;
    // Creating the node removes the resources of dead ones by itself; count them first, so that
    // the log says what was cleaned.
    let dead_nodes_found = dead_nodes(&config);
    let node = NodeBuilder::new()
        .name(&name)
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|error| RuntimeError::ipc("create the iceoryx2 node", error))?;
    // The first wait installs the SIGINT/SIGTERM handlers, so that a signal during the scene
    // loading below still ends the server cleanly.
    if termination_requested(&node) {
        return Ok(());
    }
    let dead_nodes_left = dead_nodes(&config);
    tracing::info!(
        prefix = options.prefix.as_deref().unwrap_or("(iceoryx2 default)"),
        dead_nodes_cleaned = dead_nodes_found.saturating_sub(dead_nodes_left),
        dead_nodes_left,
        "node created"
    );

    let Some(scene) = load_to_serve(&node, options)? else {
        return Ok(());
    };
    let folder = (options.scenes.clone())
        .or_else(|| options.scene.parent().map(Path::to_path_buf))
        .unwrap_or_default();
    let catalogue = control::SceneCatalogue::of(folder);
    tracing::info!(scenes = ?catalogue.names(), "scenes offered by name");
    let (session, start) = Session::start(scene, catalogue)?;
    if termination_requested(&node) {
        return Ok(());
    }
    let links = Links::default();
    let (verified_in, verified_out) = crossbeam_channel::unbounded();
    let (waker, wakeups) =
        wakeup::channel().map_err(|error| RuntimeError::ipc("make the wake-up socket", error))?;
    let manager = io_thread::InteractionManager::new(
        &node,
        session,
        &start,
        &links,
        verified_out,
        (waker.clone(), wakeups),
        options,
    )?;
    let loops = Loops::spawn(
        &links,
        options.lockstep,
        options.realtime,
        verified_in,
        waker,
    )?;
    let served = manager.serve(start.into_change(), &loops);
    links.inputs.close();
    loops.join(LOOPS_PATIENCE);
    served
}

/// The interval between parts frames at `hz`, or an error for a rate no loop can run at.
/// How often the main thread looks for a termination request while the scene loads.
const TERMINATION_POLL: Duration = Duration::from_millis(50);

/// How long the loops may take to end once termination is requested.
const LOOPS_PATIENCE: Duration = Duration::from_millis(500);

/// Loads the scene to serve on a thread of its own, while this thread watches for a termination
/// request: reading or generating large meshes takes seconds, and SIGINT or SIGTERM meanwhile
/// stops the server at once (the loading thread, which holds nothing but memory, is
/// abandoned). `None` when termination was requested.
///
/// The loaded scene's trees, hulls and adjacency are then built in the background, the parts in
/// parallel ([`Scene::prepare`]), and the loops, which need them for their first frame, wait for
/// the builds under way rather than repeat them. The server serves the scene's description and
/// geometry once its hands are set up; their segment trees are built in rayon's pool too, where
/// they may wait behind the parts.
fn load_to_serve(
    node: &Node<ipc::Service>,
    options: &RunOptions,
) -> Result<Option<Scene>, RuntimeError> {
    let (sender, loaded) = crossbeam_channel::bounded(1);
    let (path, load) = (options.scene.clone(), options.load.clone());
    std::thread::Builder::new()
        .name("scene-loader".into())
        .spawn(move || {
            let started = Instant::now();
            let scene = Scene::load_with(&path, &load);
            if let Ok(scene) = &scene {
                tracing::info!(
                    scene = scene.name,
                    source = %scene.source.display(),
                    parts = scene.parts.len(),
                    triangles = scene.triangle_count(),
                    publish_hz = scene.rates.publish_hz,
                    seconds = started.elapsed().as_secs_f64(),
                    "scene loaded"
                );
                // Parts are cheap to clone: their meshes and trees are shared.
                let parts = scene.parts.clone();
                let name = scene.name.clone();
                let spawned = std::thread::Builder::new()
                    .name("scene-preparer".into())
                    .spawn(move || {
                        Scene::prepare_parts(&parts, &log_prepared(&name, &parts));
                        tracing::info!(
                            scene = name,
                            seconds = started.elapsed().as_secs_f64(),
                            "scene ready"
                        );
                    });
                if let Err(error) = spawned {
                    tracing::warn!(%error, "cannot prepare the scene in the background; the loops will");
                }
            }
            // The receiver is gone only when termination was requested.
            let _ = sender.send(scene);
        })?;
    loop {
        match loaded.recv_timeout(TERMINATION_POLL) {
            Ok(scene) => return Ok(Some(scene?)),
            Err(RecvTimeoutError::Timeout) => {
                if termination_requested(node) {
                    return Ok(None);
                }
            }
            Err(RecvTimeoutError::Disconnected) => return Err(RuntimeError::LoaderFailed),
        }
    }
}

fn publish_period(hz: f64) -> Result<Duration, RuntimeError> {
    Duration::try_from_secs_f64(1.0 / hz)
        .ok()
        .filter(|period| !period.is_zero())
        .ok_or(RuntimeError::PublishRate { hz })
}

/// How many nodes on this configuration's prefix belong to processes that died.
fn dead_nodes(config: &iceoryx2::config::Config) -> usize {
    let mut dead = 0;
    // A listing that fails counts what it saw: the count only goes to the log.
    let _ = Node::<ipc::Service>::list(config, |state| {
        dead += usize::from(matches!(state, NodeState::Dead(_)));
        CallbackProgression::Continue
    });
    dead
}

fn termination_requested(node: &Node<ipc::Service>) -> bool {
    let requested = node.wait(Duration::ZERO).is_err();
    if requested {
        tracing::info!("termination requested before serving; shutting down");
    }
    requested
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn publish_periods_come_from_positive_finite_rates_only() {
        let period = publish_period(60.0).expect("60 Hz");
        assert!((period.as_secs_f64() - 1.0 / 60.0).abs() < 1e-9);
        for hz in [0.0, -5.0, f64::NAN, f64::INFINITY, 1e-300, 1e12] {
            assert!(
                matches!(publish_period(hz), Err(RuntimeError::PublishRate { .. })),
                "{hz} Hz"
            );
        }
    }
}
