//! A session over scripted poses of the peg beside the block of `configs/peg_insert.toml`: the
//! minimum, the time below the threshold and the contact interval it reports.

use std::path::Path;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::Session;
use crate::report::{Interval, Status};
use crate::scene::Scene;

/// The peg upright beside the block's +x face (at x = 0.04), its nearest vertex `gap` metres
/// from it.
fn peg_beside(scene: &Scene, gap: f64) -> Vec<Isometry3<f64>> {
    let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let reach = (scene.parts[1].mesh.vertices().iter())
        .map(|vertex| -(turn * vertex).x)
        .fold(f64::NEG_INFINITY, f64::max);
    let peg = Isometry3::from_parts(Translation3::new(0.04 + reach + gap, 0.0, 0.1), turn);
    vec![scene.parts[0].pose, peg]
}

#[test]
fn a_pass_by_the_block_gives_its_minimum_time_below_and_contact() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/peg_insert.toml");
    let scene = Scene::load(&file).expect("the scene loads");
    let mut session = Session::new(&scene, 0.005);
    assert_eq!(session.pairs_measured(), 1);
    // Far, within the threshold, touching (twice at the same pose), within, far; 0.1 s apart.
    let gaps = [0.02, 0.003, 1e-5, 1e-5, 0.003, 0.02];
    for (sample, gap) in gaps.into_iter().enumerate() {
        session.observe(sample, 0.1 * sample as f64, &peg_beside(&scene, gap));
    }
    let report = session.finish("scripted".to_owned(), gaps.len(), 0);
    let [pair] = report.pairs.as_slice() else {
        panic!("one pair reported: {report:?}");
    };
    assert_eq!((pair.a.as_str(), pair.b.as_str()), ("block", "peg"));
    assert_eq!(pair.status, Status::Contact);
    let minimum = pair.minimum.as_ref().expect("a minimum");
    assert!(
        (minimum.clearance_m - 1e-5).abs() < 1e-12,
        "{}",
        minimum.clearance_m
    );
    assert_eq!(minimum.sample, 2, "the first of the two closest frames");
    assert!(
        (minimum.point_a[0] - 0.04).abs() < 1e-9,
        "{:?}",
        minimum.point_a
    );
    assert_eq!(pair.frames_below, 4);
    assert!(
        (pair.seconds_below - 0.4).abs() < 1e-12,
        "{}",
        pair.seconds_below
    );
    assert_eq!(
        pair.contacts,
        [Interval {
            begin: 2,
            end: Some(4)
        }]
    );
    assert_eq!(pair.clash_frames, 0);
    let drawn: Vec<bool> = pair.timeline.iter().map(|(_, d)| d.is_some()).collect();
    assert_eq!(
        drawn,
        [true, true, true, true, false],
        "from the first frame within reach"
    );
}
