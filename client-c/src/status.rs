//! Status codes, the thread's last error message, and the guard that keeps panics and errors
//! from crossing into C.

use std::cell::RefCell;
use std::ffi::{CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

use vas_client_rs::ClientError;

/// What a call of this library returned: [`VasStatus::Ok`] or [`VasStatus::Empty`] on success,
/// a negative code on an error, whose words [`vas_last_error_message`] gives.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VasStatus {
    /// Done.
    Ok = 0,
    /// Done, but there is nothing to give yet: no frame of that kind (or no geometry) has arrived
    /// since the client connected. The out-parameters are left as they were.
    Empty = 1,
    /// A pointer argument that must not be null was null.
    NullArgument = -1,
    /// An argument is out of its range: an unknown role, side or metaphor code, a string that
    /// is not UTF-8 or too long.
    InvalidArgument = -2,
    /// The client was used on another thread than the one that connected it (its iceoryx2
    /// ports belong to that thread).
    WrongThread = -3,
    /// The client lacks the role the call needs (render for frames, input for samples).
    MissingRole = -4,
    /// The server's services have no room for another client of this role.
    Full = -5,
    /// No answer within the time-out: no server on this prefix, or it is stuck.
    Timeout = -6,
    /// The server refused a control request (an unknown scene name, a load while loading).
    Refused = -7,
    /// The server sent something this library cannot read (a newer or corrupt peer).
    Protocol = -8,
    /// iceoryx2 failed: the prefix, a service or a port could not be opened or used.
    Ipc = -9,
    /// The library panicked: a bug. The client that was called should be freed.
    Panic = -10,
    /// This system lacks what the call needs (file descriptors, on Windows).
    Unsupported = -11,
}

/// An error on its way to C: its status code and its words.
#[derive(Debug)]
pub(crate) struct Failure {
    pub(crate) status: VasStatus,
    pub(crate) message: String,
}

impl Failure {
    /// A null pointer where `argument` was expected.
    pub(crate) fn null(argument: &str) -> Self {
        Self {
            status: VasStatus::NullArgument,
            message: format!("{argument} is null"),
        }
    }

    /// An argument out of its range.
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Self {
            status: VasStatus::InvalidArgument,
            message: message.into(),
        }
    }
}

impl From<ClientError> for Failure {
    fn from(error: ClientError) -> Self {
        let status = match &error {
            ClientError::MissingRole { .. } => VasStatus::MissingRole,
            ClientError::Full { .. } => VasStatus::Full,
            ClientError::Timeout { .. } => VasStatus::Timeout,
            ClientError::Refused { .. } => VasStatus::Refused,
            ClientError::UnknownCode(_) | ClientError::WireText(_) | ClientError::Geometry(_) => {
                VasStatus::Protocol
            }
            _ => VasStatus::Ipc,
        };
        Self {
            status,
            message: error.to_string(),
        }
    }
}

thread_local! {
    /// The message of the last error on this thread, for [`vas_last_error_message`].
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// Keeps `message` as this thread's last error (a NUL inside it ends it early).
fn set_last_error(message: &str) {
    let text = message.split('\0').next().unwrap_or_default();
    let text = CString::new(text).unwrap_or_default();
    LAST_ERROR.with(|last| *last.borrow_mut() = text);
}

/// Runs the body of an exported function: its error becomes a status code and the thread's last
/// error, and so does a panic, which never unwinds into C.
pub(crate) fn guard(body: impl FnOnce() -> Result<VasStatus, Failure>) -> VasStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(status)) => status,
        Ok(Err(failure)) => {
            set_last_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            let what = (payload.downcast_ref::<&str>().copied())
                .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
                .unwrap_or("no message");
            set_last_error(&format!("the vas client library panicked: {what}"));
            VasStatus::Panic
        }
    }
}

/// The words of the last error a call of this library returned on the calling thread, as a
/// NUL-terminated UTF-8 string; empty before the first error.
///
/// The string belongs to the library: it stays valid until the next call that fails on this
/// thread. Copy it to keep it. Never null.
#[unsafe(no_mangle)]
pub extern "C" fn vas_last_error_message() -> *const c_char {
    LAST_ERROR.with(|last| last.borrow().as_ptr())
}

#[cfg(test)]
mod tests {
    use std::ffi::CStr;

    use super::*;

    fn last_error() -> String {
        // SAFETY: the pointer is this thread's message, valid until the next failing call.
        unsafe { CStr::from_ptr(vas_last_error_message()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_is_a_status_and_a_message() {
        let status = guard(|| panic!("a test's panic"));
        assert_eq!(status, VasStatus::Panic);
        assert_eq!(
            last_error(),
            "the vas client library panicked: a test's panic"
        );
    }

    #[test]
    fn an_error_keeps_its_words_until_the_next_error() {
        assert_eq!(
            guard(|| Err(Failure::null("client"))),
            VasStatus::NullArgument
        );
        assert_eq!(guard(|| Ok(VasStatus::Ok)), VasStatus::Ok);
        assert_eq!(last_error(), "client is null");
        let with_nul = Failure::invalid("cut\0here");
        assert_eq!(guard(|| Err(with_nul)), VasStatus::InvalidArgument);
        assert_eq!(last_error(), "cut");
    }
}
