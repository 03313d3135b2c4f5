//! Headless Chromium driven through chromedriver (WebDriver), for the viewer's browser tests and
//! its latency benchmark. Debian's `chromium` and `chromium-driver` packages provide both.

use std::net::SocketAddr;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::wd::WindowHandle;
use fantoccini::{Client, ClientBuilder};
use serde::de::DeserializeOwned;
use serde_json::{Value, json};
use tokio::net::TcpStream;

use crate::http::http_request;
use crate::{PATIENCE, Spawned};

/// How often a condition is looked at again while waiting for it.
const POLL: Duration = Duration::from_millis(20);

/// The last `count` lines of the text file at `path`, or why it cannot be read.
fn last_lines(path: &Path, count: usize) -> String {
    match std::fs::read_to_string(path) {
        Ok(text) => {
            let lines: Vec<&str> = text.lines().collect();
            lines[lines.len().saturating_sub(count)..].join("\n")
        }
        Err(error) => format!("({} cannot be read: {error})", path.display()),
    }
}

/// Only one browser at a time: two Chromiums rendering with SwiftShader on a small machine would
/// each take longer than both in turn. Async, because a test holds its turn across awaits (each
/// test has a runtime of its own; this lock needs none).
static ONE_BROWSER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

const CHROMIUM: &str = "/usr/bin/chromium";
const CHROMEDRIVER: &str = "/usr/bin/chromedriver";

/// Headless Chromium in a fresh profile, driven over WebDriver; ended when dropped.
pub struct Browser {
    /// The WebDriver session.
    pub client: Client,
    driver: Spawned,
    driver_port: u16,
    /// Chromium's profile and chromedriver's log.
    scratch: tempfile::TempDir,
    _turn: tokio::sync::MutexGuard<'static, ()>,
}

impl Browser {
    /// Starts chromedriver and a headless Chromium whose window is `width` × `height`.
    pub async fn start(width: u32, height: u32) -> Self {
        for program in [CHROMIUM, CHROMEDRIVER] {
            assert!(
                Path::new(program).exists(),
                "{program} is missing: the viewer's browser tests need Debian's chromium and \
                 chromium-driver (apt-get install chromium chromium-driver)"
            );
        }
        let turn = ONE_BROWSER.lock().await;
        // Under /tmp whatever TMPDIR says, and Chromium's temporary files in it: Chromium puts its
        // single-instance socket in TMPDIR and exits at once when that path is longer than a
        // socket address may be (108 bytes).
        let scratch = tempfile::Builder::new()
            .prefix("vas-chromium-")
            .tempdir_in("/tmp")
            .expect("a scratch directory");
        let profile = scratch.path().join("profile");
        // The log, with Chromium's own output in it, says why a browser that would not start
        // exited; a failed start prints its end.
        let log = scratch.path().join("chromedriver.log");
        let port = free_port();
        // Through sh, to set a umask that leaves the owner every bit: Chromium checks that the
        // directory it makes for its single-instance socket has mode 0700 and crashes at start
        // otherwise, which a umask such as 0222 (read-only files by default) gives it. `exec`
        // keeps the process id, so dropping `Spawned` still ends chromedriver.
        let mut driver = Command::new("/bin/sh");
        driver
            .args(["-c", "umask 077 && exec \"$0\" \"$@\"", CHROMEDRIVER])
            .arg(format!("--port={port}"))
            .arg(format!("--log-path={}", log.display()))
            .arg("--enable-chrome-logs")
            .env("TMPDIR", scratch.path())
            .stdout(Stdio::null())
            // A process group of its own, which Chromium's processes join: a test that fails
            // before `close` still ends them all when the browser is dropped.
            .process_group(0);
        let driver = Spawned::spawn(driver);
        let driver_url = format!("http://127.0.0.1:{port}");
        wait_for_port(port).await;
        let args = [
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--use-gl=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--disable-quic",
            // Shared memory from a temporary file, so a small /dev/shm cannot end the browser.
            "--disable-dev-shm-usage",
            // Pages in background tabs keep their timers and sockets running.
            "--disable-background-timer-throttling",
            "--disable-renderer-backgrounding",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--window-size={width},{height}"),
        ];
        let capabilities = json!({
            "goog:chromeOptions": { "binary": CHROMIUM, "args": args }
        });
        let client = ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
            .capabilities(
                capabilities
                    .as_object()
                    .expect("capabilities are an object")
                    .clone(),
            )
            .connect(&driver_url)
            .await
            .unwrap_or_else(|error| {
                panic!(
                    "cannot start Chromium through chromedriver: {error}\n\
                     the end of chromedriver's log:\n{}",
                    last_lines(&log, 80)
                )
            });
        Self {
            client,
            driver,
            driver_port: port,
            scratch,
            _turn: turn,
        }
    }

    /// Panics with what failed and the end of chromedriver's log, which says why.
    fn failed(&self, what: &str, error: impl std::fmt::Display) -> ! {
        let log = self.scratch.path().join("chromedriver.log");
        panic!(
            "{what}: {error}\nthe end of chromedriver's log:\n{}",
            last_lines(&log, 40)
        )
    }

    /// Opens `url` in `count` windows (the first is the session's own), each a page of its own
    /// that is drawn as a visible one; returns their handles.
    pub async fn open_windows(&self, url: &str, count: usize) -> Vec<WindowHandle> {
        let first = self.client.window().await;
        let mut windows =
            vec![first.unwrap_or_else(|error| self.failed("the first window", error))];
        for _ in 1..count {
            let window = self.client.new_window(false).await;
            windows.push(
                window
                    .unwrap_or_else(|error| self.failed("a new window", error))
                    .handle,
            );
        }
        for window in &windows {
            self.load(window, url).await;
        }
        windows
    }

