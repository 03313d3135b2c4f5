//! The recorded scenarios of the replay fixtures: scripted motions of the right hand placed in
//! their scenes.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use vas_server::scene::{Part, Scene};

use super::{HANDLE_RADIUS, Keyframe, ScriptedGrasp, fist, open_hand};

mod unheld;

use unheld::{FlatPush, release_in_mid_air};

/// A scene lacks a part a recorded scenario moves or aims at.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("scene {scene:?} has no part named {part:?}, which scenario {scenario} needs")]
pub struct MissingPart {
    /// The scene's name.
    pub scene: String,
    /// The scenario.
    pub scenario: RecordedScenario,
    /// The part's name.
    pub part: &'static str,
}

/// The recorded scenarios of the replay fixtures: each a scripted motion of the right hand in its
/// scene, placed from the poses of the scene's parts (so that a scene moved as a whole gives the
/// same motion relative to its parts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordedScenario {
    /// A power grasp on a peg standing beside a block, carried over the block's hole, lowered
    /// into it and released there.
    PegInsert,
    /// A power grasp on a pipe lying before an open sheet, pushed along its axis through the
    /// sheet's hole and released.
    PipeThroughSheet,
    /// Thumb and index tips pinch a small pin, lift it and open.
    PrecisionPinch,
    /// The flat hand, fingers straight, pushes the side of a block standing on a table 2 cm
    /// across the table and withdraws; nothing is grasped.
    Push,
    /// A power grasp on a handle, then the cart drives and turns while the hand stays still in
    /// the cart's frame; then the hand opens.
    NavigateHolding,
    /// In the demo scene: a power grasp on the peg standing on the table, carried over the
    /// block, lowered into its hole and released; it drops through onto the table.
    DemoPegIntoBlock,
    /// The flat hand, thumb up, pushes a slider standing in a slot along the slot, aiming past
    /// its end stop, and withdraws.
    PushAlongRail,
    /// The flat hand pushes a block standing on a table before a wall, aiming past the wall, and
    /// withdraws.
    PushIntoWall,
    /// A power grasp on a peg above a table, lifted and released in mid-air: it settles.
    ReleaseOverTable,
    /// A power grasp on a peg above a tilted plane, lifted and released in mid-air: it settles.
    ReleaseOverSlope,
    /// A power grasp on a peg with nothing below, lifted and released in mid-air: it settles.
    ReleaseOverNothing,
    /// The flat hand, thumb up, pushes a block standing on a table over the table's edge, and
    /// withdraws: the block tips over the edge and falls onto the ground.
    PushOffTable,
}

impl fmt::Display for RecordedScenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How far above the block's top the peg's lower end is carried (metres).
const PEG_CARRY_GAP: f64 = 0.02;
/// How deep the peg's lower end goes into the hole (metres).
const PEG_INSERT_DEPTH: f64 = 0.035;
/// How far the hand strays sideways while the peg goes down the second half of its way into the
/// hole, before it comes back (metres): more than the hole's clearance, so the peg slides down
/// along the hole's wall.
const PEG_DRIFT: f64 = 0.002;
/// How far the pipe's leading end goes past the sheet (metres).
const PIPE_PASS_BEYOND: f64 = 0.06;
/// How far the hand sinks while the pipe makes the second half of its way, before it comes back
/// (metres): more than the hole's clearance, so the pipe slides along the sheet's rim.
const PIPE_DRIFT: f64 = 0.004;
/// How far above its middle the demo's peg is grasped (metres): the fingers stacked along the
/// upright peg then stay clear of the table, and of the block's top while the peg goes in.
const DEMO_GRASP_RAISE: f64 = 0.02;
/// How deep the demo's peg goes into the block's hole (metres).
const DEMO_INSERT_DEPTH: f64 = 0.01;
/// How far short of the demo's peg the palm stops while the fingers close on it (metres): the
/// demo scene pushes parts, and a palm pressing on the peg alone would push it away.
const DEMO_PALM_GAP: f64 = 0.0015;
/// How far the palm then presses into the demo's peg (metres), the fingers around it: a power
/// grasp, which holds, so nothing pushes the peg.
const DEMO_PALM_PRESS: f64 = 0.002;
/// The thumb's flex values (CyberGlove order: rotation, its two joints, abduction).
const THUMB: std::ops::Range<usize> = 0..4;
/// How far the hand draws back from the demo's peg while it opens (metres): it lets go touching
/// nothing, so no push holds the peg and it settles.
const DEMO_WITHDRAW: f64 = 0.03;
/// The palm's inside face, this far from the hand root along -z (metres).
const PALM_FACE: f64 = 0.0125;
/// The palm's middle, this far from the hand root along +y (metres).
const PALM_MIDDLE: f64 = 0.055;
/// The push aims this far into the block (metres): the block is pushed as far.
const PUSH_DEPTH: f64 = 0.02;
/// The push along the rail aims this far into the slider (metres): 2 cm past the end stop.
const RAIL_PUSH_DEPTH: f64 = 0.05;
/// How far above the slider's middle the palm's middle is (metres): the hand, thumb up, clears
/// the rails and the end stop, and its palm lies within the slider's face.
const RAIL_PUSH_RAISE: f64 = 0.01;
/// The push into the wall aims this far into the block (metres): 2 cm past the wall.
const WALL_PUSH_DEPTH: f64 = 0.03;
/// The push off the table aims this far into the block (metres): its middle 2.5 cm past the
/// table's edge.
const TABLE_PUSH_DEPTH: f64 = 0.04;
/// How far the cart drives while the hand holds the handle (metres, in the world).
const CART_DRIVE: [f64; 3] = [0.3, 0.2, 0.0];
/// How far the cart turns about its vertical axis meanwhile (degrees).
const CART_TURN_DEGREES: f64 = 40.0;

