//! The expected outcome of every recorded scenario, in one place: the fixture tests check the
//! offline replay against it, and end-to-end tests can check the live server's output against it.
//!
//! The figures follow from the scenes (`configs/`) and the scripts
//! (`crate::script::RecordedScenario`); `tests/fixtures/README.md` lists the same
//! table.

use std::fmt;
use std::path::PathBuf;

use crate::script::RecordedScenario;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use vas_protocol::{EventKind, GraspType};

use crate::captured::CapturedMotion;

/// A grasp, release or hand-over the replay must produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExpectedEvent {
    /// The hand, by its place in the scene's hands.
    pub hand: usize,
    /// Grasp, release, hand-over, push begin or push end.
    pub kind: EventKind,
    /// The part's name in the scene.
    pub part: &'static str,
    /// The grasp type of a grasp; [`GraspType::None`] for a release.
    pub grasp: GraspType,
}

/// Where a part must be at the end of the replay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpectedPose {
    /// The part's name in the scene.
    pub part: &'static str,
    /// Its position in the world, metres.
    pub position: [f64; 3],
    /// Its orientation: roll, pitch, yaw in degrees (about x, then y, then z, fixed axes).
    pub rpy_degrees: [f64; 3],
    /// How far its position may be from `position` (metres).
    pub position_tolerance: f64,
    /// How far its orientation may be from `rpy_degrees` (radians).
    pub angle_tolerance: f64,
}

impl ExpectedPose {
    /// The expected pose as an isometry.
    pub fn pose(&self) -> Isometry3<f64> {
        let [roll, pitch, yaw] = self.rpy_degrees.map(f64::to_radians);
        Isometry3::from_parts(
            Translation3::from(self.position),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }

    /// How far `pose` is from the expected pose: (position error in metres, angle in radians).
    pub fn errors(&self, pose: &Isometry3<f64>) -> (f64, f64) {
        let expected = self.pose();
        (
            (pose.translation.vector - expected.translation.vector).norm(),
            pose.rotation.angle_to(&expected.rotation),
        )
    }

    /// Whether `pose` is within both tolerances.
    pub fn holds(&self, pose: &Isometry3<f64>) -> bool {
        let (position, angle) = self.errors(pose);
        position <= self.position_tolerance && angle <= self.angle_tolerance
    }
}

/// Where a recorded scenario's samples come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// A scripted tracker and glove trajectory.
    Script(RecordedScenario),
    /// The captured hands, as hand-joints samples.
    Captured(CapturedMotion),
    /// The two-handed hand-over: the right hand by tracker and glove, the left by hand joints.
    HandOver,
    /// The same hand-over between two users: the first user's right hand by tracker and
    /// glove, the second user's left hand by hand joints.
    UsersHandOver,
}

impl Motion {
    /// The name, also the fixture's file stem.
    pub fn name(self) -> &'static str {
        match self {
            Motion::Script(script) => script.name(),
            Motion::Captured(captured) => captured.name(),
            Motion::HandOver => "two_hand_handover",
            Motion::UsersHandOver => "two_user_handover",
        }
    }
}

impl fmt::Display for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A recorded scenario: its motion, scene, fixture and expected outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scenario {
    /// The motion; its name is the fixture's file stem.
    pub motion: Motion,
    /// The scene file, in `configs/`.
    pub scene: &'static str,
    /// The grasp, release and push events, in order; no others may happen.
    pub events: &'static [ExpectedEvent],
    /// Where the scenario's part ends.
    pub final_pose: ExpectedPose,
    /// At some frame the held part must have been held back at least this far (metres) from
    /// where the hand held it: an obstacle stopped it and it slid. Zero: no such requirement.
    pub min_held_back: f64,
}

impl Scenario {
    /// The fixture's file name, in `tests/fixtures/`.
    pub fn fixture_file(&self) -> String {
        format!("{}.jsonl", self.motion.name())
    }

    /// The fixture's path in this repository.
    pub fn fixture_path(&self) -> PathBuf {
        crate::fixtures_dir().join(self.fixture_file())
    }

    /// The scene's path in this repository.
    pub fn scene_path(&self) -> PathBuf {
        crate::configs_dir().join(self.scene)
    }
}

const fn grasp(part: &'static str, grasp: GraspType) -> ExpectedEvent {
    by(0, EventKind::Grasp, part, grasp)
}

const fn release(part: &'static str) -> ExpectedEvent {
    by(0, EventKind::Release, part, GraspType::None)
}

