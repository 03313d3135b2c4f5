//! The [`Client`]: the renderer's connection to a vas server.

use std::sync::Arc;
use std::time::{Duration, Instant};

use iceoryx2::port::client::Client as ControlPort;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::{event, publish_subscribe};
use serde::Serialize;
use vas_protocol::services::{self, config_with_prefix};
use vas_protocol::{
    ClearanceFrame, ControlRequest, ControlRequestKind, ControlResponse, ControlStatus, ForceFrame,
    GeometryHeader, GloveSample, HandFrame, HandJointsSample, HandSide, InputStats, MAX_PATH_BYTES,
    MeshData, PART_MOVABLE, PartState, PartsFrameHeader, SceneGeometry, SimEvent, SlidingMetaphor,
    TrackerSample, WirePose, WireText,
};

use crate::ClientError;
use crate::recording::InputSample;
use crate::wait::{Wake, deadline_after, new_waitset, signal_mode, wait_until_ready};

/// How long a control request that reached no server waits before it is sent again (a server
/// may be starting).
const CONTROL_RETRY: Duration = Duration::from_millis(20);

/// What a [`Client`] does, and so which ports it holds: every service takes only so many ports
/// (see [`vas_protocol::services::clients`]), and a port a client does not use is a renderer or
/// an operator refused.
///
/// Every client holds a control client (scene info, input counters, reset, loads, metaphor):
/// [`Roles::CONTROL`] is that alone. [`Roles::RENDER`] adds a subscriber on each output service
/// (parts, hand, events, force, clearance, geometry) for [`Client::wait`] and [`Client::receive`];
/// [`Roles::INPUT`] adds a publisher and its notifier on each input stream (tracker, glove, hand
/// joints) for [`Client::send_tracker`] and the other sends. Roles combine with `|`; the default
/// is [`Roles::ALL`], every port, as a client had before there were roles.
///
/// ```
/// use vas_client::Roles;
///
/// // A headset's bridge that reads the answers to its samples.
/// let device = Roles::INPUT | Roles::RENDER;
/// assert_eq!(device, Roles::ALL);
/// assert!(Roles::RENDER.contains(Roles::CONTROL));
/// assert!(!Roles::RENDER.contains(Roles::INPUT));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Roles(u8);

impl Roles {
    /// The control service only: what an operator's command (`vas-client reset`, `load-scene`,
    /// `scenes`, `set-metaphor`, `info`) takes. Every other role includes it.
    pub const CONTROL: Roles = Roles(0);
    /// Reads the server's output: a renderer, a viewer, `vas-client watch` (with control).
    pub const RENDER: Roles = Roles(1);
    /// Sends input: a device bridge, a replay, `vas-client send-*` (with control).
    pub const INPUT: Roles = Roles(2);
    /// Every role: renders and sends. The default.
    pub const ALL: Roles = Roles(Self::RENDER.0 | Self::INPUT.0);

    /// Whether these roles include every one of `other`.
    pub const fn contains(self, other: Roles) -> bool {
        self.0 & other.0 == other.0
    }
}

impl Default for Roles {
    /// [`Roles::ALL`], so that a client opened without saying keeps every port.
    fn default() -> Self {
        Roles::ALL
    }
}

impl std::ops::BitOr for Roles {
    type Output = Roles;

    fn bitor(self, other: Roles) -> Roles {
        Roles(self.0 | other.0)
    }
}

impl std::ops::BitOrAssign for Roles {
    fn bitor_assign(&mut self, other: Roles) {
        self.0 |= other.0;
    }
}

impl std::fmt::Display for Roles {
    /// `control`, `render`, `input` or `render and input`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(
            match (self.contains(Roles::RENDER), self.contains(Roles::INPUT)) {
                (false, false) => "control",
                (true, false) => "render",
                (false, true) => "input",
                (true, true) => "render and input",
            },
        )
    }
}

