//! An analytic world of balls and a floor whose collision test with the hand's
//! ideal segment shapes is exact and shares no code with the collision module.

use nalgebra::{Isometry3, Point3, Vector3};

use vas_server::grasping::clasp::{HandPose, ObjectSet, SegmentPlacement};
use vas_server::grasping::model::{HandModel, SegmentId};

/// Solid balls and an optional solid floor (everything below a height).
#[derive(Debug, Clone, Default)]
pub struct BallWorld {
    /// Height of the floor's top; object 0 when present.
    pub floor: Option<f64>,
    /// Balls (centre, radius); ball `k` is object `k + 1`.
    pub balls: Vec<(Point3<f64>, f64)>,
}

impl BallWorld {
    /// Which objects a segment at `pose` (world) intersects. A segment's shape is the hull of
    /// spheres around centres that lie on an axis-aligned segment or rectangle of its frame, so
    /// the hull of the centres is their bounding box and distances to it are exact.
    pub fn hits(&self, model: &HandModel, segment: SegmentId, pose: &Isometry3<f64>) -> ObjectSet {
        let shape = &model.segments()[segment].shape;
        let mut lo = shape.centres[0];
        let mut hi = shape.centres[0];
        for c in &shape.centres {
            lo = lo.inf(c);
            hi = hi.sup(c);
        }
        let mut hit = ObjectSet::EMPTY;
        if let Some(height) = self.floor {
            let lowest = shape
                .centres
                .iter()
                .map(|c| (pose * c).z)
                .fold(f64::INFINITY, f64::min);
            if lowest - shape.radius < height {
                hit = hit.union(ObjectSet::single(0));
            }
        }
        for (k, (centre, radius)) in self.balls.iter().enumerate() {
            let local = pose.inverse_transform_point(centre);
            let nearest = Point3::from(Vector3::from_fn(|i, _| local[i].clamp(lo[i], hi[i])));
            if (local - nearest).norm() < shape.radius + radius {
                hit = hit.union(ObjectSet::single(k + 1));
            }
        }
        hit
    }

    /// The collision test in the form the clasp takes.
    pub fn collider<'a>(
        &'a self,
        model: &'a HandModel,
    ) -> impl FnMut(SegmentId, &SegmentPlacement) -> ObjectSet + 'a {
        move |segment, placement| self.hits(model, segment, &placement.world())
    }

    /// The objects any segment of the hand intersects at `pose`.
    pub fn hand_hits(&self, model: &HandModel, pose: &HandPose) -> ObjectSet {
        model
            .segment_poses(&pose.flex)
            .iter()
            .enumerate()
            .fold(ObjectSet::EMPTY, |acc, (s, local)| {
                acc.union(self.hits(model, s, &(pose.root * local)))
            })
    }
}
