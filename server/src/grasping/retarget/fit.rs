//! The retargeting: a hand root and 22 flex values for a sample of OpenXR joints.
//!
//! The root is the wrist joint (turned into the model's frame convention); OpenXR's wrist turns
//! with the palm, so the wrist angles start at rest. From the palm out, each joint's angles are
//! the rotation of its bone relative to its parent segment, split about the model's joint axes:
//! the rotations that turn the segment's direction to the measured bone (joint to next joint),
//! in the parent's frame as the angles found so far pose it. Only the bones' directions are
//! used, not their twist about themselves, which trackers report loosely. A degree of freedom
//! that swings its segment about a pivot away from the joint (the palm arch) comes from where
//! the joint is. The flex values are the least-squares solution of the angles' linear
//! combinations (a flex value may drive several joints, and a joint several flex values),
//! clamped to the limits. Tracked joints do not sit exactly where a rigid 22-DOF hand can put
//! them, so a few damped least-squares steps then move the flex values (the wrist's too) so that
//! the model's fingertips meet the tracked tips; on joints the model can reproduce they start at
//! the answer and change nothing.

use std::f64::consts::{PI, TAU};

use nalgebra::{
    DMatrix, Isometry3, Point3, SMatrix, SVector, Translation3, Unit, UnitQuaternion, Vector3,
};
use thiserror::Error;

use super::joints::{HandJoints, Joint, JointsError};
use super::skeleton::Skeleton;
use crate::grasping::model::Dof;
use crate::grasping::{FLEX_COUNT, FlexVector, HandModel};
use vas_protocol::HandSide;

/// Number of fingertip coordinates the refinement matches.
const TIP_COORDINATES: usize = 15;

/// The most refinement steps per sample.
const REFINE_STEPS: usize = 3;

/// The damping of the refinement steps at first, in metres: a flex change that would move a
/// fingertip less than this per radian is held back, so nearly singular poses (a straight
/// finger) do not make the angles jump.
const DAMPING_M: f64 = 2e-3;

/// The refinement stops once every fingertip is this close, in metres.
const TIP_TOLERANCE_M: f64 = 2e-5;

/// The refinement stops once no flex value moves more than this in a step, in radians.
const SETTLED_RAD: f64 = 1e-4;

/// The fingertips' coordinates, thumb first.
type Tips = SVector<f64, TIP_COORDINATES>;

/// The fingertips' coordinates by the flex values.
type TipJacobian = SMatrix<f64, TIP_COORDINATES, FLEX_COUNT>;

/// Why a sample could not be retargeted, or a model cannot be.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RetargetError {
    /// The sample is malformed or impossible.
    #[error(transparent)]
    Joints(#[from] JointsError),
    /// The sample is of the other hand.
    #[error("a {sample:?} hand sample cannot drive a {model:?} hand model")]
    WrongSide {
        /// The model's side.
        model: HandSide,
        /// The sample's side.
        sample: HandSide,
    },
    /// The model has a joint the retargeting cannot split into its degrees of freedom.
    #[error("segment {segment:?}: {reason}")]
    Unsupported {
        /// The segment's name.
        segment: String,
        /// Why.
        reason: &'static str,
    },
}

/// A retargeted sample: the hand root in the joints' frame and the flex values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Retarget {
    /// The hand root (the model's root frame in the frame the joints are given in).
    pub root: Isometry3<f64>,
    /// The 22 flex values, radians, within the model's limits.
    pub flex: FlexVector,
}

/// A degree of freedom's axis where forward kinematics put it, relative to the root.
#[derive(Debug, Clone, Copy)]
struct DofAxis<'a> {
    segment: usize,
    pivot: Point3<f64>,
    axis: Unit<Vector3<f64>>,
    dof: &'a Dof,
}

/// Retargets samples of one hand onto one hand model.
#[derive(Debug, Clone)]
pub struct Retargeter {
    model: HandModel,
    skeleton: Skeleton,
    /// Maps the degrees of freedom's angles, in model order, to the flex values.
    angles_to_flex: DMatrix<f64>,
    /// For every flex value, the digits (bits as [`Skeleton::carries`]) whose tips it moves.
    flex_digits: [u8; FLEX_COUNT],
}

