//! A segment of the hand: its joint's degrees of freedom, its collision shape, its flex limits.

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

use super::{Finger, FlexVector, JointLevel, SegmentId, VariableSet};

/// One revolute degree of freedom: a rotation by `Σ gain_i · F[flex_i]` about the line through
/// `pivot` along `axis`, both in the segment's frame after its base rotation and the preceding
/// degrees of freedom. The pivot is the joint origin except for joints that sit elsewhere, such
/// as the palm arch that swings the ring and little fingers about the middle of the palm.
#[derive(Debug, Clone, PartialEq)]
pub struct Dof {
    /// Rotation axis.
    pub axis: Unit<Vector3<f64>>,
    /// A point on the rotation axis.
    pub pivot: Point3<f64>,
    /// The flex values driving the angle, with their gains.
    pub terms: Vec<(usize, f64)>,
}

impl Dof {
    /// The joint angle for a flex vector.
    pub fn angle(&self, flex: &FlexVector) -> f64 {
        self.terms.iter().map(|&(i, gain)| gain * flex[i]).sum()
    }

    /// The joint's motion for a flex vector: the rotation about the pivot.
    pub fn motion(&self, flex: &FlexVector) -> Isometry3<f64> {
        self.motion_by(self.angle(flex))
    }

    /// The joint's motion when its angle is `angle` radians.
    pub fn motion_by(&self, angle: f64) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_axis_angle(&self.axis, angle);
        // p + R (x - p) = R x + (p - R p)
        let shift = self.pivot.coords - rotation * self.pivot.coords;
        Isometry3::from_parts(Translation3::from(shift), rotation)
    }
}

/// A segment's collision shape: the convex hull of spheres of radius `radius` centred at
/// `centres` (in the segment's frame).
#[derive(Debug, Clone, PartialEq)]
pub struct SweptHull {
    /// Sphere centres, in metres.
    pub centres: Vec<Point3<f64>>,
    /// Sphere radius, in metres.
    pub radius: f64,
}

impl SweptHull {
    /// The largest distance from the segment's origin to a point of the shape.
    pub fn reach(&self) -> f64 {
        self.centres
            .iter()
            .map(|c| c.coords.norm())
            .fold(0.0, f64::max)
            + self.radius
    }
}

/// One rigid segment of the hand.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// Name from the config, unique within the hand.
    pub name: String,
    /// The parent segment; `None` for the palm, whose parent is the hand root.
    pub parent: Option<SegmentId>,
    /// Which digit (or the palm) the segment belongs to.
    pub finger: Finger,
    /// Where along the digit it sits.
    pub level: JointLevel,
    /// Joint position in the parent's frame.
    pub origin: Vector3<f64>,
    /// Fixed rotation applied at the joint before the degrees of freedom.
    pub base_rotation: UnitQuaternion<f64>,
    /// The joint's degrees of freedom, applied in order.
    pub dofs: Vec<Dof>,
    /// The collision shape, in the segment's frame.
    pub shape: SweptHull,
    /// The variables the joint itself owns (its flex values; the root for the palm).
    pub own_variables: VariableSet,
    /// Every variable the segment's pose depends on: its own and its ancestors'.
    pub variables: VariableSet,
}

/// Joint limits of one flex value, in radians.
#[derive(Debug, Clone, PartialEq)]
pub struct FlexLimit {
    /// Sensor name from the config.
    pub name: String,
    /// Smallest accepted angle.
    pub min: f64,
    /// Largest accepted angle.
    pub max: f64,
}
