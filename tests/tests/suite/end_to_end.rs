//! End to end: the real `vas-server` binary, the client library and the `vas-client` tool, each
//! test on its own iceoryx2 prefix so that the tests run in parallel without meeting.

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::time::Instant;

use vas_client::recording::{InputSample, Recording, RecordingHeader, RecordingWriter};
use vas_client::{Client, ClientError, Frame, PartsFrame, Wake};
use vas_protocol::HandSide;
use vas_protocol::{
    ControlStatus, FLEX_COUNT, FLEX_LIMITS_RAD, GloveSample, HandFrame, InputStamp,
    SlidingMetaphor, TrackerSample, wall_clock_ns,
};
use vas_server::runtime::hand_joints::wire_joints;
use vas_server::scene::{Scene, default_scene_path};
use vas_testkit::hands::{PINCH, captured};
use vas_testkit::{
    PATIENCE, Server, Spawned, binary, configs_dir, fixtures_dir, forget_prefix, tracker,
    unique_prefix,
};

/// Waits for frames and receives them, failing the test after [`PATIENCE`].
fn next_frames(client: &mut Client, what: &str) -> Vec<Frame> {
    assert_eq!(
        client.wait(PATIENCE).expect("wait"),
        Wake::Ready,
        "timed out waiting for {what}"
    );
    client.receive().expect("receive")
}

/// Receives frames until `wanted` picks one, failing the test after [`PATIENCE`].
fn wait_for<T>(client: &mut Client, what: &str, mut wanted: impl FnMut(&Frame) -> Option<T>) -> T {
    let deadline = Instant::now() + PATIENCE;
    loop {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        if let Some(found) = next_frames(client, what).iter().find_map(&mut wanted) {
            return found;
        }
    }
}

pub(crate) fn hand_answering(client: &mut Client, stamp: InputStamp) -> HandFrame {
    wait_for(client, "the answering hand frame", |frame| match frame {
        Frame::Hand(hand) if hand.tracker == stamp || hand.glove == stamp => Some(*hand),
        _ => None,
    })
}

#[test]
fn scene_info_and_parts_frames_match_the_scene_config() {
    let mut server = Server::start("sceneinfo");
    let mut client = server.connect();
    let scene = Scene::load(&default_scene_path()).expect("the default scene loads");

    let info = client.scene_info(PATIENCE).expect("scene info");
    assert_eq!(info.name, scene.name);
    assert_eq!(info.parts.len(), scene.parts.len());
    for (id, (described, part)) in info.parts.iter().zip(&scene.parts).enumerate() {
        assert_eq!(described.id as usize, id);
        assert_eq!(described.name, part.name);
        assert_eq!(described.group, part.group);
        assert_eq!(described.mesh_source, part.mesh_source);
        assert_eq!(described.movable, part.movable);
        assert!(!described.truncated);
        let pose = described.initial_pose.to_isometry();
        assert!((pose.translation.vector - part.pose.translation.vector).norm() < 1e-12);
        assert!(pose.rotation.angle_to(&part.pose.rotation) < 1e-9);
    }

    let frame: PartsFrame = wait_for(&mut client, "a parts frame", |frame| match frame {
        Frame::Parts(parts) => Some(parts.clone()),
        _ => None,
    });
    assert_eq!(frame.header.part_count as usize, scene.parts.len());
    assert_eq!(frame.parts.len(), scene.parts.len());
    for (state, part) in frame.parts.iter().zip(&scene.parts) {
        let pose = state.pose().to_isometry();
        assert!((pose.translation.vector - part.pose.translation.vector).norm() < 1e-12);
    }
}

#[test]
fn a_tracker_sample_is_answered_by_a_hand_frame_carrying_its_seq() {
    let mut server = Server::start("answer");
    let mut client = server.connect();
    let mut sample = tracker(42, [0.1, -0.2, 0.3]);
    sample.cart.position = [0.0, 0.0, 1.0];
    client.send_tracker(&sample).expect("send");

    let frame = hand_answering(&mut client, sample.stamp());
    assert_eq!(frame.tracker.seq, 42);
    assert_eq!(frame.root.position, [0.1, -0.2, 1.3], "cart * hand");
    assert!(frame.timestamp_ns >= sample.timestamp_ns);
    let side = frame.side().expect("a hand frame names its side");
    assert_eq!(client.latest_hand_of(0, side), Some(&frame));
    assert!(client.latest_hands().contains(&frame));
    let stats = client.input_stats(PATIENCE).expect("stats");
    assert_eq!(stats.tracker_accepted, 1);
}

