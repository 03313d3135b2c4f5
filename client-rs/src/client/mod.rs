//! The [`Client`]: the renderer's connection to a vas server.
//!
//! One concept a file: [`Roles`] (which ports a client holds), the [`ClientBuilder`] that
//! connects, the role's ports, the frames received and the newest state kept of them, and the
//! control requests; this file holds the client and its frame loop.

mod builder;
mod control;
mod frames;
mod latest;
mod ports;
mod roles;

use std::sync::Arc;
use std::time::{Duration, Instant};

use iceoryx2::port::client::Client as ControlPort;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use vas_protocol::{
    ClearanceFrame, ControlRequest, ControlResponse, GloveSample, HandFrame, HandJointsSample,
    HandSide, SceneGeometry, TrackerSample,
};

pub use builder::ClientBuilder;
pub(crate) use builder::create_node;
pub use control::{HandInfo, PartInfo, SceneInfo};
pub use frames::{Frame, PartsFrame, Received};
pub use roles::Roles;

use crate::ClientError;
use crate::recording::InputSample;
use crate::wait::{Wake, empty_listeners, wait_until_ready};
use latest::Latest;
use ports::{Inputs, Outputs};

/// A connection to a vas server: sends input, receives frames, asks the control service.
///
/// It holds the ports of its [`Roles`] only: a client opened without the render role cannot
/// [`Client::wait`] or [`Client::receive`], one without the input role cannot send samples
/// (both are [`ClientError::MissingRole`]). All ports belong to one iceoryx2 node on the chosen
/// prefix. The client is not `Send` (iceoryx2 ports are bound to their thread): create it on
/// the thread that uses it.
pub struct Client {
    node: Node<ipc::Service>,
    control: ControlPort<ipc::Service, ControlRequest, (), ControlResponse, ()>,
    control_notifier: Notifier<ipc::Service>,
    control_listener: Listener<ipc::Service>,
    /// The render role's ports, when it was taken.
    outputs: Option<Outputs>,
    /// The input role's ports, when it was taken.
    inputs: Option<Inputs>,
    waitset: WaitSet<ipc::Service>,
    /// The newest state received, for the `latest_*` accessors and [`Client::geometry`].
    latest: Latest,
}

impl Client {
    /// Connects on `prefix` (the server's `--prefix`, or the configured default for `None`)
    /// with every role ([`Roles::ALL`]), leaving signal handling to the application.
    pub fn connect(prefix: Option<&str>) -> Result<Self, ClientError> {
        ClientBuilder::default().prefix(prefix).connect()
    }

    /// Options for a connection: its prefix, its roles, signal handling.
    pub fn builder() -> ClientBuilder {
        ClientBuilder::default()
    }

    /// The roles this client holds the ports of.
    pub fn roles(&self) -> Roles {
        let mut roles = Roles::CONTROL;
        if self.outputs.is_some() {
            roles |= Roles::RENDER;
        }
        if self.inputs.is_some() {
            roles |= Roles::INPUT;
        }
        roles
    }

    /// Takes `roles` as well, creating the ports of those the client does not hold yet: e.g. a
    /// viewer takes the input role once a headset sends hand joints. On an error (such as
    /// [`ClientError::Full`]) the client keeps the roles it had.
    pub fn take_roles(&mut self, roles: Roles) -> Result<(), ClientError> {
        if roles.contains(Roles::RENDER) && self.outputs.is_none() {
            self.outputs = Some(Outputs::open(&self.node)?);
        }
        if roles.contains(Roles::INPUT) && self.inputs.is_none() {
            self.inputs = Some(Inputs::open(&self.node)?);
        }
        Ok(())
    }

    /// The input role's ports, or the error saying this client did not take it.
    fn inputs(&self, action: &'static str) -> Result<&Inputs, ClientError> {
        self.inputs.as_ref().ok_or(ClientError::MissingRole {
            role: Roles::INPUT,
            action,
        })
    }

    /// The render role's ports, or the error saying this client did not take it.
    fn outputs(&self, action: &'static str) -> Result<&Outputs, ClientError> {
        self.outputs.as_ref().ok_or(ClientError::MissingRole {
            role: Roles::RENDER,
            action,
        })
    }

    /// Sends a tracker sample and wakes the server.
    pub fn send_tracker(&self, sample: &TrackerSample) -> Result<(), ClientError> {
        self.inputs("send a tracker sample")?.tracker.send(sample)
    }

    /// Returns once the server has taken in every sample this client sent before the call; call
    /// it before dropping a client whose last samples matter.
    ///
    /// A sent sample stays in this client's shared memory until the server takes it, and goes
    /// with the client: a program that sends and exits at once loses the samples the server has
    /// not taken yet. The server takes in input before it answers a control request, so one
    /// round trip is enough.
    pub fn flush_inputs(&self, timeout: Duration) -> Result<(), ClientError> {
        self.input_stats(timeout).map(drop)
    }