impl RecordedScenario {
    /// Every recorded scenario, in the order of the fixtures' documentation.
    pub const ALL: [RecordedScenario; 12] = [
        RecordedScenario::PegInsert,
        RecordedScenario::PipeThroughSheet,
        RecordedScenario::PrecisionPinch,
        RecordedScenario::Push,
        RecordedScenario::NavigateHolding,
        RecordedScenario::DemoPegIntoBlock,
        RecordedScenario::PushAlongRail,
        RecordedScenario::PushIntoWall,
        RecordedScenario::ReleaseOverTable,
        RecordedScenario::ReleaseOverSlope,
        RecordedScenario::ReleaseOverNothing,
        RecordedScenario::PushOffTable,
    ];

    /// The scenario's name: its fixture's file stem.
    pub fn name(self) -> &'static str {
        match self {
            RecordedScenario::PegInsert => "peg_insert",
            RecordedScenario::PipeThroughSheet => "pipe_through_sheet",
            RecordedScenario::PrecisionPinch => "precision_pinch",
            RecordedScenario::Push => "push",
            RecordedScenario::NavigateHolding => "navigate_holding",
            RecordedScenario::DemoPegIntoBlock => "demo_peg_into_block",
            RecordedScenario::PushAlongRail => "push_along_rail",
            RecordedScenario::PushIntoWall => "push_into_wall",
            RecordedScenario::ReleaseOverTable => "release_over_table",
            RecordedScenario::ReleaseOverSlope => "release_over_slope",
            RecordedScenario::ReleaseOverNothing => "release_over_nothing",
            RecordedScenario::PushOffTable => "push_off_table",
        }
    }

    /// What the recording shows, for its header.
    pub fn description(self) -> &'static str {
        match self {
            RecordedScenario::PegInsert => {
                "power grasp on the peg, carried over the block, lowered 3.5 cm into its hole \
                 (the hand straying 2 mm sideways on the way down, so the peg slides along the \
                 hole's wall), released there"
            }
            RecordedScenario::PipeThroughSheet => {
                "power grasp on the pipe, pushed along its axis through the open sheet's hole \
                 until its end is 6 cm past the sheet (the hand sinking 4 mm on the way, so the \
                 pipe slides along the hole's rim), released"
            }
            RecordedScenario::PrecisionPinch => {
                "thumb and index tips pinch the pin, lift it 5 cm, and open"
            }
            RecordedScenario::Push => {
                "the flat hand, thumb up, pushes against the side of the block on the table, \
                 aiming 2 cm into it, and withdraws; nothing is grasped"
            }
            RecordedScenario::NavigateHolding => {
                "power grasp on the handle, then the cart drives 36 cm and turns 40 degrees with \
                 the hand still in the cart's frame, then the hand opens"
            }
            RecordedScenario::DemoPegIntoBlock => {
                "in the demo scene: the fingers close on the peg, then the palm (a power grasp); \
                 carried over the block, lowered 1 cm into its hole (1 mm of clearance); the hand \
                 opens drawing back, and the peg drops through the hole onto the table"
            }
            RecordedScenario::PushAlongRail => {
                "the flat hand, thumb up, pushes the slider along its slot, aiming 2 cm past the \
                 end stop, and withdraws; nothing is grasped"
            }
            RecordedScenario::PushIntoWall => {
                "the flat hand, thumb up, pushes the block on the table towards the wall 1 cm \
                 behind it, aiming 3 cm into it, and withdraws; nothing is grasped"
            }
            RecordedScenario::ReleaseOverTable => {
                "power grasp on the peg above the table, lifted 3 cm, released in mid-air"
            }
            RecordedScenario::ReleaseOverSlope => {
                "power grasp on the peg above the tilted plane, lifted 3 cm, released in mid-air"
            }
            RecordedScenario::ReleaseOverNothing => {
                "power grasp on the peg with nothing below, lifted 3 cm, released in mid-air"
            }
            RecordedScenario::PushOffTable => {
                "the flat hand, thumb up, pushes the block on the table, aiming 4 cm into it, its \
                 middle past the table's edge, and withdraws; nothing is grasped"
            }
        }
    }

    /// The trajectory in `scene`, to be sampled with [`sample`](super::sample); the cart starts at the world's
    /// origin.
    pub fn keyframes(self, scene: &Scene) -> Result<Vec<Keyframe>, MissingPart> {
        let part = |name: &'static str| {
            scene
                .parts
                .iter()
                .find(|p| p.name == name)
                .ok_or_else(|| MissingPart {
                    scene: scene.name.clone(),
                    scenario: self,
                    part: name,
                })
        };
        Ok(match self {
            RecordedScenario::PegInsert => peg_insert(part("peg")?, part("block")?),
            RecordedScenario::PipeThroughSheet => pipe_through_sheet(part("pipe")?, part("sheet")?),
            RecordedScenario::PrecisionPinch => precision_pinch(part("pin")?),
            RecordedScenario::Push => FlatPush {
                raise: 0.0,
                depth: PUSH_DEPTH,
            }
            .keyframes(part("block")?),
            RecordedScenario::NavigateHolding => navigate_holding(part("handle")?),
            RecordedScenario::DemoPegIntoBlock => demo_peg_into_block(part("peg")?, part("block")?),
            RecordedScenario::PushAlongRail => FlatPush {
                raise: RAIL_PUSH_RAISE,
                depth: RAIL_PUSH_DEPTH,
            }
            .keyframes(part("slider")?),
            RecordedScenario::PushIntoWall => FlatPush {
                raise: 0.0,
                depth: WALL_PUSH_DEPTH,
            }
            .keyframes(part("block")?),
            RecordedScenario::PushOffTable => FlatPush {
                raise: 0.0,
                depth: TABLE_PUSH_DEPTH,
            }
            .keyframes_then_fall(part("block")?),
            RecordedScenario::ReleaseOverTable
            | RecordedScenario::ReleaseOverSlope
            | RecordedScenario::ReleaseOverNothing => release_in_mid_air(part("peg")?),
        })
    }
}

