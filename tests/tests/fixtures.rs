//! The recorded scenarios, replayed offline through the server's per-sample interaction model:
//! each fixture is what its generator writes today, and its replay gives the expected grasp and
//! release events, the expected final part pose, and no penetration by parry.

use vas_client::recording::Recording;
use vas_server::scene::Scene;
use vas_tests::offline::{self, OfflineRun};
use vas_tests::scenarios::{EXPECTED, Scenario};

fn replay(scenario: &Scenario) -> (Scene, OfflineRun) {
    let scene = Scene::load(&scenario.scene_path()).expect("the scenario's scene loads");
    let recording =
        Recording::load(&scenario.fixture_path()).expect("the scenario's fixture loads");
    assert_eq!(recording.header.scene, scene.name, "{}", scenario.script);
    let run = offline::replay(&scene, &recording).expect("the fixture replays");
    (scene, run)
}

fn check(scenario: &Scenario) {
    let (scene, run) = replay(scenario);
    let name = scenario.script;
    let expected = &scenario.final_pose;
    let pose = run
        .final_pose(&scene, expected.part)
        .expect("the expected part is in the scene");
    let (position_error, angle_error) = expected.errors(&pose);
    let part = scene
        .parts
        .iter()
        .position(|p| p.name == expected.part)
        .expect("the expected part is in the scene");
    eprintln!(
        "{name}: {} frames, events {:?}, final {} off by {:.2e} m and {:.2e} rad, touched in {} \
         frames, {} penetrations",
        run.frames,
        run.events
            .iter()
            .map(|e| format!("{:?} {} {:?} @{}", e.kind, e.part, e.grasp, e.frame))
            .collect::<Vec<_>>(),
        expected.part,
        position_error,
        angle_error,
        run.touched_frames[part],
        run.penetrations.len()
    );
    assert_eq!(run.rejected, 0, "{name}");
    assert!(
        run.penetrations.is_empty(),
        "{name}: {} penetrations, first {:?}",
        run.penetrations.len(),
        &run.penetrations[..run.penetrations.len().min(5)]
    );
    let events: Vec<_> = run
        .events
        .iter()
        .map(|e| (e.kind, e.part.as_str(), e.grasp))
        .collect();
    let wanted: Vec<_> = scenario
        .events
        .iter()
        .map(|e| (e.kind, e.part, e.grasp))
        .collect();
    assert_eq!(events, wanted, "{name}");
    assert!(
        run.touched_frames[part] > 0,
        "{name}: the hand never touched {}",
        expected.part
    );
    assert!(
        expected.holds(&pose),
        "{name}: {} ends at {pose:?}, {position_error:.2e} m and {angle_error:.2e} rad from \
         {:?}",
        expected.part,
        expected.pose()
    );
}

#[test]
fn peg_insert() {
    check(&EXPECTED[0]);
}

#[test]
fn pipe_through_sheet() {
    check(&EXPECTED[1]);
}

#[test]
fn precision_pinch() {
    check(&EXPECTED[2]);
}

#[test]
fn push() {
    check(&EXPECTED[3]);
}

#[test]
fn navigate_holding() {
    check(&EXPECTED[4]);
}
