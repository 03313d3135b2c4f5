//! Errors of the client library.

use std::time::Duration;

use vas_protocol::services::{PrefixError, ServiceOpenError};
use vas_protocol::{ControlRequestKind, ControlStatus, UnknownCode, WireTextError};

/// What went wrong talking to a vas server.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The iceoryx2 prefix is not usable.
    #[error(transparent)]
    Prefix(#[from] PrefixError),
    /// A service could not be opened, e.g. because its settings or types do not match.
    #[error(transparent)]
    Service(#[from] ServiceOpenError),
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
}

impl ClientError {
    /// A [`ClientError::Ipc`] for `action` from any iceoryx2 error.
    pub(crate) fn ipc(action: &'static str, error: impl std::fmt::Debug) -> Self {
        Self::Ipc {
            action,
            reason: format!("{error:?}"),
        }
    }

    /// A [`ClientError::Ipc`] for a port that could not be created.
    pub(crate) fn port(error: impl std::fmt::Debug) -> Self {
        Self::ipc("create a port", error)
    }
}
