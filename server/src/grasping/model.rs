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

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::Deserialize;

use crate::geometry::{ConfigFileError, FileLimits, describe_toml_error, read_config_text};

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

/// A set of clasp variables as a bit mask: bit `v` is flex value `v`, bit [`ROOT_VARIABLE`] the
/// hand root.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct VariableSet(pub u32);

impl VariableSet {
    /// The empty set.
    pub const EMPTY: VariableSet = VariableSet(0);
    /// Every variable: the flex values and the root.
    pub const ALL: VariableSet = VariableSet((1 << VARIABLE_COUNT) - 1);

    /// The set holding only `variable`.
    pub fn single(variable: usize) -> Self {
        VariableSet(1 << variable)
    }

    /// True when `variable` is in the set.
    pub fn contains(self, variable: usize) -> bool {
        self.0 & (1 << variable) != 0
    }

    /// True when the sets share a variable.
    pub fn intersects(self, other: VariableSet) -> bool {
        self.0 & other.0 != 0
    }

    /// True when the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The variables in both sets.
    pub fn and(self, other: VariableSet) -> Self {
        VariableSet(self.0 & other.0)
    }

    /// The variables in either set.
    pub fn or(self, other: VariableSet) -> Self {
        VariableSet(self.0 | other.0)
    }

    /// The variables of `self` that are not in `other`.
    pub fn without(self, other: VariableSet) -> Self {
        VariableSet(self.0 & !other.0)
    }

    /// The variables in increasing order.
    pub fn iter(self) -> impl Iterator<Item = usize> {
        (0..VARIABLE_COUNT).filter(move |&v| self.contains(v))
    }
}

/// Which hand a model is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// A right hand: the thumb is on the `-x` side of the palm.
    Right,
    /// A left hand: the thumb is on the `+x` side.
    Left,
}

impl Side {
    /// The other hand.
    pub fn mirrored(self) -> Side {
        match self {
            Side::Right => Side::Left,
            Side::Left => Side::Right,
        }
    }
}

/// Which part of the hand a segment belongs to (the analysis' semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Finger {
    /// The palm.
    Palm,
    /// The thumb.
    Thumb,
    /// The index finger.
    Index,
    /// The middle finger.
    Middle,
    /// The ring finger.
    Ring,
    /// The little finger.
    Pinky,
}

impl Finger {
    /// The five digits, thumb first, then the fingers from the thumb side outward.
    pub const DIGITS: [Finger; 5] = [
        Finger::Thumb,
        Finger::Index,
        Finger::Middle,
        Finger::Ring,
        Finger::Pinky,
    ];

    /// Position across the hand: 0 for the thumb, 1 for the index ... 4 for the pinky; `None`
    /// for the palm. Two fingers are neighbours when their positions differ by one.
    pub fn position(self) -> Option<usize> {
        Finger::DIGITS.iter().position(|&f| f == self)
    }
}

/// Where along its digit a segment sits (the analysis' semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointLevel {
    /// The palm itself.
    Palm,
    /// The segment nearest the palm (moved by the MCP joint; the thumb's metacarpal).
    Inner,
    /// The middle segment.
    Middle,
    /// The tip segment.
    Outer,
}

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

/// A validated hand model.
#[derive(Debug, Clone, PartialEq)]
pub struct HandModel {
    name: String,
    side: Side,
    limits: Vec<FlexLimit>,
    segments: Vec<Segment>,
    /// For every variable, a bound on how far (metres) any point of the hand moves per radian
    /// of the variable; see [`HandModel::lever`].
    levers: [f64; VARIABLE_COUNT],
}

