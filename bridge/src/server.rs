//! The bridge's side of a server's lifetime: the state its threads share, and waiting for a
//! server to answer.
//!
//! The vas client library connects to services, not to a server: its ports outlive a server
//! that dies, and it does not reconnect by itself. So the bridge does what the viewer does: the
//! output thread waits until a server answers, serves it until it falls silent and stops
//! answering, and starts afresh with new ports (a new server's geometry and latest frames then
//! arrive as a late joiner's history). Each start bumps [`Shared::epoch`], and the input and
//! control threads take new ports of their own when they see it change.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use vas_client::{Client, ClientError, Roles, Wake};
use zenoh::handlers::FifoChannelHandler;

use crate::latest::Latest;
use crate::stats::Stats;

/// How long a server has to answer a control request before it is taken as gone.
pub const CONTROL_TIMEOUT: Duration = Duration::from_secs(2);
/// How long one look for a server lasts while there is none.
const LOOK: Duration = Duration::from_millis(250);
/// Longest wait for a zenoh sample or query: bounds how late a stop or a new server is noticed.
const TICK: Duration = Duration::from_millis(100);
/// How long a thread waits before it tries again after an iceoryx2 error.
pub const RETRY: Duration = Duration::from_millis(500);

/// What the bridge's threads share.
#[derive(Debug, Default)]
pub struct Shared {
    /// Set when the bridge stops (a termination signal).
    pub stop: AtomicBool,
    /// One more each time the output thread connects to a server.
    pub epoch: AtomicU64,
    /// The scene generation of the latest geometry, 0 before any.
    pub generation: AtomicU64,
    /// Set while the control thread waits for a load or reset, which may keep the server
    /// silent for longer than the output thread waits for an answer.
    pub loading: AtomicBool,
    /// The counters.
    pub stats: Stats,
    /// The latest state, for the queryables.
    pub latest: Mutex<Latest>,
}

impl Shared {
    /// Whether the bridge stops.
    pub fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// The current epoch.
    pub fn epoch(&self) -> u64 {
        self.epoch.load(Ordering::Acquire)
    }

    /// The next item `handler` receives, waiting a tick at a time; `None` once the bridge stops
    /// or the channel closes (logged as `what` closed).
    pub fn next<T>(&self, handler: &FifoChannelHandler<T>, what: &str) -> Option<T> {
        while !self.stopping() {
            match handler.recv_timeout(TICK) {
                Ok(Some(item)) => return Some(item),
                Ok(None) => continue,
                Err(error) => {
                    tracing::error!(%error, "the {what} closed");
                    return None;
                }
            }
        }
        None
    }
}

/// Connects a client with `roles` on `prefix`, letting iceoryx2 catch termination signals so
/// that the bridge stops cleanly.
pub fn connect(prefix: Option<&str>, roles: Roles) -> Result<Client, ClientError> {
    Client::builder()
        .prefix(prefix)
        .roles(roles)
        .handle_termination_signals(true)
        .connect()
}

/// Looks for a server on `prefix` until one answers (true) or the bridge stops (false).
pub fn wait_for_server(prefix: Option<&str>, shared: &Shared) -> Result<bool, ClientError> {
    let client = connect(prefix, Roles::CONTROL)?;
    let mut said = false;
    while !shared.stopping() {
        match client.input_stats(LOOK) {
            Ok(_) => return Ok(true),
            Err(ClientError::Timeout { .. }) => {
                if !said {
                    tracing::info!(prefix, "waiting for a vas server");
                    said = true;
                }
                if client.sleep(Duration::ZERO) == Wake::Terminated {
                    shared.stop.store(true, Ordering::Relaxed);
                }
            }
            Err(error) => return Err(error),
        }
    }
    Ok(false)
}

/// A client of a thread that follows the output thread's epochs: taken anew when the epoch
/// changed, so that its ports are those of the current server.
pub struct Follower {
    prefix: Option<String>,
    roles: Roles,
    client: Option<(u64, Client)>,
}

impl Follower {
    /// A follower that connects with `roles` on `prefix`.
    pub fn new(prefix: Option<&str>, roles: Roles) -> Self {
        Self {
            prefix: prefix.map(str::to_owned),
            roles,
            client: None,
        }
    }

    /// The client of the current epoch, connected now if need be; `None` (logged) when it
    /// cannot connect.
    pub fn client(&mut self, shared: &Shared) -> Option<&Client> {
        let epoch = shared.epoch();
        if self.client.as_ref().is_none_or(|(of, _)| *of != epoch) {
            self.client = None;
            match connect(self.prefix.as_deref(), self.roles) {
                Ok(client) => self.client = Some((epoch, client)),
                Err(error) => {
                    let roles = self.roles;
                    tracing::warn!(%error, %roles, "cannot connect to the vas services");
                    std::thread::sleep(RETRY);
                }
            }
        }
        self.client.as_ref().map(|(_, client)| client)
    }

    /// Forgets the client, so that the next call connects afresh.
    pub fn drop_client(&mut self) {
        self.client = None;
    }
}
