//! The interaction manager: the I/O thread that owns every port.
//!
//! It validates input into the [`Session`]'s input state and hands each accepted sample's target
//! to the grasping loop; it publishes what the collision loop verified (hand, parts, events,
//! force), and answers control requests, sending their changes down the loops between frames.
//! Parts are also published at the scene's publish rate, so that a renderer sees the scene while
//! no input arrives.
//!
//! In lockstep the next sample's frame is handed over only when the previous one came back
//! verified: each sample gets exactly one frame, whatever the timing.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use vas_protocol::{
    ControlResponse, ControlStatus, ForceFrame, HAND_SEGMENT_COUNT, HandFrame, InputStats,
    PART_GRASPED, PartState, PartsFrameHeader, SimEvent, WirePose, wall_clock_ns,
};

use super::clearance::{self, ClearanceJob, ClearanceWatch};
use super::control::{self, Session};
use super::geometry::ServedGeometry;
use super::inputs::TrackingClock;
use super::loader::{Loaded, PendingRequest, SceneLoader};
use super::loops::{Links, LoopWork, Loops};
use super::owners::{HandOwner, hand_owners};
use super::ports::{Ports, Wakeups};
use super::rendezvous::{ANNOUNCED_WAIT, AwakeWatch, Handoff, Work};
use super::wakeup::{Waker, WakeupReceiver};
use super::{RunOptions, RuntimeError, publish_period};
use crate::simulation::frames::{InputFrame, Stamps, VerifiedFrame};
use crate::simulation::restart::{Change, Restart};

/// How often the input counters are logged, when they changed.
const STATS_LOG_PERIOD: Duration = Duration::from_secs(5);

/// Owns the ports and the session; validates input, publishes frames, answers control.
pub(super) struct InteractionManager {
    wakeups: Wakeups,
    /// Woken by the collision loop and the scene loader.
    internal: WakeupReceiver,
    io: Io,
}

/// What the loop changes: ports, session, the way to the loops, the published state.
struct Io {
    ports: Ports,
    session: Session,
    inputs: Arc<Handoff<InputFrame, Change>>,
    verified: Receiver<VerifiedFrame>,
    /// Whether this thread waits awake for verified frames (then the collision loop does not
    /// wake it).
    watch: Arc<AwakeWatch>,
    answer: Answer,
    lockstep: Lockstep,
    /// Loads requested scenes apart from this thread.
    loader: SceneLoader,
    /// The served scene's render meshes.
    geometry: ServedGeometry,
    /// The user and side of each of the served scene's hands, in its order (the first user's
    /// right hand in a scene without hand models, for the hand the tracker places).
    /// Shared, so that publishing a frame reads them without copying them while it mutates `self`.
    hand_owners: Arc<[HandOwner]>,
    /// The latest published part states, for the periodic parts frames.
    parts: Vec<PartState>,
    /// Measures the published frames' clearance beside the loops.
    clearance: ClearanceWatch,
    hand_frames: u64,
    parts_frames: u64,
    logged_stats: InputStats,
    stats_logged_at: Instant,
}

/// The latest frame handed to the loops and how long the loops took to answer one: the I/O thread
/// waits for the answer awake, like a loop woken by an announcement, when it comes within
/// [`ANNOUNCED_WAIT`].
#[derive(Default)]
struct Answer {
    /// The stamps of the latest frame sent and when it was sent, until its answer is taken.
    awaited: Option<(Stamps, Instant)>,
    /// From sending a frame to taking its answer, the last time one was answered.
    lead: Duration,
}

impl Answer {
    /// True when an answer is awaited and the last one came quickly enough to wait awake for.
    fn worth_waiting_awake(&self) -> bool {
        self.awaited.is_some() && self.lead <= ANNOUNCED_WAIT
    }

    /// Notes a verified frame: the answer, if it carries the awaited stamps.
    fn take(&mut self, stamps: Stamps) {
        if let Some((awaited, sent_at)) = self.awaited
            && awaited == stamps
        {
            self.lead = sent_at.elapsed();
            self.awaited = None;
        }
    }
}

