//! Recordings made of the real captured hands (`tests/fixtures/hands/`): hand-joints samples of
//! the relaxed hand moving in on a pin, then closing into the captured pinch around it, or
//! staying relaxed.
//!
//! The hand is placed from the pin's pose in the scene: the captured pinch, retargeted onto the
//! scene's hand model, has its thumb and index fingertips on either side of the pin's axis, the
//! pin's middle halfway between them, and the pin's axis across both the line between the
//! fingertips and the line from the middle finger's tip (so that the pin points away from the
//! other fingers). The relaxed hand, its wrist put on the pinch's, starts [`APPROACH_M`] back
//! along the line from the wrist to that point and moves in; the pinch then blends in joint by joint (positions linearly,
//! orientations by slerp), and the closed hand lifts the pin [`LIFT_M`]. Without the pinch the
//! relaxed hand goes on [`PRESS_M`] towards the pin as its index knuckle would, and runs into
//! it. With tracking losses, the samples of the lost stretches say so (no valid joint).
//!
//! Samples come at [`RATE_HZ`], numbered from 1 and stamped from zero, their values
//! [rounded](crate::hands::rounded()); two runs write identical files.

use std::fmt;

use anyhow::{Context, bail};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use vas_client::recording::InputSample;
use vas_protocol::{HAND_JOINT_COUNT, HandJointsSample, HandSide, JointLocation};
use vas_server::grasping::retarget::{HandJoints, Joint, Retargeter};
use vas_server::runtime::hand_joints::wire_joints;
use vas_server::scene::Scene;

use crate::hands::{PINCH, RELAXED, captured, rounded};

/// Hand-joints samples per second: a headset's hand tracking rate.
pub const RATE_HZ: f64 = 50.0;

/// Nanoseconds between samples.
const PERIOD_NS: u64 = 20_000_000;

/// How far back the relaxed hand starts (metres).
pub const APPROACH_M: f64 = 0.08;

/// How far past the pinching place the relaxed hand goes on (metres), in the direction that
/// takes its index knuckle to the pin, so that it runs into the pin (the pin sits about 7 cm from
/// the knuckle, between the open thumb and index finger).
pub const PRESS_M: f64 = 0.07;

/// How far the closed hand lifts the pin (metres, straight up).
pub const LIFT_M: f64 = 0.03;

/// The part the hand goes for.
pub const PIN: &str = "pin";

/// A motion made of the captured hands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CapturedMotion {
    /// The relaxed hand moves in on the pin, closes into the captured pinch around it and
    /// lifts it.
    PinchPin,
    /// The relaxed hand moves in on the pin as for the pinch, stays relaxed and goes on
    /// [`PRESS_M`] towards its index knuckle, running into the pin.
    RelaxedApproach,
    /// The pinch and lift of [`CapturedMotion::PinchPin`], then the hand's tracking lost for
    /// [`SHORT_LOSS_S`], back for a while, and lost for [`LONG_LOSS_S`].
    TrackingLoss,
}

/// The short loss of tracking while the pin is held (seconds): within the default grace.
pub const SHORT_LOSS_S: f64 = 0.2;

/// The long loss of tracking while the pin is held (seconds): beyond the default grace.
pub const LONG_LOSS_S: f64 = 2.0;

/// When the long loss of [`CapturedMotion::TrackingLoss`] begins (seconds from the start).
pub const LONG_LOSS_FROM_S: f64 = 2.6;

/// A moment of a motion: where the hand is and how far it has closed.
#[derive(Debug, Clone, Copy)]
struct Key {
    /// Seconds from the start.
    time: f64,
    /// How far back along the approach (metres).
    back: f64,
    /// How far on from the pinching place towards the pin, as the relaxed index knuckle goes
    /// (metres).
    press: f64,
    /// How far the pinch has blended in: 0 relaxed, 1 pinching.
    closed: f64,
    /// How far up (metres).
    up: f64,
    /// Whether the hand's tracking is lost until the next key (its samples say so).
    lost: bool,
}

impl CapturedMotion {
    /// Every captured motion.
    pub const ALL: [CapturedMotion; 3] = [
        CapturedMotion::PinchPin,
        CapturedMotion::RelaxedApproach,
        CapturedMotion::TrackingLoss,
    ];

