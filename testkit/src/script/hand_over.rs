//! The scripted two-handed hand-over: the right hand power-grasps one end of a long handle, the
//! left hand grasps the other end and takes it over, the right hand opens and withdraws, the left
//! hand pushes the handle's free end into the hole of a block beside it and lets go.
//!
//! Each hand runs the scripted power grasp ([`ScriptedGrasp::PowerOnHandle`]) at its end of the
//! handle, the left one mirrored in the world's `x = 0` plane, where the handle's middle is.

use nalgebra::{Isometry3, Translation3, Vector3};

use super::{HANDLE_RADIUS, Keyframe, ScriptedGrasp, fist, open_hand};
use vas_server::geometry::{TriMesh, shapes};

/// How far from the handle's middle each hand grasps it (metres): the hands' palms, 9 cm wide,
/// stay 5 cm apart.
pub const GRIP_OFFSET: f64 = 0.07;

/// The handle's length (metres): 3.5 cm of it reach beyond each hand's thumb side.
pub const HANDLE_LENGTH: f64 = 0.3;

/// How far the left hand pushes the handle along its axis, towards the block at -x (metres).
pub const INSERT: f64 = 0.09;

/// The gap between the handle's right end and the block's face, before the push (metres): its end
/// goes [`INSERT`] minus this into the hole.
pub const BLOCK_GAP: f64 = 0.06;

/// The block's length along the handle's axis (metres).
pub const BLOCK_LENGTH: f64 = 0.04;

/// The block's square cross-section's side (metres).
pub const BLOCK_WIDTH: f64 = 0.06;

/// The radius of the block's hole (metres): the clearance takes the few millimetres the handle
/// sinks while the hands hold it (each hand's script aims 5 mm into the part it grasps).
pub const HOLE_RADIUS: f64 = HANDLE_RADIUS + 0.006;

/// How far the right hand withdraws upwards once open (metres).
pub const WITHDRAW: f64 = 0.1;

/// When the hand-over's steps must have happened, in seconds from its start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandOverMilestones {
    /// The right hand holds the handle by now.
    pub right_grasped_by: f64,
    /// The left hand has taken it over by now.
    pub left_grasped_by: f64,
    /// The left hand has pushed it into the block and still holds it.
    pub inserted: f64,
}

/// The milestones of [`keyframes`].
pub const MILESTONES: HandOverMilestones = HandOverMilestones {
    right_grasped_by: 0.55,
    left_grasped_by: 1.15,
    inserted: 2.15,
};

/// The handle's pose: across both palms, its middle at the world's `x = 0`.
pub fn handle_pose() -> Isometry3<f64> {
    let script = ScriptedGrasp::PowerOnHandle.part_pose();
    Translation3::new(-script.translation.x, 0.0, 0.0) * script
}

/// The block's pose: its hole (along its own `z`) on the handle's axis, its face [`BLOCK_GAP`]
/// beyond the end of the handle the right hand holds (towards -x).
pub fn block_pose() -> Isometry3<f64> {
    let handle = handle_pose();
    let along = BLOCK_GAP + BLOCK_LENGTH / 2.0;
    Translation3::new(-(HANDLE_LENGTH / 2.0 + along), 0.0, 0.0) * handle
}

/// The block's mesh, in its own frame (its hole along `z`).
pub fn block_mesh(triangles: usize) -> TriMesh {
    shapes::box_with_hole(BLOCK_WIDTH, BLOCK_LENGTH, HOLE_RADIUS, triangles)
}

/// The handle's mesh, in its own frame (its axis is `z`).
pub fn handle_mesh(triangles: usize) -> TriMesh {
    shapes::cylinder(HANDLE_RADIUS, HANDLE_LENGTH, triangles)
}

/// The right hand's and the left hand's trajectories, on one time line (both end at the same
/// time), to be sampled with [`super::sample`]. Every key's time is a multiple of 50 ms,
/// so that at a multiple of 20 Hz both give the same number of samples, at the same times.
pub fn keyframes() -> [Vec<Keyframe>; 2] {
    let script = ScriptedGrasp::PowerOnHandle;
    let grasped_by = script.milestones().grasped_by;
    let mut grasp = script.keyframes();
    grasp.retain(|key| key.time <= grasped_by);
    // The script's hand, moved to the right of the handle's middle.
    let handle = handle_pose().translation.vector - script.part_pose().translation.vector;
    let to_grip = Translation3::from(handle - Vector3::x() * GRIP_OFFSET);
    let placed = |key: &Keyframe, delay: f64| Keyframe {
        time: key.time + delay,
        tracker: to_grip * key.tracker,
        ..*key
    };
    let closed = placed(grasp.last().expect("keyframes"), 0.0);
    let moved = |by: Vector3<f64>, key: Keyframe, time: f64| Keyframe {
        time,
        tracker: Translation3::from(by) * key.tracker,
        ..key
    };
    let withdrawn = |key, time| moved(Vector3::z() * WITHDRAW, key, time);
    // The left hand's keys are mirrored in x = 0 at the end: towards +x here is towards the
    // block, at -x, in the world.
    let pushed = |key, time| moved(Vector3::x() * INSERT, key, time);
    let at = |key: Keyframe, time: f64| Keyframe { time, ..key };
    let open = |key: Keyframe, time: f64| Keyframe {
        time,
        flex: open_hand(),
        ..key
    };
    let mut right: Vec<Keyframe> = grasp.iter().map(|key| placed(key, 0.0)).collect();
    right.extend([
        at(closed, 1.3),
        open(closed, 1.5),
        open(closed, 1.55),
        withdrawn(open(closed, 1.7), 1.7),
        withdrawn(open(closed, 2.45), 2.45),
    ]);
    let delay = 0.6;
    let mut left: Vec<Keyframe> = vec![placed(&grasp[0], 0.0)];
    left.extend(grasp.iter().map(|key| placed(key, delay)));
    let closed = placed(grasp.last().expect("keyframes"), delay);
    debug_assert_eq!(closed.flex, fist());
    left.extend([
        at(closed, 1.8),
        pushed(closed, 2.1),
        pushed(closed, 2.15),
        pushed(open(closed, 2.35), 2.35),
        pushed(open(closed, 2.45), 2.45),
    ]);
    [right, left.iter().map(Keyframe::mirrored).collect()]
}
