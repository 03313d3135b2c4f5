//! Scripted hand motions: keyframed tracker and glove trajectories sampled at a fixed rate, the
//! scripted grasps that the tests check and benchmark B6 times (their parts, poses and
//! trajectories), and the recorded scenarios of the replay fixtures, placed in their scenes.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

use super::{Part, Scene};
use crate::geometry::TriMesh;
use crate::geometry::shapes;
use crate::grasping::analysis::{GraspType, PrecisionKind};
use crate::grasping::hand::HandInput;
use crate::grasping::model::{FLEX_COUNT, FlexVector};

/// A keyframe: where the cart and the tracked hand are, and what the glove says, at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyframe {
    /// Seconds from the start.
    pub time: f64,
    /// The cart in the world.
    pub cart: Isometry3<f64>,
    /// The hand root in the cart's frame.
    pub tracker: Isometry3<f64>,
    /// Joint angles, radians.
    pub flex: FlexVector,
}

impl Keyframe {
    /// A keyframe with the cart at the world's origin.
    pub fn new(time: f64, tracker: Isometry3<f64>, flex: FlexVector) -> Keyframe {
        Keyframe {
            time,
            cart: Isometry3::identity(),
            tracker,
            flex,
        }
    }

    /// The same keyframe for the other hand: the cart and the hand root mirrored in the world's
    /// `x = 0` plane (positions get `x` negated, rotations `R` become `S R S` for
    /// `S = diag(-1, 1, 1)`), the flex values as they are (a mirrored hand model reads them so).
    pub fn mirrored(&self) -> Keyframe {
        let mirror = |pose: &Isometry3<f64>| {
            let t = pose.translation.vector;
            let q = pose.rotation.quaternion();
            Isometry3::from_parts(
                Translation3::new(-t.x, t.y, t.z),
                UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q.w, q.i, -q.j, -q.k)),
            )
        };
        Keyframe {
            cart: mirror(&self.cart),
            tracker: mirror(&self.tracker),
            ..*self
        }
    }

    /// The input sample it stands for (flex values as the glove sends them, in `f32`).
    pub fn input(&self) -> HandInput {
        HandInput {
            cart: self.cart,
            tracker: self.tracker,
            flex: self.flex.map(|v| v as f32),
        }
    }
}

/// The keyframes sampled at `rate_hz`, interpolating linearly between them (rotations by slerp).
pub fn sample(keys: &[Keyframe], rate_hz: f64) -> Vec<Keyframe> {
    let mut out = Vec::new();
    for pair in keys.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let n = ((b.time - a.time) * rate_hz).round() as usize;
        for i in 0..n {
            let t = i as f64 / n as f64;
            out.push(Keyframe {
                time: a.time + t * (b.time - a.time),
                cart: a.cart.lerp_slerp(&b.cart, t),
                tracker: a.tracker.lerp_slerp(&b.tracker, t),
                flex: std::array::from_fn(|v| a.flex[v] + t * (b.flex[v] - a.flex[v])),
            });
        }
    }
    out.extend(keys.last());
    out
}

/// The keyframes at `time`, interpolated as [`sample`] does (before the first key, the first;
/// after the last, the last); `None` without keys.
pub fn keyframe_at(keys: &[Keyframe], time: f64) -> Option<Keyframe> {
    let next = keys.partition_point(|key| key.time <= time);
    match (
        next.checked_sub(1).map(|i| keys[i]),
        keys.get(next).copied(),
    ) {
        (Some(a), Some(b)) => {
            let t = (time - a.time) / (b.time - a.time);
            Some(Keyframe {
                time,
                cart: a.cart.lerp_slerp(&b.cart, t),
                tracker: a.tracker.lerp_slerp(&b.tracker, t),
                flex: std::array::from_fn(|v| a.flex[v] + t * (b.flex[v] - a.flex[v])),
            })
        }
        (Some(key), None) | (None, Some(key)) => Some(Keyframe { time, ..key }),
        (None, None) => None,
    }
}

/// A hand posture: flex values in degrees by CyberGlove index, the others zero.
pub fn posture(values: &[(usize, f64)]) -> FlexVector {
    let mut flex = [0.0; FLEX_COUNT];
    for &(i, degrees) in values {
        flex[i] = degrees.to_radians();
    }
    flex
}

/// The open hand: fingers straight, the thumb spread in the plane of the palm.
pub fn open_hand() -> FlexVector {
    posture(&[(0, -30.0), (3, 45.0)])
}

