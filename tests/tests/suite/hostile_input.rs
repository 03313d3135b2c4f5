//! Hostile input to a running server (issue 50): mesh files and a tree-cache file whose counts
//! lie, loaded under an address-space limit; a file that is no scene, whose content must not
//! come back in the error; a sample rejected, which `send-tracker --answer` reports with its
//! reason; a sample stamped far in the future, refused and counted.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use vas_client::{Client, ClientError};
use vas_protocol::{ControlStatus, wall_clock_ns};
use vas_testkit::{
    PATIENCE, STARTUP_TIMEOUT, Server, Spawned, binary, configs_dir, forget_prefix, tracker,
    unique_prefix,
};

/// The address space the server may have: `ulimit -v 1000000` (KiB). An 84-byte STL once made
/// the server reserve 1.8 GB for the triangles its header counts, and abort.
const ADDRESS_SPACE_BYTES: u64 = 1_000_000 * 1024;

/// `vas-server run --prefix PREFIX ARGS`, its address space limited to [`ADDRESS_SPACE_BYTES`].
fn start_limited(prefix: &str, args: &[&str]) -> Spawned {
    let mut command = Command::new(binary("vas-server"));
    command
        .args(["run", "--prefix", prefix])
        .args(args)
        .stdout(Stdio::null());
    // SAFETY: the closure runs in the child between fork and exec, and only calls setrlimit(2),
    // which is async-signal-safe, on a value of its own.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: ADDRESS_SPACE_BYTES,
                rlim_max: ADDRESS_SPACE_BYTES,
            };
            match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    Spawned::spawn(command)
}

/// The malformed-count mesh files of the loading tests.
fn malformed(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../server/tests/loading/malformed_counts")
        .join(name)
}

/// Writes a scene of one part, the mesh `mesh` or a box when `None`, as `folder/name.toml`.
fn write_scene(folder: &Path, name: &str, mesh: Option<&Path>) -> String {
    let shape = match mesh {
        Some(mesh) => format!("mesh = {:?}", mesh.display().to_string()),
        None => "shape = { kind = \"box\", size = [0.1, 0.1, 0.1], triangles = 1200 }".to_owned(),
    };
    let hand = configs_dir().join("hands/right.toml");
    let scene = folder.join(format!("{name}.toml"));
    let text = format!(
        "name = {name:?}\nhand = {:?}\n\n[[parts]]\nname = \"part\"\n{shape}\n",
        hand.display().to_string()
    );
    std::fs::write(&scene, text).expect("write the scene");
    scene.display().to_string()
}

/// The message of a load the server refuses.
fn refusal(client: &Client, scene: &str) -> String {
    match client.load_scene(scene, PATIENCE) {
        Err(ClientError::Refused {
            status, message, ..
        }) => {
            assert_eq!(status, ControlStatus::SceneLoadFailed, "{message}");
            message
        }
        other => panic!("{scene}: {other:?}"),
    }
}