/// Work waiting for the frame in flight, in lockstep.
struct Lockstep {
    enabled: bool,
    in_flight: bool,
    /// The frame in flight is published and its clearance is being measured.
    awaiting_clearance: bool,
    waiting: VecDeque<LoopWork<InputFrame>>,
}

impl InteractionManager {
    /// Opens the ports for the session's scene, which `start` starts the loops on; hands work to
    /// the loops through `links`, takes their frames from `verified`, and wakes for them and for
    /// loaded scenes on `internal` (`waker` is its sending end).
    pub(super) fn new(
        node: &Node<ipc::Service>,
        session: Session,
        start: &Restart,
        links: &Links,
        verified: Receiver<VerifiedFrame>,
        (waker, internal): (Waker, WakeupReceiver),
        options: &RunOptions,
    ) -> Result<Self, RuntimeError> {
        let mut session = session;
        // Lockstep replays must give the same frames every time: their hands' tracking is timed
        // by the samples. A free-running server serves a live user: by the system clock.
        session.inputs.set_clock(if options.lockstep {
            TrackingClock::SampleTime
        } else {
            TrackingClock::Arrival
        });
        let geometry = ServedGeometry::of(start);
        let hand_owners = hand_owners(&session.scene);
        let (ports, wakeups) = Ports::open(
            node,
            session.scene.parts.len(),
            geometry.geometry().encoded_len(),
        )?;
        let mut clearance = ClearanceWatch::spawn(waker.clone(), options.lockstep)?;
        clearance.restart(&start.scene, start.epoch);
        let mut io = Io {
            ports,
            parts: Vec::new(),
            clearance,
            session,
            inputs: Arc::clone(&links.inputs),
            verified,
            watch: Arc::clone(&links.io_watch),
            answer: Answer::default(),
            loader: SceneLoader::new(waker, options.load.clone()),
            geometry,
            hand_owners,
            lockstep: Lockstep {
                enabled: options.lockstep,
                in_flight: false,
                awaiting_clearance: false,
                waiting: VecDeque::new(),
            },
            hand_frames: 0,
            parts_frames: 0,
            logged_stats: InputStats::default(),
            stats_logged_at: Instant::now(),
        };
        io.reset_parts();
        Ok(Self {
            wakeups,
            internal,
            io,
        })
    }

    /// Serves until a termination signal (or a loop's failure): wakes on input, control and
    /// verified frames, and at the scene's publish rate.
    pub(super) fn serve(mut self, start: Change, loops: &Loops) -> Result<(), RuntimeError> {
        let waitset = WaitSetBuilder::new()
            .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
            .create::<ipc::Service>()
            .map_err(|error| RuntimeError::ipc("create the WaitSet", error))?;
        let attach = |error| RuntimeError::ipc("attach to the WaitSet", error);
        // The guards keep the listeners attached until the loop ends.
        let attached = self
            .wakeups
            .listeners()
            .map(|listener| waitset.attach_notification(listener))
            .into_iter()
            .collect::<Result<Vec<_>, _>>()
            .map_err(attach)?;
        let internal = waitset
            .attach_notification(&self.internal)
            .map_err(attach)?;
        let io = &mut self.io;
        let mut publish_hz = io.session.scene.rates.publish_hz;
        let mut publish_tick = waitset
            .attach_interval(publish_period(publish_hz)?)
            .map_err(attach)?;

        io.submit(Work::Control(start));
        io.publish_geometry();
        io.publish_parts(None);
        tracing::info!(lockstep = io.lockstep.enabled, "serving");
        loop {
            let mut publish_due = false;
            let mut fired = [false; Wakeups::COUNT];
            let mut woken = false;
            let outcome = waitset
                .wait_and_process_once(|attachment| {
                    publish_due |= attachment.has_event_from(&publish_tick);
                    woken |= attachment.has_event_from(&internal);
                    for (fired, guard) in fired.iter_mut().zip(&attached) {
                        *fired |= attachment.has_event_from(guard);
                    }
                    CallbackProgression::Continue
                })
                .map_err(|error| RuntimeError::ipc("wait on the WaitSet", error))?;
            if outcome == WaitSetRunResult::TerminationRequest {
                break;
            }
            // `Interrupt` means a signal cut the wait short; if it was SIGINT or SIGTERM, the
            // next wait reports the termination request.
            let input_due = fired[..Wakeups::INPUTS].contains(&true);
            if input_due && !(io.lockstep.enabled && io.lockstep.in_flight) {
                // The grasping loop wakes while the samples are taken in.
                io.inputs.announce();
            }
            io.log_failure(self.wakeups.drain(fired));
            if woken && let Err(error) = self.internal.drain() {
                tracing::error!(%error, "cannot take the internal wake-ups");
            }
            io.process_input_samples();
            io.answer_control_requests();
            io.publish_verified_frames();
            io.publish_clearance();
            let scene_hz = io.session.scene.rates.publish_hz;
            if scene_hz != publish_hz {
                publish_hz = scene_hz;
                match publish_period(scene_hz) {
                    Ok(period) => {
                        publish_tick = waitset.attach_interval(period).map_err(attach)?;
                        tracing::info!(?period, "publishing at the loaded scene's rate");
                    }
                    Err(error) => tracing::error!("{error}; the publish rate stays"),
                }
            }
            if publish_due {
                if loops.any_ended() {
                    return Err(RuntimeError::LoopEnded);
                }
                io.notice_silent_hands();
                io.publish_parts(None);
                io.log_failure(io.ports.update_connections());
                io.log_stats_if_due();
            }
        }
        tracing::info!(stats = ?io.session.inputs.stats(), "termination requested; shutting down");
        Ok(())
    }
}

