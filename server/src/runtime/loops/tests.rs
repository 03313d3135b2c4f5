use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};
use vas_protocol::{EventKind, InputStamp};

use super::*;
use crate::runtime::wakeup;
use crate::simulation::frames::HandTarget;
use crate::simulation::interaction::Interaction;
use crate::simulation::restart::Restart;
use vas_testkit::script::{ScriptedGrasp, sample};

/// Input samples per second.
const RATE: f64 = 1000.0;

/// The scripted handle lying where the scripted power grasp closes on it, with the right hand.
fn handle_scene(folder: &Path) -> Arc<Scene> {
    let pose = ScriptedGrasp::PowerOnHandle.part_pose();
    assert!(
        (pose.rotation.angle_to(&UnitQuaternion::from_axis_angle(
            &Vector3::y_axis(),
            FRAC_PI_2
        )))
        .abs()
            < 1e-12,
        "the config below turns the handle as the script does"
    );
    let hand = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands/right.toml");
    let text = format!(
        "name = \"handle\"\nhand = {hand:?}\n\n[[parts]]\nname = \"handle\"\n\
         shape = {{ kind = \"cylinder\", radius = 0.016, height = 0.12, triangles = 2000 }}\n\
         position = [{}, {}, {}]\nrotation = [0.0, {h}, 0.0, {h}]\nmovable = true\n",
        pose.translation.x,
        pose.translation.y,
        pose.translation.z,
        h = std::f64::consts::FRAC_1_SQRT_2,
    );
    let file = folder.join("handle.toml");
    std::fs::write(&file, text).expect("the scene file is written");
    Arc::new(Scene::load(&file).expect("the scene loads"))
}

#[test]
fn the_loops_in_lockstep_give_the_offline_interaction_frame_by_frame() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let scene = handle_scene(folder.path());
    let script = ScriptedGrasp::PowerOnHandle;
    let mut keys = script.keyframes();
    keys.retain(|key| key.time <= script.milestones().carried);
    // The script's keyframes, as this crate's hand input (the kit links its own copy of the
    // library, whose types are not this test's).
    let inputs: Vec<HandInput> = sample(&keys, RATE)
        .iter()
        .map(|key| HandInput {
            cart: key.cart,
            tracker: key.tracker,
            flex: key.flex.map(|value| value as f32),
        })
        .collect();

    let mut offline = {
        let restart = Restart::new(Arc::clone(&scene), 1).expect("the hand builds");
        Interaction::new(
            restart.hands,
            &scene.parts,
            scene.params.sliding.clone(),
            scene.params.unheld(),
            period(scene.rates.sliding_hz).as_secs_f64(),
        )
    };
    let expected: Vec<(Isometry3<f64>, Isometry3<f64>)> = inputs
        .iter()
        .map(|input| {
            let frame = offline.step(&[HandTarget::tracking(*input)]).remove(0);
            (
                frame.hand.pose.root,
                offline.part_poses().next().expect("a part"),
            )
        })
        .collect();

    let links = Links::default();
    let (verified_in, verified_out) = crossbeam_channel::unbounded();
    let (waker, _wakeups) = wakeup::channel().expect("socket pair");
    let loops =
        Loops::spawn(&links, true, None, verified_in, waker).expect("the loop threads start");
    let restart = Restart::new(Arc::clone(&scene), 1).expect("the hand builds");
    links.inputs.send(Work::Control(restart.into_change()));
    let mut grasps = 0;
    for (seq, (input, (root, handle))) in (1u64..).zip(inputs.iter().zip(&expected)) {
        let stamp = InputStamp {
            seq,
            timestamp_ns: seq,
        };
        links.inputs.send(Work::Frame(InputFrame {
            stamps: Stamps {
                tracker: stamp,
                glove: stamp,
                joints: InputStamp::default(),
            },
            hands: vec![HandTarget::tracking(*input)],
        }));
        let frame = verified_out
            .recv_timeout(Duration::from_secs(60))
            .expect("every frame comes back verified");
        assert_eq!(frame.stamps.tracker, stamp);
        assert_eq!(frame.hands[0].root, *root, "sample {seq}: the hand");
        assert_eq!(frame.parts[0].pose, *handle, "sample {seq}: the handle");
        grasps += frame
            .events
            .iter()
            .filter(|event| event.kind == EventKind::Grasp)
            .count();
    }
    links.inputs.close();
    loops.join(Duration::from_secs(30));
    assert_eq!(grasps, 1, "the handle is grasped once");
    let start = scene.parts[0].pose;
    let end = expected.last().expect("frames").1;
    assert!(
        (end.translation.vector - start.translation.vector).norm() > 0.05,
        "the handle was carried"
    );
}
