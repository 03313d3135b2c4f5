//! `vas-bridge` end to end, with a client nobody here wrote: the Python zenoh package
//! (`eclipse-zenoh`, the minor version of the bridge's Rust crate), driven by
//! `tests/python/remote_client.py`, which decodes from `docs/wire.md` alone. A lockstep server,
//! the bridge on a free loopback port (no multicast scouting) and the script: it fetches and
//! decodes the geometry, parts and hand frames, sends a hand's joints and sees the hand follow,
//! has bad bytes and a stray user's sample counted and resets the scene. Then the server dies and
//! another comes on the same prefix, and the bridge's zenoh peer goes and comes back: the same
//! bridge, never restarted, serves the new server to it. And B13's `vas-bridge-bench
//! subscribers` runs B7 beside remote subscribers, each of which receives the outputs.
//!
//! The Python interpreter is `$VAS_PYTHON`, else the workspace's `.venv` (`.ci/run` makes it;
//! the README's set-up says how): without it, or without the package, the tests fail.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use vas_client::Client;
use vas_protocol::ControlRequest;
use vas_testkit::{PATIENCE, Server, Spawned, binary, configs_dir, fixtures_dir};

/// The workspace root.
fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The Python with the zenoh package; fails the test when there is none.
fn python() -> PathBuf {
    let python = std::env::var_os("VAS_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join(".venv/bin/python"));
    let imports = Command::new(&python)
        .args(["-c", "import zenoh"])
        .status()
        .is_ok_and(|status| status.success());
    assert!(
        imports,
        "{} cannot import zenoh: `python3 -m venv .venv && .venv/bin/pip install \
         eclipse-zenoh==1.10.2` (or set VAS_PYTHON)",
        python.display()
    );
    python
}

/// A loopback port nothing listens on now.
fn free_port() -> u16 {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("bind a loopback port");
    listener.local_addr().expect("its address").port()
}

/// A free loopback endpoint.
pub(super) fn endpoint() -> String {
    format!("tcp/127.0.0.1:{}", free_port())
}

/// A bridge for `prefix` with `extra` arguments (its zenoh endpoints), returned once it bridges.
pub(super) fn start_bridge(prefix: &str, session: &str, extra: &[&str]) -> Spawned {
    let mut args = vec![
        "--prefix",
        prefix,
        "--session",
        session,
        "--no-multicast-scouting",
    ];
    args.extend_from_slice(extra);
    let bridge = Spawned::start(&binary("vas-bridge"), &args, Stdio::null());
    assert!(
        bridge.wait_for_log("bridging", PATIENCE),
        "the bridge starts: {}",
        bridge.log()
    );
    bridge
}

/// Runs the remote client with `extra` arguments (its zenoh endpoint first); returns its JSON
/// summary.
fn remote_client(session: &str, extra: &[&str]) -> serde_json::Value {
    let workspace = workspace();
    let mut command = Command::new(python());
    command
        .arg(workspace.join("tests/python/remote_client.py"))
        .args(["--session", session, "--spec"])
        .arg(workspace.join("docs/wire.md"))
        .arg("--recording")
        .arg(fixtures_dir().join("captured_relaxed_approach.jsonl"))
        .args(extra)
        .stdout(Stdio::piped());
    let mut client = Spawned::spawn(command);
    let mut stdout = String::new();
    (client.take_stdout().expect("piped"))
        .read_to_string(&mut stdout)
        .expect("read the summary");
    let status = client.wait_exit(PATIENCE).expect("the client ends");
    assert!(
        status.success(),
        "the remote client failed:\n{}",
        client.log()
    );
    serde_json::from_str(&stdout).unwrap_or_else(|error| panic!("{error}: {stdout:?}"))
}

/// The lockstep server of the test, on the captured hand's scene.
fn server(test: &str) -> Server {
    let scene = configs_dir().join("precision_pinch.toml");
    Server::start_with(
        test,
        &["--scene", scene.to_str().expect("UTF-8"), "--lockstep"],
    )
}

/// Checks a summary: the geometry and frames decoded, the hand followed, the reset.
fn check_summary(summary: &serde_json::Value) {
    assert_eq!(summary["parts"], 1, "the pin: {summary}");
    assert_eq!(summary["hands"], 1, "{summary}");
    let moved = summary["moved"].as_array().expect("moved");
    let lifted = moved[2].as_f64().expect("a number");
    assert!(
        (lifted - 0.03).abs() < 1e-3,
        "the hand rose with its joints: {summary}"
    );
    assert!(summary["reset_generation"].as_u64() > summary["generation"].as_u64());
}

/// The server's counters: the bridged samples count as its own input.
fn joints_accepted(server: &mut Server) -> u64 {
    let client = Client::connect(Some(server.prefix())).expect("connect");
    server.wait_ready(&client);
    client.input_stats(PATIENCE).expect("stats").joints_accepted
}

#[test]
fn a_python_client_decodes_frames_drives_a_hand_and_resets_the_scene() {
    let mut server = server("bridge_python");
    let client = server.connect();
    // The bridge takes input for the scene's user only: a stray publisher's samples for
    // another user are refused and counted.
    let scene = client
        .control(ControlRequest::scene_info(), PATIENCE)
        .expect("scene info");
    let user = scene.user_name(0).expect("a scene has a user").to_owned();
    drop(client);
    let endpoint = endpoint();
    let bridge = start_bridge(
        server.prefix(),
        "python",
        &["--listen", &endpoint, "--user", &user],
    );
    let summary = remote_client("python", &["--connect", &endpoint, "--stray-user", "1"]);
    check_summary(&summary);
    assert_eq!(summary["users"][0], user.as_str(), "{summary}");
    assert_eq!(summary["bridge"]["refused_size"], 1, "{summary}");
    assert_eq!(summary["bridge"]["refused_version"], 1, "{summary}");
    assert_eq!(summary["bridge"]["refused_user"], 1, "{summary}");
    let samples = summary["samples"].as_u64().expect("samples");
    assert_eq!(
        joints_accepted(&mut server),
        samples,
        "the server took every sample"
    );
    drop(bridge);
}

/// Waits until the bridge's log has `count` lines containing `text`.
fn wait_for_lines(bridge: &Spawned, text: &str, count: usize) {
    let deadline = Instant::now() + PATIENCE;
    while bridge.log().matches(text).count() < count {
        assert!(
            Instant::now() < deadline,
            "no {count} × {text:?}: {}",
            bridge.log()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_bridge_serves_a_server_that_went_away_and_came_back() {
    let mut first = server("bridge_restart");
    drop(first.connect());
    let prefix = first.prefix().to_owned();
    // The bridge connects to its zenoh peer, which listens only while it runs.
    let endpoint = endpoint();
    let bridge = start_bridge(&prefix, "restart", &["--connect", &endpoint]);
    wait_for_lines(&bridge, "serving a vas server", 1);
    check_summary(&remote_client("restart", &["--listen", &endpoint]));

    // The server dies without a word; the bridge notices and waits for another.
    first.process.signal(libc::SIGKILL);
    assert!(
        first.process.wait_exit(PATIENCE).is_some(),
        "the first server dies"
    );
    wait_for_lines(&bridge, "lost the vas server", 1);
    let scene = configs_dir().join("precision_pinch.toml");
    let args = [
        "run",
        "--prefix",
        &prefix,
        "--scene",
        scene.to_str().expect("UTF-8"),
        "--lockstep",
    ];
    let second = Spawned::start(&binary("vas-server"), &args, Stdio::null());
    wait_for_lines(&bridge, "serving a vas server", 2);

    // The zenoh peer comes back, and the same bridge, never restarted, finds it again and
    // serves it the new server.
    let summary = remote_client("restart", &["--listen", &endpoint]);
    check_summary(&summary);
    assert_eq!(summary["bridge"]["servers"], 2, "{summary}");
    // The first server goes last: dropping it forgets the prefix, once nothing uses it.
    drop((bridge, second, first));
}

/// B13's remote subscribers: `vas-bridge-bench subscribers` attaches its zenoh sessions, runs
/// B7 (`vas-bench e2e`) beside them and reports what each one received through the bridge, at
/// the full rate and as renderers asking for 90 Hz.
#[test]
fn b7_runs_beside_remote_subscribers_that_each_receive_the_outputs() {
    let server = Server::start("bridge_subscribers");
    let endpoint = endpoint();
    let bridge = start_bridge(
        server.prefix(),
        "held",
        &["--listen", &endpoint, "--rate", "90"],
    );
    let e2e = binary("vas-bench");
    for rate in [None, Some("90")] {
        let mut args: Vec<&str> = vec![
            "--connect",
            &endpoint,
            "--session",
            "held",
            "subscribers",
            "--count",
            "2",
        ];
        args.extend(rate.map(|hz| ["--hz", hz]).into_iter().flatten());
        args.extend([
            "--",
            e2e.to_str().expect("UTF-8"),
            "e2e",
            "--prefix",
            server.prefix(),
            "--samples",
            "40",
            "--warmup",
            "5",
        ]);
        let mut tool = Spawned::start(&binary("vas-bridge-bench"), &args, Stdio::null());
        let status = tool.wait_exit(PATIENCE).expect("the benchmark ends");
        let log = tool.log();
        assert!(status.success(), "{log}");
        let received: Vec<u64> = (log.lines())
            .find_map(|line| line.split_once("2 remote subscribers received ["))
            .and_then(|(_, rest)| rest.split_once(']'))
            .map(|(counts, _)| counts.split(", ").map(|n| n.parse().expect("a count")))
            .expect("the subscribers' counts")
            .collect();
        assert_eq!(received.len(), 2, "{log}");
        // B7's answers reached each through the bridge (how many: parts and hand frames may be
        // dropped under congestion or thinned, events never; a thinned stream's first frame
        // goes out at once).
        assert!(
            received.iter().all(|&count| count > 0),
            "{rate:?}: {received:?}"
        );
    }
    drop(bridge);
}
