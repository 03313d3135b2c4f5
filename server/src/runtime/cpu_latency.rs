//! A CPU latency request (`vas-server run --cpu-latency US`): Linux's PM QoS device
//! `/dev/cpu_dma_latency`, held open while the server runs.
//!
//! A thread woken on an idle core waits for the core to leave its idle state: from a deep one,
//! or in a virtual machine from a halt that handed the core back to the host, tens and at times
//! hundreds of microseconds. Every sample that finds the server asleep pays it, and so does each
//! loop woken on the other core. While the request is held, idle cores use only states that wake
//! within the given time (0: they poll, never sleeping), which costs power and takes that
//! latency away. The kernel withdraws the request when the file is closed, however the server
//! ends.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The kernel's CPU latency QoS device.
pub const DEVICE: &str = "/dev/cpu_dma_latency";

/// A held CPU latency request; dropping it withdraws the request.
#[derive(Debug)]
pub struct CpuLatencyRequest {
    /// The open device: the request lasts as long as it is open.
    _device: File,
}

/// Why the request could not be made.
#[derive(Debug, thiserror::Error)]
#[error(
    "cannot hold the CPU wake-up latency at {microseconds} us through {}: {source}; it needs \
     write access to it (as root)",
    path.display()
)]
pub struct CpuLatencyError {
    /// The latency asked for.
    pub microseconds: u32,
    /// The device written.
    pub path: PathBuf,
    /// What the system said.
    #[source]
    pub source: std::io::Error,
}

impl CpuLatencyRequest {
    /// Asks the kernel to keep every core's wake-up latency within `microseconds` until the
    /// request is dropped.
    pub fn hold(microseconds: u32) -> Result<Self, CpuLatencyError> {
        Self::hold_at(Path::new(DEVICE), microseconds)
    }

    /// Writes the request to `path` (the device, or a file in tests) and keeps it open.
    fn hold_at(path: &Path, microseconds: u32) -> Result<Self, CpuLatencyError> {
        let error = |source| CpuLatencyError {
            microseconds,
            path: path.to_owned(),
            source,
        };
        // The device takes the latency as a binary 32-bit signed integer.
        let value = i32::try_from(microseconds)
            .map_err(|_| error(std::io::Error::other("the latency does not fit 31 bits")))?;
        let mut device = OpenOptions::new().write(true).open(path).map_err(error)?;
        device.write_all(&value.to_ne_bytes()).map_err(error)?;
        Ok(Self { _device: device })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_request_is_the_latency_as_a_32_bit_integer() {
        let folder = tempfile::tempdir().expect("a scratch folder");
        let path = folder.path().join("device");
        std::fs::write(&path, b"").expect("a stand-in for the device");
        let request = CpuLatencyRequest::hold_at(&path, 25).expect("written");
        assert_eq!(
            std::fs::read(&path).expect("read back"),
            25i32.to_ne_bytes()
        );
        drop(request);
    }

    #[test]
    fn a_request_that_cannot_be_made_says_where_and_what_it_needs() {
        let folder = tempfile::tempdir().expect("a scratch folder");
        let missing = folder.path().join("no-such-device");
        let error = CpuLatencyRequest::hold_at(&missing, 0).expect_err("no device");
        let message = error.to_string();
        assert!(
            message.starts_with(&format!(
                "cannot hold the CPU wake-up latency at 0 us through {}: ",
                missing.display()
            )) && message.ends_with("it needs write access to it (as root)"),
            "{message}"
        );
        let too_long = CpuLatencyRequest::hold_at(&missing, u32::MAX).expect_err("too long");
        assert!(
            too_long.to_string().contains("does not fit 31 bits"),
            "{too_long}"
        );
    }
}