/// The angle about `axis` that turns `from` toward `to`, both seen along the axis.
fn angle_about(axis: &Unit<Vector3<f64>>, from: &Vector3<f64>, to: &Vector3<f64>) -> f64 {
    let from = from - axis.into_inner() * axis.dot(from);
    let to = to - axis.into_inner() * axis.dot(to);
    axis.dot(&from.cross(&to)).atan2(from.dot(&to))
}

/// The angles `(a, b)` of the rotations about `first`, then `second`, that turn `rest` to the
/// direction of `to` (as near as they can), with the smaller turn about `first` of the two
/// solutions. From `R(first, a) R(second, b) rest = to`: the component of `R(first, -a) to`
/// along `second` must be `rest`'s, which gives `a`; then `b` turns `rest` to it about `second`.
fn two_axes(
    first: &Unit<Vector3<f64>>,
    second: &Unit<Vector3<f64>>,
    rest: &Unit<Vector3<f64>>,
    to: &Vector3<f64>,
) -> (f64, f64) {
    let Some(to) = Unit::try_new(*to, 0.0) else {
        return (0.0, 0.0);
    };
    let along = first.into_inner() * first.dot(second);
    let across = second.into_inner() - along;
    let (c, s) = (to.dot(&across), to.dot(&first.cross(second)));
    let amplitude = c.hypot(s);
    let a = if amplitude > 1e-12 {
        let centre = s.atan2(c);
        let offset = ((rest.dot(second) - to.dot(&along)) / amplitude)
            .clamp(-1.0, 1.0)
            .acos();
        let wrap = |x: f64| (x + PI).rem_euclid(TAU) - PI;
        let (low, high) = (wrap(centre - offset), wrap(centre + offset));
        if low.abs() <= high.abs() { low } else { high }
    } else {
        0.0 // The direction lies along the first axis, which cannot turn it.
    };
    let turned = UnitQuaternion::from_axis_angle(first, -a) * to.into_inner();
    (a, angle_about(second, rest, &turned))
}

impl Retargeter {
    /// A retargeter for `model`. Each joint may have a leading degree of freedom about a pivot
    /// away from the joint, then at most two about axes through it.
    pub fn new(model: HandModel) -> Result<Retargeter, RetargetError> {
        let mut rows: Vec<[f64; FLEX_COUNT]> = Vec::new();
        for segment in model.segments() {
            for (i, dof) in segment.dofs.iter().enumerate() {
                let pivoted = dof.pivot.coords.norm() > 0.0;
                if pivoted && i > 0 {
                    return Err(RetargetError::Unsupported {
                        segment: segment.name.clone(),
                        reason: "only the first degree of freedom may have a pivot",
                    });
                }
                let mut row = [0.0; FLEX_COUNT];
                for &(flex, gain) in &dof.terms {
                    row[flex] += gain;
                }
                rows.push(row);
            }
            let through_joint = segment
                .dofs
                .iter()
                .filter(|d| d.pivot.coords.norm() == 0.0)
                .count();
            if through_joint > 2 {
                return Err(RetargetError::Unsupported {
                    segment: segment.name.clone(),
                    reason: "more than two degrees of freedom about axes through the joint",
                });
            }
        }
        let gains = DMatrix::from_fn(rows.len(), FLEX_COUNT, |r, c| rows[r][c]);
        let angles_to_flex = gains
            .pseudo_inverse(1e-9)
            .expect("the tolerance is not negative");
        let skeleton = Skeleton::new(&model);
        let mut flex_digits = [0u8; FLEX_COUNT];
        for (segment, carries) in model.segments().iter().zip(&skeleton.carries) {
            for &(f, _) in segment.dofs.iter().flat_map(|d| &d.terms) {
                flex_digits[f] |= carries;
            }
        }
        Ok(Retargeter {
            model,
            skeleton,
            angles_to_flex,
            flex_digits,
        })
    }

    /// The hand model samples are retargeted onto.
    pub fn model(&self) -> &HandModel {
        &self.model
    }

    /// The correspondence of the model's segments and the joints.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// The root and the flex values for a sample of this retargeter's hand.
    pub fn fit(&self, joints: &HandJoints) -> Result<Retarget, RetargetError> {
        self.check(joints)?;
        let root = root_of(joints);
        let mut flex = self.analytic(&root, joints);
        self.refine(&root, joints, &mut flex);
        Ok(Retarget { root, flex })
    }

