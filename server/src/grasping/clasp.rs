//! The clasp minimisation (the paper's section 4, Figure 10): move the hand from its last valid
//! configuration toward a new target as far as it can go without any segment intersecting a
//! part, and find which segments touch what.
//!
//! The hand's configuration is the root pose `M` and the 22 flex values `F`: 23 variables. Each
//! variable has an interval between its valid value (`lo`, from the last valid configuration,
//! known to be free) and its invalid value (`hi`, the target until a collision says otherwise),
//! kept as interpolation parameters in `[0, 1]`: flex values linearly, the root's position linearly
//! and its rotation by slerp. Each step tries one configuration:
//!
//! * every unfixed variable at a trial value inside its interval (the target first; after a
//!   collision at the target, a step just past the fixing tolerance, since a hand pressed against
//!   a part is usually at it already; otherwise the middle);
//! * the segments that move are checked for collision, the palm first, then from the
//!   fingertips toward the palm; a segment whose moving variables are all blamed by a collision
//!   already is not checked, since its answer could change nothing but its own collision flag
//!   (and near misses, a segment resting a fraction of a millimetre from a part, are the
//!   costliest queries);
//! * a variable is *colliding* if a segment depending on it collides: its `hi` becomes the trial;
//! * the other variables' `lo` become the trial, except where a segment depends on both a
//!   colliding and a non-colliding variable: that segment was never checked at the mixed pose the
//!   new `lo` values would give, so those variables keep their `lo`. This keeps the invariant that
//!   the configuration of all `lo` values is free: the result is collision-free by construction.
//! * a variable whose interval is narrower than its tolerance (radians for a flex value, metres
//!   of motion of any hand point for the root) is fixed; several may be fixed in one step; a cap
//!   on the steps fixes the rest.
//!
//! The root is minimised first, with the flex values at their valid values, then the flex values
//! with the root fixed: two stages of the same iteration. Interpolated together, as the paper
//! has it, the root would be blamed for every collision of every segment, since every segment
//! depends on it: fingers pressing on a part (the glove closes further than the virtual fingers
//! can) would stop the whole hand, and a hand holding a part could not carry it anywhere.
//!
//! Touch flags follow the paper: a segment's collision flag is set whenever it collides; when a
//! variable the segment's joint owns is fixed, the segment is marked touching if its flag is set;
//! then the flags of the segments further down the chain are cleared, because their collisions may
//! have been caused by this joint's motion. Variables fixed in the same step are taken from the
//! fingertips toward the root, so that a fingertip resting on a part while the whole finger
//! presses on is marked before its parents clear its flag.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use super::model::{FlexVector, HandModel, ROOT_VARIABLE, SegmentId, VARIABLE_COUNT, VariableSet};

/// The number of segments of every hand: the palm and five digits of three segments.
pub const SEGMENT_COUNT: usize = 16;

/// A set of objects, bit `k` standing for the collider's object `k` (at most 64 objects near a
/// hand at once).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct ObjectSet(pub u64);

impl ObjectSet {
    /// No object.
    pub const EMPTY: ObjectSet = ObjectSet(0);

    /// The set holding only object `k` (`k < 64`).
    pub fn single(k: usize) -> Self {
        ObjectSet(1 << k)
    }

    /// True when no object is in the set.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// True when object `k` is in the set.
    pub fn contains(self, k: usize) -> bool {
        k < 64 && self.0 & (1 << k) != 0
    }

    /// The objects in either set.
    pub fn union(self, other: ObjectSet) -> Self {
        ObjectSet(self.0 | other.0)
    }

    /// The objects, in increasing order.
    pub fn iter(self) -> impl Iterator<Item = usize> {
        (0..64).filter(move |&k| self.contains(k))
    }
}

/// A hand configuration: the root pose `M` (world) and the flex vector `F`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandPose {
    /// The hand root (the tracked wrist) in the world.
    pub root: Isometry3<f64>,
    /// The 22 joint angles, radians.
    pub flex: FlexVector,
}

/// Where a segment is during a trial: the hand root in the world and the segment relative to
/// the root. Objects attached to the hand are checked in the root's frame, so that moving the
/// root never makes them collide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentPlacement {
    /// The hand root in the world.
    pub root: Isometry3<f64>,
    /// The segment in the root's frame.
    pub local: Isometry3<f64>,
    /// True when every flex value is at its valid value, so that the segment is where it was
    /// relative to the root in the valid configuration: objects attached to the hand cannot
    /// collide with it and need no check.
    pub flex_valid: bool,
}

