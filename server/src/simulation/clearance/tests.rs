use std::path::Path;

use nalgebra::{Isometry3, Translation3};

use super::*;

/// Cubes of 10 cm: a static block at the origin, a movable peg and a movable spare, and a static
/// part far away; `parts` is the watch's mode, the threshold 5 mm.
fn scene(folder: &Path, parts: &str) -> Arc<Scene> {
    let cube = |name: &str, x: f64, movable: bool| {
        format!(
            "[[parts]]\nname = \"{name}\"\nshape = {{ kind = \"box\", size = [0.1, 0.1, 0.1], \
             triangles = 12 }}\nposition = [{x}, 0.0, 0.0]\nmovable = {movable}\n\n"
        )
    };
    let text = format!(
        "name = \"cubes\"\n\n[params.clearance]\nthreshold = 0.005\nparts = \"{parts}\"\n\n{}{}{}{}",
        cube("block", 0.0, false),
        cube("peg", 0.5, true),
        cube("spare", -0.5, true),
        cube("far", 10.0, false),
    );
    let file = folder.join("cubes.toml");
    std::fs::write(&file, text).expect("the scene file is written");
    Arc::new(Scene::load(&file).expect("the scene loads"))
}

const BLOCK: PartId = 0;
const PEG: PartId = 1;
const SPARE: PartId = 2;

/// Every part's pose: the peg `peg_gap` to the right of the block, the spare `spare_gap` to its
/// left.
fn poses(peg_gap: f64, spare_gap: f64) -> Vec<Isometry3<f64>> {
    let at = |x: f64| Isometry3::from_parts(Translation3::new(x, 0.0, 0.0), Default::default());
    vec![at(0.0), at(0.1 + peg_gap), at(-0.1 - spare_gap), at(10.0)]
}

fn kinds(outcome: &ClearanceOutcome) -> Vec<(ClearanceKind, PartId, PartId)> {
    (outcome.events.iter())
        .map(|event| (event.kind, event.reading.part, event.reading.other))
        .collect()
}

#[test]
fn a_held_part_comes_below_and_is_restored_past_the_hysteresis() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let mut stage = ClearanceStage::new(scene(folder.path(), "held")).expect("a threshold");
    let always = || true;
    // Far: nothing; the spare, close to the block but not held, is not watched.
    let outcome = stage.measure(&poses(0.02, 0.003), &[PEG], always);
    assert!(outcome.below.is_empty() && outcome.events.is_empty());
    let outcome = stage.measure(&poses(0.003, 0.003), &[PEG], always);
    assert_eq!(kinds(&outcome), [(ClearanceKind::Below, PEG, BLOCK)]);
    let reading = outcome.below[0];
    assert!((reading.distance - 0.003).abs() < 1e-9, "{reading:?}");
    assert!(
        (reading.point.x - 0.053).abs() < 1e-9,
        "on the peg: {reading:?}"
    );
    assert!(
        (reading.other_point.x - 0.05).abs() < 1e-9,
        "on the block: {reading:?}"
    );
    assert!(!reading.stale);
    // In the hysteresis band: still below, no event.
    let outcome = stage.measure(&poses(0.0052, 0.003), &[PEG], always);
    assert!(outcome.events.is_empty());
    assert_eq!(outcome.below.len(), 1);
    assert!((outcome.below[0].distance - 0.0052).abs() < 1e-9);
    // Past threshold × 1.1: restored, with the distance.
    let outcome = stage.measure(&poses(0.0056, 0.003), &[PEG], always);
    assert_eq!(kinds(&outcome), [(ClearanceKind::Restored, PEG, BLOCK)]);
    assert!((outcome.events[0].reading.distance - 0.0056).abs() < 1e-9);
    assert!(outcome.below.is_empty());
}