#[test]
fn glove_values_beyond_the_joint_limits_are_clamped_and_counted() {
    let mut server = Server::start("clamp");
    let mut client = server.connect();
    let mut flex = [0.2f32; FLEX_COUNT];
    flex[5] = 3.0;
    let sample = GloveSample {
        seq: 7,
        timestamp_ns: wall_clock_ns(),
        flex,
        user: 0,
        side: 0,
    };
    client.send_glove(&sample).expect("send");
    // The clasp brings the fingers to the glove's values over a few frames (it moves a segment at
    // most a few millimetres per frame), so the first answer may be on its way there.
    let limit = FLEX_LIMITS_RAD[5].1;
    let frame = wait_for(
        &mut client,
        "the clamped joint at its limit",
        |frame| match frame {
            Frame::Hand(hand) if hand.glove == sample.stamp() => {
                assert!(hand.flex[5] <= limit, "beyond the limit: {}", hand.flex[5]);
                (hand.flex[5] == limit).then_some(*hand)
            }
            _ => None,
        },
    );
    assert_eq!(frame.flex[4], 0.2);
    let stats = client.input_stats(PATIENCE).expect("stats");
    assert_eq!((stats.glove_accepted, stats.glove_values_clamped), (1, 1));
}

#[test]
fn a_nan_sample_is_rejected_and_counted_and_the_server_keeps_answering() {
    let mut server = Server::start("nan");
    let mut client = server.connect();
    let nan = tracker(1, [f64::NAN, 0.0, 0.0]);
    let mut unnormalised = tracker(2, [0.0; 3]);
    unnormalised.hand.rotation = [0.0, 0.0, 0.0, 2.0];
    let valid = tracker(3, [0.5, 0.5, 0.5]);
    for sample in [&nan, &unnormalised, &valid] {
        client.send_tracker(sample).expect("send");
    }

    // Frames arrive in order: every hand frame up to the answer to seq 3 must answer it.
    let mut answered = Vec::new();
    wait_for(
        &mut client,
        "the answer to the valid sample",
        |frame| match frame {
            Frame::Hand(hand) => {
                answered.push(hand.tracker.seq);
                (hand.tracker == valid.stamp()).then_some(())
            }
            _ => None,
        },
    );
    assert_eq!(answered, [3], "rejected samples get no hand frame");
    let stats = client.input_stats(PATIENCE).expect("stats");
    assert_eq!(stats.tracker_rejected_non_finite, 1);
    assert_eq!(stats.tracker_rejected_quaternion, 1);
    assert_eq!(stats.tracker_accepted, 1);
    assert!(
        server.process.wait_for_log("input rejected", PATIENCE),
        "the rejection is logged"
    );

    let after = tracker(4, [0.0, 0.1, 0.0]);
    client.send_tracker(&after).expect("send");
    assert_eq!(hand_answering(&mut client, after.stamp()).tracker.seq, 4);
}

/// Writes a recording of `count` tracker samples 1 ms apart.
fn long_recording(path: &std::path::Path, count: u64) {
    let mut writer = RecordingWriter::create(path, &RecordingHeader::new("demo", "a slow sweep"))
        .expect("create");
    for seq in 1..=count {
        let mut sample = tracker(seq, [seq as f64 * 1e-4, 0.0, 1.0]);
        sample.timestamp_ns = seq * 1_000_000;
        writer.write(&InputSample::Tracker(sample)).expect("write");
    }
}

#[test]
fn a_lockstep_replay_whose_server_dies_stops_and_says_so() {
    const SAMPLES: u64 = 20_000;
    let mut server = Server::start_with("replaygone", &["--lockstep"]);
    let mut observer = server.connect();
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = dir.path().join("sweep.jsonl");
    long_recording(&recording, SAMPLES);
    let mut replay = server.client_tool(
        &["replay", "--lockstep", recording.to_str().expect("utf-8")],
        Stdio::null(),
    );
    wait_for(&mut observer, "the replay's frames", |frame| match frame {
        Frame::Hand(hand) if hand.tracker.seq >= 20 => Some(()),
        _ => None,
    });
    drop(observer);
    server.process.signal(libc::SIGKILL);
    // Without the check it waited out every remaining sample's timeout: hours.
    let status = replay.wait_exit(PATIENCE).expect("the replay stops");
    assert!(!status.success());
    assert!(
        replay
            .log()
            .contains("no vas server answers on this prefix any more"),
        "{}",
        replay.log()
    );
}

