//! The child processes of the benchmarks that talk to a server: a `vas-server run` on a private
//! prefix, which B0 and B8 start, time to its first answer and stop, and what they share with
//! B7's echo (stopping a child by its pid) and the soak (reading a process's memory).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use vas_client::Client;
use vas_client::recording::InputSample;
use vas_protocol::TrackerSample;
use vas_protocol::services::remove_prefix_segment;

use crate::e2e::round_trip;

/// The server binary: `explicit`, or `vas-server` beside this program.
pub fn server_binary(explicit: Option<&Path>) -> Result<PathBuf> {
    match explicit {
        Some(path) => Ok(path.to_owned()),
        None => Ok(std::env::current_exe()
            .context("locating vas-bench")?
            .with_file_name("vas-server")),
    }
}

/// A `vas-server run` on a private prefix, its stderr written to a log file. Stop it with
/// [`ServerProcess::stop`], which also removes its prefix from shared memory; dropped without,
/// it is only stopped.
pub struct ServerProcess {
    child: Child,
    prefix: String,
    log: PathBuf,
}

/// A server that has answered its first input sample, and the client that sent it.
pub struct ReadyServer {
    pub server: ServerProcess,
    pub client: Client,
    /// From starting the process to the answer.
    pub ready: Duration,
}

impl ServerProcess {
    /// How long a stopped server may take to exit before it is killed.
    const EXIT_PATIENCE: Duration = Duration::from_secs(5);

    /// Starts `binary run --prefix PREFIX ARGS...`, its stderr written to `log`; then connects
    /// once it answers control requests, sends `first` and waits for the hand frame answering
    /// it. The wait for control is one small request at a time (the input counters), not the
    /// scene's description, whose one request per part would add a large scene's round trips to
    /// the time measured. Each wait gives up after `timeout`; a server that exits meanwhile (a bad scene) is
    /// noticed within a second, and the error shows its log.
    pub fn start_ready(
        binary: &Path,
        prefix: &str,
        args: &[&OsStr],
        log: &Path,
        first: TrackerSample,
        timeout: Duration,
    ) -> Result<ReadyServer> {
        let started = Instant::now();
        let child = Command::new(binary)
            .args(["run", "--prefix", prefix])
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(log).context("the server's log")?)
            .spawn()
            .with_context(|| format!("starting {}", binary.display()))?;
        let mut server = ServerProcess {
            child,
            prefix: prefix.to_owned(),
            log: log.to_owned(),
        };
        let mut client = crate::args::connect(Some(prefix))?;
        while let Err(error) = client.input_stats(Duration::from_secs(1)) {
            if !server.is_running() || started.elapsed() > timeout {
                let log = server.log_text();
                server.stop(client);
                bail!("the server does not answer control requests ({error}); its log:\n{log}");
            }
        }
        match round_trip(&mut client, InputSample::Tracker(first), timeout, drop) {
            Ok(Some(_)) => Ok(ReadyServer {
                ready: started.elapsed(),
                server,
                client,
            }),
            failed => {
                server.stop(client);
                Err(failed
                    .err()
                    .unwrap_or_else(|| anyhow!("no answer to the first sample within {timeout:?}")))
            }
        }
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The server's log file.
    pub fn log(&self) -> &Path {
        &self.log
    }

    fn log_text(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// Stops the server with SIGINT (killing it if it does not end in time) once `client`, its
    /// last user on this prefix, is gone, and removes the prefix from shared memory.
    pub fn stop(mut self, client: Client) {
        drop(client);
        stop_child(&mut self.child, libc::SIGINT, Self::EXIT_PATIENCE, "server");
        // SAFETY: the server has ended (killed if SIGINT did not end it) and the last client on
        // its prefix is gone.
        if let Err(error) = unsafe { remove_prefix_segment(&self.prefix) } {
            tracing::warn!(%error, "the server's prefix stays in shared memory");
        }
    }
}

impl Drop for ServerProcess {
    fn drop(&mut self) {
        if self.is_running() {
            stop_child(&mut self.child, libc::SIGINT, Self::EXIT_PATIENCE, "server");
        }
    }
}

/// Sends `signal` to `child` (by its pid) and waits up to `patience` for it to end; kills it if
/// it does not. `name` says which child in the log.
pub fn stop_child(child: &mut Child, signal: libc::c_int, patience: Duration, name: &str) {
    let pid = child.id();
    // SAFETY: kill(2) only sends a signal; `pid` is our child, not yet reaped (the caller owns
    // its `Child` and it is waited for only below), so the id names no other process.
    let signalled =
        libc::pid_t::try_from(pid).is_ok_and(|pid| unsafe { libc::kill(pid, signal) } == 0);
    let deadline = Instant::now() + patience;
    while signalled && Instant::now() < deadline {
        match child.try_wait() {
            Ok(Some(_)) => return,
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(_) => break,
        }
    }
    tracing::warn!(
        pid,
        "the {name} did not stop on signal {signal}; killing it"
    );
    if let Err(error) = child.kill().and_then(|()| child.wait().map(drop)) {
        tracing::error!(pid, %error, "cannot kill the {name}");
    }
}

/// A memory figure of process `pid` in KiB: `field` (`VmRSS`, `VmHWM`) of `/proc/<pid>/status`.
pub fn status_kib(pid: u32, field: &str) -> Result<u64> {
    let path = format!("/proc/{pid}/status");
    let status = std::fs::read_to_string(&path)
        .with_context(|| format!("reading {path}: is process {pid} (the server) running?"))?;
    parse_status_kib(&status, field).with_context(|| format!("{path} has no readable {field} line"))
}

/// The value in KiB of `field` in a `/proc/<pid>/status` text.
fn parse_status_kib(status: &str, field: &str) -> Option<u64> {
    let line = status.lines().find_map(|line| {
        line.strip_prefix(field)
            .and_then(|rest| rest.strip_prefix(':'))
    })?;
    let mut fields = line.split_whitespace();
    let kib = fields.next()?.parse().ok()?;
    (fields.next() == Some("kB")).then_some(kib)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_figures_are_read_from_a_status_text() {
        let status = "Name:\tvas-server\nVmPeak:\t  900 kB\nVmHWM:\t  20000 kB\n\
                      VmRSS:\t   12345 kB\nThreads:\t4\n";
        assert_eq!(parse_status_kib(status, "VmRSS"), Some(12345));
        assert_eq!(parse_status_kib(status, "VmHWM"), Some(20000));
        assert_eq!(parse_status_kib("Name:\tx\n", "VmRSS"), None);
        assert_eq!(parse_status_kib("VmRSS:\tlots kB\n", "VmRSS"), None);
        assert_eq!(parse_status_kib("VmRSS:\t12 MB\n", "VmRSS"), None);
        assert_eq!(parse_status_kib("VmRSSx:\t12 kB\n", "VmRSS"), None);
    }

    #[test]
    fn this_process_has_resident_memory() {
        let kib = status_kib(std::process::id(), "VmRSS").expect("our own status");
        assert!(kib > 0);
        let peak = status_kib(std::process::id(), "VmHWM").expect("our own peak");
        assert!(peak >= kib);
    }

    #[test]
    fn a_missing_process_is_a_clear_error() {
        // Process ids are below 2^22 on Linux.
        let error = status_kib(u32::MAX, "VmRSS").expect_err("no such process");
        assert!(error.to_string().contains("is process"), "{error}");
    }
}
