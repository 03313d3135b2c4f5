//! Reading a hand config: the file's TOML, every value checked, the segments' tree built, and a
//! `mirror_of` config made from its original.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use nalgebra::{Point3, Unit, UnitQuaternion, Vector3};

use super::file::{
    DofEntry, FlexEntry, HandFile, ROOT_PARENT, SegmentEntry, ShapeEntry, parse_hand_file,
    read_hand_file,
};
use super::{
    Dof, FLEX_COUNT, Finger, FlexLimit, HandConfigError, HandModel, JointLevel, MAX_FLEX_GAIN,
    MAX_FLEX_LIMIT_DEG, MAX_HAND_LENGTH_M, ROOT_VARIABLE, Segment, SegmentId, SweptHull,
    VARIABLE_COUNT, VariableSet,
};
use crate::geometry::{ConfigFileError, FileLimits, read_config_text};

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

    /// The model a full description (no `mirror_of`) gives: its flex limits, its segments' tree,
    /// checked for the anatomy the grasp analysis relies on.
    fn from_file(path: &Path, file: HandFile) -> Result<HandModel, HandConfigError> {
        let refuse = Refuse(path);
        let limits = flex_limits(&refuse, &file.flex)?;
        let segments = segments(&refuse, &file.segment)?;
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
}

/// The joint limits of the 22 flex values, in CyberGlove order.
fn flex_limits(refuse: &Refuse, entries: &[FlexEntry]) -> Result<Vec<FlexLimit>, HandConfigError> {
    if entries.len() != FLEX_COUNT {
        return Err(refuse.at(
            "flex",
            format!(
                "expected {FLEX_COUNT} entries in CyberGlove order, found {}",
                entries.len()
            ),
        ));
    }
    entries
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
        .collect()
}

/// The segments, each hanging from the root or from a segment listed before it.
fn segments(refuse: &Refuse, entries: &[SegmentEntry]) -> Result<Vec<Segment>, HandConfigError> {
    let mut index_of: HashMap<&str, SegmentId> = HashMap::new();
    let mut segments: Vec<Segment> = Vec::with_capacity(entries.len());
    for (i, entry) in entries.iter().enumerate() {
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
                return Err(refuse.at(key(&format!("base_rotations[{j}].angle_deg")), "not finite"));
            }
            base_rotation *= UnitQuaternion::from_axis_angle(&axis, r.angle_deg.to_radians());
        }
        let mut own = if parent.is_none() {
            VariableSet::single(ROOT_VARIABLE)
        } else {
            VariableSet::EMPTY
        };
        let mut dofs = Vec::with_capacity(entry.dofs.len());
        for (j, entry) in entry.dofs.iter().enumerate() {
            let dof = dof(refuse, &|field| key(&format!("dofs[{j}].{field}")), entry)?;
            for &(flex, _) in &dof.terms {
                own = own.or(VariableSet::single(flex));
            }
            dofs.push(dof);
        }
        let shape = swept_hull(
            refuse,
            &|field| key(&format!("shape.{field}")),
            &entry.shape,
        )?;
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
            shape,
            own_variables: own,
            variables: inherited.or(own),
        });
    }
    Ok(segments)
}

/// One revolute degree of freedom: its axis, pivot and flex terms; `key` names a field of it.
fn dof(
    refuse: &Refuse,
    key: &dyn Fn(&str) -> String,
    d: &DofEntry,
) -> Result<Dof, HandConfigError> {
    let axis =
        unit_axis(d.axis).ok_or_else(|| refuse.at(key("axis"), "must be finite and non-zero"))?;
    if d.flex.is_empty() {
        return Err(refuse.at(key("flex"), "names no flex value"));
    }
    if let Some(&bad) = d.flex.iter().find(|&&f| f >= FLEX_COUNT) {
        return Err(refuse.at(
            key("flex"),
            format!("flex index {bad} is not below {FLEX_COUNT}"),
        ));
    }
    let gains = match &d.gains {
        None => vec![1.0; d.flex.len()],
        Some(g) if g.len() == d.flex.len() && g.iter().all(|x| x.abs() <= MAX_FLEX_GAIN) => {
            g.clone()
        }
        Some(_) => {
            return Err(refuse.at(
                key("gains"),
                format!("needs one finite gain per flex index, each within ±{MAX_FLEX_GAIN}"),
            ));
        }
    };
    let pivot = match d.pivot {
        None => Point3::origin(),
        Some(p) => {
            Point3::from(length_vector(p).ok_or_else(|| refuse.at(key("pivot"), too_long()))?)
        }
    };
    Ok(Dof {
        axis,
        pivot,
        terms: d.flex.iter().copied().zip(gains).collect(),
    })
}

/// A segment's collision shape; `key` names a field of it.
fn swept_hull(
    refuse: &Refuse,
    key: &dyn Fn(&str) -> String,
    shape: &ShapeEntry,
) -> Result<SweptHull, HandConfigError> {
    if !(shape.radius > 0.0 && shape.radius <= MAX_HAND_LENGTH_M) {
        return Err(refuse.at(
            key("radius"),
            format!("must be a positive number of metres, at most {MAX_HAND_LENGTH_M}"),
        ));
    }
    if shape.centres.is_empty() {
        return Err(refuse.at(key("centres"), "needs at least one sphere centre"));
    }
    let centres = shape
        .centres
        .iter()
        .map(|&c| length_vector(c).map(Point3::from))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| refuse.at(key("centres"), too_long()))?;
    Ok(SweptHull {
        centres,
        radius: shape.radius,
    })
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
pub(super) fn variable_levers(segments: &[Segment]) -> [f64; VARIABLE_COUNT] {
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
