//! The two-hand hand-over replayed with the tracking filter on: the left hand, its root trailing
//! its script, carries the handle it just took over into the right hand's fingers that still
//! ring it. The collision loop's verifier keeps the handle where it was until those fingers
//! are gone, so that no frame the server publishes has a hand segment inside a part.

use vas_client::recording::Recording;
use vas_protocol::EventKind;
use vas_server::scene::Scene;
use vas_testkit::offline;
use vas_testkit::scenarios::{EXPECTED, Motion};

#[test]
fn the_filtered_hand_over_publishes_no_penetration() {
    let scenario = (EXPECTED.iter())
        .find(|scenario| scenario.motion == Motion::HandOver)
        .expect("the hand-over is a scenario");
    let mut scene = Scene::load(&scenario.scene_path()).expect("the scene loads");
    scene.params.tracking.filter = true;
    let recording = Recording::load(&scenario.fixture_path()).expect("the fixture loads");
    let run = offline::replay(&scene, &recording).expect("the fixture replays");
    let kinds: Vec<_> = (run.events.iter())
        .map(|e| (e.hand, e.kind, e.part.as_str()))
        .collect();
    eprintln!("{} frames, events {kinds:?}", run.frames);
    assert_eq!(run.rejected, 0);
    assert!(
        kinds.contains(&(0, EventKind::HandOver, "handle")),
        "the right hand hands the handle over: {kinds:?}"
    );
    assert!(
        run.penetrations.is_empty(),
        "{} penetrations, first {:?}",
        run.penetrations.len(),
        &run.penetrations[..run.penetrations.len().min(5)]
    );
}
