//! Hand-joint samples as hand targets: the wire sample read as the retargeting's
//! [`HandJoints`], validated and retargeted onto the scene's hand model
//! ([`grasping::retarget`](crate::grasping::retarget)), into the root and flex values a tracker
//! and a glove would give.
//!
//! The retargeter works on the scene's hand model as the scene configures it, uncalibrated. A
//! calibration resizes the model's segments to the user's bones, but the flex values must be
//! those of the hand that clasps, collides and is drawn: its segment meshes in every loop and on
//! `vas/scene/geometry`. Calibrating that hand means building it anew, which is a restart of the
//! loops and a new geometry generation, not something to do behind the user's back on the first
//! samples. Uncalibrated, the retargeting still turns every joint as measured, and its
//! refinement brings the model's fingertips as near the tracked tips as the model's segments
//! allow.
//!
//! The retargeted root and flex values, not the 26 joints, go through the hand's One Euro
//! filter ([`StreamFilter`]): they are what drives the hand, so smoothing them is what holds a
//! still hand still, with 23 streams instead of 52; the retargeting's checks see the joints as
//! tracked; and a weighted mean of flex values within the joint limits stays within them, where
//! smoothed joints could make a hand the retargeting no longer fits as well.

use nalgebra::{Isometry3, Point3, Quaternion};
use vas_protocol::{
    FLEX_COUNT, HAND_JOINT_COUNT, HandJointsSample, HandSide, InputRejection, InputStamp,
    JointLocation,
};

use crate::grasping::HandModel;
use crate::grasping::retarget::{
    HandJoints, JointFlags, JointPose, JointsError, RetargetError, Retargeter,
};
use crate::scene::TrackingParams;
use crate::simulation::filter::{NonFiniteSample, Passage, Sample, StreamFilter, TimeFault};

/// Why a hand-joints sample was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JointsRejection {
    /// The sample names a side the scene has no hand for, or no side at all.
    #[error("side code {side} names no hand of the scene")]
    NoSuchHand {
        /// The side code received.
        side: u32,
    },
    /// The joints are not a hand: not finite, not unit quaternions, out of anatomical order or
    /// with bones of impossible length.
    #[error(transparent)]
    Joints(JointsError),
    /// The sample is refused before its joints are read (a timestamp ahead of the server's
    /// clock).
    #[error(transparent)]
    Sample(InputRejection),
    /// The retargeted hand is not finite (the filter refuses it).
    #[error(transparent)]
    Filter(NonFiniteSample),
}

/// What an accepted hand-joints sample says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointsOutcome {
    /// The hand is tracked: its target is the retargeted sample.
    Tracked,
    /// A joint the retargeting needs is not valid (OpenXR's way of saying that the hand is not
    /// tracked): the hand keeps its target and its frames say it is untracked.
    Untracked,
}

/// The latest hand target that hand-joints samples gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointsTarget {
    /// The latest accepted sample.
    pub stamp: InputStamp,
    /// When the latest sample was taken in, on the inputs' tracking clock (ns).
    pub at_ns: u64,
    /// The hand root in tracking space and the flex values of the latest tracked sample;
    /// `None` until one came.
    pub pose: Option<(Isometry3<f64>, [f32; FLEX_COUNT])>,
    /// Whether the latest sample tracked the hand.
    pub tracked: bool,
    /// When the latest tracked sample was taken in, on the inputs' tracking clock (ns); `None`
    /// until one came.
    pub tracked_ns: Option<u64>,
}

/// A hand that hand-joints samples can drive: its retargeter, filter and latest target.
#[derive(Debug, Clone)]
pub struct JointsHand {
    retargeter: Retargeter,
    filter: StreamFilter<FLEX_COUNT>,
    target: Option<JointsTarget>,
}

impl JointsHand {
    /// Joint samples onto `model`, smoothed as `tracking` says; `None`, with the reason logged,
    /// for a model the retargeting cannot split into its degrees of freedom (it still takes
    /// tracker and glove input).
    pub fn new(model: &HandModel, tracking: &TrackingParams) -> Option<JointsHand> {
        match Retargeter::new(model.clone()) {
            Ok(retargeter) => Some(JointsHand {
                retargeter,
                filter: StreamFilter::new(tracking),
                target: None,
            }),
            Err(error) => {
                tracing::warn!(
                    model = model.name(),
                    %error,
                    "the hand model cannot be retargeted; it takes no hand-joints samples"
                );
                None
            }
        }
    }

    /// The hand's side, as the wire names it.
    pub fn side(&self) -> HandSide {
        self.retargeter.model().side()
    }

    /// The latest target, `None` before the first accepted sample.
    pub fn target(&self) -> Option<&JointsTarget> {
        self.target.as_ref()
    }

    /// Forgets the target and the filter's samples (a reset).
    pub fn forget_target(&mut self) {
        self.target = None;
        self.filter.restart();
    }

