//! OpenXR joints of a posed hand model: what a tracker would report for the model's hand, so
//! that the retargeting can be checked against known angles and other inputs can be driven from
//! glove data.

use nalgebra::{Isometry3, Point3};

use super::fit::Retargeter;
use super::joints::{HandJoints, Joint, JointPose};
use super::skeleton::joint_to_segment;
use crate::grasping::FlexVector;

/// Where a finger's metacarpal joint sits on the palm, as a fraction of the way from the wrist
/// to the knuckle (the model has no metacarpal bones; the retargeting does not use the joint).
const METACARPAL_FRACTION: f64 = 0.4;

impl Retargeter {
    /// The 26 joints of the model posed by `root` and `flex`. OpenXR's wrist turns with the
    /// palm, so the wrist joint takes the palm's pose: the wrist angles are not seen.
    pub fn synthesize(&self, root: &Isometry3<f64>, flex: &FlexVector) -> HandJoints {
        let model = self.model();
        let skeleton = self.skeleton();
        let segments = model.segments();
        let poses = model.segment_poses(flex);
        let joint_of_frame = |pose: &Isometry3<f64>, segment: usize| {
            (root * pose).rotation * skeleton.frame[segment].inverse()
        };
        let palm = root * poses[model.palm()];
        let wrist = JointPose::tracked(
            palm.translation.vector.into(),
            palm.rotation * joint_to_segment().inverse(),
            segments[model.palm()].shape.radius,
        );
        let mut joints = HandJoints {
            side: model.side(),
            joints: [wrist; Joint::ALL.len()],
        };
        for digit in &skeleton.digits {
            for (i, &id) in digit.segments.iter().enumerate() {
                let at = root * poses[id];
                joints.joints[digit.joints[i].index()] = JointPose::tracked(
                    at.translation.vector.into(),
                    joint_of_frame(&poses[id], id),
                    segments[id].shape.radius,
                );
            }
            let outer = digit.segments[2];
            joints.joints[digit.joints[3].index()] = JointPose::tracked(
                root * poses[outer] * digit.tip,
                joint_of_frame(&poses[outer], outer),
                segments[outer].shape.radius,
            );
        }
        // A finger's metacarpal joint: on the line from the wrist to its knuckle, turned as the
        // palm; the palm joint halfway along the middle finger's metacarpal bone.
        for (metacarpal, knuckle) in [
            (Joint::IndexMetacarpal, Joint::IndexProximal),
            (Joint::MiddleMetacarpal, Joint::MiddleProximal),
            (Joint::RingMetacarpal, Joint::RingProximal),
            (Joint::LittleMetacarpal, Joint::LittleProximal),
        ] {
            let to_knuckle = joints.get(knuckle).position - wrist.position;
            joints.joints[metacarpal.index()] = JointPose {
                position: wrist.position + to_knuckle * METACARPAL_FRACTION,
                ..wrist
            };
        }
        let base = joints.get(Joint::MiddleMetacarpal).position;
        let knuckle = joints.get(Joint::MiddleProximal).position;
        joints.joints[Joint::Palm.index()] = JointPose {
            position: Point3::from((base.coords + knuckle.coords) / 2.0),
            ..wrist
        };
        joints
    }
}