    /// The name, also the fixture's file stem.
    pub fn name(self) -> &'static str {
        match self {
            CapturedMotion::PinchPin => "captured_pinch_pin",
            CapturedMotion::RelaxedApproach => "captured_relaxed_approach",
            CapturedMotion::TrackingLoss => "captured_tracking_loss",
        }
    }

    /// What the recording shows, for its header.
    pub fn description(self) -> &'static str {
        match self {
            CapturedMotion::PinchPin => {
                "the captured relaxed hand moves in on the pin, closes into the captured pinch \
                 around it and lifts it 3 cm"
            }
            CapturedMotion::RelaxedApproach => {
                "the captured relaxed hand moves in on the pin as for the pinch, stays relaxed \
                 and goes on 7 cm, its index knuckle towards the pin, running into it"
            }
            CapturedMotion::TrackingLoss => {
                "the captured pinch lifts the pin 3 cm; the hand's tracking is lost for 0.2 s, \
                 comes back for 0.4 s and is lost for 2 s"
            }
        }
    }

    fn keys(self) -> Vec<Key> {
        let key = |time, back, press, closed, up| Key {
            time,
            back,
            press,
            closed,
            up,
            lost: false,
        };
        let mut keys = vec![
            key(0.0, APPROACH_M, 0.0, 0.0, 0.0),
            key(0.6, 0.0, 0.0, 0.0, 0.0),
        ];
        let lifted = |time| key(time, 0.0, 0.0, 1.0, LIFT_M);
        let lost = |time| Key {
            lost: true,
            ..lifted(time)
        };
        match self {
            CapturedMotion::PinchPin => keys.extend([
                key(1.1, 0.0, 0.0, 1.0, 0.0),
                key(1.4, 0.0, 0.0, 1.0, 0.0),
                lifted(1.8),
                lifted(2.0),
            ]),
            CapturedMotion::RelaxedApproach => keys.extend([
                key(1.0, 0.0, PRESS_M, 0.0, 0.0),
                key(1.3, 0.0, PRESS_M, 0.0, 0.0),
            ]),
            CapturedMotion::TrackingLoss => keys.extend([
                key(1.1, 0.0, 0.0, 1.0, 0.0),
                key(1.4, 0.0, 0.0, 1.0, 0.0),
                lifted(1.8),
                lost(2.0),
                lifted(2.0 + SHORT_LOSS_S),
                lost(LONG_LOSS_FROM_S),
                lost(LONG_LOSS_FROM_S + LONG_LOSS_S),
            ]),
        }
        keys
    }

    /// The motion's hand-joints samples in `scene` (its hand and its part [`PIN`]).
    pub fn samples(self, scene: &Scene) -> anyhow::Result<Vec<InputSample>> {
        let hand = scene.hands.first().context("the scene has no hand")?;
        let side = hand.model.side();
        let retargeter = Retargeter::new(hand.model.as_ref().clone())?;
        let pin = scene
            .parts
            .iter()
            .find(|part| part.name == PIN)
            .with_context(|| format!("the scene has no part {PIN:?}"))?;
        let pinch = captured(PINCH, side)?;
        let relaxed = on_wrist(&captured(RELAXED, side)?, &pinch);
        let (placement, approach) = placement(&retargeter, &pinch, &pin.pose)?;
        let knuckle = placement * relaxed.get(Joint::IndexProximal).position;
        let press = (pin.pose.translation.vector - knuckle.coords).normalize();
        let mut samples = Vec::new();
        for (key, seq) in sampled(&self.keys()).into_iter().zip(1u64..) {
            let timestamp_ns = (seq - 1) * PERIOD_NS;
            if key.lost {
                samples.push(InputSample::HandJoints(untracked(side, seq, timestamp_ns)));
                continue;
            }
            let shift = Translation3::from(
                -approach * key.back + press * key.press + Vector3::z() * key.up,
            );
            let lifted = Isometry3::from_parts(shift, UnitQuaternion::identity()) * placement;
            let joints = rounded(&blend(&relaxed, &pinch, key.closed).transformed(&lifted));
            joints
                .validate()
                .with_context(|| format!("{self}: sample {seq} is no hand"))?;
            samples.push(InputSample::HandJoints(wire_joints(
                &joints,
                seq,
                timestamp_ns,
            )));
        }
        Ok(samples)
    }
}

