//! Hand-joints input through the real `vas-server`: samples built from the captured hands drive
//! the scene's hand (retargeted as the server's own retargeter does), an untracked sample leaves
//! the hand where it is and says so, impossible samples are counted and the server goes on, and
//! `vas-client send-hand-joints` sends one.

use std::process::Stdio;
use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use vas_client::Client;
use vas_client::recording::InputSample;
use vas_protocol::{HandFrame, HandJointsSample, HandSegment, HandSide, wall_clock_ns};
use vas_server::grasping::HandModel;
use vas_server::grasping::retarget::{HandJoints, Joint, Retargeter};
use vas_server::runtime::hand_joints::wire_joints;
use vas_testkit::hands::{PINCH, RELAXED, captured};
use vas_testkit::{PATIENCE, Server, configs_dir};

/// A right hand and, far from where the test moves it, one part.
fn scene(folder: &std::path::Path) -> std::path::PathBuf {
    let hand = configs_dir().join("hands/right.toml");
    let text = format!(
        "name = \"hand joints\"\nhand = {hand:?}\n\n[[parts]]\nname = \"far\"\n\
         shape = {{ kind = \"cylinder\", radius = 0.01, height = 0.05, triangles = 100 }}\n\
         position = [3.0, 3.0, 3.0]\nmovable = true\n"
    );
    let path = folder.join("scene.toml");
    std::fs::write(&path, text).expect("the scene is written");
    path
}

/// Where the test holds the captured hands: 30 cm up, turned a little.
fn placement() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.05, -0.1, 0.3),
        UnitQuaternion::from_euler_angles(0.2, -0.3, 0.5),
    )
}

/// Sends one sample and returns the hand frame answering it (in lockstep, every accepted sample
/// gets one).
fn answer(client: &mut Client, sample: HandJointsSample) -> HandFrame {
    let input = InputSample::HandJoints(sample).with_timestamp(wall_clock_ns());
    client.send_input(&input).expect("send");
    client
        .wait_for_hand_frame(PATIENCE, |frame| input.is_answered_by(frame), drop)
        .expect("wait")
        .expect("an answer")
}

/// Numbers the samples a test sends.
struct Sender {
    seq: u64,
}

impl Sender {
    fn sample(&mut self, joints: &HandJoints) -> HandJointsSample {
        self.seq += 1;
        wire_joints(joints, self.seq, 0)
    }

    /// Sends `joints` until the hand is where the retargeter puts them (it moves at most 5 mm a
    /// frame); returns that frame.
    fn until_reached(
        &mut self,
        client: &mut Client,
        retargeter: &Retargeter,
        joints: &HandJoints,
    ) -> HandFrame {
        let fit = retargeter.fit(joints).expect("the capture retargets");
        let flex = fit.flex.map(|v| v as f32);
        let deadline = Instant::now() + PATIENCE;
        loop {
            assert!(
                Instant::now() < deadline,
                "the hand never reached the joints"
            );
            let frame = answer(client, self.sample(joints));
            assert_eq!(frame.tracked, 1);
            let root = frame.root.to_isometry();
            let off = (root.translation.vector - fit.root.translation.vector).norm();
            if frame.flex == flex && off < 1e-9 && root.rotation.angle_to(&fit.root.rotation) < 1e-9
            {
                return frame;
            }
        }
    }
}

/// The distance between the thumb's and the index finger's tip segments (their origins).
fn pinch_gap(frame: &HandFrame) -> f64 {
    let at = |segment: HandSegment| {
        frame.segments[segment as usize]
            .to_isometry()
            .translation
            .vector
    };
    (at(HandSegment::ThumbDistal) - at(HandSegment::IndexDistal)).norm()
}

