//! The examples of `client-rs/examples/` and `server/examples/`, run as their READMEs run them:
//! each client example against a real `vas-server` on its own prefix, the server example on its
//! own. Each must end successfully within [`PATIENCE`] and print what it is there to show.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::sync::mpsc;
use std::time::Instant;

use vas_client::recording::Recording;
use vas_client::{Client, Frame, HandFrame, HandSegment, Wake, wall_clock_ns};
use vas_testkit::{PATIENCE, Server, Spawned, configs_dir, example, fixtures_dir, tracker};

/// Runs the example `name` with `args`, and returns its stdout lines once it exited
/// successfully.
fn run_example(name: &str, args: &[&str]) -> Vec<String> {
    let mut process = Spawned::start(&example(name), args, Stdio::piped());
    let stdout = process.take_stdout().expect("piped");
    let lines: Vec<String> = BufReader::new(stdout)
        .lines()
        .map_while(Result::ok)
        .collect();
    let status = process
        .wait_exit(PATIENCE)
        .unwrap_or_else(|| panic!("the example {name} still runs after {PATIENCE:?}"));
    assert!(
        status.success(),
        "the example {name} failed with {status}:\n{}",
        process.log()
    );
    lines
}

/// The value of `key=` in a line of `key=value` words (the value ends at the next space, or at
/// the closing bracket of a list).
fn field<'a>(line: &'a str, key: &str) -> &'a str {
    let start = line
        .find(&format!(" {key}="))
        .unwrap_or_else(|| panic!("no {key}= in {line:?}"))
        + key.len()
        + 2;
    let rest = &line[start..];
    let end = if rest.starts_with('[') {
        rest.find(']').expect("a closed list") + 1
    } else {
        rest.find(' ').unwrap_or(rest.len())
    };
    &rest[..end]
}

/// Parses a printed `[x, y, z]`.
fn floats(list: &str) -> Vec<f64> {
    list.trim_matches(['[', ']'])
        .split(", ")
        .map(|value| value.parse().expect("a number"))
        .collect()
}

/// Whether a printed list is `expected` to 1e-12.
fn close(list: &str, expected: &[f64]) -> bool {
    let values = floats(list);
    values.len() == expected.len()
        && values
            .iter()
            .zip(expected)
            .all(|(v, e)| (v - e).abs() < 1e-12)
}

/// Whether a printed list is `expected` to within `tolerance`.
fn near(list: &str, expected: &[f64], tolerance: f64) -> bool {
    let values = floats(list);
    values.len() == expected.len()
        && (values.iter().zip(expected)).all(|(v, e)| (v - e).abs() <= tolerance)
}