/// Options of a [`Client`] connection.
#[derive(Debug, Clone, Default)]
pub struct ClientBuilder {
    prefix: Option<String>,
    handle_termination_signals: bool,
    roles: Roles,
}

impl ClientBuilder {
    /// Connect on this iceoryx2 prefix (the server's `--prefix`); with `None`, the prefix of
    /// the iceoryx2 configuration is used.
    pub fn prefix(mut self, prefix: Option<&str>) -> Self {
        self.prefix = prefix.map(str::to_owned);
        self
    }

    /// Let iceoryx2 catch SIGINT and SIGTERM, so that [`Client::wait`] and [`Client::sleep`]
    /// report [`Wake::Terminated`] instead of the process dying. Off by default: a library
    /// should not take over the signals of the application that links it.
    pub fn handle_termination_signals(mut self, handle: bool) -> Self {
        self.handle_termination_signals = handle;
        self
    }

    /// Take these roles only, holding only their ports ([`Roles::ALL`] by default): a
    /// renderer takes `Roles::RENDER`, an operator's tool `Roles::CONTROL`, a device that
    /// reads its answers `Roles::INPUT | Roles::RENDER`. [`Client::take_roles`] adds roles
    /// later.
    pub fn roles(mut self, roles: Roles) -> Self {
        self.roles = roles;
        self
    }

    /// Opens the vas services of the client's roles and creates their ports.
    pub fn connect(self) -> Result<Client, ClientError> {
        let node = create_node(self.prefix.as_deref(), self.handle_termination_signals)?;
        let control = services::open_control(&node)?;
        let control_wakeup = services::open_wakeup(&node, services::CONTROL)?;
        let mut client = Client {
            control: control
                .client_builder()
                .create()
                .map_err(ClientError::port)?,
            control_notifier: control_wakeup
                .notifier_builder()
                .create()
                .map_err(ClientError::port)?,
            control_listener: control_wakeup
                .listener_builder()
                .create()
                .map_err(ClientError::port)?,
            outputs: None,
            inputs: None,
            waitset: new_waitset(self.handle_termination_signals)?,
            latest_parts: None,
            latest_hand: None,
            latest_clearance: None,
            latest_geometry: None,
            node,
        };
        client.take_roles(self.roles)?;
        Ok(client)
    }
}

/// The ports of the render role: a subscriber on each output service, and a listener on its
/// wake-up service.
struct Outputs {
    parts: Subscriber<ipc::Service, [PartState], PartsFrameHeader>,
    parts_listener: Listener<ipc::Service>,
    hand: Subscriber<ipc::Service, HandFrame, ()>,
    hand_listener: Listener<ipc::Service>,
    events: Subscriber<ipc::Service, SimEvent, ()>,
    events_listener: Listener<ipc::Service>,
    force: Subscriber<ipc::Service, ForceFrame, ()>,
    force_listener: Listener<ipc::Service>,
    clearance: Subscriber<ipc::Service, ClearanceFrame, ()>,
    clearance_listener: Listener<ipc::Service>,
    geometry: Subscriber<ipc::Service, [u8], GeometryHeader>,
    geometry_listener: Listener<ipc::Service>,
}