/// A fist, the thumb across: what the glove says when the hand closes on a handle.
pub fn fist() -> FlexVector {
    posture(&[
        (0, 60.0),
        (1, 40.0),
        (2, 40.0),
        (3, 10.0),
        (4, 85.0),
        (5, 90.0),
        (6, 70.0),
        (7, 85.0),
        (8, 90.0),
        (9, 70.0),
        (11, 85.0),
        (12, 90.0),
        (13, 70.0),
        (15, 85.0),
        (16, 90.0),
        (17, 70.0),
    ])
}

fn pose(translation: [f64; 3], rotation: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(Vector3::from(translation)), rotation)
}

fn at(translation: [f64; 3]) -> Isometry3<f64> {
    pose(translation, UnitQuaternion::identity())
}

/// The radius of the scripted power grasp's handle (metres).
pub const HANDLE_RADIUS: f64 = 0.016;

/// When a scripted grasp must have happened, in seconds from its start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Milestones {
    /// The part is grasped by now.
    pub grasped_by: f64,
    /// The part has been carried to its farthest place and is still held.
    pub carried: f64,
    /// The hand lets go only after this.
    pub release_after: f64,
}

/// The scripted grasps of the tests and of benchmark B6, for the right hand; named after their
/// parts on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScriptedGrasp {
    /// The hand comes down on a handle (a cylinder of radius 1.6 cm, 12 cm long, across the
    /// palm), closes a fist around it, carries it away turning, and opens.
    PowerOnHandle,
    /// Thumb and index tips close on a small screw, lift it and open.
    TipPinchOfScrew,
    /// The open hand, palm up, comes up under a block, carries it and tips it off.
    GravityUnderBlock,
}

impl fmt::Display for ScriptedGrasp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.part_name())
    }
}

impl ScriptedGrasp {
    /// Every scripted grasp.
    pub const ALL: [ScriptedGrasp; 3] = [
        ScriptedGrasp::PowerOnHandle,
        ScriptedGrasp::TipPinchOfScrew,
        ScriptedGrasp::GravityUnderBlock,
    ];

