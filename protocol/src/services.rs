//! Service names and the quality-of-service settings of every vas service.
//!
//! Server and clients open each service with `open_or_create` and these exact settings, so that
//! either side may start first. Every publish-subscribe service has an event service of the same
//! name: a writer notifies it after each send, and readers wait on it instead of polling. The
//! control service has one too, notified by the client after a request and by the server after
//! its responses.
//!
//! The `open_*` functions below are the only place these settings are applied, so that the server
//! and every client open identical services.

use iceoryx2::config::Config;
use iceoryx2::node::Node;
use iceoryx2::prelude::{FileName, SemanticString, ServiceName};
use iceoryx2::service::Service;
use iceoryx2::service::port_factory::{event, publish_subscribe, request_response};

use crate::{
    ClearanceFrame, ControlRequest, ControlResponse, ForceFrame, GeometryHeader, GloveSample,
    HandFrame, HandJointsSample, PartState, PartsFrameHeader, SimEvent, TrackerSample,
};

/// Tracker samples ([`crate::TrackerSample`]), clients to server.
pub const TRACKER: &str = "vas/input/tracker";
/// Glove samples ([`crate::GloveSample`]), clients to server.
pub const GLOVE: &str = "vas/input/glove";
/// Hand-joint samples ([`crate::HandJointsSample`]), clients to server.
pub const HAND_JOINTS: &str = "vas/input/hand_joints";
/// Parts frames: a [`crate::PartsFrameHeader`] user header over a slice of [`crate::PartState`].
pub const PARTS: &str = "vas/output/parts";
/// Hand frames ([`crate::HandFrame`]).
pub const HAND: &str = "vas/output/hand";
/// Simulation events ([`crate::SimEvent`]).
pub const EVENTS: &str = "vas/output/events";
/// Force feedback ([`crate::ForceFrame`]).
pub const FORCE: &str = "vas/output/force";
/// Part pairs closer than the scene's clearance threshold ([`crate::ClearanceFrame`]), one
/// frame per parts frame measured.
pub const CLEARANCE: &str = "vas/output/clearance";
/// Render geometry of the scene: a [`crate::GeometryHeader`] user header over the bytes of a
/// [`crate::SceneGeometry`], one sample per scene generation.
pub const GEOMETRY: &str = "vas/scene/geometry";
/// Control requests and responses ([`crate::ControlRequest`], [`crate::ControlResponse`]).
pub const CONTROL: &str = "vas/control";

/// How many clients of each role the services take; every port limit below follows from these.
///
/// A client holds the ports of its roles only (`vas_client::Roles`): every client holds a
/// control client; one with the render role also a subscriber on each output service and the
/// geometry service; one with the input role also a publisher on each input stream. So renderers
/// and input devices are bounded by the output and input services, and the control service takes
/// enough clients for all of them and operators besides: however many renderers and devices
/// connect, an operator can still reset or load a scene.
pub mod clients {
    /// Clients with the render role: 16 renderers (viewers, `vas-client watch`), and 4 input
    /// devices beside them that read the answers to their samples (a viewer forwarding a
    /// headset, `vas-client send-* --answer`, a lockstep replay).
    pub const READERS: usize = 20;
    /// Clients with the input role: device bridges, viewers forwarding a headset, replays,
    /// `vas-client send-*`. As many as there were clients of every role before roles existed,
    /// so that 16 clients of the default roles still connect (the 17th is refused by the input
    /// streams).
    pub const SENDERS: usize = 16;
    /// Control clients kept for operators (`vas-client reset`, `load-scene`, `scenes`,
    /// `set-metaphor`, `info`), beyond one for every reader and one for every sender.
    pub const OPERATORS: usize = 4;
    /// Nodes a service takes beyond those of the ports it takes: a client that comes when the
    /// ports are all taken opens the service before it asks for a port, and is to be told that
    /// the ports are full, not that the service has no room for its node.
    pub const SPARE_NODES: usize = 4;
}

/// Settings of an input service (tracker, glove, hand joints).
pub mod input {
    /// Every client with the input role publishes on every input stream.
    pub const MAX_PUBLISHERS: usize = super::clients::SENDERS;
    /// The server, plus recorders.
    pub const MAX_SUBSCRIBERS: usize = 8;
    /// Samples buffered per subscriber; with safe overflow the oldest are dropped first, so a
    /// stalled server resumes with recent input rather than stale input.
    pub const SUBSCRIBER_BUFFER: usize = 64;
    /// Inputs have no history: an old sample is no target.
    pub const HISTORY: usize = 0;
    /// Nodes that may take part in the service: every publisher's and subscriber's (the server
    /// is a subscriber), and spares. A client without the input role does not open the service.
    pub const MAX_NODES: usize = MAX_PUBLISHERS + MAX_SUBSCRIBERS + super::clients::SPARE_NODES;
}

