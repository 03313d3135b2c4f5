//! Grasp analysis: from what touches a part, and how, to the type of grasp (the paper's five
//! rules, refined into the grasp types the paper names).
//!
//! Pure functions over the touching segments of one part, their semantics (palm, thumb, finger;
//! inner, middle, outer) and their contacts (where, which side of the segment, which way). The
//! order of the rules:
//!
//! 1. a contact on the back of the hand or of a finger: **push** (parts are never grasped with
//!    the back of the hand);
//! 2. the palm touches with its palmar side, no thumb, every contact pushes upward (against
//!    gravity, within a tilt) and the part's centre of mass is above the contacts: **gravity**
//!    (the part rests on the open hand);
//! 3. only one segment touches: **push** (paper rule 1);
//! 4. without the palm: thumb and fingers touch, the thumb opposing a finger: **precision**
//!    (paper rule 3), told apart by the
//!    fingers involved and the segments used: tip pinch (thumb and one fingertip), key (the thumb
//!    against the side of the index), three-jaw chuck (thumb, index and middle at their tips),
//!    otherwise, with thumb and two fingers, the **3-point pinch**; fingers without the thumb:
//!    **cigarette** when two neighbouring fingers hold the part between their sides, otherwise
//!    **push** (paper rule 2);
//! 5. with the palm: a middle or outer segment touches and some digit opposes the palm:
//!    **power** (paper rule 4), otherwise (only inner segments, paper rule 5, or a flat hand
//!    pressed on a face) **push**.
//!
//! Opposition (two contact normals more than an angle apart, the fingers closing *on* the part)
//! goes beyond the paper's rules, which count touching segments only: it keeps a flat hand or
//! two fingertips pressed on one face from counting as a grasp.

use std::fmt;

use nalgebra::{Point3, Unit, Vector3};
use parry3d::query::PointQuery;
use parry3d::shape::{ConvexPolyhedron, Segment as ParrySegment};
use serde::Serialize;

use super::model::{Finger, JointLevel, SegmentId};

/// Which side of a segment a contact is on, in the segment's frame (`-z` palmar, `+y` toward the
/// tip).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSide {
    /// The inside of the hand: finger pads, the palm's palmar face.
    Palmar,
    /// The back of the hand or of a finger.
    Dorsal,
    /// The side of a segment, toward a neighbouring finger.
    Lateral,
    /// The end of a fingertip.
    Tip,
}

/// Where and how a segment touches a part.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// Points of the contact region, in the world.
    pub points: Vec<Point3<f64>>,
    /// The segment's mean outward normal over the contact, in the world: the direction from the
    /// hand into the part.
    pub normal: Unit<Vector3<f64>>,
    /// Which side of the segment touches.
    pub side: ContactSide,
}

impl Contact {
    /// The mean of the contact points.
    pub fn centre(&self) -> Point3<f64> {
        mean(&self.points)
    }

    /// The contact moved rigidly by `pose` (from the frame it is written in to another).
    pub fn transformed(&self, pose: &nalgebra::Isometry3<f64>) -> Contact {
        Contact {
            points: self.points.iter().map(|p| pose * p).collect(),
            normal: pose.rotation * self.normal,
            side: self.side,
        }
    }
}

/// One segment touching the part under analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct Touch {
    /// The segment.
    pub segment: SegmentId,
    /// Its digit, or the palm.
    pub finger: Finger,
    /// Its place along the digit.
    pub level: JointLevel,
    /// How it touches.
    pub contact: Contact,
}

/// The sub-types of precision grasping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PrecisionKind {
    /// Thumb and one fingertip (a screw).
    TipPinch,
    /// Thumb, index and middle fingertips.
    ThreeJawChuck,
    /// The thumb against the side of the index (a key).
    Key,
    /// Thumb and fingers in another combination.
    Other,
}

/// The class the grasp analysis gives a hand's hold on a part: the paper's taxonomy, precision
/// grasps by kind. The wire carries it as a flat `vas_protocol::GraspType` code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspClass {
    /// Touching without holding: the part can be pushed, not carried.
    Push,
    /// Thumb and fingers, without the palm.
    Precision(PrecisionKind),
    /// Thumb and two fingers with more than their tips (a pen held to write).
    ThreePointPinch,
    /// Two neighbouring fingers holding the part between their sides.
    Cigarette,
    /// The whole hand: palm and the outer segments of the fingers.
    Power,
    /// The part resting on the open hand.
    Gravity,
}

