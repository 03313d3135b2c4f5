//! The recorded scenarios replayed in lockstep through the real `vas-server` binary with the
//! client library: the grasp and release events in order, the final part pose, no penetration
//! in any published frame (judged by parry), and the same output on a second replay after a
//! reset.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Isometry3;
use vas_client::recording::{InputSample, Recording};
use vas_client::{Client, Frame};
use vas_protocol::{EventKind, GraspType, HandFrame, InputStamp, SimEvent, wall_clock_ns};
use vas_server::runtime::frames::Restart;
use vas_server::scene::Scene;
use vas_tests::offline::{Oracle, VisibleHand};
use vas_tests::scenarios::{EXPECTED, Scenario};
use vas_tests::{PATIENCE, Server};

/// A hand frame without its frame number and timestamps (which differ between runs).
#[derive(Debug, PartialEq)]
struct Answer {
    /// Sequence numbers of the tracker and glove samples it answers.
    seqs: [u64; 2],
    /// Root position and rotation.
    root: [f64; 7],
    /// Flex values, bit for bit.
    flex: Vec<u32>,
    /// Touching segments.
    touching: u32,
    /// Grasp type code.
    grasp: u32,
}

/// What one replay published.
#[derive(Debug, PartialEq)]
struct Replay {
    /// Per sample, the hand frame answering it.
    answers: Vec<Answer>,
    /// Every event: kind, grasp, part, other.
    events: Vec<[u32; 4]>,
    /// The last parts frame's poses.
    final_poses: Vec<Isometry3<f64>>,
    /// Penetrations parry found in the published frames.
    penetrations: Vec<String>,
}

/// Sends every sample of `recording`, each after the answer to the previous one, and gathers
/// what the server published.
fn replay(client: &mut Client, scene: &Scene, oracle: &Oracle, recording: &Recording) -> Replay {
    let mut out = Replay {
        answers: Vec::new(),
        events: Vec::new(),
        final_poses: Vec::new(),
        penetrations: Vec::new(),
    };
    let mut poses: Vec<Isometry3<f64>> = scene.parts.iter().map(|part| part.pose).collect();
    let mut held: Option<usize> = None;
    for (index, recorded) in recording.samples.iter().enumerate() {
        let input = recorded.input.with_timestamp(wall_clock_ns());
        let stamp = InputStamp {
            seq: input.seq(),
            timestamp_ns: input.timestamp_ns(),
        };
        client.send_input(&input).expect("send");
        let answers = |hand: &HandFrame| match input {
            InputSample::Tracker(_) => hand.tracker == stamp,
            InputSample::Glove(_) => hand.glove == stamp,
        };
        let deadline = Instant::now() + PATIENCE;
        let answer = loop {
            assert!(Instant::now() < deadline, "sample {index}: no answer");
            client.wait(PATIENCE).expect("wait");
            let mut found = None;
            for frame in client.receive().expect("receive") {
                match frame {
                    Frame::Parts(parts) => {
                        poses = parts
                            .parts
                            .iter()
                            .map(|state| state.pose().to_isometry())
                            .collect();
                    }
                    Frame::Event(event) => {
                        record_event(&mut out, &mut held, &event);
                    }
                    Frame::Hand(hand) if answers(&hand) => found = Some(hand),
                    Frame::Hand(_) | Frame::Force(_) => {}
                }
            }
            if let Some(hand) = found {
                break hand;
            }
        };
        let root = answer.root.to_isometry();
        let hand = VisibleHand {
            root,
            flex: answer.flex.map(f64::from),
            held,
        };
        out.penetrations
            .extend(oracle.penetrations(scene, &poses, &hand, index));
        let [x, y, z] = answer.root.position;
        let [qx, qy, qz, qw] = answer.root.rotation;
        out.answers.push(Answer {
            seqs: [answer.tracker.seq, answer.glove.seq],
            root: [x, y, z, qx, qy, qz, qw],
            flex: answer.flex.iter().map(|v| v.to_bits()).collect(),
            touching: answer.touching,
            grasp: answer.grasp_type,
        });
    }
    // The last frame's parts and events were published before its hand frame.
    for frame in client.receive().expect("receive") {
        match frame {
            Frame::Parts(parts) => {
                poses = parts
                    .parts
                    .iter()
                    .map(|state| state.pose().to_isometry())
                    .collect();
            }
            Frame::Event(event) => record_event(&mut out, &mut held, &event),
            Frame::Hand(_) | Frame::Force(_) => {}
        }
    }
    out.final_poses = poses;
    out
}