#[test]
fn a_part_let_go_close_stays_listed_until_restored_and_costs_nothing_at_rest() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let mut stage = ClearanceStage::new(scene(folder.path(), "held")).expect("a threshold");
    let always = || true;
    let outcome = stage.measure(&poses(0.001, 0.5), &[PEG], always);
    assert_eq!(kinds(&outcome), [(ClearanceKind::Below, PEG, BLOCK)]);
    // Released where it is: still listed, and the unchanged poses are not queried again.
    let outcome = stage.measure(&poses(0.001, 0.5), &[], always);
    assert!(outcome.events.is_empty());
    assert_eq!((outcome.below.len(), outcome.queried), (1, 0));
    assert!(!outcome.below[0].stale);
    // Knocked away: restored.
    let outcome = stage.measure(&poses(0.05, 0.5), &[], always);
    assert_eq!(kinds(&outcome), [(ClearanceKind::Restored, PEG, BLOCK)]);
    // Not held and apart: no longer watched.
    let outcome = stage.measure(&poses(0.001, 0.5), &[], always);
    assert!(outcome.below.is_empty() && outcome.events.is_empty());
}

#[test]
fn movable_mode_watches_every_movable_part_held_or_not() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let mut stage = ClearanceStage::new(scene(folder.path(), "movable")).expect("a threshold");
    let outcome = stage.measure(&poses(0.004, 0.002), &[], || true);
    assert_eq!(
        kinds(&outcome),
        [
            (ClearanceKind::Below, PEG, BLOCK),
            (ClearanceKind::Below, SPARE, BLOCK)
        ]
    );
    // Closest first.
    let listed: Vec<_> = outcome.below.iter().map(|r| r.part).collect();
    assert_eq!(listed, [SPARE, PEG]);
}

#[test]
fn pairs_past_the_deadline_are_stale_and_measured_first_next_time() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let mut stage = ClearanceStage::new(scene(folder.path(), "movable")).expect("a threshold");
    // Time for one query only: the peg's pair (ids first) is measured, the spare's is overdue.
    let outcome = stage.measure(&poses(0.004, 0.002), &[], || false);
    assert_eq!((outcome.queried, outcome.stale), (1, 1));
    assert_eq!(kinds(&outcome), [(ClearanceKind::Below, PEG, BLOCK)]);
    assert_eq!(
        outcome.below.len(),
        1,
        "the spare's pair was never measured"
    );
    // Both moved: the overdue spare goes first, the peg's pair keeps its reading, stale.
    let outcome = stage.measure(&poses(0.003, 0.001), &[], || false);
    assert_eq!(kinds(&outcome), [(ClearanceKind::Below, SPARE, BLOCK)]);
    let spare = outcome
        .below
        .iter()
        .find(|r| r.part == SPARE)
        .expect("listed");
    let peg = outcome
        .below
        .iter()
        .find(|r| r.part == PEG)
        .expect("listed");
    assert!(!spare.stale && (spare.distance - 0.001).abs() < 1e-9);
    assert!(peg.stale && (peg.distance - 0.004).abs() < 1e-9, "{peg:?}");
    // No time at all: both keep their readings, stale, and nothing changes state.
    let outcome = stage.unmeasured();
    assert!(outcome.events.is_empty() && outcome.queried == 0);
    assert_eq!(outcome.below.len(), 2);
    assert!(outcome.below.iter().all(|reading| reading.stale));
    // With time, everything is fresh again.
    let outcome = stage.measure(&poses(0.003, 0.001), &[], || true);
    assert!(outcome.below.iter().all(|reading| !reading.stale));
    assert!((outcome.below[1].distance - 0.003).abs() < 1e-9);
}

#[test]
fn a_scene_without_a_threshold_has_no_watch() {
    let folder = tempfile::tempdir().expect("a temporary folder");
    let file = folder.path().join("plain.toml");
    std::fs::write(&file, "name = \"plain\"\n").expect("written");
    let scene = Arc::new(Scene::load(&file).expect("loads"));
    assert!(ClearanceStage::new(scene).is_none());
}
