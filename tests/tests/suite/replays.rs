//! The recorded scenarios replayed in lockstep through the real `vas-server` binary with the
//! client library: the grasp and release events in order, the final part pose, no penetration
//! in any published frame (judged by parry), and the same output on a second replay after a
//! reset. The samples go straight into the server's input streams here; [`check_through`] sends
//! them another way in (the bridge's zenoh peers, in `bridge_users.rs`) and judges the same.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Isometry3;
use vas_client::recording::{InputSample, Recording};
use vas_client::{Client, Frame};
use vas_protocol::{EventKind, GraspType, HandFrame, HandSide, SimEvent, wall_clock_ns};
use vas_server::grasping::HandModel;
use vas_server::scene::Scene;
use vas_server::simulation::restart::Restart;
use vas_testkit::offline::{Oracle, VisibleHand};
use vas_testkit::scenarios::{EXPECTED, Scenario};
use vas_testkit::{PATIENCE, Server};

/// Whose hand a frame or event is: the user's index and the side code.
type HandKey = (u32, u32);

/// A hand frame without its frame number and timestamps (which differ between runs).
#[derive(Debug, PartialEq)]
struct Answer {
    /// The hand's user and side code.
    hand: HandKey,
    /// Sequence numbers of the tracker, glove and hand-joints samples it answers.
    seqs: [u64; 3],
    /// Root position and rotation.
    root: [f64; 7],
    /// Flex values, bit for bit.
    flex: Vec<u32>,
    /// Touching segments.
    touching: u32,
    /// Grasp type code.
    grasp: u32,
    /// Whether the hand is tracked.
    tracked: u32,
}

/// What one replay published.
#[derive(Debug, PartialEq)]
pub(crate) struct Replay {
    /// Per sample, the hand frames of the frame answering it, one per hand.
    answers: Vec<Vec<Answer>>,
    /// Every event: kind, user, hand, grasp, part, other.
    pub(crate) events: Vec<[u32; 6]>,
    /// The last parts frame's poses.
    final_poses: Vec<Isometry3<f64>>,
    /// Whether a parts frame flagged a part pushed (how many did depends on the publishing rate).
    pushed_seen: bool,
    /// Penetrations parry found in the published frames.
    penetrations: Vec<String>,
}

/// The scene's hands as the judge needs them: user and side code, and model, in the scene's
/// order.
type Hands<'a> = [(HandKey, &'a HandModel)];

impl Replay {
    /// The user of every event but contacts (grasps, hand-overs, releases), in order.
    pub(crate) fn grasping_users(&self) -> Vec<u32> {
        let contacts = [EventKind::ContactBegin, EventKind::ContactEnd].map(|kind| kind as u32);
        (self.events.iter())
            .filter(|[kind, ..]| !contacts.contains(kind))
            .map(|&[_, user, ..]| user)
            .collect()
    }
}

/// The way a replay's samples reach the server.
pub(crate) trait Inputs {
    /// Hands `input` to the server; `client` is the replay's own connection, which reads what
    /// the server answers.
    fn send(&mut self, client: &Client, input: &InputSample);
}

/// Straight into the server's input streams, as `vas-client replay` sends them.
struct Direct;

impl Inputs for Direct {
    fn send(&mut self, client: &Client, input: &InputSample) {
        client.send_input(input).expect("send");
    }
}

/// Sends every sample of `recording` through `inputs`, each after the answer to the previous
/// one, and gathers what the server published.
fn replay(
    client: &mut Client,
    inputs: &mut impl Inputs,
    scene: &Scene,
    (oracle, hands): (&Oracle, &Hands),
    recording: &Recording,
) -> Replay {
    let mut out = Replay {
        answers: Vec::new(),
        events: Vec::new(),
        final_poses: Vec::new(),
        pushed_seen: false,
        penetrations: Vec::new(),
    };
    let mut seen = Seen {
        poses: scene.parts.iter().map(|part| part.pose).collect(),
        held: BTreeMap::new(),
        hands: BTreeMap::new(),
    };
    // Stamped as `vas-client replay --lockstep` stamps them: the recording's times, ending now,
    // so that a replay faster than real time never stamps a sample ahead of the server's clock.
    let start_ns = wall_clock_ns().saturating_sub(recording.duration_ns());
    for (index, recorded) in recording.samples.iter().enumerate() {
        let input = recorded.stamped(start_ns);
        inputs.send(client, &input);
        let deadline = Instant::now() + PATIENCE;
        let mut answered = None;
        // The answer, then every hand's frame of the same frame (they come one after another).
        let frames = loop {
            assert!(Instant::now() < deadline, "sample {index}: no answer");
            client.wait(PATIENCE).expect("wait");
            let hands_seen = seen.take(&mut out, client.receive().expect("receive"));
            answered = answered.or_else(|| {
                (hands_seen.iter())
                    .find(|hand| input.is_answered_by(hand))
                    .map(|hand| hand.frame)
            });
            if let Some(frame) = answered
                && let Some(frames) = seen.hand_frames(frame, hands)
            {
                break frames;
            }
        };
        let visible: Vec<VisibleHand> = (frames.iter())
            .zip(hands)
            .map(|(frame, &(key, model))| {
                let hand = VisibleHand {
                    root: frame.root.to_isometry(),
                    flex: frame.flex.map(f64::from),
                    held: seen.held.get(&key).copied(),
                };
                assert_segments_placed(frame, &hand, model, index);
                hand
            })
            .collect();
        out.penetrations
            .extend(oracle.penetrations(scene, &seen.poses, &visible, index));
        out.answers.push(frames.iter().map(answer).collect());
    }
    // The last frame's parts and events were published before its hand frames.
    seen.take(&mut out, client.receive().expect("receive"));
    out.final_poses = seen.poses;
    out
}