impl fmt::Display for GraspClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            GraspClass::Push => "push",
            GraspClass::Precision(PrecisionKind::TipPinch) => "precision:tip_pinch",
            GraspClass::Precision(PrecisionKind::ThreeJawChuck) => "precision:three_jaw_chuck",
            GraspClass::Precision(PrecisionKind::Key) => "precision:key",
            GraspClass::Precision(PrecisionKind::Other) => "precision",
            GraspClass::ThreePointPinch => "three_point_pinch",
            GraspClass::Cigarette => "cigarette",
            GraspClass::Power => "power",
            GraspClass::Gravity => "gravity",
        })
    }
}

impl GraspClass {
    /// True for every type that holds the part (all but push).
    pub fn holds(self) -> bool {
        self != GraspClass::Push
    }

    /// How firmly the type holds, to choose between parts touched at once: power, 3-point,
    /// precision, cigarette, gravity, push.
    pub fn firmness(self) -> u8 {
        match self {
            GraspClass::Power => 5,
            GraspClass::ThreePointPinch => 4,
            GraspClass::Precision(_) => 3,
            GraspClass::Cigarette => 2,
            GraspClass::Gravity => 1,
            GraspClass::Push => 0,
        }
    }
}

/// Tuning of the analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalysisParams {
    /// The direction against gravity, in the world.
    pub up: Unit<Vector3<f64>>,
    /// The largest angle (radians) between a contact normal and `up` for a part to rest on it.
    pub max_rest_tilt: f64,
    /// How far (metres) the centre of mass may lie outside the contacts, seen from above, for a
    /// part to rest on the hand.
    pub support_margin: f64,
    /// The smallest angle (radians) between two contact normals for the contacts to oppose each
    /// other, as fingers closing on a part do (a flat hand pressed on a face does not).
    pub min_opposition: f64,
    /// How much the angles above are relaxed (radians) to keep holding a part already held, so
    /// that a grasp near a threshold does not flicker.
    pub hold_slack: f64,
}

impl AnalysisParams {
    /// The thresholds for a part already held: tilt and opposition relaxed by `hold_slack`.
    pub fn for_held(&self) -> AnalysisParams {
        AnalysisParams {
            max_rest_tilt: self.max_rest_tilt + self.hold_slack,
            min_opposition: (self.min_opposition - self.hold_slack).max(0.0),
            ..*self
        }
    }
}

impl Default for AnalysisParams {
    fn default() -> Self {
        AnalysisParams {
            up: Vector3::z_axis(),
            max_rest_tilt: 45f64.to_radians(),
            support_margin: 0.01,
            min_opposition: 60f64.to_radians(),
            hold_slack: 15f64.to_radians(),
        }
    }
}

/// The grasp that `touches` (every segment touching one part) have on a part whose centre of
/// mass is at `centre_of_mass` (world); `None` when nothing touches.
pub fn classify(
    touches: &[Touch],
    centre_of_mass: &Point3<f64>,
    params: &AnalysisParams,
) -> Option<GraspClass> {
    if touches.is_empty() {
        return None;
    }
    if touches
        .iter()
        .any(|t| t.contact.side == ContactSide::Dorsal)
    {
        return Some(GraspClass::Push);
    }
    let palm = touches.iter().any(|t| t.finger == Finger::Palm);
    let thumb = touches.iter().any(|t| t.finger == Finger::Thumb);
    if palm && !thumb && rests_on_hand(touches, centre_of_mass, params) {
        return Some(GraspClass::Gravity);
    }
    if touches.len() == 1 {
        return Some(GraspClass::Push);
    }
    let fingers: Vec<Finger> = distinct(
        touches
            .iter()
            .map(|t| t.finger)
            .filter(|f| !matches!(f, Finger::Palm | Finger::Thumb)),
    );
    let opposed = |a: Finger, b: &dyn Fn(&Touch) -> bool| {
        let max_cos = params.min_opposition.cos();
        touches.iter().filter(|t| t.finger == a).any(|ta| {
            touches
                .iter()
                .filter(|tb| b(tb))
                .any(|tb| ta.contact.normal.dot(&tb.contact.normal) < max_cos)
        })
    };
    let grasp = if palm {
        let beyond_inner = touches
            .iter()
            .any(|t| matches!(t.level, JointLevel::Middle | JointLevel::Outer));
        if beyond_inner && opposed(Finger::Palm, &|t| t.finger != Finger::Palm) {
            GraspClass::Power
        } else {
            GraspClass::Push
        }
    } else if thumb && !fingers.is_empty() {
        if opposed(Finger::Thumb, &|t| t.finger != Finger::Thumb) {
            precision(touches, &fingers)
        } else {
            GraspClass::Push
        }
    } else if is_cigarette(touches, &fingers) {
        GraspClass::Cigarette
    } else {
        GraspClass::Push
    };
    Some(grasp)
}