impl SegmentPlacement {
    /// The segment in the world.
    pub fn world(&self) -> Isometry3<f64> {
        self.root * self.local
    }
}

/// Tuning of the clasp minimisation, read from a scene's `[params.clasp]` table; every field has
/// a default.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClaspParams {
    /// A flex value is fixed when its valid-invalid interval is narrower than this (radians).
    pub flex_tolerance: f64,
    /// The root is fixed when its valid-invalid interval moves no point of the hand by more
    /// than this (metres).
    pub root_tolerance: f64,
    /// Cap on the iteration steps of each stage (root, then flex values); what is left unfixed
    /// stays at its valid value.
    pub max_steps: u32,
    /// The most any variable may move the hand per minimisation (metres). A target farther away
    /// is approached over several frames, so a jump of the tracker or glove cannot carry a
    /// segment through a thin part; at the input rates of trackers and gloves it never limits.
    pub max_motion: f64,
}

impl Default for ClaspParams {
    fn default() -> Self {
        ClaspParams {
            flex_tolerance: 0.005,
            root_tolerance: 0.0005,
            max_steps: 24,
            max_motion: 0.005,
        }
    }
}

/// A clasp parameter outside its valid range: the key and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("clasp.{key}: {reason}")]
pub struct ClaspParamError {
    /// The offending key, relative to the `[clasp]` table.
    pub key: &'static str,
    /// Why its value is refused.
    pub reason: String,
}

/// The most steps a stage may be allowed: far more than any minimisation needs, so that a typo
/// cannot make one frame's minimisation run for seconds.
const MAX_STEPS_LIMIT: u32 = 10_000;

impl ClaspParams {
    /// Checks every value's range, so that a scene with bad clasp parameters is refused at load.
    pub fn validate(&self) -> Result<(), ClaspParamError> {
        let within = |key: &'static str, value: f64, max: f64, unit: &str| {
            if value.is_finite() && value > 0.0 && value <= max {
                Ok(())
            } else {
                Err(ClaspParamError {
                    key,
                    reason: format!(
                        "must be positive and at most {max} {unit}, got {}",
                        vas_protocol::Readable(value)
                    ),
                })
            }
        };
        within("flex_tolerance", self.flex_tolerance, 0.5, "rad")?;
        within("root_tolerance", self.root_tolerance, 0.1, "m")?;
        within("max_motion", self.max_motion, 1.0, "m")?;
        if !(1..=MAX_STEPS_LIMIT).contains(&self.max_steps) {
            return Err(ClaspParamError {
                key: "max_steps",
                reason: format!(
                    "must be between 1 and {MAX_STEPS_LIMIT}, got {}",
                    self.max_steps
                ),
            });
        }
        Ok(())
    }
}

/// What one minimisation found.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaspOutcome {
    /// The new valid configuration: collision-free if the start was.
    pub pose: HandPose,
    /// Per segment, the objects it was marked touching by the touch-flag rules.
    pub touching: [ObjectSet; SEGMENT_COUNT],
    /// Iteration steps taken.
    pub steps: u32,
    /// Segment collision checks made.
    pub checks: u32,
    /// True when every variable reached its target.
    pub reached_target: bool,
}

/// The hand's motion from a valid configuration toward a target, as interpolation of the 23
/// variables with parameters in `[0, 1]`.
struct Path {
    from: HandPose,
    to: HandPose,
    /// Root rotation from `from` to `to`, as a rotation vector in the `from` root's frame.
    rotation: nalgebra::Vector3<f64>,
    /// Per variable, a bound on how far a hand point moves over the whole path (metres).
    motion: [f64; VARIABLE_COUNT],
}

