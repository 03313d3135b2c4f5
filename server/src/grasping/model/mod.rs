//! The hand model: a kinematic tree of rigid segments read from a TOML file and validated.
//!
//! A hand is a palm and five fingers (thumb, index, middle, ring, pinky) of three segments each:
//! inner, middle and outer, chained palm → inner → middle → outer. Every segment has a joint
//! (its origin in the parent's frame, a fixed base rotation, then revolute degrees of freedom whose
//! angles are linear combinations of the 22 flex values) and a collision shape: the convex hull of
//! spheres of one radius around a few centres (two centres make a capsule, four a rounded slab).
//!
//! Frame conventions, for every segment: `+y` points along the segment toward its tip, `-z` is the
//! palmar side (the pad of a finger, the inside of the palm) and `+z` the back of the hand. The
//! root frame is the tracker's: the wrist, with the palm's frame at rest equal to it. A left hand
//! is the mirror image of a right hand in the `x = 0` plane; a config may say `mirror_of` to get
//! one from the other instead of repeating every number.

mod anatomy;
mod file;
mod kinematics;
mod mirror;
mod segment;
mod validate;
mod variables;

use vas_protocol::HandSide;

use crate::geometry::ConfigFileError;

pub use anatomy::{Finger, JointLevel};
pub use segment::{Dof, FlexLimit, Segment, SweptHull};
pub use variables::VariableSet;

/// Number of flex values: the CyberGlove's 22 sensors, in the order of
/// `vas_protocol::FLEX_JOINT_NAMES`.
pub const FLEX_COUNT: usize = 22;

/// Index of the hand root (the tracked matrix M) among the clasp's variables; the flex values are
/// variables `0..FLEX_COUNT`.
pub const ROOT_VARIABLE: usize = FLEX_COUNT;

/// Number of variables the clasp interpolates: the 22 flex values and the hand root.
pub const VARIABLE_COUNT: usize = FLEX_COUNT + 1;

/// The largest length in a hand config (joint origins, pivots, sphere centres and radii), in
/// metres: far beyond any hand, and small enough that every lever and pose derived from the model
/// stays finite.
pub const MAX_HAND_LENGTH_M: f64 = 10.0;

/// The largest magnitude of a joint limit, in degrees.
pub const MAX_FLEX_LIMIT_DEG: f64 = 360.0;

/// The largest magnitude of a flex value's gain: with the limits, it keeps every joint angle (a
/// sum of gains times flex values) finite.
pub const MAX_FLEX_GAIN: f64 = 100.0;

/// The 22 flex values (joint angles in radians), in CyberGlove order.
pub type FlexVector = [f64; FLEX_COUNT];

/// Index of a segment in [`HandModel::segments`].
pub type SegmentId = usize;

/// A validated hand model.
#[derive(Debug, Clone, PartialEq)]
pub struct HandModel {
    name: String,
    side: HandSide,
    limits: Vec<FlexLimit>,
    segments: Vec<Segment>,
    /// For every variable, a bound on how far (metres) any point of the hand moves per radian
    /// of the variable; see [`HandModel::lever`].
    levers: [f64; VARIABLE_COUNT],
}

/// Why a hand config was refused: the file, the key and the reason.
pub type HandConfigError = ConfigFileError;

impl HandModel {
    /// The model's name from its config.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Right or left hand.
    pub fn side(&self) -> HandSide {
        self.side
    }

    /// Joint limits of the 22 flex values.
    pub fn limits(&self) -> &[FlexLimit] {
        &self.limits
    }

    /// The segments, parents before children; index 0 is the palm.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// How far from the hand root any point of the hand can be, whatever its flex values: along
    /// each segment's chain, the joint offsets and, per degree of freedom, twice its pivot's
    /// distance (a rotation about a pivot `p` moves a point by at most `2 |p|` more than it
    /// turns it), then the segment's own reach.
    pub fn reach(&self) -> f64 {
        let mut frame_reach = Vec::with_capacity(self.segments.len());
        let mut reach: f64 = 0.0;
        for segment in &self.segments {
            let parent = segment.parent.map_or(0.0, |p| frame_reach[p]);
            let pivots: f64 = segment
                .dofs
                .iter()
                .map(|d| 2.0 * d.pivot.coords.norm())
                .sum();
            let frame = parent + segment.origin.norm() + pivots;
            frame_reach.push(frame);
            reach = reach.max(frame + segment.shape.reach());
        }
        reach
    }

    /// The palm's segment id.
    pub fn palm(&self) -> SegmentId {
        0
    }

    /// A bound on how far (metres) any point of the hand moves when `variable` changes by one
    /// radian (for the root: when it rotates by one radian about its origin; its translation
    /// moves every point one for one). Relates the clasp's tolerances to distances.
    pub fn lever(&self, variable: usize) -> f64 {
        self.levers[variable]
    }
}

#[cfg(test)]
pub(crate) mod tests;
