//! Scripted hand motions: keyframed tracker and glove trajectories sampled at a fixed rate, the
//! scripted grasps that the tests check and benchmark B6 times (their parts, poses and
//! trajectories), and the recorded scenarios of the replay fixtures, placed in their scenes.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

use vas_server::geometry::TriMesh;
use vas_server::geometry::shapes;
use vas_server::grasping::analysis::{GraspClass, PrecisionKind};
use vas_server::grasping::hand::HandInput;
use vas_server::grasping::model::{FLEX_COUNT, FlexVector};

pub mod hand_over;
mod recorded;
pub mod shove;

pub use recorded::{MissingPart, RecordedScenario, power_grasp_at};

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
    pub fn expected(self) -> GraspClass {
        match self {
            ScriptedGrasp::PowerOnHandle => GraspClass::Power,
            ScriptedGrasp::TipPinchOfScrew => GraspClass::Precision(PrecisionKind::TipPinch),
            ScriptedGrasp::GravityUnderBlock => GraspClass::Gravity,
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
mod tests;