impl Path {
    fn new(model: &HandModel, from: &HandPose, to: &HandPose, max_motion: f64) -> (Path, bool) {
        let mut to = *to;
        let mut clipped = false;
        let mut motion = [0.0; VARIABLE_COUNT];
        for (v, (goal, start)) in to.flex.iter_mut().zip(&from.flex).enumerate() {
            let delta = *goal - start;
            motion[v] = delta.abs() * model.lever(v);
            if motion[v] > max_motion {
                *goal = start + delta * max_motion / motion[v];
                motion[v] = max_motion;
                clipped = true;
            }
        }
        let mut rotation = (from.root.rotation.inverse() * to.root.rotation).scaled_axis();
        let mut translation = to.root.translation.vector - from.root.translation.vector;
        let root_motion = translation.norm() + rotation.norm() * model.lever(ROOT_VARIABLE);
        motion[ROOT_VARIABLE] = root_motion;
        if root_motion > max_motion {
            let scale = max_motion / root_motion;
            rotation *= scale;
            translation *= scale;
            motion[ROOT_VARIABLE] = max_motion;
            clipped = true;
        }
        to.root = Isometry3::from_parts(
            Translation3::from(from.root.translation.vector + translation),
            from.root.rotation * UnitQuaternion::from_scaled_axis(rotation),
        );
        (
            Path {
                from: *from,
                to,
                rotation,
                motion,
            },
            clipped,
        )
    }

    /// The configuration with each variable at its parameter.
    fn at(&self, t: &[f64; VARIABLE_COUNT]) -> HandPose {
        let flex = std::array::from_fn(|v| {
            self.from.flex[v] + t[v] * (self.to.flex[v] - self.from.flex[v])
        });
        let s = t[ROOT_VARIABLE];
        let translation = self
            .from
            .root
            .translation
            .vector
            .lerp(&self.to.root.translation.vector, s);
        let rotation =
            self.from.root.rotation * UnitQuaternion::from_scaled_axis(self.rotation * s);
        HandPose {
            root: Isometry3::from_parts(Translation3::from(translation), rotation),
            flex,
        }
    }
}

/// Per-model facts the minimisation needs, computed once.
#[derive(Debug, Clone)]
pub struct ClaspPlan {
    /// Per segment, the variables its pose depends on.
    depends: [VariableSet; SEGMENT_COUNT],
    /// Per variable, the segments whose joint owns it.
    owners: [u16; VARIABLE_COUNT],
    /// Per variable, the segments depending on it but not owning it (whose flags its fixing clears).
    dependents: [u16; VARIABLE_COUNT],
    /// The variables from the fingertips toward the root: the order of fixing within a step.
    fixing_order: [usize; VARIABLE_COUNT],
    /// The palm, then the segments from the fingertips toward the palm: the order of checking
    /// within a step.
    checking_order: [SegmentId; SEGMENT_COUNT],
}

impl ClaspPlan {
    /// Derives the dependency structure of `model`, which must have [`SEGMENT_COUNT`] segments
    /// (every validated hand model has).
    pub fn new(model: &HandModel) -> ClaspPlan {
        let segments = model.segments();
        assert_eq!(
            segments.len(),
            SEGMENT_COUNT,
            "a validated hand has {SEGMENT_COUNT} segments"
        );
        let depends = std::array::from_fn(|s| segments[s].variables);
        let mut owners = [0u16; VARIABLE_COUNT];
        let mut dependents = [0u16; VARIABLE_COUNT];
        let mut depth = [0usize; VARIABLE_COUNT];
        let mut segment_depth = [0usize; SEGMENT_COUNT];
        for (s, segment) in segments.iter().enumerate() {
            segment_depth[s] = segment.parent.map_or(0, |p| segment_depth[p] + 1);
            for v in segment.own_variables.iter() {
                owners[v] |= 1 << s;
                depth[v] = depth[v].max(segment_depth[s]);
            }
            for v in segment.variables.without(segment.own_variables).iter() {
                dependents[v] |= 1 << s;
            }
        }
        let mut fixing_order: [usize; VARIABLE_COUNT] = std::array::from_fn(|v| v);
        fixing_order.sort_by_key(|&v| std::cmp::Reverse(depth[v]));
        // The palm first: it owns the root, whose fixing clears every other segment's flag, so
        // its flag is the one a root collision must set. Then the fingertips toward the palm.
        let mut checking_order: [SegmentId; SEGMENT_COUNT] = std::array::from_fn(|s| s);
        checking_order.sort_by_key(|&s| (s != model.palm(), std::cmp::Reverse(segment_depth[s])));
        ClaspPlan {
            depends,
            owners,
            dependents,
            fixing_order,
            checking_order,
        }
    }
}

