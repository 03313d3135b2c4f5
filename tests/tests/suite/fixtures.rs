//! The recorded scenarios, replayed offline through the server's per-sample interaction model:
//! each fixture is what its generator writes today, and its replay gives the expected grasp and
//! release events, the expected final part pose, and no penetration by parry.

use std::fs;

use nalgebra::Isometry3;

use vas_client::recording::Recording;
use vas_protocol::EventKind::{self, PushEnd, Release};
use vas_server::scene::Scene;
use vas_testkit::captured::CapturedMotion;
use vas_testkit::fixtures::write_fixture;
use vas_testkit::offline::{self, OfflineRun};
use vas_testkit::scenarios::{EXPECTED, Motion, Scenario};
use vas_testkit::script::RecordedScenario;

fn replay(scenario: &Scenario) -> (Scene, OfflineRun) {
    let scene = Scene::load(&scenario.scene_path()).expect("the scenario's scene loads");
    let recording =
        Recording::load(&scenario.fixture_path()).expect("the scenario's fixture loads");
    assert_eq!(recording.header.scene, scene.name, "{}", scenario.motion);
    let run = offline::replay(&scene, &recording).expect("the fixture replays");
    (scene, run)
}

fn scenario(name: &str) -> &'static Scenario {
    EXPECTED
        .iter()
        .find(|scenario| scenario.motion.name() == name)
        .expect("a recorded scenario")
}

/// Checks `scenario` and replays it a second time: the same run.
fn check_twice(scenario: &Scenario) -> (Scene, OfflineRun) {
    let (scene, run) = check(scenario);
    assert_eq!(
        replay(scenario).1,
        run,
        "{}: a second replay",
        scenario.motion
    );
    (scene, run)
}

fn check(scenario: &Scenario) -> (Scene, OfflineRun) {
    let (scene, run) = replay(scenario);
    let name = scenario.motion;
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
         frames, held back up to {:.2e} m, {} penetrations",
        run.frames,
        run.events
            .iter()
            .map(|e| format!(
                "{:?} {} {:?} hand {} @{}",
                e.kind, e.part, e.grasp, e.hand, e.frame
            ))
            .collect::<Vec<_>>(),
        expected.part,
        position_error,
        angle_error,
        run.touched_frames[part],
        run.max_held_back,
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
        .map(|e| (e.hand, e.kind, e.part.as_str(), e.grasp))
        .collect();
    let wanted: Vec<_> = scenario
        .events
        .iter()
        .map(|e| (e.hand, e.kind, e.part, e.grasp))
        .collect();
    assert_eq!(events, wanted, "{name}");
    assert!(
        run.touched_frames[part] > 0,
        "{name}: the hand never touched {}",
        expected.part
    );
    assert!(
        run.max_held_back >= scenario.min_held_back,
        "{name}: held back at most {:.2e} m, less than {:.2e} m",
        run.max_held_back,
        scenario.min_held_back
    );
    assert!(
        expected.holds(&pose),
        "{name}: {} ends at {pose:?}, {position_error:.2e} m and {angle_error:.2e} rad from \
         {:?}",
        expected.part,
        expected.pose()
    );
    (scene, run)
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

#[test]
fn demo_peg_into_block() {
    check(&EXPECTED[5]);
}

#[test]
fn captured_pinch_pin() {
    check(&EXPECTED[6]);
}

#[test]
fn captured_relaxed_approach() {
    check(&EXPECTED[7]);
}

#[test]
fn two_hand_handover() {
    check(&EXPECTED[9]);
}

#[test]
fn two_user_handover() {
    check_twice(scenario("two_user_handover"));
}

#[test]
fn captured_tracking_loss() {
    check(&EXPECTED[8]);
}

#[test]
fn push_along_rail() {
    check_twice(scenario("push_along_rail"));
}

#[test]
fn push_into_wall() {
    check_twice(scenario("push_into_wall"));
}

#[test]
fn release_over_table() {
    let (scene, run) = lands_within_half_a_second(scenario("release_over_table"), Release);
    let gap = nearest_gap(&scene, &run.final_poses, "peg");
    assert!(gap <= 1.0, "the peg rests {gap} mm above the table");
}

#[test]
fn release_over_slope() {
    let (scene, run) = lands_within_half_a_second(scenario("release_over_slope"), Release);
    let gap = nearest_gap(&scene, &run.final_poses, "peg");
    assert!(gap <= 1.0, "the peg rests {gap} mm above the slope");
}

#[test]
fn release_over_nothing() {
    let (scene, run) = lands_within_half_a_second(scenario("release_over_nothing"), Release);
    let peg = part_index(&scene, "peg");
    let lowest = (scene.parts[peg].mesh.vertices().iter())
        .map(|v| (run.final_poses[peg] * v).z)
        .fold(f64::INFINITY, f64::min);
    let floor = scene.params.release.floor;
    assert!(
        (lowest - floor).abs() <= 1e-6,
        "the peg's lowest point is at {lowest}, the floor at {floor}"
    );
}

#[test]
fn push_off_table() {
    let (scene, run) = lands_within_half_a_second(scenario("push_off_table"), PushEnd);
    let gap = nearest_gap(&scene, &run.final_poses, "block");
    assert!(gap <= 1.0, "the block rests {gap} mm above the ground");
    let block = part_index(&scene, "block");
    let lowest = (scene.parts[block].mesh.vertices().iter())
        .map(|v| (run.final_poses[block] * v).z)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (0.0..=0.001).contains(&lowest),
        "the block's lowest point is at z = {lowest}, not on the ground"
    );
}