/// Settings of an output service (parts, hand, events, force) and of the geometry service.
pub mod output {
    /// One server publishes: a second server on the same prefix fails to start.
    pub const MAX_PUBLISHERS: usize = 1;
    /// Every client with the render role subscribes to every output service.
    pub const MAX_SUBSCRIBERS: usize = super::clients::READERS;
    /// Frames buffered per subscriber; readers want the latest frame, older ones are dropped.
    pub const SUBSCRIBER_BUFFER: usize = 16;
    /// A reader that (re)connects gets the latest frame at once (parts, force, clearance).
    pub const HISTORY: usize = 1;
    /// The hand service keeps one frame per hand a scene may have: the server publishes every
    /// hand's frame each frame, so the last [`crate::MAX_HANDS`] samples are the latest frame of
    /// each hand, and a reader that (re)connects gets every hand at once, not only the hand
    /// published last.
    pub const HAND_HISTORY: usize = crate::MAX_HANDS;
    /// Events are not state: a late reader gets no history of them.
    pub const EVENTS_HISTORY: usize = 0;
    /// Nodes that may take part in the service: the server's, every reader's, and spares. A
    /// client without the render role does not open the service.
    pub const MAX_NODES: usize = MAX_PUBLISHERS + MAX_SUBSCRIBERS + super::clients::SPARE_NODES;
    /// Initial capacity of a parts frame, in parts; the publisher grows it for larger scenes.
    pub const INITIAL_MAX_PARTS: usize = 64;
}

/// Settings of the geometry service.
pub mod geometry {
    /// A reader that (re)connects gets the current generation's geometry at once.
    pub const HISTORY: usize = 1;
    /// Geometry samples buffered per reader: the current one and the next.
    pub const SUBSCRIBER_BUFFER: usize = 2;
}

/// Settings of the control service.
pub mod control {
    use super::clients::{OPERATORS, READERS, SENDERS, SPARE_NODES};

    /// One server answers.
    pub const MAX_SERVERS: usize = 1;
    /// Every client holds one control client: one for each reader (20) and each sender (16),
    /// counted apart although a device that reads its answers is both, so that even when every
    /// render and input slot is taken by a client of its own, the 4 operators' slots are left:
    /// 40. With 16 renderers, an input device and an operator connected, 18 are taken.
    pub const MAX_CLIENTS: usize = READERS + SENDERS + OPERATORS;
    /// Requests one client may have outstanding.
    pub const MAX_ACTIVE_REQUESTS_PER_CLIENT: usize = 4;
    /// Responses buffered per request (each request gets exactly one).
    pub const MAX_RESPONSE_BUFFER: usize = 2;
    /// Nodes that may take part in the service: every client's, the server's, and spares.
    pub const MAX_NODES: usize = MAX_CLIENTS + MAX_SERVERS + SPARE_NODES;
}

/// Settings of the event service paired with each service above, sized for the largest pairing:
/// the control service's.
pub mod wakeup {
    use super::{control, input, output};

    /// The writers of the paired service: the control service's are every control client (after
    /// a request) and the server (after its responses); an input stream's are its publishers, an
    /// output's the server.
    pub const MAX_NOTIFIERS: usize = control::MAX_CLIENTS + control::MAX_SERVERS;
    /// The readers of the paired service: the control service's are, again, every control client
    /// (for their responses) and the server; an output's are its subscribers, an input's the
    /// server and the recorders.
    pub const MAX_LISTENERS: usize = control::MAX_CLIENTS + control::MAX_SERVERS;
    /// Nodes that may take part in the service: as many as in the paired service.
    pub const MAX_NODES: usize = max(control::MAX_NODES, max(input::MAX_NODES, output::MAX_NODES));

    const fn max(a: usize, b: usize) -> usize {
        if a > b { a } else { b }
    }
}

/// A service that could not be opened or created.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("cannot open the service {service}: {reason}")]
pub struct ServiceOpenError {
    /// The service name.
    pub service: &'static str,
    /// What iceoryx2 reported.
    pub reason: String,
}