/// Runs the clasp minimisation from the valid configuration `valid` toward `target`.
///
/// `collides(segment, placement)` answers which objects the segment intersects at a trial
/// placement (empty when none); the minimisation never looks at geometry itself, so it works with
/// any collision test. The returned configuration is free of collisions provided `valid` is.
pub fn clasp<F>(
    model: &HandModel,
    plan: &ClaspPlan,
    valid: &HandPose,
    target: &HandPose,
    params: &ClaspParams,
    mut collides: F,
) -> ClaspOutcome
where
    F: FnMut(SegmentId, &SegmentPlacement) -> ObjectSet,
{
    let (path, clipped) = Path::new(model, valid, target, params.max_motion);
    let mut run = Minimisation::new(model, plan, &path, params);
    let root = VariableSet::single(ROOT_VARIABLE);
    for stage in [root, VariableSet::ALL.without(root)] {
        run.stage(stage, &mut collides);
    }
    let reached_target =
        !clipped && (0..VARIABLE_COUNT).all(|v| run.lo[v] == 1.0 || path.motion[v] == 0.0);
    ClaspOutcome {
        pose: path.at(&run.lo),
        touching: run.touching,
        steps: run.steps,
        checks: run.checks,
        reached_target,
    }
}

/// One clasp minimisation under way: per variable, the valid (`lo`) and colliding (`hi`) end of
/// its interval along the path; per segment, its collision flags and its touch flags.
struct Minimisation<'a> {
    model: &'a HandModel,
    plan: &'a ClaspPlan,
    path: &'a Path,
    params: &'a ClaspParams,
    /// Per variable, the tolerance in the units of `path.motion` (metres of hand motion).
    tolerance: [f64; VARIABLE_COUNT],
    lo: [f64; VARIABLE_COUNT],
    hi: [f64; VARIABLE_COUNT],
    flags: [ObjectSet; SEGMENT_COUNT],
    touching: [ObjectSet; SEGMENT_COUNT],
    poses: [Isometry3<f64>; SEGMENT_COUNT],
    steps: u32,
    checks: u32,
}

impl<'a> Minimisation<'a> {
    fn new(
        model: &'a HandModel,
        plan: &'a ClaspPlan,
        path: &'a Path,
        params: &'a ClaspParams,
    ) -> Self {
        Minimisation {
            model,
            plan,
            path,
            params,
            tolerance: std::array::from_fn(|v| {
                if v == ROOT_VARIABLE {
                    params.root_tolerance
                } else {
                    params.flex_tolerance * model.lever(v)
                }
            }),
            lo: [0.0; VARIABLE_COUNT],
            hi: [1.0; VARIABLE_COUNT],
            flags: [ObjectSet::EMPTY; SEGMENT_COUNT],
            touching: [ObjectSet::EMPTY; SEGMENT_COUNT],
            poses: [Isometry3::identity(); SEGMENT_COUNT],
            steps: 0,
            checks: 0,
        }
    }

    /// Minimises the variables of `stage` until each is fixed: trial values, a check of the
    /// segments that move, the intervals narrowed, then what is close enough fixed.
    fn stage<F>(&mut self, stage: VariableSet, collides: &mut F)
    where
        F: FnMut(SegmentId, &SegmentPlacement) -> ObjectSet,
    {
        // A stage whose variables do not move would only re-check the valid configuration.
        let mut unfixed = if stage.iter().all(|v| self.path.motion[v] == 0.0) {
            VariableSet::EMPTY
        } else {
            stage
        };
        let mut first_trial = true;
        let mut near_step_pending = VariableSet::EMPTY;
        let mut stage_steps = 0;
        while !unfixed.is_empty() {
            let trial = self.trial(unfixed, first_trial, near_step_pending);
            let colliding = self.check(&trial, unfixed, collides);
            near_step_pending = self.narrow(&trial, unfixed, colliding, first_trial);
            first_trial = false;
            self.steps += 1;
            stage_steps += 1;
            unfixed = self.fix(unfixed, stage_steps >= self.params.max_steps);
        }
    }

    /// Step 1, the trial values: the target first, then the middle of each unfixed interval (just
    /// short of the tolerance past the valid value, for a variable whose target collided).
    fn trial(
        &self,
        unfixed: VariableSet,
        first_trial: bool,
        near_step_pending: VariableSet,
    ) -> [f64; VARIABLE_COUNT] {
        let (lo, hi) = (&self.lo, &self.hi);
        let mut trial = *lo;
        for v in unfixed.iter() {
            trial[v] = if first_trial {
                1.0
            } else if near_step_pending.contains(v) {
                // If this collides, the variable is fixed at once.
                let near = lo[v] + 0.9 * self.tolerance[v] / self.path.motion[v];
                near.min(0.5 * (lo[v] + hi[v]))
            } else {
                0.5 * (lo[v] + hi[v])
            };
        }
        trial
    }

