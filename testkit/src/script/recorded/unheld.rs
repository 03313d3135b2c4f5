//! The recorded scenarios of parts no hand holds: the flat hand pushing a part (free, along a
//! slot, into a wall), and a part grasped, lifted and released in mid-air to settle.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{UnitQuaternion, Vector3};
use vas_server::scene::Part;

use super::{Keyframe, PALM_FACE, PALM_MIDDLE, extent, open_and_rest, power_grasp_at, shift, then};
use crate::script::{open_hand, pose};

/// The pushing palm starts this far from the part (metres).
const PUSH_GAP: f64 = 0.02;
/// How fast the pushing hand moves in (metres per second).
const PUSH_SPEED: f64 = 0.1;
/// How far the released part is lifted above where it was grasped (metres).
const RELEASE_LIFT: f64 = 0.03;
/// How long the recording goes on after the hand has opened (seconds): longer than any of the
/// released parts takes to settle.
const SETTLE_WAIT: f64 = 0.4;

/// How long the recording of a push off a support goes on after the hand has withdrawn
/// (seconds): longer than the pushed part takes to tip over and land below.
const FALL_WAIT: f64 = 0.6;

/// A push by the flat hand, fingers straight along -y, thumb up, palm towards +x (its
/// little-finger edge is its lowest, so that it reaches down to a part standing on a table): it
/// starts [`PUSH_GAP`] before the
/// part's near face with its palm's middle level with the part's middle raised by `raise`,
/// holds, moves in at [`PUSH_SPEED`] until it aims `depth` into the part (the part is pushed as
/// far, unless something stops it), holds, and withdraws to where it started.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FlatPush {
    /// How far above the part's middle the palm's middle is (metres).
    pub(super) raise: f64,
    /// How far into the part the hand aims (metres).
    pub(super) depth: f64,
}

impl FlatPush {
    /// The trajectory against `part`.
    pub(super) fn keyframes(self, part: &Part) -> Vec<Keyframe> {
        // Palm (the hand's -z) towards +x, fingers along +y, thumb down, turned half a turn
        // about x.
        let palm_towards_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -FRAC_PI_2);
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI) * palm_towards_x;
        let (near, _) = extent(part, &Vector3::x());
        let centre = part.pose.translation.vector;
        let start = pose(
            [
                near - PUSH_GAP - PALM_FACE,
                centre.y + PALM_MIDDLE,
                centre.z + self.raise,
            ],
            rotation,
        );
        let travel = PUSH_GAP + self.depth;
        let mut keys = vec![Keyframe::new(0.0, start, open_hand())];
        then(&mut keys, 0.1, |_| {});
        then(&mut keys, travel / PUSH_SPEED, shift(travel * Vector3::x()));
        then(&mut keys, 0.1, |_| {});
        then(&mut keys, 0.3, |k| k.tracker = start);
        then(&mut keys, 0.05, |_| {});
        keys
    }

    /// The trajectory against `part`, then [`FALL_WAIT`] of stillness while the part, pushed off
    /// what supported it, falls.
    pub(super) fn keyframes_then_fall(self, part: &Part) -> Vec<Keyframe> {
        let mut keys = self.keyframes(part);
        then(&mut keys, FALL_WAIT, |_| {});
        keys
    }
}

/// A power grasp on the upright cylinder `peg` at its middle (the cylinder's axis taken
/// downwards puts the thumb on top), lifted [`RELEASE_LIFT`], the hand opened, and
/// [`SETTLE_WAIT`] of stillness while the released peg settles along its own axis, out of the
/// fist.
pub(super) fn release_in_mid_air(peg: &Part) -> Vec<Keyframe> {
    let handle = peg.pose * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
    let (left, right) = extent(peg, &Vector3::x());
    let mut keys = power_grasp_at(&handle, (right - left) / 2.0);
    then(&mut keys, 0.3, shift(RELEASE_LIFT * Vector3::z()));
    then(&mut keys, 0.05, |_| {});
    open_and_rest(&mut keys);
    then(&mut keys, SETTLE_WAIT, |_| {});
    keys
}