#[test]
fn captured_hands_drive_the_hand_and_impossible_ones_are_counted() {
    let folder = tempfile::tempdir().expect("a scratch folder");
    let scene = scene(folder.path());
    let mut server = Server::start_with(
        "hand_joints",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let mut client = server.connect();
    let model = HandModel::load(&configs_dir().join("hands/right.toml")).expect("the right hand");
    let retargeter = Retargeter::new(model).expect("the right hand retargets");
    let relaxed = captured(RELAXED, HandSide::Right)
        .expect("the capture reads")
        .transformed(&placement());
    let pinch = captured(PINCH, HandSide::Right)
        .expect("the capture reads")
        .transformed(&placement());
    let mut sender = Sender { seq: 0 };

    let open = sender.until_reached(&mut client, &retargeter, &relaxed);
    assert_eq!(open.hand, HandSide::Right as u32);
    let closed = sender.until_reached(&mut client, &retargeter, &pinch);
    let (open_gap, closed_gap) = (pinch_gap(&open), pinch_gap(&closed));
    eprintln!("thumb to index tip segments: relaxed {open_gap:.4} m, pinch {closed_gap:.4} m");
    assert!(
        closed_gap < open_gap - 0.02,
        "the hand closed from {open_gap} m to {closed_gap} m only"
    );

    // Tracking lost: the hand stays and says so.
    let mut lost = sender.sample(&pinch);
    for joint in &mut lost.joints {
        joint.flags = 0;
    }
    let untracked = answer(&mut client, lost);
    assert_eq!(untracked.tracked, 0);
    assert_eq!((untracked.root, untracked.flex), (closed.root, closed.flex));

    // Impossible hands: refused, counted, unanswered.
    let at = |joint: Joint| joint.index();
    let edits: [&dyn Fn(&mut HandJointsSample); 4] = [
        &|s| s.joints[at(Joint::IndexTip)].position[0] = f64::NAN,
        &|s| s.joints[at(Joint::Wrist)].rotation = [0.0, 0.0, 0.0, 2.0],
        &|s| s.joints.swap(at(Joint::RingProximal), at(Joint::RingTip)),
        &|s| s.side = HandSide::Left as u32,
    ];
    for edit in edits {
        let mut sample = sender.sample(&pinch);
        edit(&mut sample);
        client.send_hand_joints(&sample).expect("send");
    }
    let stats = client.input_stats(PATIENCE).expect("stats");
    assert_eq!(
        [
            stats.joints_rejected_non_finite,
            stats.joints_rejected_quaternion,
            stats.joints_rejected_anatomy,
            stats.joints_rejected_no_such_hand,
            stats.joints_untracked,
        ],
        [1, 1, 1, 1, 1]
    );
    assert_eq!(stats.rejected(), 4);
    assert!(server.process.is_running());

    // The server goes on, and the tool sends a sample from JSON.
    let accepted = stats.joints_accepted;
    let file = folder.path().join("relaxed.json");
    let sample = sender.sample(&relaxed);
    std::fs::write(&file, serde_json::to_string(&sample).expect("JSON")).expect("written");
    let seq = (sender.seq + 1).to_string();
    let tool = server.client_tool(
        &[
            "send-hand-joints",
            file.to_str().expect("UTF-8"),
            "--seq",
            &seq,
            "--answer",
        ],
        Stdio::piped(),
    );
    let output = wait_for_output(tool);
    let printed: serde_json::Value = serde_json::from_str(&output).expect("a JSON hand frame");
    assert_eq!(
        printed["hand"]["joints"]["seq"].to_string(),
        seq,
        "{output}"
    );
    assert_eq!(printed["hand"]["tracked"], 1, "{output}");
    assert_eq!(
        client.input_stats(PATIENCE).expect("stats").joints_accepted,
        accepted + 1
    );
}

/// A free-running server times tracking by its own clock: a hand whose samples stop coming is
/// published untracked while nothing else comes.
#[test]
fn a_free_running_server_notices_a_hand_whose_samples_stop() {
    let folder = tempfile::tempdir().expect("a scratch folder");
    let scene = scene(folder.path());
    let mut server =
        Server::start_with("silent_hand", &["--scene", scene.to_str().expect("UTF-8")]);
    let mut client = server.connect();
    let pinch = captured(PINCH, HandSide::Right)
        .expect("the capture reads")
        .transformed(&placement());
    let tracked = answer(&mut client, wire_joints(&pinch, 1, 0));
    assert_eq!(tracked.tracked, 1);
    let lost = client
        .wait_for_hand_frame(PATIENCE, |frame| frame.tracked == 0, drop)
        .expect("wait")
        .expect("a frame saying the hand is untracked");
    assert_eq!(lost.joints.seq, 1, "no other sample came");
    // Where tracking left it (its fingers may still be closing on the last target).
    assert_eq!(lost.root, tracked.root);
    assert!(server.process.is_running());
}

/// What a finished tool printed on stdout; fails the test if it failed.
fn wait_for_output(mut tool: vas_testkit::Spawned) -> String {
    let mut stdout = tool.take_stdout().expect("piped");
    let status = tool
        .wait_exit(PATIENCE + Duration::from_secs(5))
        .expect("the tool ends");
    assert!(status.success(), "the tool failed:\n{}", tool.log());
    let mut text = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut text).expect("stdout");
    text
}