    /// Opens `url` in `count` more tabs of the current window and makes the current tab current
    /// (and shown) again; returns the tabs' handles. A tab that is not shown keeps its page
    /// running, receiving and handling messages, but draws no animation frames.
    pub async fn open_tabs(&self, url: &str, count: usize) -> Vec<WindowHandle> {
        let current = self.client.window().await;
        let current = current.unwrap_or_else(|error| self.failed("the current tab", error));
        let mut tabs = Vec::new();
        for _ in 0..count {
            let tab = self.client.new_window(true).await;
            let tab = tab
                .unwrap_or_else(|error| self.failed("a new tab", error))
                .handle;
            self.load(&tab, url).await;
            tabs.push(tab);
        }
        self.switch_to(&current).await;
        tabs
    }

    /// Makes `window` current and loads `url` in it.
    async fn load(&self, window: &WindowHandle, url: &str) {
        self.switch_to(window).await;
        let opened = self.client.goto(url).await;
        opened.unwrap_or_else(|error| self.failed("open the page", error));
    }

    /// Makes `window` the current one, whose page [`Browser::eval`] and the others look at.
    pub async fn switch_to(&self, window: &WindowHandle) {
        self.client
            .switch_to_window(window.clone())
            .await
            .unwrap_or_else(|error| self.failed("switch windows", error));
    }

    /// Evaluates `expression` in the current page and returns its value.
    pub async fn eval<T: DeserializeOwned>(&self, expression: &str) -> T {
        let value = self
            .client
            .execute(&format!("return {expression};"), Vec::new())
            .await
            .unwrap_or_else(|error| self.failed(&format!("evaluating {expression}"), error));
        serde_json::from_value(value.clone())
            .unwrap_or_else(|error| panic!("{expression} gave {value}: {error}"))
    }

    /// Waits until `expression` is truthy in the current page.
    pub async fn wait_for(&self, expression: &str) {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let value: Value = self.eval(&format!("!!({expression})")).await;
            if value == Value::Bool(true) {
                return;
            }
            assert!(Instant::now() < deadline, "waited for {expression}");
            tokio::time::sleep(POLL).await;
        }
    }

    /// Sends a Chrome DevTools Protocol command to the current page through chromedriver.
    pub async fn cdp(&self, command: &str, params: Value) {
        let session = self
            .client
            .session_id()
            .await
            .expect("session id")
            .expect("a session");
        let body = json!({ "cmd": command, "params": params }).to_string();
        let address = SocketAddr::from(([127, 0, 0, 1], self.driver_port));
        let path = format!("/session/{session}/goog/cdp/execute");
        let (status, answer) = http_request(address, "POST", &path, Some(&body)).await;
        assert_eq!(
            status,
            200,
            "CDP {command} failed: {}",
            String::from_utf8_lossy(&answer)
        );
    }

    /// A screenshot of the window, decoded: (width, height, RGBA rows).
    pub async fn screenshot(&self) -> Screenshot {
        let png = self.client.screenshot().await.expect("screenshot");
        let decoder = png::Decoder::new(std::io::Cursor::new(png.clone()));
        let mut reader = decoder.read_info().expect("a PNG");
        let mut pixels = vec![0; reader.output_buffer_size().expect("a buffer size")];
        let info = reader.next_frame(&mut pixels).expect("a frame");
        assert_eq!(info.bit_depth, png::BitDepth::Eight, "8-bit screenshot");
        let channels = info.color_type.samples();
        Screenshot {
            width: info.width,
            height: info.height,
            channels,
            pixels,
            png,
        }
    }

    /// Ends the session and the browser.
    pub async fn close(self) {
        let _ = self.client.clone().close().await;
    }
}

impl Drop for Browser {
    /// Ends chromedriver and every Chromium process it started (chromedriver's own ending leaves
    /// them running). The group cannot be another's yet: chromedriver is reaped after this.
    fn drop(&mut self) {
        if let Ok(group) = libc::pid_t::try_from(self.driver.id()) {
            // SAFETY: a signal to the process group chromedriver leads; it fails harmlessly if
            // they have all ended.
            unsafe { libc::kill(-group, libc::SIGKILL) };
        }
    }
}

/// A decoded screenshot.
pub struct Screenshot {
    pub width: u32,
    pub height: u32,
    channels: usize,
    pixels: Vec<u8>,
    /// The screenshot as Chromium encoded it.
    pub png: Vec<u8>,
}

impl Screenshot {
    /// The RGB colour at pixel (x, y).
    pub fn rgb(&self, x: u32, y: u32) -> [u8; 3] {
        let at = (y as usize * self.width as usize + x as usize) * self.channels;
        [self.pixels[at], self.pixels[at + 1], self.pixels[at + 2]]
    }

    /// Whether some pixel within `radius` of (x, y) satisfies `matches`.
    pub fn any_near(
        &self,
        (x, y): (f64, f64),
        radius: i64,
        matches: impl Fn([u8; 3]) -> bool,
    ) -> bool {
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        (-radius..=radius).any(|dy| {
            (-radius..=radius).any(|dx| {
                let (px, py) = (cx + dx, cy + dy);
                px >= 0
                    && py >= 0
                    && px < i64::from(self.width)
                    && py < i64::from(self.height)
                    && matches(self.rgb(px as u32, py as u32))
            })
        })
    }
}

/// A port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|listener| listener.local_addr())
        .expect("a free port")
        .port()
}

/// Waits until something accepts connections on `port`.
async fn wait_for_port(port: u16) {
    let deadline = Instant::now() + PATIENCE;
    while TcpStream::connect(("127.0.0.1", port)).await.is_err() {
        assert!(
            Instant::now() < deadline,
            "chromedriver does not listen on {port}"
        );
        tokio::time::sleep(POLL).await;
    }
}
