use super::*;
use vas_server::scene::Scene;

#[test]
fn sampling_interpolates_between_keyframes_at_the_rate() {
    let a = Keyframe::new(0.0, Isometry3::identity(), [0.0; FLEX_COUNT]);
    let mut b = Keyframe::new(0.01, at([0.01, 0.0, 0.0]), [1.0; FLEX_COUNT]);
    b.cart = at([0.0, 0.02, 0.0]);
    let samples = sample(&[a, b], 1000.0);
    assert_eq!(samples.len(), 11);
    assert!((samples[5].tracker.translation.x - 0.005).abs() < 1e-12);
    assert!((samples[5].cart.translation.y - 0.01).abs() < 1e-12);
    assert!((samples[5].flex[3] - 0.5).abs() < 1e-12);
    assert_eq!(samples[10], b);
}

#[test]
fn a_recorded_scenario_names_the_part_its_scene_lacks() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/push.toml");
    let scene = Scene::load(&path).expect("the push scene loads");
    assert!(RecordedScenario::Push.keyframes(&scene).is_ok());
    let error = RecordedScenario::PrecisionPinch
        .keyframes(&scene)
        .expect_err("the push scene has no pin");
    assert_eq!(error.part, "pin");
    assert_eq!(error.scenario, RecordedScenario::PrecisionPinch);
    assert!(error.to_string().contains("\"pin\""), "{error}");
}

#[test]
fn scripted_parts_have_about_the_requested_triangles() {
    for script in ScriptedGrasp::ALL {
        let n = script.part_mesh(10_000).triangles().len();
        assert!((8_000..12_000).contains(&n), "{script:?}: {n}");
    }
}