    /// The part's name.
    pub fn part_name(self) -> &'static str {
        match self {
            ScriptedGrasp::PowerOnHandle => "handle",
            ScriptedGrasp::TipPinchOfScrew => "screw",
            ScriptedGrasp::GravityUnderBlock => "block",
        }
    }

    /// The grasp the analysis must recognise.
    pub fn expected(self) -> GraspType {
        match self {
            ScriptedGrasp::PowerOnHandle => GraspType::Power,
            ScriptedGrasp::TipPinchOfScrew => GraspType::Precision(PrecisionKind::TipPinch),
            ScriptedGrasp::GravityUnderBlock => GraspType::Gravity,
        }
    }

    /// The part's mesh with about `triangles` triangles, in its own frame.
    pub fn part_mesh(self, triangles: usize) -> TriMesh {
        match self {
            ScriptedGrasp::PowerOnHandle => shapes::cylinder(HANDLE_RADIUS, 0.12, triangles),
            ScriptedGrasp::TipPinchOfScrew => screw(triangles),
            ScriptedGrasp::GravityUnderBlock => {
                shapes::cuboid(Vector3::new(0.04, 0.05, 0.03), triangles)
            }
        }
    }

    /// The part's pose in the world at the start.
    pub fn part_pose(self) -> Isometry3<f64> {
        match self {
            // Across the palm, 3 cm below the palm's inside face.
            ScriptedGrasp::PowerOnHandle => pose(
                [-0.005, 0.075, -0.0585],
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2),
            ),
            // Where the thumb and index tips meet in a pinch.
            ScriptedGrasp::TipPinchOfScrew => at([-0.0295, 0.121, -0.0717]),
            // Over the palm (of the hand turned palm up), 2 cm above it.
            ScriptedGrasp::GravityUnderBlock => at([-0.005, 0.055, 0.0125 + 0.02 + 0.015]),
        }
    }

    /// The trajectory, to be sampled with [`sample`].
    pub fn keyframes(self) -> Vec<Keyframe> {
        let k = Keyframe::new;
        match self {
            ScriptedGrasp::PowerOnHandle => {
                let tilted = pose(
                    [0.05, 0.1, 0.04],
                    UnitQuaternion::from_euler_angles(0.4, 0.2, 0.3),
                );
                vec![
                    k(0.0, at([0.0, 0.0, 0.02]), open_hand()),
                    // Down onto the handle, pressing 5 mm into it.
                    k(0.2, at([0.0, 0.0, -0.035]), open_hand()),
                    // The fist closes around it.
                    k(0.5, at([0.0, 0.0, -0.035]), fist()),
                    k(0.55, at([0.0, 0.0, -0.035]), fist()),
                    // Carried away, turning.
                    k(0.85, tilted, fist()),
                    k(0.9, tilted, fist()),
                    // The hand opens.
                    k(1.1, tilted, open_hand()),
                    k(1.2, tilted, open_hand()),
                ]
            }
            ScriptedGrasp::TipPinchOfScrew => {
                let preshape = posture(&[(0, 30.0), (3, 40.0), (4, 20.0), (5, 15.0), (6, 5.0)]);
                let pinch = posture(&[
                    (0, 70.0),
                    (3, 25.0),
                    (1, 30.0),
                    (2, 15.0),
                    (4, 60.0),
                    (5, 45.0),
                    (6, 20.0),
                ]);
                let lifted = at([0.0, 0.02, 0.05]);
                vec![
                    k(0.0, Isometry3::identity(), preshape),
                    k(0.3, Isometry3::identity(), pinch),
                    k(0.35, Isometry3::identity(), pinch),
                    k(0.6, lifted, pinch),
                    k(0.65, lifted, pinch),
                    k(0.85, lifted, preshape),
                    k(0.9, lifted, preshape),
                ]
            }
            ScriptedGrasp::GravityUnderBlock => {
                let palm_up = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
                let tipped = palm_up
                    * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 80f64.to_radians());
                vec![
                    k(0.0, pose([0.0, 0.0, 0.0], palm_up), open_hand()),
                    // Up under the block, pressing 5 mm into it.
                    k(0.2, pose([0.0, 0.0, 0.025], palm_up), open_hand()),
                    k(0.25, pose([0.0, 0.0, 0.025], palm_up), open_hand()),
                    // Carried sideways and up.
                    k(0.5, pose([0.1, 0.05, 0.08], palm_up), open_hand()),
                    k(0.55, pose([0.1, 0.05, 0.08], palm_up), open_hand()),
                    // Tipped over: the block would slide off.
                    k(0.75, pose([0.1, 0.05, 0.08], tipped), open_hand()),
                    k(0.8, pose([0.1, 0.05, 0.08], tipped), open_hand()),
                ]
            }
        }
    }

    /// When the grasp, the carrying and the release happen.
    pub fn milestones(self) -> Milestones {
        match self {
            ScriptedGrasp::PowerOnHandle => Milestones {
                grasped_by: 0.55,
                carried: 0.9,
                release_after: 0.9,
            },
            ScriptedGrasp::TipPinchOfScrew => Milestones {
                grasped_by: 0.35,
                carried: 0.65,
                release_after: 0.65,
            },
            ScriptedGrasp::GravityUnderBlock => Milestones {
                grasped_by: 0.25,
                carried: 0.55,
                release_after: 0.55,
            },
        }
    }
}

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
    /// The flat hand, fingers straight, pushes against the side of a block and withdraws;
    /// nothing is grasped.
    Push,
    /// A power grasp on a handle, then the cart drives and turns while the hand stays still in
    /// the cart's frame; then the hand opens.
    NavigateHolding,
    /// In the demo scene: a power grasp on the peg standing on the table, carried over the
    /// block, lowered into its hole and released there.
    DemoPegIntoBlock,
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
/// The palm's inside face, this far from the hand root along -z (metres).
const PALM_FACE: f64 = 0.0125;
/// The palm's middle, this far from the hand root along +y (metres).
const PALM_MIDDLE: f64 = 0.055;
/// The pushing palm starts this far from the block (metres).
const PUSH_GAP: f64 = 0.02;
/// The push aims this far into the block (metres): the hand must stop at its face.
const PUSH_DEPTH: f64 = 0.02;
/// How far the cart drives while the hand holds the handle (metres, in the world).
const CART_DRIVE: [f64; 3] = [0.3, 0.2, 0.0];
/// How far the cart turns about its vertical axis meanwhile (degrees).
const CART_TURN_DEGREES: f64 = 40.0;