    /// Sends a glove sample and wakes the server.
    pub fn send_glove(&self, sample: &GloveSample) -> Result<(), ClientError> {
        self.inputs("send a glove sample")?.glove.send(sample)
    }

    /// Sends a hand-joints sample (one hand's 26 OpenXR joints) and wakes the server.
    pub fn send_hand_joints(&self, sample: &HandJointsSample) -> Result<(), ClientError> {
        (self.inputs("send a hand-joints sample")?.hand_joints).send(sample)
    }

    /// Sends a sample of any input stream and wakes the server.
    pub fn send_input(&self, input: &InputSample) -> Result<(), ClientError> {
        match input {
            InputSample::Tracker(sample) => self.send_tracker(sample),
            InputSample::Glove(sample) => self.send_glove(sample),
            InputSample::HandJoints(sample) => self.send_hand_joints(sample),
        }
    }

    /// Blocks until an output frame (geometry, parts, hand, event, force or clearance) is ready to be
    /// received, the timeout passes, or (with signal handling on) a termination signal arrives.
    /// Frames stay queued for [`Client::poll`] or [`Client::receive`]. Needs the render role.
    pub fn wait(&mut self, timeout: Duration) -> Result<Wake, ClientError> {
        let outputs = self.outputs("wait for frames")?;
        wait_until_ready(&self.waitset, &outputs.listeners(), timeout, || {
            outputs.has_samples()
        })
    }

    /// The file descriptors of the render role's wake-up listeners, one per output service: each
    /// becomes readable when the server publishes on its service, so that an engine's own event
    /// loop (poll, epoll, select, a run loop) can wait on them instead of [`Client::wait`].
    ///
    /// When one is readable, call [`Client::poll`] or [`Client::receive`]: they empty the
    /// listeners before they take the samples, so afterwards the descriptors stay quiet until
    /// the server publishes again (a notification that comes between the two makes one
    /// readable with nothing new to receive: a spurious wake, never a lost one). Frames queued
    /// before the first wait (a connecting client's history) do not make them readable: poll
    /// once after connecting. The descriptors belong to the client: never read, write or close
    /// them, and forget them when it is dropped. Needs the render role.
    #[cfg(unix)]
    pub fn wake_descriptors(&self) -> Result<Vec<std::os::fd::RawFd>, ClientError> {
        let outputs = self.outputs("hand out its wake-up descriptors")?;
        Ok((outputs.listeners().iter())
            // SAFETY: the number is only handed out; the listener keeps owning the descriptor.
            .map(|listener| unsafe { listener.file_descriptor().native_handle() })
            .collect())
    }

    /// Receives every queued frame, keeps the newest of each kind for [`Client::geometry`],
    /// [`Client::latest_parts`] and [`Client::latest_hands`], and returns them all in arrival
    /// order per kind: geometry, parts frames, events, force frames, clearance frames, then hand
    /// frames. The server publishes a frame's hands last; they are taken first here (and the
    /// rest after them), so that whatever the server sent before a hand frame taken, its own
    /// frame's parts and events included, comes in the same call, however the two processes
    /// interleave. It first empties the wake-up listeners, so that their descriptors are
    /// readable again only for what the server publishes after it.
    pub fn receive(&mut self) -> Result<Vec<Frame>, ClientError> {
        let outputs = self.outputs("receive frames")?;
        // Emptied first, so that a notification of a sample published meanwhile stays.
        empty_listeners(&outputs.listeners())?;
        let geometry = drain(
            || outputs.geometry.receive(),
            "receive the geometry",
            |sample| {
                let geometry = SceneGeometry::decode(sample.user_header(), sample.payload())?;
                Ok(Frame::Geometry(Arc::new(geometry)))
            },
        )?;
        let hands = drain(
            || outputs.hand.receive(),
            "receive a hand frame",
            |sample| Ok(Frame::Hand(*sample.payload())),
        )?;
        let clearance = drain(
            || outputs.clearance.receive(),
            "receive a clearance frame",
            |sample| Ok(Frame::Clearance(Box::new(*sample.payload()))),
        )?;
        let forces = drain(
            || outputs.force.receive(),
            "receive a force frame",
            |sample| Ok(Frame::Force(*sample.payload())),
        )?;
        let events = drain(
            || outputs.events.receive(),
            "receive an event",
            |sample| Ok(Frame::Event(*sample.payload())),
        )?;
        let parts = drain(
            || outputs.parts.receive(),
            "receive a parts frame",
            |sample| {
                Ok(Frame::Parts(PartsFrame {
                    header: *sample.user_header(),
                    parts: sample.payload().to_vec(),
                }))
            },
        )?;
        let frames: Vec<Frame> = [geometry, parts, events, forces, clearance, hands]
            .into_iter()
            .flatten()
            .collect();
        for frame in &frames {
            self.latest.keep(frame);
        }
        Ok(frames)
    }