#[test]
fn a_killed_client_leaves_the_server_running_and_a_new_client_gets_the_latest_frame() {
    const SAMPLES: u64 = 20_000;
    let mut server = Server::start("sigkill");
    let mut observer = server.connect();
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = dir.path().join("sweep.jsonl");
    long_recording(&recording, SAMPLES);

    let mut replay = server.client_tool(
        &["replay", recording.to_str().expect("utf-8")],
        Stdio::null(),
    );
    let seen = wait_for(&mut observer, "the replay's frames", |frame| match frame {
        Frame::Hand(hand) if hand.tracker.seq >= 20 => Some(hand.tracker.seq),
        _ => None,
    });
    replay.signal(libc::SIGKILL);
    assert!(replay.wait_exit(PATIENCE).is_some(), "the replay dies");

    assert!(
        server.process.is_running(),
        "the server survives its client's death"
    );
    let mut newcomer = Client::connect(Some(server.prefix())).expect("connect");
    // No input comes any more: the frames come from the history, which keeps a frame per hand
    // the service may have (the older first), the newest being the latest answer.
    let latest = wait_for(
        &mut newcomer,
        "the latest answer from history",
        |frame| match frame {
            Frame::Hand(hand) if hand.tracker.seq >= seen => Some(*hand),
            _ => None,
        },
    );
    assert!(
        (seen..=SAMPLES).contains(&latest.tracker.seq),
        "history holds the latest answer ({} after {seen})",
        latest.tracker.seq
    );
    newcomer
        .scene_info(PATIENCE)
        .expect("the server still answers");
    let sample = tracker(SAMPLES + 1, [0.0; 3]);
    newcomer.send_tracker(&sample).expect("send");
    assert_eq!(
        hand_answering(&mut newcomer, sample.stamp()).tracker.seq,
        SAMPLES + 1
    );
    assert!(server.process.is_running());
}

#[test]
fn control_requests_load_scenes_reset_and_set_the_metaphor() {
    let mut server = Server::start("control");
    let client = server.connect();
    let missing = configs_dir().join("missing.toml");
    match client.load_scene(missing.to_str().expect("utf-8"), PATIENCE) {
        Err(ClientError::Refused {
            status, message, ..
        }) => {
            assert_eq!(status, ControlStatus::SceneLoadFailed);
            assert!(message.contains("missing.toml"), "{message}");
        }
        other => panic!("loading a missing scene must be refused, got {other:?}"),
    }
    let peg = configs_dir().join("peg_in_hole.toml");
    let expected = Scene::load(&peg).expect("loads");
    client
        .load_scene(peg.to_str().expect("utf-8"), PATIENCE)
        .expect("load");
    let info = client.scene_info(PATIENCE).expect("scene info");
    assert_eq!(info.name, expected.name);
    assert_eq!(info.parts.len(), expected.parts.len());
    client.reset(PATIENCE).expect("reset");
    client
        .set_metaphor(SlidingMetaphor::SpiralSpring, PATIENCE)
        .expect("set metaphor");
}