/// Thumb and fingers without the palm: which precision grasp (or 3-point pinch).
fn precision(touches: &[Touch], fingers: &[Finger]) -> GraspClass {
    let tips_only = touches.iter().all(|t| t.level == JointLevel::Outer);
    match fingers {
        [_] if tips_only => GraspClass::Precision(PrecisionKind::TipPinch),
        [Finger::Index] => {
            let index_side = touches.iter().any(|t| {
                t.finger == Finger::Index
                    && t.level != JointLevel::Outer
                    && t.contact.side == ContactSide::Lateral
            });
            if index_side {
                GraspClass::Precision(PrecisionKind::Key)
            } else {
                GraspClass::Precision(PrecisionKind::Other)
            }
        }
        [Finger::Index, Finger::Middle] if tips_only => {
            GraspClass::Precision(PrecisionKind::ThreeJawChuck)
        }
        [_, _] => GraspClass::ThreePointPinch,
        _ => GraspClass::Precision(PrecisionKind::Other),
    }
}

/// Two neighbouring fingers, no thumb, each touching with its side, pressing toward each other.
fn is_cigarette(touches: &[Touch], fingers: &[Finger]) -> bool {
    let [a, b] = fingers else { return false };
    let (Some(pa), Some(pb)) = (a.position(), b.position()) else {
        return false;
    };
    if pa.abs_diff(pb) != 1
        || touches
            .iter()
            .any(|t| t.contact.side != ContactSide::Lateral)
    {
        return false;
    }
    let centre = |f: Finger| -> (Point3<f64>, Vector3<f64>) {
        let mine: Vec<&Touch> = touches.iter().filter(|t| t.finger == f).collect();
        let points: Vec<Point3<f64>> = mine.iter().map(|t| t.contact.centre()).collect();
        let normal = mine.iter().fold(Vector3::zeros(), |acc, t| {
            acc + t.contact.normal.into_inner()
        });
        (mean(&points), normal)
    };
    let (ca, na) = centre(*a);
    let (cb, nb) = centre(*b);
    na.dot(&(cb - ca)) > 0.0 && nb.dot(&(ca - cb)) > 0.0
}

/// Every contact pushes upward and the centre of mass lies above the region the contacts span.
fn rests_on_hand(touches: &[Touch], centre_of_mass: &Point3<f64>, params: &AnalysisParams) -> bool {
    let min_cos = params.max_rest_tilt.cos();
    if touches
        .iter()
        .any(|t| t.contact.normal.dot(&params.up) < min_cos)
    {
        return false;
    }
    let up = params.up.into_inner();
    let flatten = |p: &Point3<f64>| p - up * p.coords.dot(&up);
    let support: Vec<Point3<f64>> = touches
        .iter()
        .flat_map(|t| t.contact.points.iter().map(flatten))
        .collect();
    distance_to_hull(&support, &flatten(centre_of_mass), &up) <= params.support_margin
}

/// Distance from `query` to the convex hull of `points`, all in one plane with normal `up`
/// (zero inside). The hull is taken as a thin prism so that parry's 3-D hull serves; collinear
/// or single points fall back to the segment between the extremes.
fn distance_to_hull(points: &[Point3<f64>], query: &Point3<f64>, up: &Vector3<f64>) -> f64 {
    if points.is_empty() {
        return f64::INFINITY;
    }
    // Work in f32 near the query, where parry computes; centimetre-sized regions keep their
    // precision.
    let local = |p: &Point3<f64>| (p - query.coords).cast::<f32>();
    let lift = up.cast::<f32>() * 0.001;
    let prism: Vec<parry3d::math::Point<f32>> = points
        .iter()
        .flat_map(|p| {
            let q = local(p);
            [q - lift, q + lift]
        })
        .collect();
    let origin = parry3d::math::Point::<f32>::origin();
    if let Some(hull) = ConvexPolyhedron::from_convex_hull(&prism) {
        return f64::from(hull.distance_to_local_point(&origin, true));
    }
    let start = local(&points[0]);
    let end = points
        .iter()
        .map(local)
        .max_by(|a, b| (a - start).norm().total_cmp(&(b - start).norm()))
        .unwrap_or(start);
    f64::from(ParrySegment::new(start, end).distance_to_local_point(&origin, true))
}

fn mean(points: &[Point3<f64>]) -> Point3<f64> {
    let sum = points
        .iter()
        .fold(Vector3::zeros(), |acc, p| acc + p.coords);
    Point3::from(sum / points.len().max(1) as f64)
}

/// The distinct values of `items`, sorted by their position across the hand.
fn distinct(items: impl Iterator<Item = Finger>) -> Vec<Finger> {
    let mut out: Vec<Finger> = Vec::new();
    for f in items {
        if !out.contains(&f) {
            out.push(f);
        }
    }
    out.sort_by_key(|f| f.position());
    out
}

#[cfg(test)]
mod tests;