impl fmt::Display for CapturedMotion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The keys sampled at [`RATE_HZ`], linearly between them.
fn sampled(keys: &[Key]) -> Vec<Key> {
    let mut out = Vec::new();
    for pair in keys.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let n = ((b.time - a.time) * RATE_HZ).round() as usize;
        let lerp = |x: f64, y: f64, t: f64| x + t * (y - x);
        out.extend((0..n).map(|i| {
            let t = i as f64 / n as f64;
            Key {
                time: lerp(a.time, b.time, t),
                back: lerp(a.back, b.back, t),
                press: lerp(a.press, b.press, t),
                lost: a.lost,
                closed: lerp(a.closed, b.closed, t),
                up: lerp(a.up, b.up, t),
            }
        }));
    }
    out.extend(keys.last());
    out
}

/// A sample of a hand whose tracking is lost: every joint's flags 0 (neither valid nor tracked),
/// its pose zero, as a WebXR producer sends a frame without hand poses.
fn untracked(side: HandSide, seq: u64, timestamp_ns: u64) -> HandJointsSample {
    let nowhere = JointLocation {
        position: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
        radius: 0.0,
        flags: 0,
    };
    HandJointsSample {
        seq,
        timestamp_ns,
        joints: [nowhere; HAND_JOINT_COUNT],
        side: match side {
            HandSide::Right => HandSide::Right as u32,
            HandSide::Left => HandSide::Left as u32,
        },
        user: 0,
    }
}

/// Where the captured hands go: the rigid motion from the captures' frame into the world that
/// puts the retargeted pinch around the pin (see the module documentation), and the unit
/// direction, in the world, from the wrist to the pin.
fn placement(
    retargeter: &Retargeter,
    pinch: &HandJoints,
    pin: &Isometry3<f64>,
) -> anyhow::Result<(Isometry3<f64>, Vector3<f64>)> {
    let fit = retargeter.fit(pinch)?;
    let model = retargeter.synthesize(&fit.root, &fit.flex);
    let tip = |joint: Joint| model.get(joint).position;
    let (thumb, index) = (tip(Joint::ThumbTip), tip(Joint::IndexTip));
    let centre = nalgebra::center(&thumb, &index);
    let across = (index - thumb).normalize();
    let axis = across.cross(&(tip(Joint::MiddleTip) - centre));
    if axis.norm() < 1e-6 {
        bail!("the middle fingertip lies on the line between thumb and index tips");
    }
    let axis = axis.normalize();
    // The pin's frame in the captures' frame: its axis is the cylinder's z.
    let frame = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[
        across,
        axis.cross(&across),
        axis,
    ]));
    let pinch_frame = Isometry3::from_parts(
        Translation3::from(centre.coords),
        UnitQuaternion::from_rotation_matrix(&frame),
    );
    let placement = pin * pinch_frame.inverse();
    let approach = placement * (centre - pinch.get(Joint::Wrist).position);
    Ok((placement, approach.normalize()))
}

/// `hand` moved rigidly so that its wrist joint is where `other`'s is, turned as it is.
fn on_wrist(hand: &HandJoints, other: &HandJoints) -> HandJoints {
    let wrist = |joints: &HandJoints| {
        let joint = joints.get(Joint::Wrist);
        Isometry3::from_parts(Translation3::from(joint.position.coords), joint.rotation())
    };
    hand.transformed(&(wrist(other) * wrist(hand).inverse()))
}

/// Each joint `closed` of the way from `open` to `shut`: positions linearly, orientations by
/// slerp; the flags of `shut`.
fn blend(open: &HandJoints, shut: &HandJoints, closed: f64) -> HandJoints {
    let mut joints = shut.clone();
    for (joint, (a, b)) in joints
        .joints
        .iter_mut()
        .zip(open.joints.iter().zip(&shut.joints))
    {
        joint.position = a.position + (b.position - a.position) * closed;
        joint.orientation = a.rotation().slerp(&b.rotation(), closed).into_inner();
        joint.radius = a.radius + (b.radius - a.radius) * closed;
    }
    joints
}