/// A hand frame's content, without what differs between runs.
fn answer(frame: &HandFrame) -> Answer {
    let [x, y, z] = frame.root.position;
    let [qx, qy, qz, qw] = frame.root.rotation;
    Answer {
        hand: (frame.user, frame.hand),
        seqs: [frame.tracker.seq, frame.glove.seq, frame.joints.seq],
        root: [x, y, z, qx, qy, qz, qw],
        flex: frame.flex.iter().map(|v| v.to_bits()).collect(),
        touching: frame.touching,
        grasp: frame.grasp_type,
        tracked: frame.tracked,
    }
}

/// Checks that the hand frame's segment poses are the hand's verified root and flex values
/// through the model's kinematics: where a renderer draws the segments is where the oracle
/// judged them.
fn assert_segments_placed(answer: &HandFrame, hand: &VisibleHand, model: &HandModel, index: usize) {
    let expected = model.segment_poses(&hand.flex);
    assert_eq!(
        answer.segment_poses().len(),
        expected.len(),
        "sample {index}"
    );
    for (segment, (wire, local)) in answer.segment_poses().iter().zip(&expected).enumerate() {
        let expected = hand.root * local;
        let wire = wire.to_isometry();
        let offset = (wire.translation.vector - expected.translation.vector).norm();
        let angle = wire.rotation.angle_to(&expected.rotation);
        assert!(
            offset < 1e-9 && angle < 1e-9,
            "sample {index}, segment {segment}: {offset:.1e} m, {angle:.1e} rad off"
        );
    }
}

/// The state the frames received so far show: the latest part poses, each hand's latest frame
/// and held part (by user and side code).
struct Seen {
    poses: Vec<Isometry3<f64>>,
    held: BTreeMap<HandKey, usize>,
    hands: BTreeMap<HandKey, HandFrame>,
}

impl Seen {
    /// Takes in received frames: parts frames, events and hand frames update the state (events
    /// are also recorded in `out`); the hand frames are returned.
    fn take(&mut self, out: &mut Replay, frames: Vec<Frame>) -> Vec<HandFrame> {
        let mut hands = Vec::new();
        for frame in frames {
            match frame {
                Frame::Parts(parts) => {
                    out.pushed_seen |= parts.parts.iter().any(|part| part.is_pushed());
                    self.poses = parts
                        .parts
                        .iter()
                        .map(|state| state.pose().to_isometry())
                        .collect();
                }
                Frame::Event(event) => {
                    let key = (event.user, event.hand);
                    match EventKind::try_from(event.kind) {
                        Ok(EventKind::Grasp) => {
                            self.held.insert(key, event.part as usize);
                        }
                        Ok(EventKind::Release | EventKind::HandOver) => {
                            self.held.remove(&key);
                        }
                        _ => {}
                    }
                    out.events.push(identity(&event));
                }
                Frame::Hand(hand) => {
                    self.hands.insert((hand.user, hand.hand), hand);
                    hands.push(hand);
                }
                Frame::Force(_) | Frame::Clearance(_) | Frame::Geometry(_) => {}
            }
        }
        hands
    }

    /// Every hand's frame numbered `frame`, in the order of `hands`, once all have come.
    fn hand_frames(&self, frame: u64, hands: &Hands) -> Option<Vec<HandFrame>> {
        (hands.iter())
            .map(|(key, _)| {
                self.hands
                    .get(key)
                    .filter(|hand| hand.frame == frame)
                    .copied()
            })
            .collect()
    }
}

/// Replays `scenario` twice into the server's input streams and checks it; returns what the
/// first replay published.
fn check(scenario: &Scenario) -> Replay {
    check_through(scenario, |_| Direct).0
}

