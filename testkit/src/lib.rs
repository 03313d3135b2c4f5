//! What the tests and the benchmarks share, kept out of the server's library: scripted hand
//! motions and the scripted grasps ([`script`]), B1's tumbling motion ([`tumble`]), a world of
//! balls for the clasp's tests ([`balls`]); the real `vas-server` and `vas-client` binaries as
//! child processes, each test on its own iceoryx2 prefix; the recorded scenarios: their expected
//! outcomes ([`scenarios`]), their fixture generator ([`fixtures`], `make-fixtures`) and their
//! offline replay through the server's interaction model, checked by parry ([`offline`]). For the
//! viewer's tests and its benchmark: headless Chromium ([`browser`]) and plain HTTP requests
//! ([`http`]).
//!
//! Finding the binaries: a test of this crate cannot use `env!("CARGO_BIN_EXE_...")` (that only
//! names binaries of the crate under test), so [`binary`] and [`example`] run `cargo build` for
//! the workspace's binaries and examples once per test process, with the profile the tests were
//! built with, and take them from the same target directory as the test executable. When they
//! are up to date this costs one cargo invocation; when the sources changed it rebuilds them, so
//! the tests never run a stale server. The build selects the same targets as `cargo test
//! --workspace` (bins, tests and examples of every member), so cargo resolves the same
//! dependency features and reuses what the test run compiled: building only the two binaries
//! would resolve without the dev-dependencies' features and compile iceoryx2, parry and their
//! build tools a second time.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};

use vas_client::{Client, ClientError};

/// How long a server may take to load its scene and answer its first control request.
pub const STARTUP_TIMEOUT: Duration = Duration::from_secs(30);

/// How long a test waits for an answer or an event before it fails (generous: a loaded
/// machine must not fail a test; a passing test never waits this long).
pub const PATIENCE: Duration = Duration::from_secs(30);

/// The path of a workspace binary (`vas-server`, `vas-client`), built on first use.
///
/// Panics (failing the test) if cargo cannot build it: nothing can be tested without it.
pub fn binary(name: &str) -> PathBuf {
    target_dir().join(name)
}

/// The path of an example of a workspace member (`renderer`, `dop_tree_query`), built on first
/// use with the binaries.
///
/// Panics (failing the test) if cargo cannot build it.
pub fn example(name: &str) -> PathBuf {
    target_dir().join("examples").join(name)
}

/// The target directory of this test run's profile, once its binaries and examples are built.
fn target_dir() -> &'static Path {
    static TARGET_DIR: OnceLock<PathBuf> = OnceLock::new();
    TARGET_DIR.get_or_init(build_binaries)
}

fn build_binaries() -> PathBuf {
    let test_exe = std::env::current_exe().expect("the test executable has a path");
    // target/<profile dir>/deps/<test executable>
    let profile_dir = test_exe
        .parent()
        .and_then(Path::parent)
        .expect("the test executable lies in target/<profile>/deps")
        .to_owned();
    let profile = match profile_dir.file_name().and_then(|name| name.to_str()) {
        // `cargo test` builds with the test profile into target/debug; building the binaries
        // with the same profile reuses the libraries it already compiled.
        Some("debug") => "test",
        Some(other) => other,
        None => panic!("unexpected target directory {}", profile_dir.display()),
    };
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut build = Command::new(cargo);
    for (name, _) in std::env::vars_os() {
        if name.to_str().is_some_and(set_by_cargo_for_this_test) {
            build.env_remove(name);
        }
    }
    let status = build
        .args([
            "build",
            "--profile",
            profile,
            "--workspace",
            "--bins",
            "--tests",
            "--examples",
        ])
        .status()
        .expect("cargo runs");
    assert!(
        status.success(),
        "building the workspace's binaries and examples failed"
    );
    profile_dir
}

/// Whether `cargo test` set the variable `name` for this test process alone (its package's
/// name, version and directories, its binaries, its `OUT_DIR`). Build scripts such as ring's
/// declare some of them with `rerun-if-env-changed`, so a nested build that inherited them would
/// see them changed from the outer `cargo test` and rebuild ring and everything above it (zenoh,
/// the viewer, the bridge) once for every test package.
fn set_by_cargo_for_this_test(name: &str) -> bool {
    const EXACT: [&str; 6] = [
        "CARGO",
        "CARGO_CRATE_NAME",
        "CARGO_PRIMARY_PACKAGE",
        "CARGO_TARGET_TMPDIR",
        "CARGO_RUSTC_CURRENT_DIR",
        "OUT_DIR",
    ];
    const PREFIXES: [&str; 3] = ["CARGO_PKG_", "CARGO_BIN_", "CARGO_MANIFEST_"];
    EXACT.contains(&name) || PREFIXES.iter().any(|prefix| name.starts_with(prefix))
}

