//! Service names and the quality-of-service settings of every vas service.
//!
//! Server and clients open each service with `open_or_create` and these exact settings, so that
//! either side may start first. Every publish-subscribe service has an event service of the same
//! name: a writer notifies it after each send, and readers wait on it instead of polling. The
//! control service has one too, notified by the client after a request and by the server after
//! its responses.

/// Tracker samples ([`crate::TrackerSample`]), clients to server.
pub const TRACKER: &str = "vas/input/tracker";
/// Glove samples ([`crate::GloveSample`]), clients to server.
pub const GLOVE: &str = "vas/input/glove";
/// Parts frames: a [`crate::PartsFrameHeader`] user header over a slice of [`crate::PartState`].
pub const PARTS: &str = "vas/output/parts";
/// Hand frames ([`crate::HandFrame`]).
pub const HAND: &str = "vas/output/hand";
/// Simulation events ([`crate::SimEvent`]).
pub const EVENTS: &str = "vas/output/events";
/// Force feedback ([`crate::ForceFrame`]).
pub const FORCE: &str = "vas/output/force";
/// Control requests and responses ([`crate::ControlRequest`], [`crate::ControlResponse`]).
pub const CONTROL: &str = "vas/control";

/// Settings of an input service (tracker, glove).
pub mod input {
    /// Devices, replays and scripts may feed the same stream.
    pub const MAX_PUBLISHERS: usize = 8;
    /// The server, plus recorders.
    pub const MAX_SUBSCRIBERS: usize = 8;
    /// Samples buffered per subscriber; with safe overflow the oldest are dropped first, so a
    /// stalled server resumes with recent input rather than stale input.
    pub const SUBSCRIBER_BUFFER: usize = 64;
    /// Inputs have no history: an old sample is no target.
    pub const HISTORY: usize = 0;
    /// Nodes that may take part in the service.
    pub const MAX_NODES: usize = 20;
}

/// Settings of an output service (parts, hand, events, force).
pub mod output {
    /// One server publishes: a second server on the same prefix fails to start.
    pub const MAX_PUBLISHERS: usize = 1;
    /// Renderers, watchers, recorders and tests.
    pub const MAX_SUBSCRIBERS: usize = 16;
    /// Frames buffered per subscriber; readers want the latest frame, older ones are dropped.
    pub const SUBSCRIBER_BUFFER: usize = 16;
    /// A reader that (re)connects gets the latest frame at once (parts and hand).
    pub const HISTORY: usize = 1;
    /// Events are not state: a late reader gets no history of them.
    pub const EVENTS_HISTORY: usize = 0;
    /// Nodes that may take part in the service.
    pub const MAX_NODES: usize = 24;
    /// Initial capacity of a parts frame, in parts; the publisher grows it for larger scenes.
    pub const INITIAL_MAX_PARTS: usize = 64;
}

/// Settings of the control service.
pub mod control {
    /// One server answers.
    pub const MAX_SERVERS: usize = 1;
    /// Renderers, tools and tests.
    pub const MAX_CLIENTS: usize = 16;
    /// Requests one client may have outstanding.
    pub const MAX_ACTIVE_REQUESTS_PER_CLIENT: usize = 4;
    /// Responses buffered per request (each request gets exactly one).
    pub const MAX_RESPONSE_BUFFER: usize = 2;
    /// Nodes that may take part in the service.
    pub const MAX_NODES: usize = 24;
}

/// Settings of the event service paired with each service above.
pub mod event {
    /// The writers of the paired service, plus the control clients.
    pub const MAX_NOTIFIERS: usize = 24;
    /// The readers of the paired service.
    pub const MAX_LISTENERS: usize = 24;
    /// Nodes that may take part in the service.
    pub const MAX_NODES: usize = 48;
}