impl Io {
    /// Hands work to the grasping loop; in lockstep, frames wait for the one in flight.
    fn submit(&mut self, work: LoopWork<InputFrame>) {
        if !self.lockstep.enabled {
            self.send(work);
            return;
        }
        self.lockstep.waiting.push_back(work);
        self.send_waiting();
    }

    /// In lockstep: sends waiting work up to and including the next frame, unless one is in
    /// flight.
    fn send_waiting(&mut self) {
        while !self.lockstep.in_flight {
            let Some(work) = self.lockstep.waiting.pop_front() else {
                return;
            };
            self.lockstep.in_flight = matches!(work, Work::Frame(_));
            self.send(work);
        }
    }

    /// Hands work to the grasping loop, noting a frame as the awaited one.
    fn send(&mut self, work: LoopWork<InputFrame>) {
        if let Work::Frame(frame) = &work {
            self.answer.awaited = Some((frame.stamps, Instant::now()));
        }
        self.inputs.send(work);
    }

    /// A frame for a hand whose samples stopped coming (free-running only): it says the hand is
    /// untracked, and after the grace period lets go of what it holds.
    fn notice_silent_hands(&mut self) {
        if self.session.inputs.tick(wall_clock_ns()) {
            let frame = self.session.inputs.frame();
            self.submit(Work::Frame(frame));
        }
    }

    /// Takes in the waiting samples of every input stream: each accepted one is a frame.
    fn process_input_samples(&mut self) {
        self.process_tracker_samples();
        self.process_glove_samples();
        self.process_hand_joints_samples();
    }

    /// The next waiting sample of the input stream `port` picks, copied out; `None` when there
    /// is none (or receiving failed, which is logged).
    fn next_sample<T>(
        &self,
        port: impl Fn(&Ports) -> &Subscriber<ipc::Service, T, ()>,
        action: &'static str,
    ) -> Option<T>
    where
        T: Copy + std::fmt::Debug + ZeroCopySend + 'static,
    {
        match port(&self.ports).receive() {
            Ok(sample) => sample.map(|sample| *sample.payload()),
            Err(error) => {
                self.log_failure(Err(RuntimeError::ipc(action, error)));
                None
            }
        }
    }

