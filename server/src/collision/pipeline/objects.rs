//! The objects of a pipeline: their ids, their shared collision models, the slots that hold
//! them, and the checks on what callers pass in.

use super::PairKey;
use super::interest::{GroupId, InterestKey};
use crate::collision::broad_phase::Aabb;
use crate::geometry::ConvexHull;
use nalgebra::{Isometry3, Vector3};
use std::sync::Arc;
use thiserror::Error;

/// Names an object of a pipeline. Ids of removed objects are never valid again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId {
    pub(super) index: u32,
    pub(super) generation: u32,
}

impl ObjectId {
    /// The slot the object occupies; slots of removed objects are reused.
    pub fn index(self) -> u32 {
        self.index
    }

    #[cfg(test)]
    pub(crate) fn from_parts(index: u32, generation: u32) -> Self {
        ObjectId { index, generation }
    }
}

/// What the pipeline needs of a rigid object's shape, built once and shared between the objects
/// (and loops) that use the same mesh.
#[derive(Debug)]
pub struct CollisionModel<C> {
    exact: C,
    hull: ConvexHull,
    local_bounds: Aabb,
}

impl<C> CollisionModel<C> {
    /// Combines an exact-test structure and the convex hull of the same mesh.
    pub fn new(exact: C, hull: ConvexHull) -> Self {
        let first = hull.vertices()[0];
        let (min, max) = hull
            .vertices()
            .iter()
            .fold((first, first), |(lo, hi), v| (lo.inf(v), hi.sup(v)));
        let local_bounds = Aabb { min, max }.expanded(hull.tolerance());
        CollisionModel {
            exact,
            hull,
            local_bounds,
        }
    }

    /// The exact-test structure.
    pub fn exact(&self) -> &C {
        &self.exact
    }

    /// The convex hull used by the pre-check.
    pub fn hull(&self) -> &ConvexHull {
        &self.hull
    }

    /// A box enclosing the mesh in its own frame.
    pub fn local_bounds(&self) -> &Aabb {
        &self.local_bounds
    }
}

/// An object to add to a pipeline.
#[derive(Debug)]
pub struct ObjectDesc<C> {
    /// Its shape.
    pub model: Arc<CollisionModel<C>>,
    /// Its pose in the scene.
    pub pose: Isometry3<f64>,
    /// Its collision group, for the interest matrix.
    pub group: GroupId,
    /// True for objects that never move: two of them are never tested against each other.
    pub is_static: bool,
}

/// Why the pipeline refused a call.
#[derive(Debug, Error, PartialEq)]
pub enum PipelineError {
    /// The id names no object (never added, or removed).
    #[error("object {0:?} is not in the pipeline")]
    UnknownObject(ObjectId),
    /// A pose with a NaN or infinite component, or a rotation that is not a unit quaternion.
    #[error("invalid pose for {0}: {1}")]
    InvalidPose(String, &'static str),
    /// More objects than ids can name.
    #[error("the pipeline is full")]
    Full,
}

pub(super) struct Object<C> {
    pub(super) model: Arc<CollisionModel<C>>,
    pub(super) pose: Isometry3<f64>,
    pub(super) key: InterestKey,
}

pub(super) struct Slot<C> {
    pub(super) generation: u32,
    pub(super) object: Option<Object<C>>,
}

/// The object in slot `index`, which a pair names: pairs name only live objects.
pub(super) fn live<C>(slots: &[Slot<C>], index: u32) -> &Object<C> {
    slots[index as usize]
        .object
        .as_ref()
        .expect("pairs name live objects")
}

pub(super) fn models<C>(slots: &[Slot<C>], (a, b): PairKey) -> [&CollisionModel<C>; 2] {
    [a, b].map(|index| &*live(slots, index).model)
}

/// The pose of a pair's second object in its first one's frame.
pub(super) fn relative_pose<C>(slots: &[Slot<C>], (a, b): PairKey) -> Isometry3<f64> {
    live(slots, a).pose.inv_mul(&live(slots, b).pose)
}

/// Refuses poses with non-finite components or a rotation far from unit length.
pub(super) fn check_pose(
    pose: &Isometry3<f64>,
    name: impl Fn() -> String,
) -> Result<(), PipelineError> {
    let translation: &Vector3<f64> = &pose.translation.vector;
    let quaternion = pose.rotation.quaternion();
    if !translation
        .iter()
        .chain(quaternion.coords.iter())
        .all(|v| v.is_finite())
    {
        return Err(PipelineError::InvalidPose(
            name(),
            "a component is not finite",
        ));
    }
    if (quaternion.norm() - 1.0).abs() > 1e-6 {
        return Err(PipelineError::InvalidPose(
            name(),
            "the rotation is not a unit quaternion",
        ));
    }
    Ok(())
}