/// How far the scripted power grasp's hand presses into its handle (metres, along the palm's
/// normal): the clasp stops the hand at the handle's surface, so the grasp takes the handle there.
const POWER_GRASP_PRESS: f64 = 0.005;

/// The scripted power grasp up to the closed fist, placed so that its handle lies where `part`
/// (a cylinder along its z axis) is; then the hand eases its press, so that the held part, which
/// follows the tracked hand from the grasp on, stays where it was grasped.
fn power_grasp_on(part: &Part) -> Vec<Keyframe> {
    power_grasp_at(&part.pose, HANDLE_RADIUS)
}

/// The scripted power grasp up to the closed fist on a cylinder of `radius` whose axis and middle
/// are at `handle` (its z axis), the cart at the world's origin; then the hand eases its press,
/// so that the held part, which follows the tracked hand from the grasp on, stays where it was
/// grasped. The hand comes as much closer to the axis as the cylinder is thinner than the
/// script's handle, so that the palm meets its surface as it meets the handle's.
pub fn power_grasp_at(handle: &Isometry3<f64>, radius: f64) -> Vec<Keyframe> {
    let mut keys = power_grasp_closing(handle, radius, 0.0);
    then(&mut keys, 0.1, |k| {
        k.tracker *= Translation3::new(0.0, 0.0, POWER_GRASP_PRESS);
    });
    keys
}

