use std::path::Path;

use nalgebra::{Translation3, Vector3};
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryTriMesh;
use vas_protocol::GraspType as WireGraspType;

use super::*;
use crate::collision::orientation::DEFAULT_K;
use crate::scene::PartTree;
use crate::simulation::frames::{ProposedHand, Stamps};

fn peg_in_hole() -> Scene {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/peg_in_hole.toml");
    Scene::load(&file).expect("the scene loads")
}

/// parry's verdict on two parts of `scene` at the given poses, in millimetres (parry's
/// touching threshold is absolute).
fn oracle_intersects(scene: &Scene, poses: [Isometry3<f64>; 2]) -> bool {
    let parry = |id: usize| {
        let mesh = &scene.parts[id].mesh;
        let vertices = mesh
            .vertices()
            .iter()
            .map(|v| (v * 1000.0).cast::<f32>())
            .collect();
        ParryTriMesh::new(vertices, mesh.triangles().to_vec()).expect("a valid mesh")
    };
    let scaled = |pose: &Isometry3<f64>| {
        let mut pose = pose.cast::<f32>();
        pose.translation.vector *= 1000.0;
        pose
    };
    intersection_test(&scaled(&poses[0]), &parry(0), &scaled(&poses[1]), &parry(1))
        .expect("mesh pairs are supported")
}

fn candidate(poses: Vec<Isometry3<f64>>) -> CandidateFrame {
    CandidateFrame {
        stamps: Stamps::default(),
        epoch: 1,
        hands: vec![ProposedHand {
            root: Isometry3::identity(),
            flex: [0.0; vas_protocol::FLEX_COUNT],
            touching: Vec::new(),
            grasp: WireGraspType::None,
            tracked: true,
            joints: Default::default(),
            held: None,
            pushing: Vec::new(),
            events: Vec::new(),
            handed_over: Vec::new(),
        }],
        part_poses: poses,
    }
}

#[test]
fn moves_into_free_space_pass_and_moves_into_a_part_are_refused() {
    let scene = peg_in_hole();
    let mut verifier = Verifier::new(&scene, &[]);
    let block = scene.parts[0].pose;
    let start = scene.parts[1].pose;
    let mut checked = [0, 0];
    // Straight down into the hole (free: 1 % clearance), then sideways into the wall.
    for step in 0..40 {
        let down = Translation3::new(0.0, 0.0, -0.002 * f64::from(step)) * start;
        let side = Translation3::new(0.0004 * f64::from(step), 0.0, 0.0) * down;
        for proposed in [down, side] {
            let before = verifier.part_poses()[1];
            let (frame, refused) = verifier.verify(candidate(vec![block, proposed]));
            let collides = oracle_intersects(&scene, [block, proposed]);
            if collides {
                assert_eq!(refused, vec![(1, before)], "step {step}: refused");
                assert_eq!(frame.parts[1].pose, before, "step {step}: stays");
            } else {
                assert!(refused.is_empty(), "step {step}: {proposed:?} is free");
                assert_eq!(frame.parts[1].pose, proposed);
            }
            assert!(!oracle_intersects(&scene, [block, frame.parts[1].pose]));
            checked[usize::from(collides)] += 1;
        }
    }
    assert!(
        checked[0] > 10 && checked[1] > 10,
        "both kinds: {checked:?}"
    );
    assert_eq!(verifier.refused_moves(), checked[1] as u64);
}

#[test]
fn the_hand_is_refused_inside_a_part_and_kept_where_it_was() {
    // The default orientations, and another count, which every tree of the scene (the
    // parts' and the hand's) must then use.
    for k in [DEFAULT_K, 26] {
        let mut scene = peg_in_hole();
        scene.params.dop_orientations = k;
        for part in &mut scene.parts {
            part.tree = PartTree::new(k, None);
        }
        hand_refused_inside_a_part(&scene);
    }
}

fn hand_refused_inside_a_part(scene: &Scene) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands/right.toml");
    let model = Arc::new(HandModel::load(&file).expect("the hand loads"));
    let hand = crate::grasping::GraspingHand::new(
        Arc::clone(&model),
        scene.params.grasp(),
        crate::grasping::HandPose {
            root: Isometry3::identity(),
            flex: [0.0; vas_protocol::FLEX_COUNT],
        },
    )
    .expect("the segments build");
    let k = scene.params.dop_orientations;
    assert_eq!(hand.geometry().tree(0).orientations().k(), k);
    assert_eq!(scene.parts[0].tree().orientations().k(), k);
    let mut verifier = Verifier::new(scene, &[HandBodies::of(model, &hand)]);
    // One group more than the scene's, for the hand: the matrix stays tiny (a group id near
    // u16::MAX once made it 4 GiB of address space).
    assert_eq!(
        verifier.pipeline.interest().group_count(),
        scene.groups.names.len() + 1
    );
    let poses: Vec<_> = scene.parts.iter().map(|part| part.pose).collect();
    let above = Isometry3::from(Translation3::new(0.0, 0.0, 0.3));
    let mut free = candidate(poses.clone());
    free.hands[0].root = above;
    let (frame, _) = verifier.verify(free);
    assert_eq!(frame.hands[0].root, above, "free space: accepted");
    let mut inside = candidate(poses);
    inside.hands[0].root = Isometry3::from(Translation3::from(Vector3::new(0.0, 0.0, 0.025)));
    let (frame, refused) = verifier.verify(inside);
    assert!(refused.is_empty(), "no part moved");
    assert_eq!(
        frame.hands[0].root, above,
        "inside the block: the hand stays"
    );
    assert_eq!(verifier.refused_moves(), 1);
}