/// Why a hand config was refused: the file, the key and the reason.
pub type HandConfigError = ConfigFileError;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandFile {
    name: String,
    side: Side,
    mirror_of: Option<PathBuf>,
    #[serde(default)]
    flex: Vec<FlexEntry>,
    #[serde(default)]
    segment: Vec<SegmentEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FlexEntry {
    name: String,
    min_deg: f64,
    max_deg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SegmentEntry {
    name: String,
    parent: String,
    finger: Finger,
    joint: JointLevel,
    origin: [f64; 3],
    #[serde(default)]
    base_rotations: Vec<AxisAngleEntry>,
    #[serde(default)]
    dofs: Vec<DofEntry>,
    shape: ShapeEntry,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisAngleEntry {
    axis: [f64; 3],
    angle_deg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DofEntry {
    axis: [f64; 3],
    pivot: Option<[f64; 3]>,
    flex: Vec<usize>,
    gains: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeEntry {
    radius: f64,
    centres: Vec<[f64; 3]>,
}

/// The name a segment config gives as parent when the segment hangs from the hand root.
const ROOT_PARENT: &str = "root";

/// Builds [`ConfigFileError::Invalid`] for `file`.
struct Refuse<'a>(&'a Path);

impl Refuse<'_> {
    fn at(&self, key: impl fmt::Display, reason: impl fmt::Display) -> HandConfigError {
        ConfigFileError::invalid(self.0, key, reason)
    }
}

impl HandModel {
    /// Reads and validates a hand config. A config with `mirror_of` is the mirror image of the
    /// named file (a path relative to this one), which must itself be a full description. Each
    /// file may have the [default](FileLimits::default) size at most.
    pub fn load(path: &Path) -> Result<HandModel, HandConfigError> {
        HandModel::load_within(path, &FileLimits::default())
    }

    /// [`HandModel::load`] of files of at most `limits.config_bytes`.
    pub fn load_within(path: &Path, limits: &FileLimits) -> Result<HandModel, HandConfigError> {
        HandModel::from_toml(path, &read_config_text(path, limits.config_bytes)?, limits)
    }

    /// [`HandModel::load_within`] on a config's text already read from `path`: errors name
    /// `path`, and a `mirror_of` file is read relative to its folder.
    pub fn from_toml(
        path: &Path,
        text: &str,
        limits: &FileLimits,
    ) -> Result<HandModel, HandConfigError> {
        let file = parse_hand_file(path, text)?;
        match &file.mirror_of {
            None => HandModel::from_file(path, file),
            Some(relative) => {
                let refuse = Refuse(path);
                if !file.flex.is_empty() || !file.segment.is_empty() {
                    return Err(refuse.at(
                        "mirror_of",
                        "a mirrored hand takes everything from its original: remove `flex` and `segment`",
                    ));
                }
                let original_path = path.parent().unwrap_or(Path::new("")).join(relative);
                let original = read_hand_file(&original_path, limits)?;
                if original.mirror_of.is_some() {
                    return Err(refuse.at(
                        "mirror_of",
                        format!("{} is itself a mirror", original_path.display()),
                    ));
                }
                if original.side != file.side.mirrored() {
                    return Err(refuse.at(
                        "side",
                        format!(
                            "a mirror of a {:?} hand is a {:?} hand",
                            original.side,
                            original.side.mirrored()
                        ),
                    ));
                }
                let mut model = HandModel::from_file(&original_path, original)?.mirrored();
                model.name = file.name;
                Ok(model)
            }
        }
    }

    fn from_file(path: &Path, file: HandFile) -> Result<HandModel, HandConfigError> {
        let refuse = Refuse(path);
        if file.flex.len() != FLEX_COUNT {
            return Err(refuse.at(
                "flex",
                format!(
                    "expected {FLEX_COUNT} entries in CyberGlove order, found {}",
                    file.flex.len()
                ),
            ));
        }
        let limits = file
            .flex
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let within = |deg: f64| deg.abs() <= MAX_FLEX_LIMIT_DEG;
                if !(within(f.min_deg) && within(f.max_deg) && f.min_deg < f.max_deg) {
                    return Err(refuse.at(
                        format!("flex[{i}] ({})", f.name),
                        format!(
                            "need finite min_deg < max_deg within ±{MAX_FLEX_LIMIT_DEG}, got {} \
                             and {}",
                            f.min_deg, f.max_deg
                        ),
                    ));
                }
                Ok(FlexLimit {
                    name: f.name.clone(),
                    min: f.min_deg.to_radians(),
                    max: f.max_deg.to_radians(),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;

        let mut index_of: HashMap<&str, SegmentId> = HashMap::new();
        let mut segments: Vec<Segment> = Vec::with_capacity(file.segment.len());
        for (i, entry) in file.segment.iter().enumerate() {
            let key = |field: &str| format!("segment[{i}] ({}).{field}", entry.name);
            if entry.name == ROOT_PARENT || index_of.contains_key(entry.name.as_str()) {
                return Err(refuse.at(key("name"), "names must be unique and not \"root\""));
            }
            let parent = if entry.parent == ROOT_PARENT {
                None
            } else {
                Some(*index_of.get(entry.parent.as_str()).ok_or_else(|| {
                    refuse.at(
                        key("parent"),
                        format!("no segment named {:?} before this one", entry.parent),
                    )
                })?)
            };
            let origin =
                length_vector(entry.origin).ok_or_else(|| refuse.at(key("origin"), too_long()))?;
            let mut base_rotation = UnitQuaternion::identity();
            for (j, r) in entry.base_rotations.iter().enumerate() {
                let axis = unit_axis(r.axis).ok_or_else(|| {
                    refuse.at(
                        key(&format!("base_rotations[{j}].axis")),
                        "must be finite and non-zero",
                    )
                })?;
                if !r.angle_deg.is_finite() {
                    return Err(
                        refuse.at(key(&format!("base_rotations[{j}].angle_deg")), "not finite")
                    );
                }
                base_rotation *= UnitQuaternion::from_axis_angle(&axis, r.angle_deg.to_radians());
            }
            let mut dofs = Vec::with_capacity(entry.dofs.len());
            let mut own = if parent.is_none() {
                VariableSet::single(ROOT_VARIABLE)
            } else {
                VariableSet::EMPTY
            };
            for (j, d) in entry.dofs.iter().enumerate() {
                let axis = unit_axis(d.axis).ok_or_else(|| {
                    refuse.at(
                        key(&format!("dofs[{j}].axis")),
                        "must be finite and non-zero",
                    )
                })?;
                if d.flex.is_empty() {
                    return Err(refuse.at(key(&format!("dofs[{j}].flex")), "names no flex value"));
                }
                if let Some(&bad) = d.flex.iter().find(|&&f| f >= FLEX_COUNT) {
                    return Err(refuse.at(
                        key(&format!("dofs[{j}].flex")),
                        format!("flex index {bad} is not below {FLEX_COUNT}"),
                    ));
                }
                let gains = match &d.gains {
                    None => vec![1.0; d.flex.len()],
                    Some(g)
                        if g.len() == d.flex.len()
                            && g.iter().all(|x| x.abs() <= MAX_FLEX_GAIN) =>
                    {
                        g.clone()
                    }
                    Some(_) => {
                        return Err(refuse.at(
                            key(&format!("dofs[{j}].gains")),
                            format!(
                                "needs one finite gain per flex index, each within \
                                 ±{MAX_FLEX_GAIN}"
                            ),
                        ));
                    }
                };
                for &f in &d.flex {
                    own = own.or(VariableSet::single(f));
                }
                let pivot =
                    match d.pivot {
                        None => Point3::origin(),
                        Some(p) => Point3::from(length_vector(p).ok_or_else(|| {
                            refuse.at(key(&format!("dofs[{j}].pivot")), too_long())
                        })?),
                    };
                dofs.push(Dof {
                    axis,
                    pivot,
                    terms: d.flex.iter().copied().zip(gains).collect(),
                });
            }
            if !(entry.shape.radius > 0.0 && entry.shape.radius <= MAX_HAND_LENGTH_M) {
                return Err(refuse.at(
                    key("shape.radius"),
                    format!("must be a positive number of metres, at most {MAX_HAND_LENGTH_M}"),
                ));
            }
            if entry.shape.centres.is_empty() {
                return Err(refuse.at(key("shape.centres"), "needs at least one sphere centre"));
            }
            let centres = entry
                .shape
                .centres
                .iter()
                .map(|&c| length_vector(c).map(Point3::from))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| refuse.at(key("shape.centres"), too_long()))?;
            let inherited = parent.map_or(VariableSet::EMPTY, |p| segments[p].variables);
            index_of.insert(entry.name.as_str(), segments.len());
            segments.push(Segment {
                name: entry.name.clone(),
                parent,
                finger: entry.finger,
                level: entry.joint,
                origin,
                base_rotation,
                dofs,
                shape: SweptHull {
                    centres,
                    radius: entry.shape.radius,
                },
                own_variables: own,
                variables: inherited.or(own),
            });
        }
        check_anatomy(&refuse, &segments)?;
        let levers = variable_levers(&segments);
        Ok(HandModel {
            name: file.name,
            side: file.side,
            limits,
            segments,
            levers,
        })
    }

    /// The mirror image of this hand in the `x = 0` plane (a right hand becomes a left hand).
    ///
    /// A reflection `S = diag(-1, 1, 1)` maps a rotation about axis `a` by `θ` to a rotation about
    /// `-S a` by `θ`, so points get `x` negated and rotation axes get `y` and `z` negated; flex
    /// values keep their meaning.
    pub fn mirrored(&self) -> HandModel {
        let point = |p: &Point3<f64>| Point3::new(-p.x, p.y, p.z);
        let axis = |a: &Unit<Vector3<f64>>| Unit::new_unchecked(Vector3::new(a.x, -a.y, -a.z));
        let rotation = |q: &UnitQuaternion<f64>| match q.axis_angle() {
            Some((a, angle)) => UnitQuaternion::from_axis_angle(&axis(&a), angle),
            None => UnitQuaternion::identity(),
        };
        let segments = self
            .segments
            .iter()
            .map(|s| Segment {
                origin: Vector3::new(-s.origin.x, s.origin.y, s.origin.z),
                base_rotation: rotation(&s.base_rotation),
                dofs: s
                    .dofs
                    .iter()
                    .map(|d| Dof {
                        axis: axis(&d.axis),
                        pivot: point(&d.pivot),
                        terms: d.terms.clone(),
                    })
                    .collect(),
                shape: SweptHull {
                    centres: s.shape.centres.iter().map(point).collect(),
                    radius: s.shape.radius,
                },
                ..s.clone()
            })
            .collect();
        HandModel {
            name: format!("{} (mirrored)", self.name),
            side: self.side.mirrored(),
            limits: self.limits.clone(),
            segments,
            levers: self.levers,
        }
    }

    /// This hand with its segments' geometry (joint origins, pivots, shapes) changed by `edit`,
    /// as a per-user calibration does; the tree, the degrees of freedom' axes and flex terms and
    /// the limits stay as they are.
    pub fn reshaped(&self, edit: impl FnOnce(&mut [Segment])) -> HandModel {
        let mut segments = self.segments.clone();
        edit(&mut segments);
        debug_assert!(
            segments
                .iter()
                .zip(&self.segments)
                .all(|(new, old)| { new.parent == old.parent && new.dofs.len() == old.dofs.len() })
        );
        let levers = variable_levers(&segments);
        HandModel {
            name: self.name.clone(),
            side: self.side,
            limits: self.limits.clone(),
            segments,
            levers,
        }
    }

    /// The model's name from its config.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Right or left hand.
    pub fn side(&self) -> Side {
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

fn read_hand_file(path: &Path, limits: &FileLimits) -> Result<HandFile, HandConfigError> {
    parse_hand_file(path, &read_config_text(path, limits.config_bytes)?)
}

fn parse_hand_file(path: &Path, text: &str) -> Result<HandFile, HandConfigError> {
    toml::from_str(text)
        .map_err(|error| ConfigFileError::syntax(path, describe_toml_error(text, &error)))
}

/// Why a position was refused.
fn too_long() -> String {
    format!("must be finite and within {MAX_HAND_LENGTH_M} m")
}

/// A position in a segment's frame: finite, every coordinate within [`MAX_HAND_LENGTH_M`].
fn length_vector(v: [f64; 3]) -> Option<Vector3<f64>> {
    v.iter()
        .all(|c| c.abs() <= MAX_HAND_LENGTH_M)
        .then(|| Vector3::from(v))
}

/// The direction of a finite, non-zero vector; scaled to a largest component of 1 first, so
/// that the square of a long vector's length does not overflow.
fn unit_axis(v: [f64; 3]) -> Option<Unit<Vector3<f64>>> {
    let v = Vector3::from(v);
    let largest = v.amax();
    (v.iter().all(|c| c.is_finite()) && largest > 0.0).then(|| Unit::new_normalize(v / largest))
}

/// Checks the structure the grasp analysis relies on: the palm first and hanging from the root,
/// then each digit a chain palm → inner → middle → outer.
fn check_anatomy(refuse: &Refuse, segments: &[Segment]) -> Result<(), HandConfigError> {
    let Some(palm) = segments.first() else {
        return Err(refuse.at("segment", "the hand has no segments"));
    };
    if palm.finger != Finger::Palm || palm.level != JointLevel::Palm || palm.parent.is_some() {
        return Err(refuse.at(
            format!("segment[0] ({})", palm.name),
            "the first segment must be the palm (finger and joint \"palm\", parent \"root\")",
        ));
    }
    for (i, s) in segments.iter().enumerate().skip(1) {
        let key = format!("segment[{i}] ({})", s.name);
        if s.finger == Finger::Palm || s.level == JointLevel::Palm {
            return Err(refuse.at(key, "only the first segment may be the palm"));
        }
        let expected_parent_level = match s.level {
            JointLevel::Inner => JointLevel::Palm,
            JointLevel::Middle => JointLevel::Inner,
            JointLevel::Outer => JointLevel::Middle,
            JointLevel::Palm => unreachable!("refused above"),
        };
        let parent = s.parent.map(|p| &segments[p]);
        let parent_ok = parent.is_some_and(|p| {
            p.level == expected_parent_level
                && (p.finger == s.finger || expected_parent_level == JointLevel::Palm)
        });
        if !parent_ok {
            return Err(refuse.at(
                format!("{key}.parent"),
                format!(
                    "a {:?} segment of the {:?} must hang from its {:?} segment",
                    s.level, s.finger, expected_parent_level
                ),
            ));
        }
    }
    for finger in Finger::DIGITS {
        for level in [JointLevel::Inner, JointLevel::Middle, JointLevel::Outer] {
            let count = segments
                .iter()
                .filter(|s| s.finger == finger && s.level == level)
                .count();
            if count != 1 {
                return Err(refuse.at(
                    "segment",
                    format!("the {finger:?} needs exactly one {level:?} segment, found {count}"),
                ));
            }
        }
    }
    Ok(())
}

/// For every variable, a bound on the distance any point of the hand moves per unit change of
/// the variable. A joint rotating by `gain · ΔF` moves the points below it by at most
/// `|gain| · ΔF` times their distance from the joint (bounded by the triangle inequality along the
/// chain); summing over every joint a variable drives covers coupled joints. For the root the
/// bound is per radian of rotation about the root; its translation moves every point one for one.
fn variable_levers(segments: &[Segment]) -> [f64; VARIABLE_COUNT] {
    // reach_below[s]: distance bound from s's joint origin to any point of s or its descendants.
    let mut reach_below: Vec<f64> = segments.iter().map(|s| s.shape.reach()).collect();
    for i in (0..segments.len()).rev() {
        if let Some(p) = segments[i].parent {
            reach_below[p] = reach_below[p].max(segments[i].origin.norm() + reach_below[i]);
        }
    }
    let mut levers = [0.0; VARIABLE_COUNT];
    for (i, s) in segments.iter().enumerate() {
        if s.parent.is_none() {
            levers[ROOT_VARIABLE] += s.origin.norm() + reach_below[i];
        }
        for dof in &s.dofs {
            for &(v, gain) in &dof.terms {
                levers[v] += gain.abs() * (dof.pivot.coords.norm() + reach_below[i]);
            }
        }
    }
    levers
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    pub(crate) fn hands_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands")
    }

    /// The project's right hand, for tests across the grasping module.
    pub(crate) fn right_hand() -> HandModel {
        HandModel::load(&hands_dir().join("right.toml")).expect("right hand loads")
    }

    fn segment(model: &HandModel, name: &str) -> SegmentId {
        model
            .segments()
            .iter()
            .position(|s| s.name == name)
            .unwrap_or_else(|| panic!("no segment {name}"))
    }

    fn assert_pose(pose: &Isometry3<f64>, translation: [f64; 3], rotation: UnitQuaternion<f64>) {
        let t = Vector3::from(translation);
        assert!(
            (pose.translation.vector - t).norm() < 1e-12,
            "translation {} != {t}",
            pose.translation.vector
        );
        assert!(
            pose.rotation.angle_to(&rotation) < 1e-12,
            "rotation {:?} != {rotation:?}",
            pose.rotation
        );
    }

    #[test]
    fn both_hands_load_with_sixteen_segments() {
        let right = right_hand();
        let left = HandModel::load(&hands_dir().join("left.toml")).unwrap();
        assert_eq!(right.segments().len(), 16);
        assert_eq!(left.side(), Side::Left);
        assert_eq!(left.name(), "left hand, 22 DOF");
        assert_eq!(right.limits()[4].name, "index inner (MCP)");
        assert!((right.limits()[4].max - 90f64.to_radians()).abs() < 1e-15);
    }

    #[test]
    fn forward_kinematics_of_a_curled_index_finger() {
        let model = right_hand();
        let mut flex = [0.0; FLEX_COUNT];
        let rest = model.segment_poses(&flex);
        assert_pose(
            &rest[segment(&model, "index outer")],
            [-0.029, 0.165, 0.0],
            UnitQuaternion::identity(),
        );

        // MCP at 90 degrees turns the finger to point palmar (-z); PIP at 90 more points it back
        // toward the wrist.
        flex[4] = FRAC_PI_2;
        flex[5] = FRAC_PI_2;
        let poses = model.segment_poses(&flex);
        let about_minus_x = |a: f64| UnitQuaternion::from_axis_angle(&-Vector3::x_axis(), a);
        // A segment's frame includes its own joint: the middle segment is turned by MCP and PIP.
        assert_pose(
            &poses[segment(&model, "index inner")],
            [-0.029, 0.095, 0.0],
            about_minus_x(FRAC_PI_2),
        );
        assert_pose(
            &poses[segment(&model, "index middle")],
            [-0.029, 0.095, -0.044],
            about_minus_x(2.0 * FRAC_PI_2),
        );
        assert_pose(
            &poses[segment(&model, "index outer")],
            [-0.029, 0.095 - 0.026, -0.044],
            about_minus_x(2.0 * FRAC_PI_2),
        );
    }

    #[test]
    fn forward_kinematics_of_wrist_spread_and_palm_arch() {
        let model = right_hand();
        let mut flex = [0.0; FLEX_COUNT];
        // Wrist flexion by 90 degrees turns the palm so that the fingers point palmar (-z).
        flex[20] = FRAC_PI_2;
        let poses = model.segment_poses(&flex);
        assert_pose(
            &poses[segment(&model, "middle inner")],
            [-0.0095, 0.0, -0.098],
            UnitQuaternion::from_axis_angle(&-Vector3::x_axis(), FRAC_PI_2),
        );

        // The palm arch swings the little finger about the palm's centre line x = 0: at 90
        // degrees its base is below the centre line.
        let mut flex = [0.0; FLEX_COUNT];
        flex[19] = FRAC_PI_2;
        let poses = model.segment_poses(&flex);
        let about_y = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2);
        assert_pose(
            &poses[segment(&model, "pinky inner")],
            [0.0, 0.088, -0.028],
            about_y,
        );
        // The ring finger gets half the arch.
        let half = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2 / 2.0);
        let s = (FRAC_PI_2 / 2.0).sin() * 0.0095;
        let c = (FRAC_PI_2 / 2.0).cos() * 0.0095;
        assert_pose(&poses[segment(&model, "ring inner")], [c, 0.095, -s], half);

        // Ring-middle spread (F14) plus pinky-ring spread (F18) turn the little finger about -z.
        let mut flex = [0.0; FLEX_COUNT];
        flex[14] = 0.1;
        flex[18] = 0.2;
        let poses = model.segment_poses(&flex);
        let spread = UnitQuaternion::from_axis_angle(&-Vector3::z_axis(), 0.3);
        assert_pose(
            &poses[segment(&model, "pinky inner")],
            [0.028, 0.088, 0.0],
            spread,
        );
        let tip = poses[segment(&model, "pinky middle")].translation.vector;
        let expected = Vector3::new(
            0.028 + 0.036 * 0.3f64.sin(),
            0.088 + 0.036 * 0.3f64.cos(),
            0.0,
        );
        assert!((tip - expected).norm() < 1e-12);
    }

    #[test]
    fn the_left_hand_is_the_mirror_image_of_the_right() {
        let right = right_hand();
        let left = HandModel::load(&hands_dir().join("left.toml")).unwrap();
        let mirror = Vector3::new(-1.0, 1.0, 1.0);
        let flex: FlexVector =
            std::array::from_fn(|i| 0.05 * (i as f64 + 1.0) * if i % 2 == 0 { 1.0 } else { -1.0 });
        let rp = right.segment_poses(&flex);
        let lp = left.segment_poses(&flex);
        for (r, l) in rp.iter().zip(&lp) {
            assert!(
                (l.translation.vector - r.translation.vector.component_mul(&mirror)).norm() < 1e-12
            );
            // S R S for S = diag(-1, 1, 1)
            let s = nalgebra::Matrix3::from_diagonal(&mirror);
            let expected = s * r.rotation.to_rotation_matrix().matrix() * s;
            assert!((l.rotation.to_rotation_matrix().matrix() - expected).norm() < 1e-12);
        }
    }

    #[test]
    fn variable_sets_follow_the_chain() {
        let model = right_hand();
        let tip = &model.segments()[segment(&model, "pinky outer")];
        for v in [ROOT_VARIABLE, 20, 21, 19, 14, 18, 15, 16, 17] {
            assert!(tip.variables.contains(v), "pinky tip depends on {v}");
        }
        assert!(!tip.variables.contains(4));
        assert_eq!(tip.own_variables, VariableSet::single(17));
        let palm = &model.segments()[model.palm()];
        assert_eq!(
            palm.own_variables.iter().collect::<Vec<_>>(),
            vec![20, 21, ROOT_VARIABLE]
        );
        // Every variable moves something, and the root's lever is the hand's reach (about 20 cm).
        for v in 0..VARIABLE_COUNT {
            assert!(model.lever(v) > 0.01, "variable {v}");
        }
        assert!(
            (0.15..0.3).contains(&model.lever(ROOT_VARIABLE)),
            "{}",
            model.lever(ROOT_VARIABLE)
        );
    }

    fn refusal(text: &str) -> String {
        HandModel::from_toml(Path::new("hand.toml"), text, &FileLimits::default())
            .unwrap_err()
            .to_string()
    }

    fn right_text() -> String {
        std::fs::read_to_string(hands_dir().join("right.toml")).unwrap()
    }

    #[test]
    fn bad_configs_are_refused_naming_file_key_and_reason() {
        let text = right_text();
        let cases = [
            (
                text.replacen(
                    "[[flex]]\nname = \"thumb roll\"\nmin_deg = -30\nmax_deg = 70\n",
                    "",
                    1,
                ),
                "hand.toml: flex: expected 22 entries",
            ),
            (
                text.replacen("max_deg = 70", "max_deg = -40", 1),
                "hand.toml: flex[0] (thumb roll): need finite min_deg < max_deg",
            ),
            (
                text.replacen("parent = \"index inner\"", "parent = \"indx inner\"", 1),
                "segment[5] (index middle).parent: no segment named \"indx inner\"",
            ),
            (
                text.replacen(
                    "axis = [-1.0, 0.0, 0.0], flex = [5]",
                    "axis = [0.0, 0.0, 0.0], flex = [5]",
                    1,
                ),
                "segment[5] (index middle).dofs[0].axis: must be finite and non-zero",
            ),
            (
                text.replacen("flex = [5]", "flex = [22]", 1),
                "segment[5] (index middle).dofs[0].flex: flex index 22 is not below 22",
            ),
            (
                text.replacen(
                    "flex = [19], gains = [0.5]",
                    "flex = [19], gains = [0.5, 1.0]",
                    1,
                ),
                "segment[10] (ring inner).dofs[0].gains",
            ),
            (
                text.replacen("radius = 0.0088, centres", "radius = -0.0088, centres", 1),
                "segment[5] (index middle).shape.radius",
            ),
            (
                text.replacen("name = \"index outer\"", "name = \"index middle\"", 1),
                "segment[6] (index middle).name: names must be unique",
            ),
            (
                text.replacen(
                    "finger = \"pinky\"\njoint = \"outer\"",
                    "finger = \"pinky\"\njoint = \"middle\"",
                    1,
                ),
                "segment[15] (pinky outer).parent: a Middle segment of the Pinky must hang from its Inner segment",
            ),
            (
                text.replacen(
                    "origin = [0.0, 0.048, 0.0]",
                    "origin = [0.0, 0.048, nan]",
                    1,
                ),
                "segment[2] (thumb middle).origin: must be finite and within 10 m",
            ),
            (
                text.replacen("side = \"right\"", "side = \"right\"\nhandedness = 1", 1),
                "unknown field `handedness`",
            ),
        ];
        for (config, expected) in cases {
            let message = refusal(&config);
            assert!(
                message.contains(expected),
                "expected {expected:?} in {message:?}"
            );
            assert!(message.starts_with("hand.toml"), "{message}");
        }
    }

    #[test]
    fn values_that_would_make_poses_non_finite_are_refused() {
        // Each was accepted, and gave infinite levers or NaN segment poses.
        let text = right_text();
        let cases = [
            (
                text.replacen(
                    "origin = [0.0, 0.048, 0.0]",
                    "origin = [0.0, 1e308, 0.0]",
                    1,
                ),
                "segment[2] (thumb middle).origin: must be finite and within 10 m",
            ),
            (
                text.replacen(
                    "pivot = [-0.0095, 0.0, 0.0]",
                    "pivot = [-1e300, 0.0, 0.0]",
                    1,
                ),
                "segment[10] (ring inner).dofs[0].pivot: must be finite and within 10 m",
            ),
            (
                text.replacen("[0.0, 0.026, 0.0]] }", "[0.0, 1e300, 0.0]] }", 1),
                "segment[5] (index middle).shape.centres: must be finite and within 10 m",
            ),
            (
                text.replacen("radius = 0.0088, centres", "radius = 1e300, centres", 1),
                "segment[5] (index middle).shape.radius",
            ),
            (
                text.replacen("gains = [0.5]", "gains = [1e300]", 1),
                "segment[10] (ring inner).dofs[0].gains: needs one finite gain per flex index, \
                 each within ±100",
            ),
            (
                text.replacen(
                    "name = \"palm arch\"\nmin_deg = -10\nmax_deg = 40",
                    "name = \"palm arch\"\nmin_deg = -10\nmax_deg = 1e300",
                    1,
                ),
                "flex[19] (palm arch): need finite min_deg < max_deg within ±360",
            ),
        ];
        for (config, expected) in cases {
            let message = refusal(&config);
            assert!(
                message.contains(expected),
                "expected {expected:?} in {message:?}"
            );
        }
    }

    #[test]
    fn a_long_joint_axis_is_normalised_without_overflow() {
        // The square of its length overflowed, and the axis became the zero vector.
        let text = right_text().replacen(
            "axis = [-1.0, 0.0, 0.0], flex = [5]",
            "axis = [-1e308, -1e308, 0.0], flex = [5]",
            1,
        );
        let model = HandModel::from_toml(Path::new("hand.toml"), &text, &FileLimits::default())
            .expect("loads");
        let axis = model.segments()[segment(&model, "index middle")].dofs[0].axis;
        let expected = Vector3::new(-1.0, -1.0, 0.0).normalize();
        assert!((axis.into_inner() - expected).norm() < 1e-12, "{axis:?}");
    }

    #[test]
    fn a_mirror_must_name_a_full_hand_of_the_other_side() {
        let dir = std::env::temp_dir().join(format!("vas-hand-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("right.toml"), right_text()).unwrap();
        std::fs::write(
            dir.join("wrong.toml"),
            "name = \"x\"\nside = \"right\"\nmirror_of = \"right.toml\"\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("chain.toml"),
            "name = \"x\"\nside = \"right\"\nmirror_of = \"left.toml\"\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("left.toml"),
            "name = \"x\"\nside = \"left\"\nmirror_of = \"right.toml\"\n",
        )
        .unwrap();
        let wrong = HandModel::load(&dir.join("wrong.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            wrong.contains("wrong.toml: side: a mirror of a Right hand is a Left hand"),
            "{wrong}"
        );
        let chain = HandModel::load(&dir.join("chain.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            chain.contains("chain.toml: mirror_of:") && chain.contains("is itself a mirror"),
            "{chain}"
        );
        let missing = HandModel::load(&dir.join("absent.toml"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("absent.toml: cannot read"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