/// Checks a scenario whose part settles (twice), and that the part has come to rest within half
/// a second of simulated time after the event `settles` (a release, or the end of a push): the
/// recording cut there leaves it where the whole recording does.
fn lands_within_half_a_second(scenario: &Scenario, settles: EventKind) -> (Scene, OfflineRun) {
    let (scene, run) = check_twice(scenario);
    let recording = Recording::load(&scenario.fixture_path()).expect("loads");
    let release = (run.events.iter())
        .find(|event| event.kind == settles)
        .expect("the part starts settling");
    let released_at = recording.samples[release.frame].time;
    let mut cut = recording.clone();
    cut.samples
        .retain(|sample| sample.time <= released_at + 0.5);
    assert!(
        cut.samples.len() < recording.samples.len(),
        "{}: the recording ends within half a second of the release",
        scenario.motion
    );
    let early = offline::replay(&scene, &cut).expect("replays");
    let part = part_index(&scene, scenario.final_pose.part);
    assert_eq!(
        early.final_poses[part], run.final_poses[part],
        "{}: still moving half a second after the release",
        scenario.motion
    );
    (scene, run)
}

fn part_index(scene: &Scene, name: &str) -> usize {
    (scene.parts.iter())
        .position(|p| p.name == name)
        .expect("the part is in the scene")
}

/// How far (millimetres, by parry) part `name` at `poses` is from the nearest part it is of
/// interest to.
fn nearest_gap(scene: &Scene, poses: &[Isometry3<f64>], name: &str) -> f32 {
    let part = part_index(scene, name);
    let mesh =
        |i: usize| vas_server::collision::parry_mesh::millimetre_trimesh(&scene.parts[i].mesh);
    let at = |i: usize| vas_server::collision::parry_mesh::millimetre_pose(&poses[i]);
    (0..scene.parts.len())
        .filter(|&other| other != part && scene.pair_of_interest(part, other))
        .map(|other| parry3d::query::distance(&at(part), &mesh(part), &at(other), &mesh(other)))
        .map(|distance| distance.expect("meshes are supported"))
        .fold(f32::INFINITY, f32::min)
}

/// The tracking-loss recording keeps the pin through the short loss and lets go of it only the
/// grace period (the scene's default) into the long one.
#[test]
fn a_hand_lets_go_only_once_its_tracking_is_lost_longer_than_the_grace() {
    use vas_testkit::captured::{LONG_LOSS_FROM_S, RATE_HZ};
    let (scene, run) = replay(&EXPECTED[8]);
    let grace = scene.params.tracking.grace;
    let release = (run.events.iter())
        .find(|event| event.kind == vas_protocol::EventKind::Release)
        .expect("released");
    let released_at = release.frame as f64 / RATE_HZ;
    assert!(
        (released_at - (LONG_LOSS_FROM_S + grace)).abs() <= 1.5 / RATE_HZ,
        "released at {released_at} s, not {grace} s into the loss at {LONG_LOSS_FROM_S} s"
    );
}