impl RecordedScenario {
    /// Every recorded scenario, in the order of the fixtures' documentation.
    pub const ALL: [RecordedScenario; 6] = [
        RecordedScenario::PegInsert,
        RecordedScenario::PipeThroughSheet,
        RecordedScenario::PrecisionPinch,
        RecordedScenario::Push,
        RecordedScenario::NavigateHolding,
        RecordedScenario::DemoPegIntoBlock,
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
                "the flat hand pushes against the block's side, aiming 2 cm into it, and \
                 withdraws; nothing is grasped"
            }
            RecordedScenario::NavigateHolding => {
                "power grasp on the handle, then the cart drives 36 cm and turns 40 degrees with \
                 the hand still in the cart's frame, then the hand opens"
            }
            RecordedScenario::DemoPegIntoBlock => {
                "in the demo scene: power grasp on the peg, carried over the block, lowered 1 cm \
                 into its hole (1 mm of clearance), released there"
            }
        }
    }

    /// The trajectory in `scene`, to be sampled with [`sample`]; the cart starts at the world's
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
            RecordedScenario::Push => push(part("block")?),
            RecordedScenario::NavigateHolding => navigate_holding(part("handle")?),
            RecordedScenario::DemoPegIntoBlock => demo_peg_into_block(part("peg")?, part("block")?),
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
    let script = ScriptedGrasp::PowerOnHandle;
    let thinner = Translation3::new(0.0, 0.0, HANDLE_RADIUS - radius);
    let placement = handle * (thinner * script.part_pose()).inverse();
    let mut keys: Vec<Keyframe> = script
        .keyframes()
        .into_iter()
        .filter(|k| k.time <= script.milestones().grasped_by)
        .map(|k| Keyframe {
            tracker: placement * k.tracker,
            ..k
        })
        .collect();
    then(&mut keys, 0.1, |k| {
        k.tracker *= Translation3::new(0.0, 0.0, POWER_GRASP_PRESS);
    });
    keys
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

fn demo_peg_into_block(peg: &Part, block: &Part) -> Vec<Keyframe> {
    let up = Vector3::z();
    let (lift, over) = carry_over(peg, block);
    // The cylinder's axis taken downwards puts the thumb on top, clear of the table.
    let handle = Translation3::new(0.0, 0.0, DEMO_GRASP_RAISE)
        * peg.pose
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
    let (left, right) = extent(peg, &Vector3::x());
    let mut keys = power_grasp_at(&handle, (right - left) / 2.0);
    then(&mut keys, 0.3, shift(lift));
    then(&mut keys, 0.6, shift(over));
    then(&mut keys, 0.1, |_| {});
    then(
        &mut keys,
        0.4,
        shift(-(PEG_CARRY_GAP + DEMO_INSERT_DEPTH) * up),
    );
    then(&mut keys, 0.05, |_| {});
    open_and_rest(&mut keys);
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

fn push(block: &Part) -> Vec<Keyframe> {
    // Palm (the hand's -z) towards +x, fingers along +y, thumb down.
    let palm_towards_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -FRAC_PI_2);
    let (block_near, _) = extent(block, &Vector3::x());
    let centre = block.pose.translation.vector;
    let start = pose(
        [
            block_near - PUSH_GAP - PALM_FACE,
            centre.y - PALM_MIDDLE,
            centre.z,
        ],
        palm_towards_x,
    );
    let mut keys = vec![Keyframe::new(0.0, start, open_hand())];
    then(&mut keys, 0.1, |_| {});
    then(
        &mut keys,
        0.4,
        shift((PUSH_GAP + PUSH_DEPTH) * Vector3::x()),
    );
    then(&mut keys, 0.1, |_| {});
    then(&mut keys, 0.3, |k| k.tracker = start);
    then(&mut keys, 0.05, |_| {});
    keys
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

/// A screw along x: a shaft of radius 3 mm and length 16 mm with a head of radius 5 mm, 3 mm
/// long, at its +x end; about `triangles` triangles, 4 in 7 on the shaft.
fn screw(triangles: usize) -> TriMesh {
    let along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2);
    let shaft = shapes::cylinder(0.003, 0.016, (triangles * 4 / 7).max(100));
    let head = shapes::cylinder(0.005, 0.003, (triangles * 3 / 7).max(100));
    let offset = shaft.vertices().len() as u32;
    let vertices = shaft
        .vertices()
        .iter()
        .map(|p| along_x * p)
        .chain(
            head.vertices()
                .iter()
                .map(|p| along_x * p + Vector3::new(0.0095, 0.0, 0.0)),
        )
        .collect();
    let triangles = shaft
        .triangles()
        .iter()
        .copied()
        .chain(head.triangles().iter().map(|t| t.map(|i| i + offset)))
        .collect();
    TriMesh::new(vertices, triangles)
        .expect("two valid cylinders make a valid mesh")
        .0
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