    /// Retargets a sample of this hand (its side already matched), taken in at `at_ns` on the
    /// inputs' tracking clock, smooths it and makes it the target. With the outcome, the fault
    /// of the sample's timestamp if the filter restarted for it (not after the previous one's).
    pub fn apply(
        &mut self,
        sample: &HandJointsSample,
        at_ns: u64,
    ) -> Result<(JointsOutcome, Option<TimeFault>), JointsRejection> {
        let joints = read_joints(sample, self.retargeter.model().side());
        let stamp = sample.stamp();
        match self.retargeter.fit(&joints) {
            Ok(fit) => {
                // The filter times the samples by their own timestamps, whatever the tracking
                // clock, so that a replay is smoothed alike however fast it is played.
                let raw = Sample {
                    root: fit.root,
                    values: fit.flex,
                };
                let filtered = (self.filter.apply_stamped(sample.timestamp_ns, raw))
                    .map_err(JointsRejection::Filter)?;
                self.target = Some(JointsTarget {
                    stamp,
                    at_ns,
                    pose: Some((
                        filtered.sample.root,
                        filtered.sample.values.map(|v| v as f32),
                    )),
                    tracked: true,
                    tracked_ns: Some(at_ns),
                });
                let fault = match filtered.passage {
                    Passage::Restarted(fault) => Some(fault),
                    Passage::Unfiltered | Passage::Started | Passage::Smoothed => None,
                };
                Ok((JointsOutcome::Tracked, fault))
            }
            Err(RetargetError::Joints(JointsError::NotValid { .. })) => {
                // Tracking is lost: the filter starts afresh when it is regained.
                self.filter.restart();
                self.target = Some(JointsTarget {
                    stamp,
                    at_ns,
                    pose: self.target.and_then(|target| target.pose),
                    tracked: false,
                    tracked_ns: self.target.and_then(|target| target.tracked_ns),
                });
                Ok((JointsOutcome::Untracked, None))
            }
            Err(RetargetError::Joints(error)) => Err(JointsRejection::Joints(error)),
            // Neither happens (the joints are read as the model's side, and the model was
            // accepted by `Retargeter::new`); either would mean this hand cannot take them.
            Err(RetargetError::WrongSide { .. } | RetargetError::Unsupported { .. }) => {
                Err(JointsRejection::NoSuchHand { side: sample.side })
            }
        }
    }
}

/// The joints of a wire sample, as a hand of `side`.
pub fn read_joints(sample: &HandJointsSample, side: vas_protocol::HandSide) -> HandJoints {
    HandJoints {
        side,
        joints: sample.joints.map(|joint| {
            let [x, y, z, w] = joint.rotation;
            JointPose {
                position: Point3::from(joint.position),
                orientation: Quaternion::new(w, x, y, z),
                radius: f64::from(joint.radius),
                // The four OpenXR location bits; others are not OpenXR's.
                flags: JointFlags((joint.flags & 0xf) as u8),
            }
        }),
    }
}

/// The wire sample of `joints`, numbered `seq` and stamped `timestamp_ns`: what a tracker
/// sends for them, as the hand of the scene's first user.
pub fn wire_joints(joints: &HandJoints, seq: u64, timestamp_ns: u64) -> HandJointsSample {
    let locations: [JointLocation; HAND_JOINT_COUNT] = joints.joints.map(|joint| {
        let q = joint.orientation;
        JointLocation {
            position: joint.position.coords.into(),
            rotation: [q.i, q.j, q.k, q.w],
            radius: joint.radius as f32,
            flags: u32::from(joint.flags.0),
        }
    });
    HandJointsSample {
        seq,
        timestamp_ns,
        joints: locations,
        side: joints.side as u32,
        user: 0,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::path::Path;

    use super::*;
    use crate::grasping::retarget::Capture;

    /// A captured hand of `side`, from the repository's fixtures.
    pub(crate) fn captured(name: &str, side: HandSide) -> HandJoints {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/fixtures/hands")
            .join(name);
        Capture::read(&path)
            .expect("the fixture is a valid capture")
            .joints_of(side)
    }

    #[test]
    fn joints_travel_the_wire_unchanged_but_for_the_radius_precision() {
        let joints = captured("webxr_pinch.json", HandSide::Right);
        let sample = wire_joints(&joints, 7, 70);
        assert_eq!((sample.seq, sample.timestamp_ns), (7, 70));
        assert_eq!(sample.side, HandSide::Right as u32);
        let read = read_joints(&sample, HandSide::Right);
        for (read, sent) in read.joints.iter().zip(&joints.joints) {
            assert_eq!(read.position, sent.position);
            assert_eq!(read.orientation, sent.orientation);
            assert_eq!(read.flags, sent.flags);
            assert!((read.radius - sent.radius).abs() < 1e-8);
        }
    }

    #[test]
    fn only_openxr_location_bits_are_read() {
        let mut sample = wire_joints(&captured("webxr_relaxed.json", HandSide::Left), 1, 1);
        sample.joints[3].flags = 0xffff_fff3;
        assert_eq!(
            read_joints(&sample, HandSide::Left).joints[3].flags,
            JointFlags(3)
        );
    }
}
