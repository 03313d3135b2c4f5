//! Faults the server must outlive: a server killed and restarted over its stale resources, and
//! bursts of malformed input and requests, rejected and counted without changing the state.

use std::process::Stdio;
use std::time::Instant;

use vas_client::{Client, ClientError, Frame};
use vas_protocol::services::clients::SENDERS;
use vas_protocol::{
    ControlRequest, ControlStatus, FLEX_COUNT, GloveSample, HandFrame, TrackerSample, wall_clock_ns,
};
use vas_testkit::{PATIENCE, Server, Spawned, binary, forget_prefix, tracker, unique_prefix};

/// Receives frames until the hand frame answering `sample`, failing after [`PATIENCE`].
fn answer(client: &mut Client, sample: &TrackerSample) -> HandFrame {
    let stamp = sample.stamp();
    let deadline = Instant::now() + PATIENCE;
    loop {
        assert!(Instant::now() < deadline, "no answer to {stamp:?}");
        client.wait(PATIENCE).expect("wait");
        let found = client
            .receive()
            .expect("receive")
            .into_iter()
            .find_map(|frame| match frame {
                Frame::Hand(hand) if hand.tracker == stamp => Some(hand),
                _ => None,
            });
        if let Some(hand) = found {
            return hand;
        }
    }
}

#[test]
fn a_server_killed_mid_stream_is_replaced_by_one_on_the_same_prefix() {
    let prefix = unique_prefix("stale");
    let start = || {
        Spawned::start(
            &binary("vas-server"),
            &["run", "--prefix", prefix.as_str()],
            Stdio::null(),
        )
    };
    let mut first = start();
    let mut client = Client::connect(Some(&prefix)).expect("connect");
    client
        .scene_info(PATIENCE)
        .expect("the first server answers");
    let sample = tracker(1, [0.0, -0.2, 1.2]);
    client.send_tracker(&sample).expect("send");
    answer(&mut client, &sample);
    first.signal(libc::SIGKILL);
    assert!(first.wait_exit(PATIENCE).is_some(), "the first server dies");

    // Its ports, node and shared memory are left behind; the next server cleans them up.
    let mut second = start();
    assert!(
        second.wait_for_log("serving", PATIENCE),
        "the second server serves: {}",
        second.log()
    );
    // The first server held one node (its threads wake each other without iceoryx2), and the
    // second cleaned it.
    let log = second.log();
    assert!(
        log.contains("dead_nodes_cleaned=1 dead_nodes_left=0"),
        "the log counts the dead node it cleaned: {log}"
    );
    let mut client = Client::connect(Some(&prefix)).expect("connect again");
    client
        .scene_info(PATIENCE)
        .expect("the second server answers");
    let sample = tracker(2, [0.0, -0.2, 1.2]);
    client.send_tracker(&sample).expect("send");
    assert_eq!(answer(&mut client, &sample).tracker.seq, 2);
    assert!(second.is_running());
    drop((client, first, second));
    // SAFETY: both servers and the client have ended.
    unsafe { forget_prefix(&prefix) };
}

#[test]
fn bursts_of_malformed_input_are_rejected_and_counted_and_change_nothing() {
    /// Below the input services' subscriber buffer, so that no sample is overwritten unread.
    const BURST: u64 = 40;
    let mut server = Server::start("burst");
    let mut client = server.connect();
    let scene = client.scene_info(PATIENCE).expect("scene");
    let valid = tracker(1, [0.1, -0.2, 1.3]);
    client.send_tracker(&valid).expect("send");
    let before = answer(&mut client, &valid);

    let mut seq = 1;
    for round in 0..3 {
        for _ in 0..BURST {
            seq += 1;
            let mut sample = tracker(seq, [0.0; 3]);
            match round {
                0 => sample.hand.position[1] = f64::NAN,
                1 => sample.cart.rotation = [0.0, 0.0, 0.5, 0.5],
                _ => sample.hand.position[2] = f64::INFINITY,
            }
            client.send_tracker(&sample).expect("send");
        }
        let mut flex = [0.0f32; FLEX_COUNT];
        flex[round] = f32::NAN;
        for _ in 0..BURST {
            seq += 1;
            let glove = GloveSample {
                seq,
                timestamp_ns: wall_clock_ns(),
                flex,
                user: 0,
                side: 0,
            };
            client.send_glove(&glove).expect("send");
        }
        // Requests naming parts that do not exist are refused, each with its reason.
        for id in [scene.parts.len() as u32, u32::MAX] {
            match client.control(ControlRequest::part_info(id), PATIENCE) {
                Err(ClientError::Refused { status, .. }) => {
                    assert_eq!(status, ControlStatus::NoSuchPart);
                }
                other => panic!("part {id}: {other:?}"),
            }
        }
    }
    let stats = client.input_stats(PATIENCE).expect("stats");
    assert_eq!(stats.tracker_accepted, 1);
    assert_eq!(stats.tracker_rejected_non_finite, 2 * BURST);
    assert_eq!(stats.tracker_rejected_quaternion, BURST);
    assert_eq!(stats.glove_rejected_non_finite, 3 * BURST);
    assert_eq!(stats.glove_accepted, 0);

    // The state is the one before the burst: the same hand answers the same target.
    let again = tracker(seq + 1, valid.hand.position);
    client.send_tracker(&again).expect("send");
    let after = answer(&mut client, &again);
    assert_eq!(after.root, before.root);
    assert_eq!(after.flex, before.flex);
    let parts = client.latest_parts().expect("parts frames").clone();
    for (state, part) in parts.parts.iter().zip(&scene.parts) {
        assert_eq!(state.pose(), part.initial_pose, "part {}", part.name);
    }
    assert!(server.process.is_running());
}