    /// Validates a sample and checks that it is of the model's side.
    pub fn check(&self, joints: &HandJoints) -> Result<(), RetargetError> {
        joints.validate()?;
        if joints.side != self.model.side() {
            return Err(RetargetError::WrongSide {
                model: self.model.side(),
                sample: joints.side,
            });
        }
        Ok(())
    }

    /// Flex values from the joints, segment by segment from the palm out: in the frame the
    /// model's chain gives a joint (its parent posed by the angles found so far), a leading
    /// degree of freedom about a pivot turns the joint's origin to where it was measured, and
    /// the others turn the segment's direction to the measured bone's.
    fn analytic(&self, root: &Isometry3<f64>, joints: &HandJoints) -> FlexVector {
        let segments = self.model.segments();
        let at = |joint: Joint| root.inverse_transform_point(&joints.get(joint).position);
        let mut poses: Vec<Isometry3<f64>> = Vec::with_capacity(segments.len());
        let mut angles = Vec::with_capacity(self.angles_to_flex.ncols());
        for (s, segment) in segments.iter().enumerate() {
            let parent = segment.parent.map_or(Isometry3::identity(), |p| poses[p]);
            let mut frame = parent
                * Isometry3::from_parts(Translation3::from(segment.origin), segment.base_rotation);
            // The palm has no bone: the root is the wrist joint, which turns with the palm.
            let Some(bone) = self.skeleton.bones[s] else {
                angles.extend(segment.dofs.iter().map(|_| 0.0));
                poses.push(frame);
                continue;
            };
            let mut dofs = segment.dofs.as_slice();
            if let Some(dof) = dofs.first().filter(|d| d.pivot.coords.norm() > 0.0) {
                let moved = frame.inverse_transform_point(&at(bone.from)).coords;
                let angle = angle_about(&dof.axis, &-dof.pivot.coords, &(moved - dof.pivot.coords));
                frame *= dof.motion_by(angle);
                angles.push(angle);
                dofs = &dofs[1..];
            }
            let direction = frame.inverse_transform_vector(&(at(bone.to) - at(bone.from)));
            match dofs {
                [] => {}
                [only] => {
                    let angle = angle_about(&only.axis, &bone.rest, &direction);
                    frame *= only.motion_by(angle);
                    angles.push(angle);
                }
                [first, second] => {
                    let (a, b) = two_axes(&first.axis, &second.axis, &bone.rest, &direction);
                    frame *= first.motion_by(a) * second.motion_by(b);
                    angles.extend([a, b]);
                }
                _ => unreachable!("Retargeter::new refuses more than two axes through a joint"),
            }
            poses.push(frame);
        }
        let solved = &self.angles_to_flex * nalgebra::DVector::from_vec(angles);
        let mut flex = [0.0; FLEX_COUNT];
        for (i, limit) in self.model.limits().iter().enumerate() {
            flex[i] = solved[i].clamp(limit.min, limit.max);
        }
        flex
    }