/// A renderer built only from the wire: it draws each part's mesh with the bounding box of the
/// server's own collision mesh (scale applied), each part at its pose, and each hand segment
/// where the server's hand model puts it for the verified root and flex values.
#[test]
fn the_renderer_example_draws_what_the_server_holds() {
    let mut server = Server::start("ex_renderer");
    let mut client = server.connect();
    let scene = client.scene_info(PATIENCE).expect("scene info");
    let own = vas_server::scene::Scene::load(&configs_dir().join("default.toml")).expect("loads");
    // A hand frame for the renderer to find in the hand stream's history when it connects.
    let sample = tracker(1, [0.05, -0.1, 1.2]);
    client.send_tracker(&sample).expect("send");
    let deadline = Instant::now() + PATIENCE;
    let answer = loop {
        assert!(Instant::now() < deadline, "no answer to the tracker sample");
        assert_eq!(
            client.wait(PATIENCE).expect("wait"),
            Wake::Ready,
            "no frame"
        );
        let answer =
            (client.receive().expect("receive").into_iter()).find_map(|frame| match frame {
                Frame::Hand(hand) if hand.tracker == sample.stamp() => Some(hand),
                _ => None,
            });
        if let Some(answer) = answer {
            break answer;
        }
    };

    let lines = run_example("renderer", &["--prefix", server.prefix(), "--frames", "5"]);
    let starting = |word: &str| -> Vec<&String> {
        (lines.iter())
            .filter(|line| line.starts_with(&format!("{word} ")))
            .collect()
    };
    let meshes = starting("mesh");
    assert_eq!(
        meshes.len(),
        own.parts.len(),
        "one mesh per part: {lines:#?}"
    );
    for (id, (line, part)) in meshes.iter().zip(&own.parts).enumerate() {
        assert_eq!(field(line, "part"), id.to_string());
        assert_eq!(field(line, "name"), format!("{:?}", part.name));
        let vertices = part.mesh.vertices();
        let (min, max): (Vec<f64>, Vec<f64>) = (0..3)
            .map(|axis| {
                let values = vertices.iter().map(|v| v[axis]);
                let min = values.clone().fold(f64::INFINITY, f64::min);
                (min, values.fold(f64::NEG_INFINITY, f64::max))
            })
            .unzip();
        // f32 on the wire: a micrometre at the sizes of the demo's parts.
        assert!(near(field(line, "min"), &min, 1e-6), "{line} vs {min:?}");
        assert!(near(field(line, "max"), &max, 1e-6), "{line} vs {max:?}");
        let triangles = part.mesh.triangles().len().to_string();
        assert_eq!(field(line, "triangles"), triangles);
    }
    let part_lines = starting("part");
    assert!(!part_lines.is_empty(), "{lines:#?}");
    for part in &scene.parts {
        let line = (part_lines.iter())
            .find(|line| field(line, "name") == format!("{:?}", part.name))
            .unwrap_or_else(|| panic!("{} is not printed: {lines:#?}", part.name));
        assert_eq!(field(line, "id"), part.id.to_string());
        // Nothing moves the parts: they are where the scene put them.
        let pose = part.initial_pose;
        assert!(close(field(line, "position"), &pose.position), "{line}");
        assert!(close(field(line, "rotation"), &pose.rotation), "{line}");
    }
    let hand = starting("hand");
    let hand = hand
        .first()
        .unwrap_or_else(|| panic!("no hand line: {lines:#?}"));
    assert!(
        close(field(hand, "position"), &answer.root.position),
        "{hand}"
    );
    assert_eq!(field(hand, "side"), "right");
    assert_eq!(field(hand, "grasp"), "none");
    let frame = field(hand, "frame");
    let segments: Vec<&String> = (starting("segment").into_iter())
        .filter(|line| field(line, "frame") == frame)
        .collect();
    let model = &own.hands.first().expect("the demo has a hand").model;
    let flex = answer.flex.map(f64::from);
    let local = model.segment_poses(&flex);
    assert_eq!(
        segments.len(),
        local.len(),
        "a line per segment: {lines:#?}"
    );
    let root = answer.root.to_isometry();
    for ((line, segment), local) in segments.iter().zip(HandSegment::ALL).zip(&local) {
        assert_eq!(field(line, "name"), segment.name());
        let expected = root * local;
        let position = expected.translation.vector;
        assert!(
            near(field(line, "position"), position.as_slice(), 1e-9),
            "{line}"
        );
        let q = expected.rotation.coords;
        assert!(near(field(line, "rotation"), q.as_slice(), 1e-9), "{line}");
    }
}

#[test]
fn the_send_input_example_prints_an_answer_to_every_sample() {
    let mut server = Server::start("ex_send_input");
    server.connect();
    let lines = run_example(
        "send_input",
        &["--prefix", server.prefix(), "--samples", "8"],
    );
    assert_eq!(lines[0], "scene \"demo\"");
    let answers: Vec<&String> = lines.iter().filter(|l| l.starts_with("answer ")).collect();
    assert_eq!(answers.len(), 8, "{lines:#?}");
    let mut frames = Vec::new();
    for (step, answer) in answers.iter().enumerate() {
        let stream = if step % 2 == 0 { "tracker" } else { "glove" };
        assert_eq!(field(answer, "input"), stream, "{answer}");
        assert_eq!(field(answer, "seq"), (step / 2 + 1).to_string(), "{answer}");
        frames.push(
            field(answer, "frame")
                .parse::<u64>()
                .expect("a frame number"),
        );
    }
    assert!(
        frames.windows(2).all(|pair| pair[0] < pair[1]),
        "{frames:?}"
    );
    // The hand moved along x, and its fingers bent.
    let x = |line: &str| floats(field(line, "position"))[0];
    let bend = |line: &str| field(line, "bend").parse::<f64>().expect("a number");
    let (first, last) = (answers[0], answers[answers.len() - 1]);
    assert!(x(last) > x(first), "{first}\n{last}");
    assert_eq!(bend(first), 0.0, "{first}");
    assert!(bend(last) > 0.3, "{last}");
}