/// A sample lives in its sender's shared memory until the server takes it: without the flush
/// that ends `send-tracker`, `send-glove` and `replay`, about a third of these were lost.
#[test]
fn samples_sent_just_before_the_sender_exits_are_all_taken_in() {
    const SENDS: u64 = 12;
    let mut server = Server::start("leaving");
    let observer = server.connect();
    let nan_flex = format!("NaN{}", ",0".repeat(FLEX_COUNT - 1));
    for seq in 1..=SENDS {
        let client = Client::connect(Some(server.prefix())).expect("connect");
        let mut sample = tracker(seq, [0.0; 3]);
        sample.hand.position[0] = f64::NAN;
        client.send_tracker(&sample).expect("send");
        client.flush_inputs(PATIENCE).expect("flush");
        drop(client);

        let seq = seq.to_string();
        for args in [
            [
                "send-tracker",
                "--position",
                "NaN,0,0",
                "--seq",
                seq.as_str(),
            ],
            [
                "send-glove",
                "--flex",
                nan_flex.as_str(),
                "--seq",
                seq.as_str(),
            ],
        ] {
            let mut tool = server.client_tool(&args, Stdio::null());
            let status = tool.wait_exit(PATIENCE).expect("the tool ends");
            assert!(status.success(), "{}", tool.log());
        }
    }
    let stats = observer.input_stats(PATIENCE).expect("stats");
    assert_eq!(stats.tracker_rejected_non_finite, 2 * SENDS);
    assert_eq!(stats.glove_rejected_non_finite, SENDS);
}

/// A client of the default roles opens ports on every service; as many connect as the input
/// streams take senders (the output services take more readers, the control service more
/// clients still), and one more is told so.
#[test]
fn as_many_clients_as_the_services_take_connect_and_one_more_is_told_they_are_full() {
    let mut server = Server::start("full");
    let mut clients = vec![server.connect()];
    while clients.len() < SENDERS {
        let client = Client::connect(Some(server.prefix())).expect("a client within the limit");
        clients.push(client);
    }
    for client in &clients {
        client
            .flush_inputs(PATIENCE)
            .expect("each client is served");
    }
    match Client::connect(Some(server.prefix())) {
        Err(ClientError::Full { kind }) => assert!(!kind.is_empty()),
        Err(other) => panic!("one client too many: {other}"),
        Ok(_) => panic!("one client too many connected"),
    }
    clients.pop();
    let client = Client::connect(Some(server.prefix())).expect("room again");
    client.flush_inputs(PATIENCE).expect("served");
}

/// The default scene serves within a gigabyte of address space: the interest matrix and the
/// shared memory are sized to the scene (a hand group id near `u16::MAX` once made the matrix
/// alone 4 GiB, and the server aborted under such a limit).
#[test]
fn the_default_scene_serves_within_a_gigabyte_of_address_space() {
    let prefix = unique_prefix("ulimit");
    let server = binary("vas-server");
    let mut limited = Spawned::start(
        std::path::Path::new("sh"),
        &[
            "-c",
            "ulimit -v 1000000 && exec \"$0\" run --prefix \"$1\"",
            server.to_str().expect("utf-8"),
            prefix.as_str(),
        ],
        Stdio::null(),
    );
    let mut client = Client::connect(Some(&prefix)).expect("connect");
    client
        .scene_info(PATIENCE)
        .unwrap_or_else(|error| panic!("no answer ({error}):\n{}", limited.log()));
    let sample = tracker(1, [0.0, -0.2, 1.2]);
    client.send_tracker(&sample).expect("send");
    assert_eq!(answer(&mut client, &sample).tracker.seq, 1);
    assert!(limited.is_running(), "{}", limited.log());
    drop(client);
    limited.signal(libc::SIGTERM);
    let status = limited.wait_exit(PATIENCE).expect("the server stops");
    assert!(status.success(), "{}", limited.log());
    // SAFETY: the server has exited and this test's client is gone; no process uses the prefix.
    unsafe { forget_prefix(&prefix) };
}