#[test]
fn watch_prints_frames_as_json_lines() {
    let mut server = Server::start("watch");
    server.connect();
    let mut watch = server.client_tool(&["watch", "--count", "8"], Stdio::piped());
    let stdout = watch.take_stdout().expect("piped");
    let lines: Vec<String> = BufReader::new(stdout)
        .lines()
        .map_while(Result::ok)
        .collect();
    let status = watch
        .wait_exit(PATIENCE)
        .expect("watch ends after 8 frames");
    assert!(status.success(), "{}", watch.log());
    assert_eq!(lines.len(), 8);
    let scene = Scene::load(&configs_dir().join("default.toml")).expect("loads");
    let json =
        |line: &String| -> serde_json::Value { serde_json::from_str(line).expect("a JSON line") };
    // The scene's geometry comes once, from the service's history: with the first frames, not
    // always before them (each service's history arrives when its subscriber is connected).
    let (geometry, others): (Vec<&String>, Vec<&String>) = lines
        .iter()
        .partition(|line| json(line).get("geometry").is_some());
    assert_eq!(geometry.len(), 1, "one geometry line: {lines:#?}");
    let geometry = json(geometry[0]);
    assert_eq!(geometry["geometry"]["generation"], 1, "{geometry}");
    assert_eq!(
        geometry["geometry"]["parts"],
        scene.parts.len(),
        "{geometry}"
    );
    let mut frames = Vec::new();
    for line in others {
        let json = json(line);
        frames.push(json["parts"]["frame"].as_u64().expect("a parts frame"));
        let names: Vec<&str> = (json["parts"]["parts"].as_array().expect("parts").iter())
            .map(|part| part["name"].as_str().expect("a part's name"))
            .collect();
        let expected: Vec<&str> = scene.parts.iter().map(|part| part.name.as_str()).collect();
        assert_eq!(names, expected, "parts by name: {line}");
    }
    assert!(
        frames.windows(2).all(|pair| pair[0] < pair[1]),
        "{frames:?}"
    );
}

#[test]
fn watch_says_when_no_server_answers_and_takes_the_one_that_comes() {
    let prefix = unique_prefix("watch_wait");
    let mut watch = Spawned::start(
        &binary("vas-client"),
        &["--prefix", &prefix, "watch", "--count", "1"],
        Stdio::piped(),
    );
    assert!(
        watch.wait_for_log("no vas server answers", PATIENCE),
        "watch says it waits: {}",
        watch.log()
    );
    let mut server = Spawned::start(
        &binary("vas-server"),
        &["run", "--prefix", &prefix],
        Stdio::null(),
    );
    let stdout = watch.take_stdout().expect("piped");
    let line = BufReader::new(stdout)
        .lines()
        .next()
        .expect("a frame")
        .expect("read");
    assert!(line.starts_with('{'), "{line}");
    let status = watch
        .wait_exit(PATIENCE)
        .expect("watch ends after its frame");
    assert!(status.success(), "{}", watch.log());
    server.stop();
    drop((watch, server));
    // SAFETY: the server and the tool have ended.
    unsafe { forget_prefix(&prefix) };
}

#[test]
fn watch_ends_quietly_when_its_reader_goes_away() {
    let mut server = Server::start("watch_reader_gone");
    server.connect();
    // Like `vas-client watch | head -1`: the reader takes a line and closes the pipe.
    let mut watch = server.client_tool(&["watch", "--count", "100000"], Stdio::piped());
    let stdout = watch.take_stdout().expect("piped");
    let mut first = String::new();
    BufReader::new(stdout)
        .read_line(&mut first)
        .expect("a first line");
    assert!(first.starts_with('{'), "{first}");
    let status = watch
        .wait_exit(PATIENCE)
        .expect("watch ends once its output is closed");
    assert!(status.success(), "{}", watch.log());
}

#[test]
fn record_writes_the_samples_clients_send() {
    let mut server = Server::start("record");
    let client = server.connect();
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("take.jsonl");
    let mut recorder = server.client_tool(
        &[
            "record",
            file.to_str().expect("utf-8"),
            "--count",
            "4",
            "--description",
            "four",
        ],
        Stdio::null(),
    );
    assert!(
        recorder.wait_for_log("recording", PATIENCE),
        "{}",
        recorder.log()
    );
    let first = tracker(1, [0.1, 0.0, 0.0]);
    let glove = GloveSample {
        seq: 1,
        timestamp_ns: first.timestamp_ns + 1,
        flex: [0.3; FLEX_COUNT],
        user: 0,
        side: 0,
    };
    let second = TrackerSample {
        timestamp_ns: first.timestamp_ns + 2,
        ..tracker(2, [0.2, 0.0, 0.0])
    };
    let joints = wire_joints(
        &captured(PINCH, HandSide::Right).expect("the capture reads"),
        1,
        first.timestamp_ns + 3,
    );
    client.send_tracker(&first).expect("send");
    client.send_glove(&glove).expect("send");
    client.send_tracker(&second).expect("send");
    client.send_hand_joints(&joints).expect("send");
    let status = recorder
        .wait_exit(PATIENCE)
        .expect("the recorder stops after 4 samples");
    assert!(status.success(), "{}", recorder.log());

    let recording = Recording::load(&file).expect("a valid recording");
    assert_eq!(recording.header, RecordingHeader::new("demo", "four"));
    let inputs: Vec<_> = recording
        .samples
        .iter()
        .map(|sample| sample.input)
        .collect();
    assert_eq!(
        inputs,
        [
            InputSample::Tracker(first),
            InputSample::Glove(glove),
            InputSample::Tracker(second),
            InputSample::HandJoints(joints),
        ]
    );
}

