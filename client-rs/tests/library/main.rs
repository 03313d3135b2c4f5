//! The client library against shared memory and files: its iceoryx2 ports on a private prefix
//! and the recording format, in one test binary.

mod local_ipc;
mod recording;