const fn push_begin(part: &'static str) -> ExpectedEvent {
    by(0, EventKind::PushBegin, part, GraspType::None)
}

const fn push_end(part: &'static str) -> ExpectedEvent {
    by(0, EventKind::PushEnd, part, GraspType::None)
}

const fn by(hand: usize, kind: EventKind, part: &'static str, grasp: GraspType) -> ExpectedEvent {
    ExpectedEvent {
        hand,
        kind,
        part,
        grasp,
    }
}

/// Every recorded scenario and what its replay must give.
pub const EXPECTED: [Scenario; 17] = [
    Scenario {
        motion: Motion::Script(RecordedScenario::PegInsert),
        scene: "peg_insert.toml",
        events: &[grasp("peg", GraspType::Power), release("peg")],
        // On the hole's axis, its lower end 3.5 cm below the block's top (z = 0.05), upright.
        final_pose: ExpectedPose {
            part: "peg",
            position: [0.0, 0.0, 0.135],
            rpy_degrees: [180.0, 0.0, 0.0],
            position_tolerance: 0.002,
            angle_tolerance: 0.05,
        },
        // Held back by the hole's wall (1 mm clearance) from the 2 mm stray.
        min_held_back: 0.0005,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::PipeThroughSheet),
        scene: "pipe_through_open_sheet.toml",
        events: &[grasp("pipe", GraspType::Power), release("pipe")],
        // 11 cm along x: its leading end 6 cm past the sheet (x = 0), its middle 9 cm before it.
        final_pose: ExpectedPose {
            part: "pipe",
            position: [-0.09, 0.0, 0.3],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 0.003,
            angle_tolerance: 0.05,
        },
        // Held back by the sheet's rim (2.5 mm clearance) from the 4 mm sink.
        min_held_back: 0.001,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::PrecisionPinch),
        scene: "precision_pinch.toml",
        events: &[grasp("pin", GraspType::TipPinch), release("pin")],
        // Lifted 5 cm and drawn 2 cm towards the fingers (+y).
        final_pose: ExpectedPose {
            part: "pin",
            position: [0.0, 0.02, 0.15],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 0.002,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::Push),
        scene: "push.toml",
        events: &[push_begin("block"), push_end("block")],
        // Never grasped; pushed the 2 cm the palm aims past the face it meets, along x across
        // the table, and left there, resting on the table (its top at z = 0.1398).
        final_pose: ExpectedPose {
            part: "block",
            position: [0.12, 0.0, 0.1998],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 1e-9,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::NavigateHolding),
        scene: "navigate_holding.toml",
        events: &[grasp("handle", GraspType::Power), release("handle")],
        // Carried by the cart: turned 40 degrees about the world's z axis and driven by
        // (0.3, 0.2, 0), from (0.1, 0, 0.2) to (0.3 + 0.1 cos 40°, 0.2 + 0.1 sin 40°, 0.2).
        final_pose: ExpectedPose {
            part: "handle",
            position: [0.376_604_444, 0.264_278_761, 0.2],
            rpy_degrees: [0.0, 90.0, 40.0],
            position_tolerance: 0.003,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::DemoPegIntoBlock),
        scene: "default.toml",
        // The fingers touching the peg before the palm does move nothing: no push, only the
        // power grasp the palm's touch makes.
        events: &[grasp("peg", GraspType::Power), release("peg")],
        // Let go 1 cm into the block's hole at (0.25, 0.15), it drops through the hole onto the
        // table (z = 0.75): its middle 4 cm above it, upright.
        final_pose: ExpectedPose {
            part: "peg",
            position: [0.25, 0.15, 0.79],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.002,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Captured(CapturedMotion::PinchPin),
        scene: "precision_pinch.toml",
        events: &[grasp("pin", GraspType::TipPinch)],
        // Lifted 3 cm and held.
        final_pose: ExpectedPose {
            part: "pin",
            position: [0.0, 0.0, 0.13],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 0.003,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Captured(CapturedMotion::RelaxedApproach),
        scene: "precision_pinch.toml",
        events: &[],
        // Never grasped, so never moved.
        final_pose: ExpectedPose {
            part: "pin",
            position: [0.0, 0.0, 0.1],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 1e-12,
            angle_tolerance: 1e-12,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Captured(CapturedMotion::TrackingLoss),
        scene: "precision_pinch.toml",
        // Held through the short loss; let go half a second into the long one.
        events: &[grasp("pin", GraspType::TipPinch), release("pin")],
        // Released where it was held, 3 cm up.
        final_pose: ExpectedPose {
            part: "pin",
            position: [0.0, 0.0, 0.13],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 0.003,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::HandOver,
        scene: "two_hand_handover.toml",
        events: HAND_OVER_EVENTS,
        final_pose: HAND_OVER_FINAL_POSE,
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::PushAlongRail),
        scene: "push_along_rail.toml",
        events: &[push_begin("slider"), push_end("slider")],
        // Pushed along the slot until its far face meets the end stop (x = 0.05), there held.
        final_pose: ExpectedPose {
            part: "slider",
            position: [0.03, 0.0, 0.1],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 1e-9,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::PushIntoWall),
        scene: "push_into_wall.toml",
        events: &[push_begin("block"), push_end("block")],
        // Pushed 1 cm across the table, until its far face meets the wall (x = 0.14), not the
        // 3 cm aimed at; resting on the table (its top at z = 0.1398).
        final_pose: ExpectedPose {
            part: "block",
            position: [0.11, 0.0, 0.1998],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 1e-9,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::ReleaseOverTable),
        scene: "release_over_table.toml",
        events: &[grasp("peg", GraspType::Power), release("peg")],
        // Standing on the table's top (z = 0), upright, below where it was held.
        final_pose: ExpectedPose {
            part: "peg",
            position: [0.0, 0.0, 0.04],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::ReleaseOverSlope),
        scene: "release_over_slope.toml",
        events: &[grasp("peg", GraspType::Power), release("peg")],
        // Landed on the plane tilted 10 degrees about x (its top face 1 cm from the origin) by
        // the +y edge of its lower end, at y = 0.009, z = (0.01 + 0.009 sin 10°) / cos 10°, and
        // turned 10 degrees about that edge onto its end face, not slid: its middle 9 mm across
        // and 4 cm up its end, turned, from that edge.
        final_pose: ExpectedPose {
            part: "peg",
            position: [0.0, -0.006_809, 0.049_570],
            rpy_degrees: [10.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::ReleaseOverNothing),
        scene: "release_over_nothing.toml",
        events: &[grasp("peg", GraspType::Power), release("peg")],
        // Its lowest point on the scene's floor (z = 0.05).
        final_pose: ExpectedPose {
            part: "peg",
            position: [0.0, 0.0, 0.09],
            rpy_degrees: [0.0, 0.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::Script(RecordedScenario::PushOffTable),
        scene: "push_off_table.toml",
        events: &[push_begin("block"), push_end("block")],
        // Pushed until its middle is 2.5 cm past the table's edge, it tips over the edge once the
        // push ends, falls, and lies on its front face on the ground (z = 0), a quarter turn about
        // y: its middle 3 cm up, 6 cm past the edge.
        final_pose: ExpectedPose {
            part: "block",
            position: [0.160_5, 0.0, 0.03],
            rpy_degrees: [0.0, 90.0, 0.0],
            position_tolerance: 0.001,
            angle_tolerance: 0.05,
        },
        min_held_back: 0.0,
    },
    Scenario {
        motion: Motion::UsersHandOver,
        scene: "two_user_handover.toml",
        // Hand 0 is anna's right hand, hand 1 ben's left: the events of the two-hand hand-over,
        // between users.
        events: HAND_OVER_EVENTS,
        final_pose: HAND_OVER_FINAL_POSE,
        min_held_back: 0.0,
    },
];

/// The hand-over's events: the first hand grasps the handle, the second takes it over and lets
/// go of it in the block.
const HAND_OVER_EVENTS: &[ExpectedEvent] = &[
    by(0, EventKind::Grasp, "handle", GraspType::Power),
    // The second hand's fingers and thumb hold the handle before its palm comes down.
    by(1, EventKind::Grasp, "handle", GraspType::Precision),
    by(0, EventKind::HandOver, "handle", GraspType::None),
    by(1, EventKind::Release, "handle", GraspType::None),
];

/// Where the hand-over leaves the handle: pushed 9 cm along its axis by the second hand, its end
/// 3 cm into the block's hole, sunk the 3 to 5 mm the hands' scripts press down after their
/// grasps (they aim 5 mm into the handle).
const HAND_OVER_FINAL_POSE: ExpectedPose = ExpectedPose {
    part: "handle",
    position: [-0.09, 0.075, -0.0625],
    rpy_degrees: [0.0, 90.0, 0.0],
    position_tolerance: 0.003,
    angle_tolerance: 0.05,
};