#[test]
fn the_replay_example_prints_the_grasp_and_release_of_the_peg() {
    let scene = configs_dir().join("peg_insert.toml");
    let fixture = fixtures_dir().join("peg_insert.jsonl");
    let samples = Recording::load(&fixture)
        .expect("the fixture loads")
        .samples
        .len();
    let mut server = Server::start_with(
        "ex_replay",
        &["--lockstep", "--scene", scene.to_str().expect("utf-8")],
    );
    server.connect();
    let fixture = fixture.to_str().expect("utf-8");
    let lines = run_example("replay", &["--prefix", server.prefix(), fixture]);

    let held: Vec<String> = lines
        .iter()
        .filter(|line| line.starts_with("event "))
        .filter(|line| matches!(field(line, "kind"), "Grasp" | "Release"))
        .map(|line| {
            let kind = field(line, "kind");
            format!("{kind} {} {}", field(line, "part"), field(line, "grasp"))
        })
        .collect();
    assert_eq!(
        held,
        ["Grasp \"peg\" Power", "Release \"peg\" None"],
        "{lines:#?}"
    );
    let summary = lines.last().expect("output");
    assert!(
        summary.starts_with(&format!("replayed samples={samples} events: ")),
        "{summary}"
    );
    for count in ["Grasp=1", "Release=1"] {
        assert!(summary.split(' ').any(|word| word == count), "{summary}");
    }
}

#[test]
fn the_dop_tree_example_finds_pairs_at_the_crossing_pose_only() {
    let lines = run_example("dop_tree_query", &[]);
    let triangles: u32 = field(&lines[0], "triangles").parse().expect("a count");
    // The pose lines, each with the pair lines that follow it.
    let mut poses: Vec<(&str, bool, usize, Vec<[u32; 2]>)> = Vec::new();
    for line in &lines[1..] {
        if line.starts_with("pose ") {
            poses.push((
                field(line, "name"),
                field(line, "intersects").parse().expect("a bool"),
                field(line, "pairs").parse().expect("a count"),
                Vec::new(),
            ));
        } else {
            let pair = [field(line, "a"), field(line, "b")].map(|i| i.parse().expect("an index"));
            poses.last_mut().expect("a pose line first").3.push(pair);
        }
    }
    assert_eq!(poses.len(), 2, "{lines:#?}");
    let (name, intersects, count, pairs) = &poses[0];
    assert_eq!((*name, *intersects, *count), ("apart", false, 0));
    assert!(pairs.is_empty());
    let (name, intersects, count, pairs) = &poses[1];
    assert_eq!((*name, *intersects), ("crossing", true));
    assert!(*count > 0);
    assert_eq!(pairs.len(), *count);
    assert!(
        pairs.iter().flatten().all(|&index| index < triangles),
        "{pairs:?}"
    );
}

#[test]
fn the_readme_shows_the_renderer_example_as_it_is() {
    let root = configs_dir().join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    let example = std::fs::read_to_string(root.join("client-rs/examples/renderer.rs"))
        .expect("the renderer example");
    let shown = readme
        .split_once("<!-- renderer.rs -->\n```rust\n")
        .and_then(|(_, rest)| rest.split_once("```\n<!-- /renderer.rs -->"))
        .map(|(code, _)| code)
        .expect("the README's renderer block");
    assert!(
        shown.lines().count() > 20 && example.contains(shown),
        "README.md's renderer block is not an excerpt of the example:\n{shown}"
    );
}

