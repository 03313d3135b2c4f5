//! In-process wake-ups of the I/O thread: the collision loop (a frame verified) and the scene
//! loader (a scene ready) write a byte to a socket pair whose reading end the I/O thread's WaitSet
//! watches beside its iceoryx2 listeners.
//!
//! A socket pair rather than an iceoryx2 event service, because such a service's notifier needs a
//! node of its own on the waking thread (iceoryx2 ports stay on the thread that made them). With
//! the socket pair the server holds one node for its whole life: a server killed at any instant
//! leaves the next one exactly one dead node to clean (a node killed while it was being made
//! cannot be cleaned), and a thread left behind at termination holds no shared memory.

use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::UnixStream;
use std::sync::Arc;

use iceoryx2::prelude::*;

/// A connected waker and its receiver.
pub fn channel() -> std::io::Result<(Waker, WakeupReceiver)> {
    let (writer, reader) = UnixStream::pair()?;
    // Neither end ever blocks: a full buffer means a wake-up is already pending.
    writer.set_nonblocking(true)?;
    reader.set_nonblocking(true)?;
    let fd = FileDescriptor::non_owning_new(reader.as_raw_fd())
        .ok_or_else(|| std::io::Error::other("the socket has no valid file descriptor"))?;
    Ok((
        Waker(Arc::new(writer)),
        WakeupReceiver { stream: reader, fd },
    ))
}

/// Wakes the I/O thread; cheap to clone and to send to any thread.
#[derive(Clone, Debug)]
pub struct Waker(Arc<UnixStream>);

impl Waker {
    /// Makes the receiver readable, so that the WaitSet returns.
    pub fn wake(&self) {
        match (&*self.0).write(&[1]) {
            Ok(_) => {}
            Err(error) if error.kind() == ErrorKind::WouldBlock => {}
            // The receiver is gone only when the server is shutting down.
            Err(error) if error.kind() == ErrorKind::BrokenPipe => {}
            Err(error) => tracing::error!(%error, "cannot wake the I/O thread"),
        }
    }
}

/// The reading end, attached to the I/O thread's WaitSet.
#[derive(Debug)]
pub struct WakeupReceiver {
    stream: UnixStream,
    /// `stream`'s descriptor as the WaitSet takes it; `stream` owns and closes it.
    fd: FileDescriptor,
}

impl WakeupReceiver {
    /// Takes every pending wake-up, so that the WaitSet sleeps until the next one; returns how
    /// many there were.
    pub fn drain(&self) -> std::io::Result<usize> {
        let mut buffer = [0; 64];
        let mut taken = 0;
        loop {
            match (&self.stream).read(&mut buffer) {
                Ok(0) => return Ok(taken),
                Ok(read) => taken += read,
                Err(error) if error.kind() == ErrorKind::WouldBlock => return Ok(taken),
                Err(error) if error.kind() == ErrorKind::Interrupted => {}
                Err(error) => return Err(error),
            }
        }
    }
}

impl FileDescriptorBased for WakeupReceiver {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.fd
    }
}

impl SynchronousMultiplexing for WakeupReceiver {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wake_ups_from_other_threads_are_pending_until_drained() {
        let (waker, receiver) = channel().expect("socket pair");
        assert_eq!(receiver.drain().expect("drain"), 0, "nothing pending");
        let threads: Vec<_> = (0..4)
            .map(|_| {
                let waker = waker.clone();
                std::thread::spawn(move || (0..10_000).for_each(|_| waker.wake()))
            })
            .collect();
        threads
            .into_iter()
            .for_each(|thread| thread.join().unwrap());
        assert!(receiver.drain().expect("drain") > 0, "woken");
        assert_eq!(receiver.drain().expect("drain"), 0, "drained");
        waker.wake();
        assert_eq!(receiver.drain().expect("drain"), 1, "woken again");
    }
}