/// A prefix for one test: the process id keeps concurrent test runs apart, the test name keeps
/// the tests of one run apart.
pub fn unique_prefix(test: &str) -> String {
    format!("vas_t{}_{test}_", std::process::id())
}

/// A child process whose stderr is collected line by line; stopped (SIGTERM, then SIGKILL) when
/// dropped.
pub struct Spawned {
    child: Child,
    log: Arc<(Mutex<Stderr>, Condvar)>,
}

/// What a [`Spawned`] process wrote to stderr so far, and whether the pipe has closed.
#[derive(Default)]
struct Stderr {
    lines: Vec<String>,
    closed: bool,
}

impl Spawned {
    /// Starts `program` with `args`, stdout discarded or piped as asked, stderr collected.
    pub fn start(program: &Path, args: &[&str], stdout: Stdio) -> Self {
        let mut command = Command::new(program);
        command.args(args).stdout(stdout);
        Self::spawn(command)
    }

    /// Starts `command` (its program, arguments, environment and stdout set by the caller) with
    /// no stdin, `RUST_LOG=info` and stderr collected.
    pub fn spawn(mut command: Command) -> Self {
        let mut child = command
            .env("RUST_LOG", "info")
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|error| {
                panic!("cannot start {}: {error}", command.get_program().display())
            });
        let log = Arc::new((Mutex::new(Stderr::default()), Condvar::new()));
        let stderr = child.stderr.take().expect("stderr is piped");
        let collector = Arc::clone(&log);
        std::thread::spawn(move || {
            let (collected, changed) = &*collector;
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                collected.lock().expect("log lock").lines.push(line);
                changed.notify_all();
            }
            collected.lock().expect("log lock").closed = true;
            changed.notify_all();
        });
        Self { child, log }
    }

    /// The process id.
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// Takes the child's stdout (when it was started with `Stdio::piped()`).
    pub fn take_stdout(&mut self) -> Option<std::process::ChildStdout> {
        self.child.stdout.take()
    }

    /// Everything the process wrote to stderr so far.
    pub fn log(&self) -> String {
        self.log.0.lock().expect("log lock").lines.join("\n")
    }

    /// Waits until a stderr line contains `text`; false on timeout.
    pub fn wait_for_log(&self, text: &str, timeout: Duration) -> bool {
        self.wait_for_stderr(Instant::now() + timeout, |stderr| {
            stderr.lines.iter().any(|line| line.contains(text))
        })
    }

    /// Waits until `done` holds of the stderr collected so far; false if `deadline` passes first.
    fn wait_for_stderr(&self, deadline: Instant, done: impl Fn(&Stderr) -> bool) -> bool {
        let (collected, changed) = &*self.log;
        let mut collected = collected.lock().expect("log lock");
        loop {
            if done(&collected) {
                return true;
            }
            let remaining = deadline.saturating_duration_since(Instant::now());
            if remaining.is_zero() {
                return false;
            }
            collected = changed
                .wait_timeout(collected, remaining)
                .expect("log lock")
                .0;
        }
    }

    /// Sends a signal (`libc::SIGTERM`, `libc::SIGINT`, `libc::SIGKILL`).
    pub fn signal(&self, signal: libc::c_int) {
        let pid = libc::pid_t::try_from(self.child.id()).expect("pids fit pid_t");
        // SAFETY: kill(2) only reads its arguments; the pid is our own child, not yet reaped
        // (it is reaped only in `wait_exit` or `Drop`).
        let result = unsafe { libc::kill(pid, signal) };
        assert_eq!(result, 0, "kill({pid}, {signal}) failed");
    }

    /// Whether the process still runs.
    pub fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// Waits for the process to exit; `None` if it still runs after `timeout`. Once it has
    /// exited, [`Spawned::log`] holds everything it wrote.
    pub fn wait_exit(&mut self, timeout: Duration) -> Option<ExitStatus> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.child.try_wait().expect("try_wait") {
                // Its last lines reach the log on the collecting thread, when the pipe closes
                // (later if a process it started still holds the pipe: not forever).
                self.wait_for_stderr(Instant::now() + STDERR_GRACE, |stderr| stderr.closed);
                return Some(status);
            }
            if Instant::now() >= deadline {
                return None;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Stops the process with SIGTERM, so that it removes its shared-memory resources, and kills
    /// it if it does not stop within `STOP_GRACE`. (A SIGKILLed node's resources stay until
    /// another process on its prefix cleans up dead nodes, and a test's prefix is never used
    /// again.)
    pub fn stop(&mut self) {
        if self.is_running() {
            if let Ok(pid) = libc::pid_t::try_from(self.child.id()) {
                // SAFETY: as in `signal`; the child is not reaped yet.
                unsafe { libc::kill(pid, libc::SIGTERM) };
            }
            if self.wait_exit(STOP_GRACE).is_none() {
                // Failing to kill an exited process is fine; nothing else can be done here.
                let _ = self.child.kill();
            }
        }
        let _ = self.child.wait();
    }
}

