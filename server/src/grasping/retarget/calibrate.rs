//! Per-user calibration: the hand model resized to one user's measured hand.
//!
//! From one good sample, each finger's knuckle becomes its inner segment's origin on the palm
//! (the thumb's base goes halfway from the wrist to its metacarpal joint, for the reason given at
//! `THUMB_BASE_FROM_WRIST`), and each segment's length becomes the measured bone's: the distance
//! to the next joint, for the outer segment to the tip. The shapes stretch with their segments;
//! degrees of freedom that swing a segment about a pivot (the palm arch) keep their pivot where
//! it was on the palm.

use nalgebra::Point3;

use super::fit::{RetargetError, Retargeter, root_of};
use super::joints::{HandJoints, Joint};
use crate::grasping::{FLEX_COUNT, Finger};

/// Where the thumb's base goes, as a fraction of the way from the wrist to the measured thumb
/// metacarpal joint. OpenXR skeletons swing that joint about the wrist as the thumb moves across
/// the palm (by 14 mm between the open and the pinching captures in `tests/fixtures/hands`),
/// where the model's thumb turns about a point fixed in the palm; a base nearer the wrist keeps
/// the thumb's reach, so a hand calibrated open still reaches a pinch, and the reverse.
const THUMB_BASE_FROM_WRIST: f64 = 0.5;

impl Retargeter {
    /// This retargeter with its model calibrated on `joints`, a sample of the user's hand.
    pub fn calibrated(&self, joints: &HandJoints) -> Result<Retargeter, RetargetError> {
        self.check(joints)?;
        let root = root_of(joints);
        // Positions in the palm's frame at rest, where the inner segments' origins are written.
        let rest = [0.0; FLEX_COUNT];
        let palm = root * self.model().segment_poses(&rest)[self.model().palm()];
        let at = |joint| palm.inverse_transform_point(&joints.get(joint).position);
        let wrist = at(Joint::Wrist);
        let digits = &self.skeleton().digits;
        let model = self.model().reshaped(|segments| {
            for digit in digits {
                let [mut base, middle, outer, tip] = digit.joints.map(at);
                if digit.finger == Finger::Thumb {
                    base = wrist + (base - wrist) * THUMB_BASE_FROM_WRIST;
                }
                let inner = &mut segments[digit.segments[0]];
                let shift = inner.base_rotation.inverse() * (base.coords - inner.origin);
                inner.origin = base.coords;
                for dof in &mut inner.dofs {
                    if dof.pivot.coords.norm() > 0.0 {
                        dof.pivot -= shift;
                    }
                }
                let lengths = [
                    (middle - base).norm(),
                    (outer - middle).norm(),
                    (tip - outer).norm(),
                ];
                for (i, length) in lengths.into_iter().enumerate() {
                    let id = digit.segments[i];
                    let modelled = match digit.segments.get(i + 1) {
                        Some(&child) => segments[child].origin.norm(),
                        None => digit.tip.coords.norm(),
                    };
                    if modelled <= 0.0 {
                        continue; // Nothing to stretch.
                    }
                    let scale = length / modelled;
                    if let Some(&child) = digit.segments.get(i + 1) {
                        segments[child].origin *= scale;
                    }
                    let shape = &mut segments[id].shape;
                    shape.centres = shape
                        .centres
                        .iter()
                        .map(|c| Point3::from(c.coords * scale))
                        .collect();
                }
            }
        });
        Retargeter::new(model)
    }
}
