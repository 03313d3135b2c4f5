//! The client library against shared memory and files: its iceoryx2 ports on a private prefix
//! (and their wake-up descriptors), and the recording format, in one test binary.

mod local_ipc;
mod recording;
#[cfg(unix)]
mod wake_descriptors;