fn record_event(out: &mut Replay, held: &mut Option<usize>, event: &SimEvent) {
    match EventKind::try_from(event.kind) {
        Ok(EventKind::Grasp) => *held = Some(event.part as usize),
        Ok(EventKind::Release) => *held = None,
        _ => {}
    }
    out.events
        .push([event.kind, event.grasp_type, event.part, event.other]);
}

fn check(scenario: &Scenario) {
    let name = scenario.script;
    let scene = Arc::new(Scene::load(&scenario.scene_path()).expect("the scene loads"));
    let recording = Recording::load(&scenario.fixture_path()).expect("the fixture loads");
    let bodies = Restart::new(Arc::clone(&scene), 1)
        .expect("the scene's hand builds")
        .hand_bodies
        .expect("the scene has a hand");
    let oracle = Oracle::new(&scene, &bodies);
    let scene_arg = scenario.scene_path().display().to_string();
    let mut server = Server::start_with(
        &format!("replay_{name}"),
        &["--lockstep", "--scene", &scene_arg],
    );
    let mut client = server.connect();

    let first = replay(&mut client, &scene, &oracle, &recording);
    client.reset(PATIENCE).expect("reset");
    let second = replay(&mut client, &scene, &oracle, &recording);

    assert_eq!(first.answers.len(), recording.samples.len(), "{name}");
    assert!(
        first.penetrations.is_empty(),
        "{name}: {} penetrations, first {:?}",
        first.penetrations.len(),
        &first.penetrations[..first.penetrations.len().min(5)]
    );
    let part_id = |part: &str| {
        scene
            .parts
            .iter()
            .position(|p| p.name == part)
            .expect("the expected part is in the scene") as u32
    };
    let grasps_and_releases: Vec<(u32, u32, u32)> = first
        .events
        .iter()
        .filter(|[kind, ..]| *kind == EventKind::Grasp as u32 || *kind == EventKind::Release as u32)
        .map(|&[kind, grasp, part, _]| (kind, part, grasp))
        .collect();
    let expected: Vec<(u32, u32, u32)> = scenario
        .events
        .iter()
        .map(|event| {
            let grasp = match event.kind {
                EventKind::Grasp => event.grasp,
                _ => GraspType::None,
            };
            (event.kind as u32, part_id(event.part), grasp as u32)
        })
        .collect();
    assert_eq!(grasps_and_releases, expected, "{name}: grasps and releases");
    let target = &scenario.final_pose;
    let pose = first.final_poses[part_id(target.part) as usize];
    let (position_error, angle_error) = target.errors(&pose);
    assert!(
        target.holds(&pose),
        "{name}: {} ends {position_error:.2e} m and {angle_error:.2e} rad off",
        target.part
    );
    assert_eq!(first, second, "{name}: a second replay after a reset");
    eprintln!(
        "{name}: {} samples, {} events, final pose off by {position_error:.2e} m, \
         {angle_error:.2e} rad; identical second replay",
        recording.samples.len(),
        first.events.len()
    );
}

fn scenario(name: &str) -> &'static Scenario {
    EXPECTED
        .iter()
        .find(|scenario| scenario.script.name() == name)
        .expect("a recorded scenario")
}

#[test]
fn peg_insert() {
    check(scenario("peg_insert"));
}

#[test]
fn pipe_through_sheet() {
    check(scenario("pipe_through_sheet"));
}

#[test]
fn precision_pinch() {
    check(scenario("precision_pinch"));
}

#[test]
fn push() {
    check(scenario("push"));
}

#[test]
fn navigate_holding() {
    check(scenario("navigate_holding"));
}