    /// The model's fingertip points, relative to the root, for `flex`, with every degree of
    /// freedom's axis written to `axes`; `poses` is scratch space.
    fn tips<'a>(
        &'a self,
        flex: &FlexVector,
        poses: &mut [Isometry3<f64>],
        axes: &mut Vec<DofAxis<'a>>,
    ) -> [Point3<f64>; 5] {
        axes.clear();
        self.model
            .forward_kinematics_with(flex, poses, |segment, dof, frame| {
                axes.push(DofAxis {
                    segment,
                    pivot: frame * dof.pivot,
                    axis: frame.rotation * dof.axis,
                    dof,
                });
            });
        std::array::from_fn(|d| {
            poses[self.skeleton.digits[d].segments[2]] * self.skeleton.digits[d].tip
        })
    }

    /// The Jacobian of the fingertips' coordinates by the flex values, from [`Retargeter::tips`].
    fn jacobian(&self, tips: &[Point3<f64>; 5], axes: &[DofAxis]) -> TipJacobian {
        let mut jacobian = TipJacobian::zeros();
        for &DofAxis {
            segment,
            pivot,
            axis,
            dof,
        } in axes
        {
            let carries = self.skeleton.carries[segment];
            for (d, tip) in tips.iter().enumerate() {
                if carries & (1 << d) == 0 {
                    continue;
                }
                let motion = axis.cross(&(tip - pivot));
                for &(f, gain) in &dof.terms {
                    for k in 0..3 {
                        jacobian[(3 * d + k, f)] += gain * motion[k];
                    }
                }
            }
        }
        jacobian
    }

    /// Damped least-squares steps that bring the model's fingertips to the tracked tips,
    /// within the joint limits.
    fn refine(&self, root: &Isometry3<f64>, joints: &HandJoints, flex: &mut FlexVector) {
        let target = Tips::from_iterator(self.skeleton.digits.iter().flat_map(|digit| {
            let tip = root.inverse_transform_point(&joints.get(digit.joints[3]).position);
            [tip.x, tip.y, tip.z]
        }));
        let limits = self.model.limits();
        let mut poses = vec![Isometry3::identity(); self.model.segments().len()];
        let mut axes = Vec::with_capacity(self.angles_to_flex.ncols());
        // Levenberg-Marquardt: a step that made the fingertips worse (the limits make steps
        // projected, not exact) is taken back and tried again shorter, with more damping.
        let mut damping = DAMPING_M * DAMPING_M;
        let mut best: Option<(f64, FlexVector, Tips)> = None;
        let mut jacobian = TipJacobian::zeros();
        for evaluation in 0..=REFINE_STEPS {
            let tips = self.tips(flex, &mut poses, &mut axes);
            let residual =
                target - Tips::from_iterator(tips.iter().flat_map(|t| t.coords.iter().copied()));
            let error = residual.norm_squared();
            let improved = best.as_ref().is_none_or(|b| error < b.0);
            if improved {
                best = Some((error, *flex, residual));
            } else {
                damping *= 10.0;
            }
            let (_, from, residual) = best.as_ref().expect("set on the first pass");
            *flex = *from;
            if residual.amax() < TIP_TOLERANCE_M || evaluation == REFINE_STEPS {
                break;
            }
            // The Jacobian at `from`: this evaluation's if it is the best, else kept from the
            // evaluation that was.
            if improved {
                jacobian = self.jacobian(&tips, &axes);
            }
            // J Jᵀ + λ² I, by 3 x 3 blocks of the digits each flex value moves (most move one
            // fingertip); a flex value at a limit that the step would push beyond stays.
            let gradient = jacobian.transpose() * residual;
            let mut free = [true; FLEX_COUNT];
            let mut normal = SMatrix::<f64, TIP_COORDINATES, TIP_COORDINATES>::identity() * damping;
            for (f, limit) in limits.iter().enumerate() {
                free[f] = !((flex[f] <= limit.min && gradient[f] < 0.0)
                    || (flex[f] >= limit.max && gradient[f] > 0.0));
                if !free[f] {
                    continue;
                }
                let column = jacobian.column(f);
                let digits = || (0..5).filter(|d| self.flex_digits[f] & (1 << d) != 0);
                for a in digits() {
                    for b in digits() {
                        let moves = column.fixed_rows::<3>(3 * a)
                            * column.fixed_rows::<3>(3 * b).transpose();
                        let mut block = normal.fixed_view_mut::<3, 3>(3 * a, 3 * b);
                        block += moves;
                    }
                }
            }
            let Some(cholesky) = normal.cholesky() else {
                break;
            };
            let step = jacobian.transpose() * cholesky.solve(residual);
            let mut largest: f64 = 0.0;
            for (f, limit) in limits.iter().enumerate() {
                if free[f] {
                    let moved = (flex[f] + step[f]).clamp(limit.min, limit.max);
                    largest = largest.max((moved - flex[f]).abs());
                    flex[f] = moved;
                }
            }
            if largest < SETTLED_RAD {
                break;
            }
        }
    }
}

/// The hand root for a sample: the wrist joint in the model's frame convention.
pub fn root_of(joints: &HandJoints) -> Isometry3<f64> {
    let wrist = joints.get(Joint::Wrist);
    Isometry3::from_parts(
        Translation3::from(wrist.position.coords),
        wrist.rotation() * super::skeleton::joint_to_segment(),
    )
}