/// A renderer example running beside the test, its stdout read as it prints (a pipe left
/// unread would stall it).
struct RunningRenderer {
    process: Spawned,
    printed: mpsc::Receiver<String>,
    lines: Vec<String>,
}

impl RunningRenderer {
    /// Starts the renderer on `prefix`, drawing until it is stopped.
    fn start(prefix: &str) -> Self {
        let mut process =
            Spawned::start(&example("renderer"), &["--prefix", prefix], Stdio::piped());
        let stdout = process.take_stdout().expect("piped");
        let (sender, printed) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if sender.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            process,
            printed,
            lines: Vec::new(),
        }
    }

    /// Waits until what it printed so far satisfies `done`.
    fn wait_for(&mut self, what: &str, done: impl Fn(&[String]) -> bool) {
        let deadline = Instant::now() + PATIENCE;
        while !done(&self.lines) {
            let remaining = deadline.saturating_duration_since(Instant::now());
            match self.printed.recv_timeout(remaining) {
                Ok(line) => self.lines.push(line),
                Err(_) => panic!("the renderer printed no {what}: {:#?}", self.lines),
            }
        }
    }

    /// Stops it as Ctrl-C does (it leaves cleanly) and returns everything it printed.
    fn stop(mut self) -> Vec<String> {
        self.process.signal(libc::SIGINT);
        let status = (self.process.wait_exit(PATIENCE)).expect("the renderer ends on SIGINT");
        assert!(
            status.success(),
            "the renderer failed: {}",
            self.process.log()
        );
        self.lines.extend(self.printed.iter());
        self.lines
    }
}

/// One hand as the renderer drew it: its `hand` line and the `segment` lines after it.
struct DrawnHand<'a> {
    line: &'a str,
    segments: Vec<&'a str>,
}

impl DrawnHand<'_> {
    fn frame(&self) -> u64 {
        field(self.line, "frame").parse().expect("a frame number")
    }

    fn side(&self) -> &str {
        field(self.line, "side")
    }

    /// Checks the drawing against the hand frame the server published: side, grasp, root, and
    /// each segment's name and pose, to the last digit printed.
    fn assert_draws(&self, published: &HandFrame) {
        let side = published.side().expect("a known side");
        assert_eq!(self.side(), side.name(), "{}", self.line);
        let grasp = published.grasp().expect("a known grasp");
        assert_eq!(field(self.line, "grasp"), grasp.name(), "{}", self.line);
        let root = &published.root.position;
        assert!(close(field(self.line, "position"), root), "{}", self.line);
        let poses = published.segment_poses();
        assert_eq!(self.segments.len(), poses.len(), "{}", self.line);
        for ((line, segment), pose) in self.segments.iter().zip(HandSegment::ALL).zip(poses) {
            let frame = published.frame.to_string();
            assert_eq!(
                (field(line, "frame"), field(line, "side")),
                (&*frame, side.name())
            );
            assert_eq!(field(line, "name"), segment.name(), "{line}");
            assert!(close(field(line, "position"), &pose.position), "{line}");
            assert!(close(field(line, "rotation"), &pose.rotation), "{line}");
        }
    }
}

/// The hands the renderer drew, in the order it drew them.
fn drawn_hands(lines: &[String]) -> Vec<DrawnHand<'_>> {
    let mut hands: Vec<DrawnHand> = Vec::new();
    for line in lines {
        if line.starts_with("hand ") {
            hands.push(DrawnHand {
                line,
                segments: Vec::new(),
            });
        } else if line.starts_with("segment ") {
            let hand = hands
                .last_mut()
                .expect("a segment line follows a hand line");
            hand.segments.push(line);
        }
    }
    hands
}

