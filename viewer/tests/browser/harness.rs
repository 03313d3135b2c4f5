//! What the viewer's tests run: the `vas-viewer` binary, plain HTTP and WebSocket requests to
//! it, and headless Chromium driven through chromedriver (from `vas_testkit`).

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;
pub use vas_testkit::browser::{Browser, Screenshot};
pub use vas_testkit::http::http_get;
use vas_testkit::{PATIENCE, Spawned};

/// How often a condition is looked at again while a test waits for it.
const POLL: Duration = Duration::from_millis(20);

/// A `vas-viewer` on its own port, stopped when dropped.
pub struct Viewer {
    process: Spawned,
    /// Where it serves.
    pub address: SocketAddr,
}

impl Viewer {
    /// Starts a viewer for the server on `prefix`, on a free port of 127.0.0.1.
    pub fn start(prefix: &str) -> Self {
        let program = Path::new(env!("CARGO_BIN_EXE_vas-viewer"));
        let args = ["--prefix", prefix, "--listen", "127.0.0.1:0"];
        let mut process = Spawned::start(program, &args, Stdio::piped());
        let stdout = process.take_stdout().expect("stdout is piped");
        let mut line = String::new();
        BufReader::new(stdout)
            .read_line(&mut line)
            .expect("read the viewer's stdout");
        let address = line
            .trim()
            .strip_prefix("vas-viewer: open http://")
            .and_then(|rest| rest.strip_suffix('/'))
            .and_then(|address| address.parse().ok())
            .unwrap_or_else(|| {
                panic!(
                    "the viewer did not print its URL (got {line:?}):\n{}",
                    process.log()
                )
            });
        Self { process, address }
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.address)
    }

    /// The WebSocket's URL.
    pub fn ws_url(&self) -> String {
        format!("ws://{}/ws", self.address)
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
                self.process.log()
            );
            tokio::time::sleep(POLL).await;
        }
    }
}
