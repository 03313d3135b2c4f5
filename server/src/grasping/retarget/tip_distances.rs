//! How well a retargeted hand matches the tracked one: the distance from each of the model's
//! fingertip points (the end of the digit's outer segment) to the tracked tip joint.

use super::fit::{Retarget, Retargeter};
use super::joints::HandJoints;
use crate::grasping::Finger;

/// The fingertip distances of one retargeted sample, in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingertipDistances {
    /// Thumb, index, middle, ring and pinky, as [`Finger::DIGITS`].
    pub per_digit: [f64; 5],
}

impl FingertipDistances {
    /// The digits with their distances.
    pub fn digits(&self) -> impl Iterator<Item = (Finger, f64)> + '_ {
        Finger::DIGITS.into_iter().zip(self.per_digit)
    }

    /// Root mean square of the five distances.
    pub fn rms(&self) -> f64 {
        (self.per_digit.iter().map(|d| d * d).sum::<f64>() / 5.0).sqrt()
    }

    /// The largest distance.
    pub fn max(&self) -> f64 {
        self.per_digit.iter().copied().fold(0.0, f64::max)
    }
}

impl Retargeter {
    /// The distance of each of the model's fingertips, posed by `fit`, from the tip joints of
    /// `joints` (the sample it was fitted to).
    pub fn fingertip_distances(&self, fit: &Retarget, joints: &HandJoints) -> FingertipDistances {
        let poses = self.model().segment_poses(&fit.flex);
        let per_digit = self.skeleton().digits.each_ref().map(|digit| {
            let model_tip = fit.root * (poses[digit.segments[2]] * digit.tip);
            (model_tip - joints.get(digit.joints[3]).position).norm()
        });
        FingertipDistances { per_digit }
    }
}
