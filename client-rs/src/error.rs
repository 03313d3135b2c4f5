//! Errors of the client library.

use std::time::Duration;

use iceoryx2::port::listener::ListenerCreateError;
use iceoryx2::port::notifier::NotifierCreateError;
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::service::port_factory::client::ClientCreateError;
use vas_protocol::services::{PrefixError, ServiceOpenError};

use crate::Roles;
use vas_protocol::{
    ControlRequestKind, ControlStatus, GeometryDecodeError, UnknownCode, WireTextError,
};

/// What went wrong talking to a vas server.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The iceoryx2 prefix is not usable.
    #[error(transparent)]
    Prefix(#[from] PrefixError),
    /// A service could not be opened, e.g. because its settings or types do not match.
    #[error(transparent)]
    Service(#[from] ServiceOpenError),
    /// A service already has as many ports of a kind as it takes: too many clients (or
    /// recorders) are connected to this server. Ports of a killed client are freed when the next
    /// one connects.
    #[error(
        "a vas service already has as many {kind} as it takes: too many clients or recorders \
         are connected"
    )]
    Full {
        /// The kind of port the service has no room for.
        kind: &'static str,
    },
    /// The client was opened without the role that an operation needs (see
    /// [`crate::Roles`]): it holds no ports for it.
    #[error("this client cannot {action}: it was opened without the {role} role")]
    MissingRole {
        /// The role the operation needs.
        role: Roles,
        /// What was asked.
        action: &'static str,
    },
    /// An iceoryx2 operation failed.
    #[error("cannot {action}: {reason}")]
    Ipc {
        /// What the client was doing.
        action: &'static str,
        /// What iceoryx2 reported.
        reason: String,
    },
    /// No answer within the timeout (no server on this prefix, or it is stuck).
    #[error("no answer to {what} within {timeout:?}; is a vas server running on this prefix?")]
    Timeout {
        /// What was waited for.
        what: String,
        /// The timeout.
        timeout: Duration,
    },
    /// The server refused a control request.
    #[error("control request {request:?} failed with {status:?}: {message}")]
    Refused {
        /// The request kind.
        request: ControlRequestKind,
        /// The status the server answered.
        status: ControlStatus,
        /// The server's explanation.
        message: String,
    },
    /// The server answered with a code this client does not know (a newer or corrupt peer).
    #[error(transparent)]
    UnknownCode(#[from] UnknownCode),
    /// The server answered with a malformed string.
    #[error(transparent)]
    WireText(#[from] WireTextError),
    /// A geometry sample could not be read (a corrupt or mismatched peer).
    #[error(transparent)]
    Geometry(#[from] GeometryDecodeError),
}

impl ClientError {
    /// A [`ClientError::Ipc`] for `action` from any iceoryx2 error.
    pub(crate) fn ipc(action: &'static str, error: impl std::fmt::Debug) -> Self {
        Self::Ipc {
            action,
            reason: format!("{error:?}"),
        }
    }

    /// The error of a port that could not be created: [`ClientError::Full`] where the service
    /// had no room for it, else a [`ClientError::Ipc`].
    pub(crate) fn port<E: PortCreateError>(error: E) -> Self {
        if error.service_full() {
            Self::Full { kind: E::KIND }
        } else {
            Self::ipc("create a port", error)
        }
    }
}

/// iceoryx2's errors of creating a port, told apart where the service had no room for it.
pub(crate) trait PortCreateError: std::fmt::Debug {
    /// The kind of port, plural, for messages.
    const KIND: &'static str;
    /// True when the service already had as many ports of this kind as it takes.
    fn service_full(&self) -> bool;
}

/// Implements [`PortCreateError`] for iceoryx2 error types, one `Error => "kind", FullVariant;`
/// each.
macro_rules! port_create_errors {
    ($($error:ident => $kind:literal, $full:ident;)*) => {$(
        impl PortCreateError for $error {
            const KIND: &'static str = $kind;
            fn service_full(&self) -> bool {
                matches!(self, Self::$full)
            }
        }
    )*};
}

port_create_errors! {
    PublisherCreateError => "publishers", ExceedsMaxSupportedPublishers;
    SubscriberCreateError => "subscribers", ExceedsMaxSupportedSubscribers;
    NotifierCreateError => "notifiers", ExceedsMaxSupportedNotifiers;
    ListenerCreateError => "listeners", ExceedsMaxSupportedListeners;
    ClientCreateError => "control clients", ExceedsMaxSupportedClients;
}
