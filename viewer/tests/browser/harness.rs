//! What the viewer's tests run: the `vas-viewer` binary, plain HTTP and WebSocket requests to
//! it, and headless Chromium driven through chromedriver (from `vas_testkit`).

use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::Path;
use std::process::{ExitStatus, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;
pub use vas_testkit::PATIENCE;
use vas_testkit::Spawned;
pub use vas_testkit::browser::{Browser, Screenshot};
pub use vas_testkit::http::http_get;

/// How often a condition is looked at again while a test waits for it.
const POLL: Duration = Duration::from_millis(20);

/// A `vas-viewer` on its own port, stopped when dropped.
pub struct Viewer {
    process: Spawned,
    /// Where it serves.
    pub address: SocketAddr,
    /// The page's URL, as the viewer printed it.
    url: String,
}

/// The `vas-viewer` binary.
fn program() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_vas-viewer"))
}

impl Viewer {
    /// Starts a viewer for the server on `prefix`, on a free port of 127.0.0.1.
    pub fn start(prefix: &str) -> Self {
        Self::start_with(prefix, &["--listen", "127.0.0.1:0"])
    }

    /// Starts a viewer for the server on `prefix` with `args` (a `--listen` with port 0 among
    /// them), and reads the URL it prints.
    pub fn start_with(prefix: &str, args: &[&str]) -> Self {
        let args = [&["--prefix", prefix], args].concat();
        let mut process = Spawned::start(program(), &args, Stdio::piped());
        let stdout = process.take_stdout().expect("stdout is piped");
        let mut line = String::new();
        BufReader::new(stdout)
            .read_line(&mut line)
            .expect("read the viewer's stdout");
        let url = line
            .trim()
            .strip_prefix("vas-viewer: open ")
            .map(str::to_owned);
        let address = (url.as_deref())
            .and_then(|url| url.split_once("://"))
            .and_then(|(_, rest)| rest.strip_suffix('/'))
            .and_then(|authority| authority.to_socket_addrs().ok()?.next());
        let (Some(url), Some(address)) = (url, address) else {
            panic!(
                "the viewer did not print its URL (got {line:?}):\n{}",
                process.log()
            )
        };
        Self {
            process,
            address,
            url,
        }
    }

    /// Runs a viewer with `args` that must refuse to start: its exit status and its log.
    pub fn refusal(args: &[&str]) -> (ExitStatus, String) {
        let mut process = Spawned::start(program(), args, Stdio::piped());
        let status = process.wait_exit(PATIENCE);
        let status = status.unwrap_or_else(|| panic!("still running:\n{}", process.log()));
        (status, process.log())
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        self.url.clone()
    }

    /// The WebSocket's URL.
    pub fn ws_url(&self) -> String {
        format!("ws://{}/ws", self.address)
    }

    /// The viewer's log so far.
    pub fn log(&self) -> String {
        self.process.log()
    }

    /// `GET /stats`.
    pub async fn stats(&self) -> Value {
        let (status, body) = http_get(self.address, "/stats").await;
        assert_eq!(status, 200, "GET /stats");
        serde_json::from_slice(&body).expect("/stats is JSON")
    }

    /// Waits until `/stats` satisfies `condition`, and returns it.
    pub async fn wait_for_stats(&self, what: &str, condition: impl Fn(&Value) -> bool) -> Value {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let stats = self.stats().await;
            if condition(&stats) {
                return stats;
            }
            assert!(
                Instant::now() < deadline,
                "waited for {what}; stats: {stats}\n{}",
                self.log()
            );
            tokio::time::sleep(POLL).await;
        }
    }
}