/// A prefix that iceoryx2 cannot use in resource names.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid iceoryx2 prefix {prefix:?}: {reason}")]
pub struct PrefixError {
    /// The prefix given.
    pub prefix: String,
    /// What iceoryx2 reported.
    pub reason: String,
}

/// The iceoryx2 configuration for a prefix: the global configuration, with every resource name
/// starting with `prefix` when one is given, so that servers (and tests) on different prefixes
/// never meet.
pub fn config_with_prefix(prefix: Option<&str>) -> Result<Config, PrefixError> {
    let mut config = Config::global_config().clone();
    if let Some(prefix) = prefix {
        config.global.prefix = FileName::new(prefix.as_bytes()).map_err(|error| PrefixError {
            prefix: prefix.to_owned(),
            reason: format!("{error:?}"),
        })?;
    }
    Ok(config)
}

/// Removes the shared-memory segment iceoryx2 keeps per prefix for its nodes, which outlives
/// them: for the private prefixes of tests and benchmark runs, which are never used again (each
/// would otherwise leave a file in /dev/shm). Returns whether there was one to remove.
///
/// # Safety
/// Every process that used `prefix` must have ended, and none may start using it while this
/// runs.
pub unsafe fn remove_prefix_segment(prefix: &str) -> Result<bool, PrefixError> {
    let config = config_with_prefix(Some(prefix))?;
    // SAFETY: the caller guarantees that no process uses the prefix's domain.
    unsafe {
        iceoryx2::testing::remove_global_mgmt_segment::<iceoryx2::service::ipc::Service>(&config)
    }
    .map_err(|error| PrefixError {
        prefix: prefix.to_owned(),
        reason: format!("cannot remove its segment: {error:?}"),
    })
}

/// The tracker input service.
pub type TrackerService<S> = publish_subscribe::PortFactory<S, TrackerSample, ()>;
/// The glove input service.
pub type GloveService<S> = publish_subscribe::PortFactory<S, GloveSample, ()>;
/// The hand-joints input service.
pub type HandJointsService<S> = publish_subscribe::PortFactory<S, HandJointsSample, ()>;
/// The parts output service: a frame header over a slice of part states.
pub type PartsService<S> = publish_subscribe::PortFactory<S, [PartState], PartsFrameHeader>;
/// The hand output service.
pub type HandService<S> = publish_subscribe::PortFactory<S, HandFrame, ()>;
/// The events output service.
pub type EventsService<S> = publish_subscribe::PortFactory<S, SimEvent, ()>;
/// The force output service.
pub type ForceService<S> = publish_subscribe::PortFactory<S, ForceFrame, ()>;
/// The clearance output service.
pub type ClearanceService<S> = publish_subscribe::PortFactory<S, ClearanceFrame, ()>;
/// The geometry service: a generation header over the encoded meshes.
pub type GeometryService<S> = publish_subscribe::PortFactory<S, [u8], GeometryHeader>;
/// The control service.
pub type ControlService<S> =
    request_response::PortFactory<S, ControlRequest, (), ControlResponse, ()>;

fn service_name(name: &'static str) -> Result<ServiceName, ServiceOpenError> {
    ServiceName::new(name).map_err(|error| ServiceOpenError {
        service: name,
        reason: format!("{error:?}"),
    })
}

fn open_failed(name: &'static str, error: impl std::fmt::Display) -> ServiceOpenError {
    ServiceOpenError {
        service: name,
        reason: error.to_string(),
    }
}

fn open_input<S: Service, T>(
    node: &Node<S>,
    name: &'static str,
) -> Result<publish_subscribe::PortFactory<S, T, ()>, ServiceOpenError>
where
    T: std::fmt::Debug + iceoryx2::prelude::ZeroCopySend,
{
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<T>()
        .max_publishers(input::MAX_PUBLISHERS)
        .max_subscribers(input::MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(input::SUBSCRIBER_BUFFER)
        .history_size(input::HISTORY)
        .max_nodes(input::MAX_NODES)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|error| open_failed(name, error))
}

fn open_output<S: Service, T>(
    node: &Node<S>,
    name: &'static str,
    history: usize,
) -> Result<publish_subscribe::PortFactory<S, T, ()>, ServiceOpenError>
where
    T: std::fmt::Debug + iceoryx2::prelude::ZeroCopySend,
{
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<T>()
        .max_publishers(output::MAX_PUBLISHERS)
        .max_subscribers(output::MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(output::SUBSCRIBER_BUFFER)
        .history_size(history)
        .max_nodes(output::MAX_NODES)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|error| open_failed(name, error))
}