/// Bad scenes sent over control while input streams at about 1 kHz and a renderer watches:
/// each is refused with its reason, the server keeps answering and serving its scene, nothing
/// non-finite is published, and every accepted sample is answered (the last one included) in
/// order.
#[test]
fn bad_scenes_under_load_are_refused_and_the_stream_goes_on() {
    const SAMPLES: u64 = 2_000;
    let mut server = Server::start("underload");
    let client = server.connect();
    let scene = client.scene_info(PATIENCE).expect("scene info").name;
    let dir = tempfile::tempdir().expect("temp dir");
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write");
        path.to_str().expect("utf-8").to_owned()
    };
    std::fs::write(
        dir.path().join("unit.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("empty_hand.toml"), "").unwrap();
    let part = "[[parts]]\nname = \"p\"\nmovable = true\nmesh = \"unit.obj\"\n";
    let bad = [
        write("huge.toml", &format!("name = \"s\"\n{part}scale = 1e300\n")),
        write(
            "hand.toml",
            &format!("name = \"s\"\nhand = \"empty_hand.toml\"\n{part}"),
        ),
        write(
            "rate.toml",
            &format!("name = \"s\"\n{part}[rates]\npublish_hz = 1e-300\n"),
        ),
        write("syntax.toml", "name = \n"),
    ];

    let prefix = server.prefix().to_owned();
    let watcher = std::thread::spawn(move || {
        let mut renderer = Client::connect(Some(&prefix)).expect("renderer connects");
        let (mut last_seq, mut frames) = (0, 0u64);
        while last_seq < SAMPLES {
            assert_eq!(
                renderer.wait(PATIENCE).expect("wait"),
                vas_client::Wake::Ready,
                "frames stopped at sample {last_seq}"
            );
            for frame in renderer.receive().expect("receive") {
                match frame {
                    Frame::Hand(hand) => {
                        let root = hand.root.position.iter().chain(&hand.root.rotation);
                        let segments = (hand.segments.iter())
                            .flat_map(|pose| pose.position.iter().chain(&pose.rotation));
                        assert!(
                            root.chain(segments).copied().all(f64::is_finite),
                            "{hand:?}"
                        );
                        assert!(hand.tracker.seq >= last_seq, "answers in order");
                        last_seq = hand.tracker.seq;
                        frames += 1;
                    }
                    Frame::Parts(parts) => assert!(parts.parts.iter().all(|part| {
                        part.position
                            .iter()
                            .chain(&part.rotation)
                            .all(|c| c.is_finite())
                    })),
                    Frame::Event(_)
                    | Frame::Force(_)
                    | Frame::Clearance(_)
                    | Frame::Geometry(_) => {}
                }
            }
        }
        frames
    });

    let started = Instant::now();
    for seq in 1..=SAMPLES {
        let angle = seq as f64 * 0.003;
        client
            .send_tracker(&tracker(
                seq,
                [0.1 * angle.cos(), -0.3, 1.0 + 0.05 * angle.sin()],
            ))
            .expect("send");
        if seq % 400 == 0 {
            let path = &bad[(seq / 400 - 1) as usize % bad.len()];
            match client.load_scene(path, PATIENCE) {
                Err(ClientError::Refused {
                    status, message, ..
                }) => {
                    assert_eq!(status, vas_protocol::ControlStatus::SceneLoadFailed);
                    assert!(message.contains(path.as_str()), "{message}");
                }
                other => panic!("{path} must be refused, got {other:?}"),
            }
        }
        // About 1 kHz: each sample waits for its slot.
        let due = started + std::time::Duration::from_micros(1_000 * seq);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    let frames = watcher
        .join()
        .expect("the renderer saw every sample answered");
    assert!(frames > 0);
    let info = client
        .scene_info(PATIENCE)
        .expect("the server still answers");
    assert_eq!(info.name, scene, "the scene served before is still served");
    assert_eq!(info.stats.tracker_accepted, SAMPLES);
    assert_eq!(info.stats.rejected(), 0);
}

/// A scene requested over control loads apart from the I/O thread: while it loads, the server
/// answers input and control on the scene it served, refuses a second load as busy, and swaps
/// the new scene in once it is ready.
#[test]
fn the_old_scene_is_served_while_a_requested_one_loads() {
    let mut server = Server::start("bgload");
    let mut client = server.connect();
    let served = client.scene_info(PATIENCE).expect("scene info").name;
    let large = vas_testkit::configs_dir().join("peg_insert_50k.toml");
    let large = large.to_str().expect("utf-8").to_owned();
    let prefix = server.prefix().to_owned();
    let loading = std::thread::spawn(move || {
        let loader = Client::connect(Some(&prefix)).expect("connect");
        // The probe below asks for loads too, and each occupies the loader for a moment: the
        // large load is asked for again until it, not a probe, is the one under way.
        loop {
            match loader.load_scene(&large, PATIENCE) {
                Err(ClientError::Refused {
                    status: ControlStatus::Busy,
                    ..
                }) => continue,
                answer => {
                    let response = answer.expect("the scene loads");
                    return response.scene_name.as_str().expect("utf-8").to_owned();
                }
            }
        }
    });

    // A load of a missing file fails quickly, or is refused as busy while the large load is
    // under way: the first busy answer shows the server answering during the load.
    let missing = vas_testkit::configs_dir().join("no_such_scene.toml");
    let missing = missing.to_str().expect("utf-8");
    loop {
        assert!(
            !loading.is_finished(),
            "the load ended before it was seen under way"
        );
        match client.load_scene(missing, PATIENCE) {
            Err(ClientError::Refused {
                status: ControlStatus::Busy,
                ..
            }) => break,
            Err(ClientError::Refused { status, .. }) => {
                assert_eq!(status, ControlStatus::SceneLoadFailed)
            }
            other => panic!("a missing scene cannot load: {other:?}"),
        }
    }
    let during = client
        .scene_info(PATIENCE)
        .expect("answered during the load");
    let sample = tracker(1, [0.0, -0.2, 1.2]);
    client.send_tracker(&sample).expect("send");
    assert_eq!(answer(&mut client, &sample).tracker.seq, 1);
    // Busy again: the load was under way all along (it loads and builds the 50k-triangle peg's
    // tree, far longer than these few exchanges).
    assert!(
        matches!(
            client.load_scene(missing, PATIENCE),
            Err(ClientError::Refused {
                status: ControlStatus::Busy,
                ..
            })
        ),
        "the load finished before the checks during it"
    );
    let loaded = loading.join().expect("the load is answered");
    let after = client.scene_info(PATIENCE).expect("scene info");
    assert_eq!(
        during.name, served,
        "the old scene is served during the load"
    );
    assert_eq!(loaded, "peg insert 50k");
    assert_eq!(after.name, loaded, "the loaded scene is served once ready");
    assert!(after.generation > during.generation);
}

/// SIGTERM while a large part's tree is still being built stops the server at once (the build,
/// minutes long in this profile, is abandoned), cleanly, and leaves no shared memory behind but
/// the prefix's management segment that every server leaves.
#[test]
fn a_termination_request_while_a_large_part_is_prepared_stops_the_server_cleanly() {
    let (mut server, _folder) = Server::start_on_scene(
        "terminate_preparing",
        "name = \"big\"\n\n[[parts]]\nname = \"ball\"\nmovable = true\n\
         shape = { kind = \"sphere\", radius = 0.1, triangles = 2000000 }\n",
    );
    assert!(
        server.process.wait_for_log("serving", PATIENCE),
        "the server serves while it prepares: {}",
        server.process.log()
    );
    server.process.signal(libc::SIGTERM);
    let status = server
        .process
        .wait_exit(PATIENCE)
        .expect("the server stops");
    let log = server.process.log();
    assert!(status.success(), "{status:?}: {log}");
    assert!(log.contains("termination requested"), "{log}");
    assert!(
        !log.contains("scene ready"),
        "the scene was ready before the request, so nothing was tested: {log}"
    );
    let prefix = server.prefix().to_owned();
    let left: Vec<String> = std::fs::read_dir("/dev/shm")
        .expect("list /dev/shm")
        .filter_map(|entry| entry.ok()?.file_name().into_string().ok())
        .filter(|name| name.starts_with(&prefix) && !name.ends_with("global_mgmt"))
        .collect();
    assert!(left.is_empty(), "shared memory left behind: {left:?}");
}