/// How long a process gets to stop on SIGTERM when a test ends, before it is killed.
const STOP_GRACE: Duration = Duration::from_secs(5);

/// How long [`Spawned::wait_exit`] waits, once the process has exited, for its stderr to close.
const STDERR_GRACE: Duration = Duration::from_secs(2);

impl Drop for Spawned {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Removes what a test's private prefix leaves in shared memory once nothing uses it.
///
/// # Safety
/// Every process and node of this test on `prefix` must have ended.
pub unsafe fn forget_prefix(prefix: &str) {
    // SAFETY: as the caller guarantees; a failure leaves one small file behind.
    let _ = unsafe { vas_protocol::services::remove_prefix_segment(prefix) };
}

/// A `vas-server run` on its own prefix; when dropped, stopped and its prefix forgotten (drop
/// the test's clients on it first).
pub struct Server {
    /// The process.
    pub process: Spawned,
    prefix: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        self.process.stop();
        // SAFETY: the server has ended, and a test drops its clients before its server (they
        // are made from it, so declared after it).
        unsafe { forget_prefix(&self.prefix) };
    }
}

impl Server {
    /// Starts a server for `test` on the default scene.
    pub fn start(test: &str) -> Self {
        Self::start_with(test, &[])
    }

    /// Starts a server for `test` with extra `run` arguments (e.g. `--scene FILE`).
    pub fn start_with(test: &str, extra: &[&str]) -> Self {
        let prefix = unique_prefix(test);
        let mut args = vec!["run", "--prefix", prefix.as_str()];
        args.extend_from_slice(extra);
        let process = Spawned::start(&binary("vas-server"), &args, Stdio::null());
        Self { process, prefix }
    }

    /// A server on a scene config of `toml`, written into a scratch folder that lives as long
    /// as the folder returned beside the server.
    pub fn start_on_scene(test: &str, toml: &str) -> (Self, tempfile::TempDir) {
        let folder = tempfile::tempdir().expect("a scratch folder");
        let scene = folder.path().join("scene.toml");
        std::fs::write(&scene, toml).expect("write the scene");
        let server = Server::start_with(test, &["--scene", scene.to_str().expect("a UTF-8 path")]);
        (server, folder)
    }

    /// The server's iceoryx2 prefix.
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// A client on the server's prefix, returned once the server answers control requests.
    pub fn connect(&mut self) -> Client {
        let client = Client::connect(Some(&self.prefix)).expect("client connects");
        self.wait_ready(&client);
        client
    }

    /// Waits until the server answers a scene-info request.
    pub fn wait_ready(&mut self, client: &Client) {
        match client.scene_info(STARTUP_TIMEOUT) {
            Ok(_) => {}
            Err(ClientError::Timeout { .. }) if !self.process.is_running() => {
                panic!("the server exited during start:\n{}", self.process.log())
            }
            Err(error) => panic!(
                "the server does not answer: {error}\n{}",
                self.process.log()
            ),
        }
    }

    /// Runs the `vas-client` tool against this server.
    pub fn client_tool(&self, args: &[&str], stdout: Stdio) -> Spawned {
        let mut all = vec!["--prefix", self.prefix.as_str()];
        all.extend_from_slice(args);
        Spawned::start(&binary("vas-client"), &all, stdout)
    }

    /// Runs a `vas-bench` benchmark (its subcommand and arguments) against this server.
    pub fn bench_tool(&self, args: &[&str], stdout: Stdio) -> Spawned {
        let mut all = args.to_vec();
        all.extend_from_slice(&["--prefix", self.prefix.as_str()]);
        Spawned::start(&binary("vas-bench"), &all, stdout)
    }
}

/// The repository's `configs/` directory.
pub fn configs_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("configs")
}

/// The directory of the recordings the tests replay (`tests/fixtures/`).
pub fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("tests")
        .join("fixtures")
}

pub mod balls;
pub mod browser;
pub mod captured;
pub mod fixtures;
pub mod hand_models;
pub mod hands;
pub mod http;
pub mod offline;
pub mod scenarios;
pub mod script;
pub mod tumble;

/// A tracker sample stamped now: the hand root at `position` (no rotation), the cart at the
/// origin.
pub fn tracker(seq: u64, position: [f64; 3]) -> vas_protocol::TrackerSample {
    vas_protocol::TrackerSample {
        seq,
        timestamp_ns: vas_protocol::wall_clock_ns(),
        hand: vas_protocol::WirePose {
            position,
            rotation: [0.0, 0.0, 0.0, 1.0],
        },
        cart: vas_protocol::WirePose::IDENTITY,
        sensor_id: 0,
        user: 0,
        side: 0,
        reserved: 0,
    }
}