/// The scripted power grasp's approach and closing fist on a cylinder of `radius` whose axis
/// and middle are at `handle`, with the hand held `back` metres farther from the axis than the
/// script has it (along the palm's normal; the script presses [`POWER_GRASP_PRESS`] into it).
fn power_grasp_closing(handle: &Isometry3<f64>, radius: f64, back: f64) -> Vec<Keyframe> {
    let script = ScriptedGrasp::PowerOnHandle;
    let thinner = Translation3::new(0.0, 0.0, HANDLE_RADIUS - radius);
    let placement = handle * (thinner * script.part_pose()).inverse();
    script
        .keyframes()
        .into_iter()
        .filter(|k| k.time <= script.milestones().grasped_by)
        .map(|k| Keyframe {
            tracker: placement * k.tracker * Translation3::new(0.0, 0.0, back),
            ..k
        })
        .collect()
}

/// Appends a keyframe `duration` seconds after the last one, changed by `change`.
fn then(keys: &mut Vec<Keyframe>, duration: f64, change: impl FnOnce(&mut Keyframe)) {
    let mut key = *keys.last().expect("a trajectory starts with a keyframe");
    key.time += duration;
    change(&mut key);
    keys.push(key);
}

/// Moves the hand by `offset` in the world (the cart stays at the origin).
fn shift(offset: Vector3<f64>) -> impl FnOnce(&mut Keyframe) {
    move |k| k.tracker = Translation3::from(offset) * k.tracker
}

/// Opens the hand over 0.2 s and holds still for 0.1 s.
fn open_and_rest(keys: &mut Vec<Keyframe>) {
    then(keys, 0.2, |k| k.flex = open_hand());
    then(keys, 0.1, |_| {});
}