    /// Step 2: checks the segments that move at `trial`; the unfixed variables they blame.
    fn check<F>(
        &mut self,
        trial: &[f64; VARIABLE_COUNT],
        unfixed: VariableSet,
        collides: &mut F,
    ) -> VariableSet
    where
        F: FnMut(SegmentId, &SegmentPlacement) -> ObjectSet,
    {
        let (plan, path) = (self.plan, self.path);
        let pose = path.at(trial);
        self.model.forward_kinematics(&pose.flex, &mut self.poses);
        // A segment none of whose variables leaves its valid value is where the valid
        // configuration has it: free, no need to check.
        let moved = unfixed
            .iter()
            .filter(|&v| trial[v] != self.lo[v] && path.motion[v] > 0.0)
            .fold(VariableSet::EMPTY, |acc, v| acc.or(VariableSet::single(v)));
        let flex_valid =
            !moved.intersects(VariableSet::ALL.without(VariableSet::single(ROOT_VARIABLE)));
        let mut colliding = VariableSet::EMPTY;
        for &s in &plan.checking_order {
            // Checking a segment whose moving variables are all blamed already could change
            // nothing but its own touch flag: skip it (fingertips, checked early, collide
            // most often and spare their fingers' other segments).
            let moving = plan.depends[s].and(moved);
            if moving.is_empty() || moving.without(colliding).is_empty() {
                continue;
            }
            self.checks += 1;
            let hit = collides(
                s,
                &SegmentPlacement {
                    root: pose.root,
                    local: self.poses[s],
                    flex_valid,
                },
            );
            if !hit.is_empty() {
                self.flags[s] = self.flags[s].union(hit);
                colliding = colliding.or(plan.depends[s]);
            }
        }
        colliding.and(unfixed)
    }

    /// Step 3: lowers the colliding end of the blamed variables and raises the valid end where the
    /// new configuration of valid values was checked whole; the variables whose first trial
    /// collided, for a near step next.
    fn narrow(
        &mut self,
        trial: &[f64; VARIABLE_COUNT],
        unfixed: VariableSet,
        colliding: VariableSet,
        first_trial: bool,
    ) -> VariableSet {
        let mut raised = unfixed.without(colliding);
        loop {
            let before = raised;
            for depends in &self.plan.depends {
                let moving = depends.and(unfixed);
                if moving.intersects(raised) && !moving.without(raised).is_empty() {
                    raised = raised.without(moving);
                }
            }
            if raised == before {
                break;
            }
        }
        let mut near_step_pending = VariableSet::EMPTY;
        for v in colliding.iter() {
            self.hi[v] = trial[v];
            if first_trial {
                near_step_pending = near_step_pending.or(VariableSet::single(v));
            }
        }
        for v in raised.iter() {
            self.lo[v] = trial[v];
        }
        near_step_pending
    }

    /// Step 4: fixes what is close enough (everything `at_cap`), fingertips first: a fixed variable's
    /// segments take their collision flags as touch flags, and the segments it carries forget
    /// theirs. The variables still unfixed.
    fn fix(&mut self, mut unfixed: VariableSet, at_cap: bool) -> VariableSet {
        let plan = self.plan;
        for &v in &plan.fixing_order {
            let close = (self.hi[v] - self.lo[v]) * self.path.motion[v] <= self.tolerance[v];
            if !unfixed.contains(v) || !(at_cap || close) {
                continue;
            }
            unfixed = unfixed.without(VariableSet::single(v));
            for s in bits(plan.owners[v]) {
                self.touching[s] = self.touching[s].union(self.flags[s]);
            }
            for s in bits(plan.dependents[v]) {
                self.flags[s] = ObjectSet::EMPTY;
            }
        }
        unfixed
    }
}

/// The indices of the set bits of a segment mask.
fn bits(mask: u16) -> impl Iterator<Item = usize> {
    (0..SEGMENT_COUNT).filter(move |&s| mask & (1 << s) != 0)
}