/// Opens (or creates) the tracker input service.
pub fn open_tracker<S: Service>(node: &Node<S>) -> Result<TrackerService<S>, ServiceOpenError> {
    open_input(node, TRACKER)
}

/// Opens (or creates) the glove input service.
pub fn open_glove<S: Service>(node: &Node<S>) -> Result<GloveService<S>, ServiceOpenError> {
    open_input(node, GLOVE)
}

/// Opens (or creates) the hand-joints input service.
pub fn open_hand_joints<S: Service>(
    node: &Node<S>,
) -> Result<HandJointsService<S>, ServiceOpenError> {
    open_input(node, HAND_JOINTS)
}

/// Opens (or creates) the parts output service.
pub fn open_parts<S: Service>(node: &Node<S>) -> Result<PartsService<S>, ServiceOpenError> {
    node.service_builder(&service_name(PARTS)?)
        .publish_subscribe::<[PartState]>()
        .user_header::<PartsFrameHeader>()
        .max_publishers(output::MAX_PUBLISHERS)
        .max_subscribers(output::MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(output::SUBSCRIBER_BUFFER)
        .history_size(output::HISTORY)
        .max_nodes(output::MAX_NODES)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|error| open_failed(PARTS, error))
}

/// Opens (or creates) the geometry service.
pub fn open_geometry<S: Service>(node: &Node<S>) -> Result<GeometryService<S>, ServiceOpenError> {
    node.service_builder(&service_name(GEOMETRY)?)
        .publish_subscribe::<[u8]>()
        .user_header::<GeometryHeader>()
        .max_publishers(output::MAX_PUBLISHERS)
        .max_subscribers(output::MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(geometry::SUBSCRIBER_BUFFER)
        .history_size(geometry::HISTORY)
        .max_nodes(output::MAX_NODES)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|error| open_failed(GEOMETRY, error))
}

/// Opens (or creates) the hand output service: history [`output::HAND_HISTORY`], so that a
/// reader that connects gets every hand's latest frame at once.
pub fn open_hand<S: Service>(node: &Node<S>) -> Result<HandService<S>, ServiceOpenError> {
    open_output(node, HAND, output::HAND_HISTORY)
}

/// Opens (or creates) the events output service.
pub fn open_events<S: Service>(node: &Node<S>) -> Result<EventsService<S>, ServiceOpenError> {
    open_output(node, EVENTS, output::EVENTS_HISTORY)
}

/// Opens (or creates) the force output service.
pub fn open_force<S: Service>(node: &Node<S>) -> Result<ForceService<S>, ServiceOpenError> {
    open_output(node, FORCE, output::HISTORY)
}

/// Opens (or creates) the clearance output service: history 1, so that a reader that connects
/// gets the latest pairs at once.
pub fn open_clearance<S: Service>(node: &Node<S>) -> Result<ClearanceService<S>, ServiceOpenError> {
    open_output(node, CLEARANCE, output::HISTORY)
}

/// Opens (or creates) the control service (see [`control::MAX_CLIENTS`] for how many clients it
/// takes).
pub fn open_control<S: Service>(node: &Node<S>) -> Result<ControlService<S>, ServiceOpenError> {
    node.service_builder(&service_name(CONTROL)?)
        .request_response::<ControlRequest, ControlResponse>()
        .max_servers(control::MAX_SERVERS)
        .max_clients(control::MAX_CLIENTS)
        .max_active_requests_per_client(control::MAX_ACTIVE_REQUESTS_PER_CLIENT)
        .max_response_buffer_size(control::MAX_RESPONSE_BUFFER)
        .max_nodes(control::MAX_NODES)
        .open_or_create()
        .map_err(|error| open_failed(CONTROL, error))
}

/// Opens (or creates) the event service paired with the service called `name` (one of the
/// names above), through which its writers wake its readers.
pub fn open_wakeup<S: Service>(
    node: &Node<S>,
    name: &'static str,
) -> Result<event::PortFactory<S>, ServiceOpenError> {
    node.service_builder(&service_name(name)?)
        .event()
        .max_notifiers(wakeup::MAX_NOTIFIERS)
        .max_listeners(wakeup::MAX_LISTENERS)
        .max_nodes(wakeup::MAX_NODES)
        .open_or_create()
        .map_err(|error| open_failed(name, error))
}
