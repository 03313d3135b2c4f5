//! The interaction manager: the I/O thread that owns every port.

use std::time::{Duration, Instant};

use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use vas_protocol::{InputRejection, InputStats, wall_clock_ns};

use super::ports::{Ports, Wakeups};
use super::simulation::Simulation;
use super::{RuntimeError, control};

/// How often the input counters are logged, when they changed.
const STATS_LOG_PERIOD: Duration = Duration::from_secs(5);

/// Owns the ports and the simulation; validates input, publishes frames, answers control.
pub(super) struct InteractionManager {
    wakeups: Wakeups,
    io: Io,
}

/// What the loop changes: the ports it reads and writes, the simulation, the log state.
struct Io {
    ports: Ports,
    simulation: Simulation,
    logged_stats: InputStats,
    stats_logged_at: Instant,
}

impl InteractionManager {
    /// Opens the ports for the simulation's scene.
    pub(super) fn new(
        node: &Node<ipc::Service>,
        simulation: Simulation,
    ) -> Result<Self, RuntimeError> {
        let (ports, wakeups) = Ports::open(node, simulation.scene().parts.len())?;
        Ok(Self {
            wakeups,
            io: Io {
                ports,
                simulation,
                logged_stats: InputStats::default(),
                stats_logged_at: Instant::now(),
            },
        })
    }

    /// Serves until a termination signal: wakes on input and control notifications, and at the
    /// scene's publish rate to publish the parts (a scene loaded on request brings its rate).
    pub(super) fn serve(mut self) -> Result<(), RuntimeError> {
        let waitset = WaitSetBuilder::new()
            .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
            .create::<ipc::Service>()
            .map_err(|error| RuntimeError::ipc("create the WaitSet", error))?;
        let attach = |error| RuntimeError::ipc("attach to the WaitSet", error);
        let _tracker = waitset
            .attach_notification(&self.wakeups.tracker)
            .map_err(attach)?;
        let _glove = waitset
            .attach_notification(&self.wakeups.glove)
            .map_err(attach)?;
        let _control = waitset
            .attach_notification(&self.wakeups.control)
            .map_err(attach)?;
        let io = &mut self.io;
        let mut publish_hz = io.simulation.scene().rates.publish_hz;
        let publish_period = super::publish_period(publish_hz)?;
        let mut publish_tick = waitset.attach_interval(publish_period).map_err(attach)?;

        io.publish_parts();
        tracing::info!(period = ?publish_period, "serving");
        loop {
            let mut publish_due = false;
            let outcome = waitset
                .wait_and_process_once(|attachment| {
                    publish_due |= attachment.has_event_from(&publish_tick);
                    CallbackProgression::Continue
                })
                .map_err(|error| RuntimeError::ipc("wait on the WaitSet", error))?;
            if outcome == WaitSetRunResult::TerminationRequest {
                break;
            }
            // `Interrupt` means a signal cut the wait short; if it was SIGINT or SIGTERM, the
            // next wait reports the termination request.
            io.log_failure(self.wakeups.drain());
            io.process_tracker_samples();
            io.process_glove_samples();
            io.answer_control_requests();
            let scene_hz = io.simulation.scene().rates.publish_hz;
            if scene_hz != publish_hz {
                publish_hz = scene_hz;
                match super::publish_period(scene_hz) {
                    Ok(period) => {
                        publish_tick = waitset.attach_interval(period).map_err(attach)?;
                        tracing::info!(?period, "publishing at the loaded scene's rate");
                    }
                    Err(error) => tracing::error!("{error}; the publish rate stays"),
                }
            }
            if publish_due {
                io.publish_parts();
                io.log_failure(io.ports.update_connections());
                io.log_stats_if_due();
            }
        }
        tracing::info!(stats = ?io.simulation.stats(), "termination requested; shutting down");
        Ok(())
    }
}

impl Io {
    fn process_tracker_samples(&mut self) {
        loop {
            let sample = match self.ports.tracker.receive() {
                Ok(Some(sample)) => *sample.payload(),
                Ok(None) => return,
                Err(error) => {
                    return self
                        .log_failure(Err(RuntimeError::ipc("receive tracker samples", error)));
                }
            };
            match self.simulation.apply_tracker(&sample) {
                Ok(()) => self.publish_hand(),
                Err(rejection) => self.log_rejection("tracker", sample.seq, &rejection),
            }
        }
    }

    fn process_glove_samples(&mut self) {
        loop {
            let sample = match self.ports.glove.receive() {
                Ok(Some(sample)) => *sample.payload(),
                Ok(None) => return,
                Err(error) => {
                    return self
                        .log_failure(Err(RuntimeError::ipc("receive glove samples", error)));
                }
            };
            match self.simulation.apply_glove(&sample) {
                Ok(clamped) => {
                    if clamped != 0 {
                        tracing::debug!(
                            seq = sample.seq,
                            clamped = format_args!("{clamped:#x}"),
                            "glove values clamped"
                        );
                    }
                    self.publish_hand();
                }
                Err(rejection) => self.log_rejection("glove", sample.seq, &rejection),
            }
        }
    }

    fn answer_control_requests(&mut self) {
        let mut answered = false;
        loop {
            let request = match self.ports.control.receive() {
                Ok(Some(request)) => request,
                Ok(None) => break,
                Err(error) => {
                    self.log_failure(Err(RuntimeError::ipc("receive control requests", error)));
                    break;
                }
            };
            let response = control::answer(&mut self.simulation, request.payload());
            tracing::debug!(
                kind = response.kind,
                status = response.status,
                "control request answered"
            );
            if let Err(error) = request.send_copy(response) {
                self.log_failure(Err(RuntimeError::ipc("send a control response", error)));
            }
            answered = true;
        }
        if answered {
            self.log_failure(self.ports.notify_control_clients());
        }
    }

    fn publish_hand(&mut self) {
        let frame = self.simulation.hand_frame(wall_clock_ns());
        self.log_failure(self.ports.publish_hand(frame));
    }

    fn publish_parts(&mut self) {
        let (header, states) = self.simulation.parts_frame(wall_clock_ns());
        self.log_failure(self.ports.publish_parts(header, &states));
    }

    /// The first rejected sample is a warning; later ones are counted and show in the periodic
    /// summary (a broken sender must not flood the log).
    fn log_rejection(&self, stream: &str, seq: u64, rejection: &InputRejection) {
        if self.simulation.stats().rejected() == 1 {
            tracing::warn!(stream, seq, %rejection, "input rejected; further rejections are counted");
        } else {
            tracing::debug!(stream, seq, %rejection, "input rejected");
        }
    }

    fn log_stats_if_due(&mut self) {
        let stats = self.simulation.stats();
        if stats != self.logged_stats && self.stats_logged_at.elapsed() >= STATS_LOG_PERIOD {
            tracing::info!(
                tracker_accepted = stats.tracker_accepted,
                tracker_rejected =
                    stats.tracker_rejected_non_finite + stats.tracker_rejected_quaternion,
                glove_accepted = stats.glove_accepted,
                glove_rejected = stats.glove_rejected_non_finite,
                glove_values_clamped = stats.glove_values_clamped,
                "input counters"
            );
            self.logged_stats = stats;
            self.stats_logged_at = Instant::now();
        }
    }

    /// A failed send or receive is logged and the loop goes on: one bad exchange must not stop
    /// the server.
    fn log_failure(&self, outcome: Result<(), RuntimeError>) {
        if let Err(error) = outcome {
            tracing::error!("{error}");
        }
    }
}
