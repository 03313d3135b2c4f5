//! How a client connects: its prefix, roles and signal handling.

use iceoryx2::prelude::*;
use vas_protocol::services::{self, config_with_prefix};

use super::latest::Latest;
use super::{Client, Roles};
use crate::ClientError;
use crate::wait::{new_waitset, signal_mode};

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
    /// report [`Wake::Terminated`](crate::Wake::Terminated) instead of the process dying. Off by default: a library
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
            latest: Latest::default(),
            node,
        };
        client.take_roles(self.roles)?;
        Ok(client)
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