#[test]
fn under_an_address_space_limit_every_lying_count_is_refused_and_the_server_serves_on() {
    let folder = tempfile::tempdir().expect("a scratch folder");
    let trees = folder.path().join("trees");
    let valid = write_scene(folder.path(), "valid", None);
    let prefix = unique_prefix("lying_counts");
    let trees_arg = trees.display().to_string();
    let mut server = start_limited(&prefix, &["--scene", &valid, "--tree-cache", &trees_arg]);
    let client = Client::connect(Some(&prefix)).expect("connect");
    if let Err(error) = client.scene_info(STARTUP_TIMEOUT) {
        panic!(
            "the limited server does not serve: {error}\n{}",
            server.log()
        );
    }

    for name in [
        "count.stl",
        "count.ply",
        "count.obj",
        "count.gltf",
        "count.glb",
    ] {
        let mesh = folder.path().join(name);
        std::fs::copy(malformed(name), &mesh).expect("copy the file");
        let scene = write_scene(folder.path(), name, Some(&mesh));
        let message = refusal(&client, &scene);
        assert!(message.contains(name), "{name}: {message}");
        assert!(server.is_running(), "{name}: {}", server.log());
        client.scene_info(PATIENCE).expect("the server serves on");
    }

    // The cached tree of the served scene, its node count made 2^40: refused and built again.
    let mut damaged = 0;
    for entry in std::fs::read_dir(&trees).expect("the cache folder") {
        let path = entry.expect("an entry").path();
        let mut bytes = std::fs::read(&path).expect("a cached tree");
        bytes[56..64].copy_from_slice(&(1u64 << 40).to_le_bytes());
        std::fs::write(&path, bytes).expect("damage it");
        damaged += 1;
    }
    assert_eq!(damaged, 1, "one tree cached");
    client
        .load_scene(&valid, PATIENCE)
        .expect("loads, its tree rebuilt");
    assert!(
        server.wait_for_log("cached tree refused", PATIENCE),
        "{}",
        server.log()
    );

    // A file that is no scene: named in the error, none of its content quoted.
    let secret = folder.path().join("shadow");
    std::fs::write(
        &secret,
        "root:$6$hunter2salt$hunter2hash:19000:0:99999:7:::\n",
    )
    .unwrap();
    let message = refusal(&client, &secret.display().to_string());
    assert!(message.contains(&secret.display().to_string()), "{message}");
    assert!(!message.contains("hunter2"), "{message}");

    let info = client
        .scene_info(PATIENCE)
        .expect("a later request succeeds");
    assert_eq!(info.name, "valid");
    assert!(server.is_running());
    drop(client);
    server.stop();
    // SAFETY: the server and the client have ended.
    unsafe { forget_prefix(&prefix) };
}

#[test]
fn send_tracker_answer_reports_a_rejection_and_its_reason() {
    let mut server = Server::start("rejected_answer");
    let _ready = server.connect();
    let mut tool = server.client_tool(
        &["send-tracker", "--position", "1e300,0,0", "--answer"],
        Stdio::null(),
    );
    let status = tool.wait_exit(PATIENCE).expect("the tool ends");
    let log = tool.log();
    assert!(!status.success(), "{log}");
    assert!(
        log.contains("the server rejected the sample: hand.position is beyond 1000000 m")
            && log.contains("(found 1e300)")
            && log.contains("tracker_rejected_out_of_range"),
        "{log}"
    );
    assert!(!log.contains("no hand frame answered"), "{log}");
}

#[test]
fn samples_stamped_far_ahead_of_the_servers_clock_are_rejected_and_counted() {
    let mut server = Server::start_with("ahead", &["--lockstep"]);
    let mut client = server.connect();
    let mut ahead = tracker(1, [0.0, -0.2, 1.2]);
    ahead.timestamp_ns = wall_clock_ns() + 3_600_000_000_000;
    client.send_tracker(&ahead).expect("send");
    client.flush_inputs(PATIENCE).expect("flush");
    let mut info = server.client_tool(&["info"], Stdio::piped());
    let mut out = String::new();
    std::io::Read::read_to_string(&mut info.take_stdout().expect("piped"), &mut out).unwrap();
    assert!(
        info.wait_exit(PATIENCE).expect("ends").success(),
        "{}",
        info.log()
    );
    let json: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(json["stats"]["rejected_ahead"], 1, "{json}");
    assert_eq!(json["stats"]["tracker_accepted"], 0, "{json}");
    // A sample stamped now is answered as ever.
    let now = tracker(2, [0.0, -0.2, 1.2]);
    client.send_tracker(&now).expect("send");
    let answered = client
        .wait_for_hand_frame(PATIENCE, |frame| frame.tracker == now.stamp(), drop)
        .expect("wait");
    assert!(answered.is_some_and(|frame| frame.tracked != 0));
}