/// The lowest and highest value of the part's vertices along `axis` in the world.
fn extent(part: &Part, axis: &Vector3<f64>) -> (f64, f64) {
    part.mesh
        .vertices()
        .iter()
        .map(|v| (part.pose * v).coords.dot(axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// How to carry `peg` over `block`'s hole: the lift (up, or down) that puts its lower end
/// [`PEG_CARRY_GAP`] above the block's top, then the level move over the block's middle.
fn carry_over(peg: &Part, block: &Part) -> (Vector3<f64>, Vector3<f64>) {
    let up = Vector3::z();
    let (peg_bottom, _) = extent(peg, &up);
    let (_, block_top) = extent(block, &up);
    let lift = (block_top + PEG_CARRY_GAP - peg_bottom) * up;
    let mut over = block.pose.translation.vector - peg.pose.translation.vector;
    over.z = 0.0;
    (lift, over)
}

fn peg_insert(peg: &Part, block: &Part) -> Vec<Keyframe> {
    let up = Vector3::z();
    let (lift, over) = carry_over(peg, block);
    let drift = PEG_DRIFT * Vector3::y();
    let mut keys = power_grasp_on(peg);
    then(&mut keys, 0.2, shift(lift));
    then(&mut keys, 0.5, shift(over));
    then(&mut keys, 0.05, |_| {});
    then(
        &mut keys,
        0.25,
        shift(-(PEG_CARRY_GAP + PEG_INSERT_DEPTH / 2.0) * up),
    );
    then(&mut keys, 0.25, shift(drift - PEG_INSERT_DEPTH / 2.0 * up));
    then(&mut keys, 0.1, shift(-drift));
    then(&mut keys, 0.05, |_| {});
    open_and_rest(&mut keys);
    keys
}

/// The demo scene pushes parts and settles released ones, and smooths the tracked hand: the
/// fingers close before the palm presses on the peg, so that the touch forming the grasp never
/// pushes it (only the hand's root pushes), and the hand draws back as it opens, so that it
/// lets go touching nothing and the peg drops through the hole onto the table. Each move is
/// followed by a pause in which the smoothed hand catches up with the script.
fn demo_peg_into_block(peg: &Part, block: &Part) -> Vec<Keyframe> {
    let up = Vector3::z();
    let (lift, over) = carry_over(peg, block);
    // The cylinder's axis taken downwards puts the thumb on top, clear of the table.
    let handle = Translation3::new(0.0, 0.0, DEMO_GRASP_RAISE)
        * peg.pose
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
    let (left, right) = extent(peg, &Vector3::x());
    let along_palm = |distance: f64| {
        move |k: &mut Keyframe| {
            k.tracker *= Translation3::new(0.0, 0.0, distance);
        }
    };
    // The thumb waits: thumb and fingers alone would make a precision grasp.
    let mut keys = power_grasp_closing(
        &handle,
        (right - left) / 2.0,
        POWER_GRASP_PRESS + DEMO_PALM_GAP,
    );
    for key in &mut keys {
        key.flex[THUMB].copy_from_slice(&open_hand()[THUMB]);
    }
    then(&mut keys, 0.2, |_| {});
    then(
        &mut keys,
        0.1,
        along_palm(-(DEMO_PALM_GAP + DEMO_PALM_PRESS)),
    );
    then(&mut keys, 0.3, |_| {});
    then(&mut keys, 0.2, |k| {
        k.flex = fist();
        along_palm(DEMO_PALM_PRESS)(k);
    });
    then(&mut keys, 0.3, shift(lift));
    then(&mut keys, 0.6, shift(over));
    then(&mut keys, 0.1, |_| {});
    then(
        &mut keys,
        0.4,
        shift(-(PEG_CARRY_GAP + DEMO_INSERT_DEPTH) * up),
    );
    then(&mut keys, 0.2, |_| {});
    then(&mut keys, 0.2, |k| {
        k.flex = open_hand();
        along_palm(DEMO_WITHDRAW)(k);
    });
    then(&mut keys, 0.5, |_| {});
    keys
}

fn pipe_through_sheet(pipe: &Part, sheet: &Part) -> Vec<Keyframe> {
    let mut axis = pipe.pose.rotation * Vector3::z();
    let to_sheet = sheet.pose.translation.vector - pipe.pose.translation.vector;
    if to_sheet.dot(&axis) < 0.0 {
        axis = -axis;
    }
    let (lo, hi) = extent(pipe, &axis);
    let half_length = (hi - lo) / 2.0;
    let travel = to_sheet.dot(&axis) - half_length + PIPE_PASS_BEYOND;
    let drift = -PIPE_DRIFT * Vector3::z();
    let mut keys = power_grasp_on(pipe);
    then(&mut keys, 0.05, |_| {});
    then(&mut keys, 0.3, shift(travel / 2.0 * axis));
    then(&mut keys, 0.3, shift(travel / 2.0 * axis + drift));
    then(&mut keys, 0.1, shift(-drift));
    then(&mut keys, 0.05, |_| {});
    open_and_rest(&mut keys);
    keys
}

fn precision_pinch(pin: &Part) -> Vec<Keyframe> {
    // The scripted screw lies along x in its own frame; a scene's cylinder along its z.
    let script = ScriptedGrasp::TipPinchOfScrew;
    let hand_to_pin =
        script.part_pose() * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2);
    let placement = pin.pose * hand_to_pin.inverse();
    script
        .keyframes()
        .into_iter()
        .map(|k| Keyframe {
            tracker: placement * k.tracker,
            ..k
        })
        .collect()
}

fn navigate_holding(handle: &Part) -> Vec<Keyframe> {
    let drive = Isometry3::from_parts(
        Translation3::from(Vector3::from(CART_DRIVE)),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), CART_TURN_DEGREES.to_radians()),
    );
    let mut keys = power_grasp_on(handle);
    then(&mut keys, 0.05, |_| {});
    then(&mut keys, 1.0, |k| k.cart = drive);
    then(&mut keys, 0.1, |_| {});
    open_and_rest(&mut keys);
    keys
}
