//! Forward kinematics: every segment's pose from the flex values.

use nalgebra::{Isometry3, Translation3};

use super::{Dof, FlexVector, HandModel, SegmentId};

impl HandModel {
    /// The poses of all segments relative to the hand root, for flex vector `flex`, written to
    /// `poses` (which must hold one entry per segment).
    pub fn forward_kinematics(&self, flex: &FlexVector, poses: &mut [Isometry3<f64>]) {
        self.forward_kinematics_with(flex, poses, |_, _, _| {});
    }

    /// [`HandModel::forward_kinematics`] that also shows `visit` every degree of freedom with
    /// its segment and the frame (relative to the hand root) its axis and pivot are written in:
    /// what a Jacobian of the segment poses needs.
    pub fn forward_kinematics_with<'a>(
        &'a self,
        flex: &FlexVector,
        poses: &mut [Isometry3<f64>],
        mut visit: impl FnMut(SegmentId, &'a Dof, &Isometry3<f64>),
    ) {
        assert_eq!(poses.len(), self.segments.len(), "one pose per segment");
        for (i, s) in self.segments.iter().enumerate() {
            let joint = Isometry3::from_parts(Translation3::from(s.origin), s.base_rotation);
            let mut pose = s.parent.map_or(joint, |p| poses[p] * joint);
            for dof in &s.dofs {
                visit(i, dof, &pose);
                pose *= dof.motion(flex);
            }
            poses[i] = pose;
        }
    }

    /// Allocating form of [`HandModel::forward_kinematics`].
    pub fn segment_poses(&self, flex: &FlexVector) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.segments.len()];
        self.forward_kinematics(flex, &mut poses);
        poses
    }
}