    /// Waits until a hand frame that `answers` accepts arrives and returns it; `None` on timeout
    /// or a handled termination signal. Every other frame received meanwhile goes to `others`,
    /// in [`Client::receive`]'s order, so that the events a sample caused reach the caller before
    /// the answer to it (pass `drop` to ignore them). With [`InputSample::is_answered_by`] this
    /// waits for the answer to one input sample.
    pub fn wait_for_hand_frame(
        &mut self,
        timeout: Duration,
        answers: impl Fn(&HandFrame) -> bool,
        mut others: impl FnMut(Frame),
    ) -> Result<Option<HandFrame>, ClientError> {
        let deadline = Instant::now() + timeout;
        loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            if self.wait(remaining)? != Wake::Ready {
                return Ok(None);
            }
            let mut answer = None;
            for frame in self.receive()? {
                match frame {
                    Frame::Hand(hand) if answer.is_none() && answers(&hand) => answer = Some(hand),
                    other => others(other),
                }
            }
            if answer.is_some() {
                return Ok(answer);
            }
        }
    }

    /// Receives every queued frame, keeping only the newest of each kind; like
    /// [`Client::receive`], it quiets the [`Client::wake_descriptors`].
    pub fn poll(&mut self) -> Result<Received, ClientError> {
        let mut received = Received::default();
        for frame in self.receive()? {
            match frame {
                Frame::Parts(_) => received.parts += 1,
                Frame::Hand(_) => received.hand += 1,
                Frame::Event(_) => received.events += 1,
                Frame::Force(_) => received.force += 1,
                Frame::Clearance(_) => received.clearance += 1,
                Frame::Geometry(_) => received.geometry += 1,
            }
        }
        Ok(received)
    }

    /// The newest parts frame received so far (by [`Client::poll`] or [`Client::receive`]).
    pub fn latest_parts(&self) -> Option<&PartsFrame> {
        self.latest.parts.as_ref()
    }

    /// The newest frame of each hand received so far (by [`Client::poll`] or
    /// [`Client::receive`]), by user, each user's right then left (by [`HandSide`] code): one
    /// per hand of the current scene, every user's. The server publishes every hand's frame each frame, and a client that
    /// connects gets them all at once; a load or reset forgets the hands the new scene does not
    /// have.
    pub fn latest_hands(&self) -> &[HandFrame] {
        &self.latest.hands
    }

    /// The newest frame of user `user`'s hand on `side` (see [`Client::latest_hands`]; the
    /// user's index as the scene info lists the users, 0 in a scene of one user); `None` before
    /// one arrived or when the current scene has no such hand.
    pub fn latest_hand_of(&self, user: u32, side: HandSide) -> Option<&HandFrame> {
        self.latest.hand_of(user, side)
    }

    /// The newest clearance frame received so far (by [`Client::poll`] or [`Client::receive`]):
    /// the part pairs closer than the scene's threshold, on the parts frame it names. The server
    /// publishes one per frame it measures, shortly after that frame's parts, and none while its
    /// scene has no `[params.clearance]` threshold.
    pub fn latest_clearance(&self) -> Option<&ClearanceFrame> {
        self.latest.clearance.as_deref()
    }

    /// The render meshes of the newest scene generation received so far (by [`Client::poll`]
    /// or [`Client::receive`]): every part's mesh in its own frame with its scale applied, and
    /// every hand segment's mesh in the segment's frame. A client that connects gets the
    /// current generation at once.
    pub fn geometry(&self) -> Option<&Arc<SceneGeometry>> {
        self.latest.geometry.as_ref()
    }

    /// Sleeps for `duration`; [`Wake::Terminated`] if a handled termination signal arrived.
    pub fn sleep(&self, duration: Duration) -> Wake {
        match self.node.wait(duration) {
            Ok(()) => Wake::Timeout,
            Err(_) => Wake::Terminated,
        }
    }
}

/// Every sample `next` still has, each made a frame by `frame`; `action` names a failure to
/// receive.
fn drain<S, E: std::fmt::Debug>(
    mut next: impl FnMut() -> Result<Option<S>, E>,
    action: &'static str,
    mut frame: impl FnMut(S) -> Result<Frame, ClientError>,
) -> Result<Vec<Frame>, ClientError> {
    let mut frames = Vec::new();
    while let Some(sample) = next().map_err(|error| ClientError::ipc(action, error))? {
        frames.push(frame(sample)?);
    }
    Ok(frames)
}