    fn process_tracker_samples(&mut self) {
        while let Some(sample) = self.next_sample(|ports| &ports.tracker, "receive tracker samples")
        {
            match self.session.inputs.apply_tracker(&sample) {
                Ok(()) => {
                    let frame = self.session.inputs.frame();
                    self.submit(Work::Frame(frame));
                }
                Err(rejection) => self.log_rejection("tracker", sample.seq, &rejection),
            }
        }
    }

    fn process_glove_samples(&mut self) {
        while let Some(sample) = self.next_sample(|ports| &ports.glove, "receive glove samples") {
            match self.session.inputs.apply_glove(&sample) {
                Ok(clamped) => {
                    if clamped != 0 {
                        tracing::debug!(
                            seq = sample.seq,
                            clamped = format_args!("{clamped:#x}"),
                            "glove values clamped"
                        );
                    }
                    let frame = self.session.inputs.frame();
                    self.submit(Work::Frame(frame));
                }
                Err(rejection) => self.log_rejection("glove", sample.seq, &rejection),
            }
        }
    }

    /// An untracked hand's sample is a frame too: it answers the sample, says the hand is
    /// untracked, and in lockstep each sample gets its frame.
    fn process_hand_joints_samples(&mut self) {
        while let Some(sample) =
            self.next_sample(|ports| &ports.hand_joints, "receive hand-joints samples")
        {
            match self.session.inputs.apply_hand_joints(&sample) {
                Ok(_) => {
                    let frame = self.session.inputs.frame();
                    self.submit(Work::Frame(frame));
                }
                Err(rejection) => self.log_rejection("hand_joints", sample.seq, &rejection),
            }
        }
    }