/// The hand frames each drawn frame has (by frame number), in the order they were drawn.
fn drawn_frames<'a>(hands: &'a [DrawnHand<'a>]) -> Vec<(u64, Vec<&'a DrawnHand<'a>>)> {
    let mut frames: Vec<(u64, Vec<&DrawnHand>)> = Vec::new();
    for hand in hands {
        match frames.last_mut() {
            Some((frame, drawn)) if *frame == hand.frame() => drawn.push(hand),
            _ => frames.push((hand.frame(), vec![hand])),
        }
    }
    frames
}

/// Replays `recording` in lockstep, each sample once every hand's frame of its answer came, and
/// returns each frame's hand frames as `Client::latest_hands` has them, by frame number.
fn replay_every_hand(client: &mut Client, recording: &Recording) -> BTreeMap<u64, Vec<HandFrame>> {
    let start_ns = wall_clock_ns().saturating_sub(recording.duration_ns());
    let mut published = BTreeMap::new();
    for (index, recorded) in recording.samples.iter().enumerate() {
        let input = recorded.stamped(start_ns);
        client.send_input(&input).expect("send");
        let answer = client
            .wait_for_hand_frame(PATIENCE, |hand| input.is_answered_by(hand), drop)
            .expect("wait")
            .unwrap_or_else(|| panic!("sample {index}: no answer"));
        // The other hand's frame of the same frame comes just before or just after the answer.
        while client.latest_hands().len() < 2
            || (client.latest_hands().iter()).any(|hand| hand.frame != answer.frame)
        {
            assert_eq!(
                client.wait(PATIENCE).expect("wait"),
                Wake::Ready,
                "sample {index}"
            );
            client.poll().expect("poll");
        }
        published.insert(answer.frame, client.latest_hands().to_vec());
    }
    published
}

/// Both hands of a two-hand scene, as renderer.rs draws them: a renderer connected through the
/// hand-over draws the right and the left hand of every frame it draws, where the server put
/// them; one started after it gets both hands at once, its first hands drawn being both hands
/// of the last frame.
#[test]
fn the_renderer_example_poses_both_hands_through_a_hand_over() {
    let scene = configs_dir().join("two_hand_handover.toml");
    let recording = Recording::load(&fixtures_dir().join("two_hand_handover.jsonl"))
        .expect("the fixture loads");
    let mut server = Server::start_with(
        "ex_renderer_hands",
        &["--lockstep", "--scene", scene.to_str().expect("utf-8")],
    );
    let mut client = server.connect();
    let mut early = RunningRenderer::start(server.prefix());
    early.wait_for("meshes", |lines| {
        lines.iter().any(|line| line.starts_with("mesh "))
    });
    let published = replay_every_hand(&mut client, &recording);
    let lines = early.stop();

    let hands = drawn_hands(&lines);
    let frames = drawn_frames(&hands);
    assert!(!frames.is_empty(), "no hand drawn: {lines:#?}");
    assert!(
        frames.windows(2).all(|pair| pair[0].0 < pair[1].0),
        "{lines:#?}"
    );
    for (frame, drawn) in &frames {
        let sides: Vec<&str> = drawn.iter().map(|hand| hand.side()).collect();
        assert_eq!(sides, ["right", "left"], "frame {frame}");
        let published = (published.get(frame)).unwrap_or_else(|| panic!("frame {frame} drawn"));
        for (hand, published) in drawn.iter().zip(published) {
            hand.assert_draws(published);
        }
    }

    let (&last, last_hands) = published.last_key_value().expect("frames published");
    let mut late = RunningRenderer::start(server.prefix());
    late.wait_for("two hands", |lines| {
        lines
            .iter()
            .filter(|line| line.starts_with("hand "))
            .count()
            >= 2
    });
    let lines = late.stop();
    let hands = drawn_hands(&lines);
    let (frame, first) = drawn_frames(&hands).swap_remove(0);
    assert_eq!(frame, last, "{lines:#?}");
    let sides: Vec<&str> = first.iter().map(|hand| hand.side()).collect();
    assert_eq!(sides, ["right", "left"], "{lines:#?}");
    for (hand, published) in first.iter().zip(last_hands) {
        hand.assert_draws(published);
    }
}