/// Replays the recording `fixture` with `vas-client replay --lockstep` against a server in
/// lockstep (on the scene `scene`, else the demo scene) and returns the hand frames and events
/// the tool prints, without their timestamps (which differ from run to run).
fn lockstep_answers(test: &str, fixture: &str, scene: Option<&str>) -> Vec<serde_json::Value> {
    let fixture = fixtures_dir().join(fixture);
    let expected = Recording::load(&fixture)
        .expect("the fixture loads")
        .samples
        .len();
    let scene = scene.map(|name| configs_dir().join(name).display().to_string());
    let mut arguments = vec!["--lockstep"];
    if let Some(scene) = &scene {
        arguments.extend(["--scene", scene]);
    }
    let mut server = Server::start_with(test, &arguments);
    server.connect();
    let mut replay = server.client_tool(
        &["replay", "--lockstep", fixture.to_str().expect("utf-8")],
        Stdio::piped(),
    );
    let stdout = replay.take_stdout().expect("piped");
    // Hand frames and events, without the times that differ between runs.
    let frames: Vec<serde_json::Value> = BufReader::new(stdout)
        .lines()
        .map_while(Result::ok)
        .map(|line| {
            let mut frame: serde_json::Value = serde_json::from_str(&line).expect("a JSON line");
            let (_, payload) = frame
                .as_object_mut()
                .and_then(|object| object.iter_mut().next())
                .expect("a frame of one kind");
            let payload = payload.as_object_mut().expect("an object");
            payload.remove("timestamp_ns");
            for stream in ["tracker", "glove", "joints"] {
                payload[stream]
                    .as_object_mut()
                    .expect("a stamp")
                    .remove("timestamp_ns");
            }
            frame
        })
        .collect();
    let answers = frames
        .iter()
        .filter(|frame| frame.get("hand").is_some())
        .count();
    let status = replay.wait_exit(PATIENCE).expect("the replay ends");
    assert!(status.success(), "{}", replay.log());
    assert!(
        replay
            .log()
            .contains(&format!("answered={expected} unanswered=0")),
        "{}",
        replay.log()
    );
    assert_eq!(answers, expected, "one answer per sample");
    frames
}

#[test]
fn a_lockstep_replay_answers_every_sample_the_same_way_twice() {
    let fixture = "demo_peg_into_block.jsonl";
    let once = lockstep_answers("lockstep1", fixture, None);
    assert_eq!(once, lockstep_answers("lockstep2", fixture, None));
    // What the README's walkthrough says the recording does.
    let events: Vec<&str> = once
        .iter()
        .filter_map(|frame| frame["event"]["text"].as_str())
        .collect();
    assert_eq!(
        events,
        [
            "contact begin peg – hand at sample 47",
            "grasp peg (power) at sample 112",
            "contact begin peg – block at sample 300",
            "release peg at sample 304",
            "contact end peg – block at sample 304",
            "contact end peg – hand at sample 304"
        ]
    );
}

#[test]
fn a_lockstep_replay_of_captured_hands_answers_every_joint_sample() {
    let answers = lockstep_answers(
        "lockstep_joints",
        "captured_pinch_pin.jsonl",
        Some("precision_pinch.toml"),
    );
    let events: Vec<&str> = answers
        .iter()
        .filter_map(|frame| frame["event"]["text"].as_str())
        .filter(|text| !text.starts_with("contact"))
        .collect();
    assert_eq!(events, ["grasp pin (tip_pinch) at sample 58"]);
    let last = answers.last().expect("answers");
    assert_eq!(last["hand"]["joints"]["seq"], 101, "{last}");
    assert_eq!(last["hand"]["grasp_name"], "tip_pinch", "{last}");
}