impl Outputs {
    fn open(node: &Node<ipc::Service>) -> Result<Self, ClientError> {
        let listener = |name| -> Result<Listener<ipc::Service>, ClientError> {
            services::open_wakeup(node, name)?
                .listener_builder()
                .create()
                .map_err(ClientError::port)
        };
        Ok(Outputs {
            parts: services::open_parts(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            parts_listener: listener(services::PARTS)?,
            hand: services::open_hand(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            hand_listener: listener(services::HAND)?,
            events: services::open_events(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            events_listener: listener(services::EVENTS)?,
            force: services::open_force(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            force_listener: listener(services::FORCE)?,
            clearance: services::open_clearance(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            clearance_listener: listener(services::CLEARANCE)?,
            geometry: services::open_geometry(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            geometry_listener: listener(services::GEOMETRY)?,
        })
    }
}

/// The ports of the input role: each input stream's sending end.
struct Inputs {
    tracker: InputPort<TrackerSample>,
    glove: InputPort<GloveSample>,
    hand_joints: InputPort<HandJointsSample>,
}

impl Inputs {
    fn open(node: &Node<ipc::Service>) -> Result<Self, ClientError> {
        Ok(Inputs {
            tracker: InputPort::open(
                &services::open_tracker(node)?,
                &services::open_wakeup(node, services::TRACKER)?,
                ["send a tracker sample", "notify the tracker service"],
            )?,
            glove: InputPort::open(
                &services::open_glove(node)?,
                &services::open_wakeup(node, services::GLOVE)?,
                ["send a glove sample", "notify the glove service"],
            )?,
            hand_joints: InputPort::open(
                &services::open_hand_joints(node)?,
                &services::open_wakeup(node, services::HAND_JOINTS)?,
                [
                    "send a hand-joints sample",
                    "notify the hand-joints service",
                ],
            )?,
        })
    }
}

/// Creates the node of a client or tap on `prefix`.
pub(crate) fn create_node(
    prefix: Option<&str>,
    handle_signals: bool,
) -> Result<Node<ipc::Service>, ClientError> {
    let config = config_with_prefix(prefix)?;
    let name =
        NodeName::new("vas-client").map_err(|error| ClientError::ipc("name the node", error))?;
    NodeBuilder::new()
        .name(&name)
        .config(&config)
        .signal_handling_mode(signal_mode(handle_signals))
        .create::<ipc::Service>()
        .map_err(|error| ClientError::ipc("create the iceoryx2 node", error))
}

/// A parts frame, copied out of shared memory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartsFrame {
    /// Frame number, input stamps, publish time and part count.
    #[serde(flatten)]
    pub header: PartsFrameHeader,
    /// Pose and state of every part, indexed by part id.
    pub parts: Vec<PartState>,
}

/// One received output frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
#[expect(
    clippy::large_enum_variant,
    reason = "a hand frame is the common case; boxing it would allocate per frame"
)]
pub enum Frame {
    /// A parts frame.
    Parts(PartsFrame),
    /// A hand frame.
    Hand(HandFrame),
    /// A grasp, release, contact begin or contact end.
    Event(SimEvent),
    /// The force and torque for a force-feedback device.
    Force(ForceFrame),
    /// The part pairs closer than the scene's clearance threshold on a parts frame; in JSON,
    /// the listed pairs only.
    Clearance(#[serde(serialize_with = "clearance_listed")] Box<ClearanceFrame>),
    /// The render meshes of a new scene generation (after a start, load or reset); in JSON, a
    /// summary.
    Geometry(#[serde(serialize_with = "geometry_summary")] Arc<SceneGeometry>),
}

/// A geometry frame in JSON: its generation and what it holds, not every vertex.
fn geometry_summary<S: serde::Serializer>(
    geometry: &Arc<SceneGeometry>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let triangles = |mesh: &MeshData| mesh.triangles.len();
    let mut summary = serializer.serialize_struct("Geometry", 4)?;
    summary.serialize_field("generation", &geometry.generation)?;
    summary.serialize_field("parts", &geometry.parts.len())?;
    summary.serialize_field("hands", &geometry.hands.len())?;
    let total: usize = (geometry.parts.iter())
        .chain(geometry.hands.iter().flat_map(|hand| &hand.segments))
        .map(triangles)
        .sum();
    summary.serialize_field("triangles", &total)?;
    summary.end()
}

/// A clearance frame in JSON: its header and the pairs it lists, not its empty slots.
fn clearance_listed<S: serde::Serializer>(
    frame: &ClearanceFrame,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut listed = serializer.serialize_struct("Clearance", 9)?;
    listed.serialize_field("frame", &frame.frame)?;
    listed.serialize_field("tracker", &frame.tracker)?;
    listed.serialize_field("glove", &frame.glove)?;
    listed.serialize_field("joints", &frame.joints)?;
    listed.serialize_field("timestamp_ns", &frame.timestamp_ns)?;
    listed.serialize_field("threshold", &frame.threshold)?;
    listed.serialize_field("pair_count", &frame.pair_count)?;
    listed.serialize_field("more", &frame.more)?;
    listed.serialize_field("pairs", frame.listed())?;
    listed.end()
}

/// How many frames a [`Client::poll`] received.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Received {
    /// Parts frames received.
    pub parts: usize,
    /// Hand frames received.
    pub hand: usize,
    /// Events received.
    pub events: usize,
    /// Force frames received.
    pub force: usize,
    /// Clearance frames received.
    pub clearance: usize,
    /// Geometry generations received.
    pub geometry: usize,
}

/// The server's scene, as the control service describes it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneInfo {
    /// The scene's name.
    pub name: String,
    /// The file the server loaded it from.
    pub source: String,
    /// Every part, indexed by id.
    pub parts: Vec<PartInfo>,
    /// The server's input counters at the time of the answer.
    pub stats: InputStats,
    /// The world's up direction (z up).
    pub up: [f64; 3],
    /// Metres per unit of every length (1: metres).
    pub metres_per_unit: f64,
    /// The scene's hands: side and model name.
    pub hands: Vec<HandInfo>,
    /// How many scenes the server may load by name ([`Client::scene_names`]).
    pub scenes_offered: u32,
    /// The scene's generation: one more after every load or reset, the same number as its
    /// geometry's ([`SceneGeometry::generation`]).
    pub generation: u64,
}

/// A hand of the scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HandInfo {
    /// Which hand.
    pub side: HandSide,
    /// The hand model's name.
    pub model: String,
}

/// One part of the scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartInfo {
    /// The id used in parts frames.
    pub id: u32,
    /// The part's name.
    pub name: String,
    /// Its collision group.
    pub group: String,
    /// Its geometry: the mesh path the server resolved, or a procedural shape's description.
    pub mesh_source: String,
    /// Whether it can be grasped and moved.
    pub movable: bool,
    /// Its pose when the scene was loaded.
    pub initial_pose: WirePose,
    /// The scale the scene applies to its mesh (already applied to the mesh on the wire).
    pub scale: f64,
    /// Whether a name or path was cut to fit the wire.
    pub truncated: bool,
}

/// An input stream's sending end: its publisher, and the notifier that wakes the server after
/// each sample.
struct InputPort<T: std::fmt::Debug + ZeroCopySend + 'static> {
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    /// What errors say was being done: sending a sample, then waking the server.
    actions: [&'static str; 2],
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> InputPort<T> {
    fn open(
        service: &publish_subscribe::PortFactory<ipc::Service, T, ()>,
        wakeup: &event::PortFactory<ipc::Service>,
        actions: [&'static str; 2],
    ) -> Result<Self, ClientError> {
        Ok(InputPort {
            publisher: service
                .publisher_builder()
                .create()
                .map_err(ClientError::port)?,
            notifier: wakeup
                .notifier_builder()
                .create()
                .map_err(ClientError::port)?,
            actions,
        })
    }

    /// Sends `sample` and wakes the server.
    fn send(&self, sample: &T) -> Result<(), ClientError> {
        let [sending, notifying] = self.actions;
        self.publisher
            .send_copy(*sample)
            .map_err(|error| ClientError::ipc(sending, error))?;
        self.notifier
            .notify()
            .map_err(|error| ClientError::ipc(notifying, error))?;
        Ok(())
    }
}

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
    latest_parts: Option<PartsFrame>,
    latest_hand: Option<HandFrame>,
    latest_clearance: Option<Box<ClearanceFrame>>,
    latest_geometry: Option<Arc<SceneGeometry>>,
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
        let (parts, hand, events, force) = (
            &outputs.parts,
            &outputs.hand,
            &outputs.events,
            &outputs.force,
        );
        let (geometry, clearance) = (&outputs.geometry, &outputs.clearance);
        wait_until_ready(
            &self.waitset,
            &[
                &outputs.geometry_listener,
                &outputs.parts_listener,
                &outputs.hand_listener,
                &outputs.events_listener,
                &outputs.force_listener,
                &outputs.clearance_listener,
            ],
            timeout,
            || {
                let has = |result: Result<bool, _>| {
                    result.map_err(|error| ClientError::ipc("check a subscriber", error))
                };
                Ok(has(geometry.has_samples())?
                    || has(parts.has_samples())?
                    || has(hand.has_samples())?
                    || has(events.has_samples())?
                    || has(force.has_samples())?
                    || has(clearance.has_samples())?)
            },
        )
    }

    /// Receives every queued frame, keeps the newest of each kind for [`Client::geometry`],
    /// [`Client::latest_parts`] and [`Client::latest_hand`], and returns them all in arrival
    /// order per kind: geometry, parts frames, events, force frames, clearance frames, then hand frames (the
    /// server publishes a frame's hand last, so the parts and events of a hand frame's own frame
    /// come with it or before it, and a new scene's geometry before its frames).
    pub fn receive(&mut self) -> Result<Vec<Frame>, ClientError> {
        let outputs = self.outputs("receive frames")?;
        let mut frames = Vec::new();
        while let Some(sample) = outputs
            .geometry
            .receive()
            .map_err(|error| ClientError::ipc("receive the geometry", error))?
        {
            let geometry = SceneGeometry::decode(sample.user_header(), sample.payload())?;
            frames.push(Frame::Geometry(Arc::new(geometry)));
        }
        while let Some(sample) = outputs
            .parts
            .receive()
            .map_err(|error| ClientError::ipc("receive a parts frame", error))?
        {
            frames.push(Frame::Parts(PartsFrame {
                header: *sample.user_header(),
                parts: sample.payload().to_vec(),
            }));
        }
        while let Some(sample) = outputs
            .events
            .receive()
            .map_err(|error| ClientError::ipc("receive an event", error))?
        {
            frames.push(Frame::Event(*sample.payload()));
        }
        while let Some(sample) = outputs
            .force
            .receive()
            .map_err(|error| ClientError::ipc("receive a force frame", error))?
        {
            frames.push(Frame::Force(*sample.payload()));
        }
        while let Some(sample) = outputs
            .clearance
            .receive()
            .map_err(|error| ClientError::ipc("receive a clearance frame", error))?
        {
            frames.push(Frame::Clearance(Box::new(*sample.payload())));
        }
        while let Some(sample) = outputs
            .hand
            .receive()
            .map_err(|error| ClientError::ipc("receive a hand frame", error))?
        {
            frames.push(Frame::Hand(*sample.payload()));
        }
        for frame in &frames {
            match frame {
                Frame::Geometry(geometry) => self.latest_geometry = Some(Arc::clone(geometry)),
                Frame::Parts(parts) => self.latest_parts = Some(parts.clone()),
                Frame::Hand(hand) => self.latest_hand = Some(*hand),
                Frame::Clearance(frame) => self.latest_clearance = Some(frame.clone()),
                Frame::Event(_) | Frame::Force(_) => {}
            }
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

    /// Receives every queued frame, keeping only the newest of each kind.
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
        self.latest_parts.as_ref()
    }

    /// The newest hand frame received so far (by [`Client::poll`] or [`Client::receive`]).
    pub fn latest_hand(&self) -> Option<&HandFrame> {
        self.latest_hand.as_ref()
    }

    /// The newest clearance frame received so far (by [`Client::poll`] or [`Client::receive`]):
    /// the part pairs closer than the scene's threshold, on the parts frame it names. The server
    /// publishes one per frame it measures, shortly after that frame's parts, and none while its
    /// scene has no `[params.clearance]` threshold.
    pub fn latest_clearance(&self) -> Option<&ClearanceFrame> {
        self.latest_clearance.as_deref()
    }

    /// The render meshes of the newest scene generation received so far (by [`Client::poll`]
    /// or [`Client::receive`]): every part's mesh in its own frame with its scale applied, and
    /// every hand segment's mesh in the segment's frame. A client that connects gets the
    /// current generation at once.
    pub fn geometry(&self) -> Option<&Arc<SceneGeometry>> {
        self.latest_geometry.as_ref()
    }

    /// Sleeps for `duration`; [`Wake::Terminated`] if a handled termination signal arrived.
    pub fn sleep(&self, duration: Duration) -> Wake {
        match self.node.wait(duration) {
            Ok(()) => Wake::Timeout,
            Err(_) => Wake::Terminated,
        }
    }

    /// Asks for the scene: its summary, then every part; `timeout` bounds the whole exchange.
    /// The answers describe one scene generation: when a load or reset comes between them, the
    /// questions are asked again.
    pub fn scene_info(&self, timeout: Duration) -> Result<SceneInfo, ClientError> {
        let deadline = deadline_after(timeout);
        loop {
            let summary = self.request(ControlRequest::scene_info(), deadline, timeout)?;
            if let Some(parts) = self.parts_of(&summary, deadline, timeout)? {
                return scene_info_of(&summary, parts);
            }
        }
    }

    /// Every part of the scene `summary` describes, or `None` if another generation of the
    /// scene answered meanwhile.
    fn parts_of(
        &self,
        summary: &ControlResponse,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<Option<Vec<PartInfo>>, ClientError> {
        let mut parts = Vec::with_capacity(summary.part_count as usize);
        for id in 0..summary.part_count {
            let answer = self.exchange(ControlRequest::part_info(id), deadline, timeout)?;
            if answer.generation != summary.generation {
                return Ok(None);
            }
            let part = check_status(ControlRequestKind::PartInfo, answer)?.part;
            parts.push(PartInfo {
                id: part.id,
                name: part.name.as_str()?.to_owned(),
                group: part.group.as_str()?.to_owned(),
                mesh_source: part.mesh_source.as_str()?.to_owned(),
                movable: part.flags & PART_MOVABLE != 0,
                initial_pose: part.initial_pose,
                scale: part.scale,
                truncated: part.truncated != 0,
            });
        }
        Ok(Some(parts))
    }

    /// The server's input counters (rejected, clamped and accepted samples).
    pub fn input_stats(&self, timeout: Duration) -> Result<InputStats, ClientError> {
        Ok(self.control(ControlRequest::scene_info(), timeout)?.stats)
    }

    /// Asks the server to load the scene file at `path` (as the server's file system sees it).
    pub fn load_scene(
        &self,
        path: &str,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let path = WireText::<MAX_PATH_BYTES>::new(path)?;
        self.control(ControlRequest::load_scene(path), timeout)
    }

    /// The names of the scenes the server may load by name ([`Client::load_named_scene`]);
    /// `timeout` bounds the whole exchange.
    pub fn scene_names(&self, timeout: Duration) -> Result<Vec<String>, ClientError> {
        let deadline = deadline_after(timeout);
        let first = self.request(ControlRequest::list_scene(0), deadline, timeout);
        let count = match &first {
            Ok(response) => response.listed_count,
            // An empty list refuses index 0.
            Err(ClientError::Refused { .. }) => return Ok(Vec::new()),
            Err(_) => return first.map(|_| Vec::new()),
        };
        let mut names = vec![first?.listed.as_str()?.to_owned()];
        for index in 1..count {
            let response = self.request(ControlRequest::list_scene(index), deadline, timeout)?;
            names.push(response.listed.as_str()?.to_owned());
        }
        Ok(names)
    }

    /// Asks the server to load the scene it offers as `name` (one of [`Client::scene_names`]).
    pub fn load_named_scene(
        &self,
        name: &str,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let name = WireText::<MAX_PATH_BYTES>::new(name)?;
        self.control(ControlRequest::load_named_scene(name), timeout)
    }

    /// Asks the server to put the scene back to its initial state.
    pub fn reset(&self, timeout: Duration) -> Result<ControlResponse, ClientError> {
        self.control(ControlRequest::reset(), timeout)
    }

    /// Asks the server to slide grasped parts with `metaphor`.
    pub fn set_metaphor(
        &self,
        metaphor: SlidingMetaphor,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        self.control(ControlRequest::set_metaphor(metaphor), timeout)
    }

    /// Sends any control request and waits for its answer; a status other than
    /// [`ControlStatus::Ok`] is a [`ClientError::Refused`].
    pub fn control(
        &self,
        request: ControlRequest,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        self.request(request, deadline_after(timeout), timeout)
    }

    /// Sends `request` and waits for its answer, refusing any status but [`ControlStatus::Ok`].
    fn request(
        &self,
        request: ControlRequest,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let kind = ControlRequestKind::try_from(request.kind)?;
        check_status(kind, self.exchange(request, deadline, timeout)?)
    }

    /// Sends `request` and waits for its answer, whatever its status.
    fn exchange(
        &self,
        request: ControlRequest,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let kind = ControlRequestKind::try_from(request.kind)?;
        let timed_out = || ClientError::Timeout {
            what: format!("the control request {kind:?}"),
            timeout,
        };
        loop {
            let pending = self
                .control
                .send_copy(request)
                .map_err(|error| ClientError::ipc("send a control request", error))?;
            self.control_notifier
                .notify()
                .map_err(|error| ClientError::ipc("notify the control service", error))?;
            loop {
                if let Some(response) = pending
                    .receive()
                    .map_err(|error| ClientError::ipc("receive a control response", error))?
                {
                    return Ok(*response.payload());
                }
                let remaining = deadline.saturating_duration_since(Instant::now());
                if remaining.is_zero() {
                    return Err(timed_out());
                }
                // A request that reached a server is never sent again (loading a scene twice
                // would be wrong); one that reached none is sent again once a server may be up.
                // The nap is a sleep: this client's own notification wakes its control
                // listener at once, so that waiting on it would send the request again and
                // again, spinning for as long as no server is up.
                if pending.number_of_server_connections() == 0 {
                    std::thread::sleep(remaining.min(CONTROL_RETRY));
                    break;
                }
                self.control_listener
                    .timed_wait(|_| {}, remaining)
                    .map_err(|error| ClientError::ipc("wait for a control response", error))?;
            }
        }
    }
}

/// The scene `summary` describes, with its `parts`.
fn scene_info_of(
    summary: &ControlResponse,
    parts: Vec<PartInfo>,
) -> Result<SceneInfo, ClientError> {
    let hands = (summary.hands.iter())
        .take(summary.hand_count as usize)
        .map(|hand| {
            Ok(HandInfo {
                side: HandSide::try_from(hand.side)?,
                model: hand.model.as_str()?.to_owned(),
            })
        })
        .collect::<Result<_, ClientError>>()?;
    Ok(SceneInfo {
        name: summary.scene_name.as_str()?.to_owned(),
        source: summary.scene_source.as_str()?.to_owned(),
        parts,
        stats: summary.stats,
        up: summary.up,
        metres_per_unit: summary.metres_per_unit,
        hands,
        scenes_offered: summary.listed_count,
        generation: summary.generation,
    })
}

fn check_status(
    kind: ControlRequestKind,
    response: ControlResponse,
) -> Result<ControlResponse, ClientError> {
    match ControlStatus::try_from(response.status)? {
        ControlStatus::Ok => Ok(response),
        status => Err(ClientError::Refused {
            request: kind,
            status,
            message: response.message.as_str()?.to_owned(),
        }),
    }
}