#[test]
fn the_fixtures_are_what_the_generator_writes_every_time() {
    let out = tempfile::tempdir().expect("a temporary folder");
    for scenario in &EXPECTED {
        let first = fs::read(
            write_fixture(scenario, &vas_testkit::configs_dir(), out.path()).expect("generates"),
        )
        .expect("written");
        let second = fs::read(
            write_fixture(scenario, &vas_testkit::configs_dir(), out.path()).expect("generates"),
        )
        .expect("written");
        assert_eq!(first, second, "{}: two runs differ", scenario.motion);
        let committed = fs::read(scenario.fixture_path()).expect("the fixture is committed");
        assert!(
            first == committed,
            "{}: the committed fixture is stale; regenerate it (tests/fixtures/README.md)",
            scenario.motion
        );
    }
}

#[test]
fn replaying_a_fixture_twice_gives_the_same_run() {
    let scenario = &EXPECTED[0];
    assert_eq!(replay(scenario).1, replay(scenario).1);
}

#[test]
fn the_oracle_reports_parts_and_hands_that_overlap() {
    // The peg put into the block's wall beside the hole: the two parts overlap from the start.
    let peg_insert = &EXPECTED[0];
    let mut scene = Scene::load(&peg_insert.scene_path()).expect("loads");
    let recording = Recording::load(&peg_insert.fixture_path()).expect("loads");
    let block = scene.parts[0].pose;
    scene.parts[1].pose.translation = block.translation;
    scene.parts[1].pose.translation.vector.x += 0.025;
    let run = offline::replay(&scene, &recording).expect("replays");
    assert!(
        run.penetrations
            .first()
            .is_some_and(|p| p.starts_with("frame 0: parts block and peg overlap")),
        "{:?}",
        run.penetrations.first()
    );

    // The block where the hand appears: parry finds the hand parked inside it, and the replay
    // publishes no frame with it there (the verifier keeps the hand out until the tracker
    // leads it out).
    let push = &EXPECTED[3];
    let mut scene = Scene::load(&push.scene_path()).expect("loads");
    let recording = Recording::load(&push.fixture_path()).expect("loads");
    let (targets, _) = offline::hand_targets(&scene, recording.samples.iter().map(|s| s.input));
    scene.parts[0].pose.translation.vector = targets[0][0].input.tracker.translation.vector;
    let parked = vas_server::grasping::HandPose {
        root: targets[0][0].input.cart * targets[0][0].input.tracker,
        flex: [0.0; vas_protocol::FLEX_COUNT],
    };
    let model = std::sync::Arc::clone(&scene.hands[0].model);
    let hand = vas_server::grasping::GraspingHand::new(
        std::sync::Arc::clone(&model),
        scene.params.grasp(),
        parked,
    )
    .expect("the hand builds");
    let bodies = vas_server::simulation::hand_bodies::HandBodies::of(model, &hand);
    let poses: Vec<_> = scene.parts.iter().map(|part| part.pose).collect();
    let visible = offline::VisibleHand {
        root: parked.root,
        flex: parked.flex,
        held: None,
    };
    let found = offline::Oracle::new(&scene, &[bodies]).penetrations(&scene, &poses, &[visible], 0);
    assert!(
        found
            .first()
            .is_some_and(|p| p.starts_with("frame 0: hand segment")),
        "{found:?}"
    );
    let run = offline::replay(&scene, &recording).expect("replays");
    assert!(
        run.penetrations.is_empty(),
        "{:?}",
        run.penetrations.first()
    );
}

#[test]
fn every_recorded_scenario_has_one_expected_outcome() {
    let listed: Vec<_> = EXPECTED.iter().map(|s| s.motion).collect();
    let motions: Vec<_> = (RecordedScenario::ALL.into_iter().map(Motion::Script))
        .chain(CapturedMotion::ALL.into_iter().map(Motion::Captured))
        .chain([Motion::HandOver, Motion::UsersHandOver])
        .collect();
    assert_eq!(listed.len(), motions.len());
    for motion in motions {
        let times = listed.iter().filter(|&&listed| listed == motion).count();
        assert_eq!(times, 1, "{motion} is listed {times} times");
    }
}

/// The demo's peg, let go 1 cm into the block's hole (the demo scene settles released parts),
/// drops through the hole and comes to rest on the table within half a second of the release,
/// and nothing enters anything on the way (parry judges every frame).
#[test]
fn a_released_part_settles_onto_what_is_below_it() {
    let (scene, run) = lands_within_half_a_second(scenario("demo_peg_into_block"), Release);
    let gap = nearest_gap(&scene, &run.final_poses, "peg");
    assert!(gap <= 1.0, "the peg rests {gap} mm from the nearest part");
}