/// Replays `scenario` twice, its samples sent through the [`Inputs`] that `connect` makes for
/// the server, and checks it; returns what the first replay published, the server (still
/// serving) and the inputs, for checks of their own.
pub(crate) fn check_through<I: Inputs>(
    scenario: &Scenario,
    connect: impl FnOnce(&mut Server) -> I,
) -> (Replay, Server, I) {
    let name = scenario.motion;
    let scene = Arc::new(Scene::load(&scenario.scene_path()).expect("the scene loads"));
    let recording = Recording::load(&scenario.fixture_path()).expect("the fixture loads");
    let bodies = Restart::new(Arc::clone(&scene), 1)
        .expect("the scene's hands build")
        .hand_bodies;
    let oracle = Oracle::new(&scene, &bodies);
    let hands: Vec<(HandKey, &HandModel)> = (bodies.iter().zip(&scene.hands))
        .map(|(bodies, hand)| {
            let key = (hand.user, side_code(bodies.model.side()));
            (key, bodies.model.as_ref())
        })
        .collect();
    let scene_arg = scenario.scene_path().display().to_string();
    let mut server = Server::start_with(
        &format!("replay_{name}"),
        &["--lockstep", "--scene", &scene_arg],
    );
    let mut client = server.connect();
    let mut inputs = connect(&mut server);

    let judge = (&oracle, hands.as_slice());
    let first = replay(&mut client, &mut inputs, &scene, judge, &recording);
    client.reset(PATIENCE).expect("reset");
    let second = replay(&mut client, &mut inputs, &scene, judge, &recording);

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
    let hand_events = [
        EventKind::Grasp,
        EventKind::Release,
        EventKind::HandOver,
        EventKind::PushBegin,
        EventKind::PushEnd,
    ]
    .map(|k| k as u32);
    let grasps_and_releases: Vec<[u32; 5]> = first
        .events
        .iter()
        .filter(|[kind, ..]| hand_events.contains(kind))
        .map(|&[kind, user, hand, grasp, part, _]| [user, hand, kind, part, grasp])
        .collect();
    let expected: Vec<[u32; 5]> = scenario
        .events
        .iter()
        .map(|event| {
            let grasp = match event.kind {
                EventKind::Grasp => event.grasp,
                _ => GraspType::None,
            };
            let (user, hand) = hands[event.hand].0;
            [
                user,
                hand,
                event.kind as u32,
                part_id(event.part),
                grasp as u32,
            ]
        })
        .collect();
    assert_eq!(
        grasps_and_releases, expected,
        "{name}: grasps, releases, hand-overs and pushes"
    );
    let pushes = (scenario.events.iter()).any(|event| event.kind == EventKind::PushBegin);
    assert_eq!(first.pushed_seen, pushes, "{name}: a part flagged pushed");
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
    (first, server, inputs)
}

/// A hand model's side as the wire codes it.
fn side_code(side: HandSide) -> u32 {
    match side {
        HandSide::Right => HandSide::Right as u32,
        HandSide::Left => HandSide::Left as u32,
    }
}

pub(crate) fn scenario(name: &str) -> &'static Scenario {
    EXPECTED
        .iter()
        .find(|scenario| scenario.motion.name() == name)
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

#[test]
fn captured_pinch_pin() {
    check(scenario("captured_pinch_pin"));
}

#[test]
fn captured_relaxed_approach() {
    check(scenario("captured_relaxed_approach"));
}

#[test]
fn two_hand_handover() {
    check(scenario("two_hand_handover"));
}

/// The hand-over between two users: anna's right hand grasps the handle, ben's left hand takes
/// it over and inserts it; every event names its user.
#[test]
fn two_user_handover() {
    let replay = check(scenario("two_user_handover"));
    assert_eq!(
        replay.grasping_users(),
        [0, 1, 0, 1],
        "grasp, grasp, hand-over, release: anna, ben, anna, ben"
    );
}

#[test]
fn push_along_rail() {
    check(scenario("push_along_rail"));
}

#[test]
fn push_into_wall() {
    check(scenario("push_into_wall"));
}

#[test]
fn release_over_table() {
    check(scenario("release_over_table"));
}

#[test]
fn release_over_slope() {
    check(scenario("release_over_slope"));
}

#[test]
fn release_over_nothing() {
    check(scenario("release_over_nothing"));
}

#[test]
fn push_off_table() {
    check(scenario("push_off_table"));
}

/// The hand frames say the hand is untracked exactly while its samples do, and the pin is held
/// through the short loss and let go in the long one.
#[test]
fn captured_tracking_loss() {
    let scenario = scenario("captured_tracking_loss");
    let replay = check(scenario);
    let recording = Recording::load(&scenario.fixture_path()).expect("the fixture loads");
    let lost: Vec<bool> = (recording.samples.iter())
        .map(|recorded| match recorded.input {
            InputSample::HandJoints(sample) => sample.joints.iter().all(|joint| joint.flags == 0),
            _ => false,
        })
        .collect();
    let untracked: Vec<bool> = (replay.answers.iter())
        .map(|hands| hands[0].tracked == 0)
        .collect();
    assert_eq!(untracked, lost);
    assert!(lost.iter().filter(|&&lost| lost).count() > 100);
}

/// What an event says, without its time and place: kind, user, hand, grasp, part and other, as
/// the replays compare events however they arrived.
pub(crate) fn identity(event: &SimEvent) -> [u32; 6] {
    [
        event.kind,
        event.user,
        event.hand,
        event.grasp_type,
        event.part,
        event.other,
    ]
}