    /// Answers the waiting control requests, each after taking in the input samples that came
    /// before it.
    ///
    /// A sample lives in its sender's shared memory until it is taken, and goes with the sender:
    /// one sent just before its client exits (`vas-client send-tracker`, the end of a replay) is
    /// lost unless it was taken first. Taking input before each answer makes any answer proof
    /// that every sample its client sent before the request has been taken in
    /// (`Client::flush_inputs`).
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
            self.process_input_samples();
            let loading = self.loader.is_loading();
            match control::answer(&mut self.session, request.payload(), loading) {
                control::Reply::Now(response, change) => {
                    self.respond(request, response, change);
                    answered = true;
                }
                control::Reply::Load(path) => {
                    tracing::info!(path = %path.display(), "loading a scene on request");
                    if let Some(failed) = self.loader.start(path, request) {
                        answered |= self.finish_load(failed);
                    }
                }
            }
        }
        if let Some(loaded) = self.loader.finished() {
            answered |= self.finish_load(loaded);
        }
        if answered {
            self.log_failure(self.ports.notify_control_clients());
        }
    }

    /// Answers a finished scene load: the loaded scene is swapped in here, between frames.
    fn finish_load(&mut self, loaded: Loaded) -> bool {
        let (response, change) = control::loaded(&mut self.session, loaded.outcome);
        if response.status != ControlStatus::Ok as u32 {
            tracing::warn!(message = ?response.message.as_str(), "scene load refused");
        }
        self.respond(loaded.request, response, change);
        true
    }

    /// Sends `change` down the loops and `response` to the client.
    fn respond(
        &mut self,
        request: PendingRequest,
        response: ControlResponse,
        change: Option<Change>,
    ) {
        tracing::debug!(
            kind = response.kind,
            status = response.status,
            "control request answered"
        );
        if let Some(change) = change {
            if let Change::Restart(restart) = &change {
                self.geometry.restart(restart);
                self.clearance.restart(&restart.scene, restart.epoch);
                self.hand_owners = hand_owners(&restart.scene);
            }
            let restarted = matches!(change, Change::Restart(_));
            self.submit(Work::Control(change));
            if restarted {
                self.reset_parts();
                self.publish_geometry();
                self.publish_parts(None);
            }
        }
        if let Err(error) = request.send_copy(response) {
            self.log_failure(Err(RuntimeError::ipc("send a control response", error)));
        }
    }

    /// Publishes the served scene's geometry (once per generation).
    fn publish_geometry(&mut self) {
        let geometry = self.geometry.geometry();
        self.log_failure(self.ports.publish_geometry(geometry));
    }

    /// The session's scene's parts at their configured poses, as published until the loops
    /// verify a frame of it.
    fn reset_parts(&mut self) {
        self.parts = (0u32..)
            .zip(&self.session.scene.parts)
            .map(|(id, part)| part_state(id, &part.pose, 0))
            .collect();
    }

    /// Publishes the frames the collision loop verified since the last call; when the loops
    /// usually answer quickly, first waits awake for the answer to the latest frame (see
    /// [`AwakeWatch`]).
    fn publish_verified_frames(&mut self) {
        if !self.answer.worth_waiting_awake() {
            return self.take_verified_frames();
        }
        let watch = Arc::clone(&self.watch);
        watch.wait_awake(|| {
            self.take_verified_frames();
            self.answer.awaited.is_none()
        });
    }

    fn take_verified_frames(&mut self) {
        while let Ok(frame) = self.verified.try_recv() {
            self.answer.take(frame.stamps);
            // A frame of the scene before a restart still answers its sample, but its parts
            // are not the scene's any more.
            let measuring = self.publish(&frame);
            if self.lockstep.enabled {
                // The next sample's frame waits for this one's clearance, if it is measured.
                self.lockstep.awaiting_clearance = measuring;
                self.lockstep.in_flight = measuring;
                self.send_waiting();
            }
        }
    }

    /// Publishes the clearance of the frames measured since the last call; in lockstep, then
    /// hands the loops the next frame.
    fn publish_clearance(&mut self) {
        while let Some(report) = self.clearance.take() {
            self.log_failure(clearance::publish(&self.ports, &report));
        }
        if self.lockstep.awaiting_clearance && !self.clearance.is_pending() {
            self.lockstep.awaiting_clearance = false;
            self.lockstep.in_flight = false;
            self.send_waiting();
        }
    }

    /// Publishes a verified frame; true when it was handed over to have its clearance measured.
    fn publish(&mut self, frame: &VerifiedFrame) -> bool {
        let now = wall_clock_ns();
        self.hand_frames += 1;
        let stamps = frame.stamps;
        let owners = Arc::clone(&self.hand_owners);
        let owner = |hand: usize| owners.get(hand).copied().unwrap_or_default();
        let events = frame.events.iter().map(|event| SimEvent {
            frame: self.hand_frames,
            tracker: stamps.tracker,
            glove: stamps.glove,
            joints: stamps.joints,
            timestamp_ns: now,
            kind: event.kind as u32,
            grasp_type: event.grasp as u32,
            part: event.part,
            other: event.other,
            hand: owner(event.hand).side as u32,
            segment: event.at.map_or(0, |at| at.segment),
            user: owner(event.hand).user,
            reserved: 0,
            point: event.at.map_or([0.0; 3], |at| at.point.into()),
            normal: event.at.map_or([0.0; 3], |at| at.normal.into()),
            other_point: [0.0; 3],
            distance: 0.0,
        });
        self.log_failure(self.ports.publish_events(events));
        let forces = (frame.hands.iter().enumerate()).filter_map(|(index, hand)| {
            let wrench = hand.force?;
            Some(ForceFrame {
                frame: self.hand_frames,
                tracker: stamps.tracker,
                glove: stamps.glove,
                joints: hand.joints,
                timestamp_ns: now,
                force: wrench.force.into(),
                torque: wrench.torque.into(),
                hand: owner(index).side as u32,
                user: owner(index).user,
            })
        });
        self.log_failure(self.ports.publish_forces(forces));
        if frame.epoch == self.session.epoch && frame.parts.len() == self.parts.len() {
            let changed = (0u32..)
                .zip(&frame.parts)
                .map(|(id, part)| part_state(id, &part.pose, part.flags))
                .zip(&mut self.parts)
                .fold(false, |changed, (state, published)| {
                    let differs = state != *published;
                    *published = state;
                    changed | differs
                });
            if changed || self.lockstep.enabled {
                self.publish_parts(Some(frame));
            }
        }
        let measuring = frame.epoch == self.session.epoch
            && frame.parts.len() == self.parts.len()
            && self.clearance.hand(ClearanceJob {
                epoch: frame.epoch,
                parts_frame: self.parts_frames,
                hand_frame: self.hand_frames,
                stamps,
                poses: frame.parts.iter().map(|part| part.pose).collect(),
                held: (0u32..)
                    .zip(&frame.parts)
                    .filter(|(_, part)| part.flags & PART_GRASPED != 0)
                    .map(|(id, _)| id)
                    .collect(),
            });
        // The hand frames go last: a client that waits for the answer to its sample has the
        // parts and events of the same frame by then. Every hand's frame goes out every frame,
        // moved or not, so that the hand service's last `services::output::HAND_HISTORY`
        // samples are one per hand and a reader that connects late gets every hand at once.
        let hands = (frame.hands.iter().enumerate()).map(|(index, hand)| {
            let segments = &hand.segments;
            HandFrame {
                frame: self.hand_frames,
                tracker: stamps.tracker,
                glove: stamps.glove,
                joints: hand.joints,
                timestamp_ns: wall_clock_ns(),
                root: WirePose::from_isometry(&hand.root),
                flex: hand.flex,
                touching: hand.touching,
                grasp_type: hand.grasp as u32,
                hand: owner(index).side as u32,
                tracked: u32::from(hand.tracked),
                segment_count: u32::try_from(segments.len().min(HAND_SEGMENT_COUNT))
                    .expect("at most 16"),
                user: owner(index).user,
                segments: std::array::from_fn(|i| {
                    segments
                        .get(i)
                        .map_or(WirePose::IDENTITY, WirePose::from_isometry)
                }),
            }
        });
        self.log_failure(self.ports.publish_hands(hands));
        measuring
    }

    /// Publishes the latest part states, stamped with `frame`'s inputs (or the latest inputs).
    fn publish_parts(&mut self, frame: Option<&VerifiedFrame>) {
        self.parts_frames += 1;
        let stamps = frame.map_or_else(|| self.session.inputs.frame().stamps, |f| f.stamps);
        let header = PartsFrameHeader {
            frame: self.parts_frames,
            tracker: stamps.tracker,
            glove: stamps.glove,
            joints: stamps.joints,
            timestamp_ns: wall_clock_ns(),
            part_count: u32::try_from(self.parts.len()).unwrap_or(u32::MAX),
        };
        self.log_failure(self.ports.publish_parts(header, &self.parts));
    }

    /// The first rejected sample is a warning; later ones are counted and show in the periodic
    /// summary (a broken sender must not flood the log).
    fn log_rejection(&self, stream: &str, seq: u64, rejection: &dyn std::fmt::Display) {
        if self.session.inputs.stats().rejected() == 1 {
            tracing::warn!(stream, seq, %rejection, "input rejected; further rejections are counted");
        } else {
            tracing::debug!(stream, seq, %rejection, "input rejected");
        }
    }

    fn log_stats_if_due(&mut self) {
        let stats = self.session.inputs.stats();
        if stats != self.logged_stats && self.stats_logged_at.elapsed() >= STATS_LOG_PERIOD {
            tracing::info!(
                tracker_accepted = stats.tracker_accepted,
                tracker_rejected = stats.tracker_rejected_non_finite
                    + stats.tracker_rejected_quaternion
                    + stats.tracker_rejected_out_of_range,
                glove_accepted = stats.glove_accepted,
                glove_rejected = stats.glove_rejected_non_finite,
                glove_values_clamped = stats.glove_values_clamped,
                joints_accepted = stats.joints_accepted,
                joints_untracked = stats.joints_untracked,
                joints_rejected = stats.joints_rejected(),
                frames_merged = self.inputs.merged(),
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

fn part_state(id: u32, pose: &nalgebra::Isometry3<f64>, flags: u32) -> PartState {
    let pose = WirePose::from_isometry(pose);
    PartState {
        id,
        flags,
        position: pose.position,
        rotation: pose.rotation,
    }
}
