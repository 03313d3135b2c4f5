//! The collision interest matrix: which object pairs are worth testing at all (PAPER §2).
//!
//! Two static objects are never tested (neither can ever move into the other). Beyond that, pairs
//! can be ruled out by group (the parts of one welded assembly, the hand against itself) and by
//! object (two parts that touch by design). The matrix knows nothing of scenes: the scene loader
//! maps its group names and part names onto [`GroupId`]s and [`ObjectId`]s.

use super::objects::ObjectId;
use rustc_hash::FxHashSet;

/// A collision group: objects are assigned one each; rules between groups apply to all members.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GroupId(pub u16);

/// What the interest matrix looks at for one object of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InterestKey {
    /// The object.
    pub object: ObjectId,
    /// Its collision group.
    pub group: GroupId,
    /// Whether it never moves.
    pub is_static: bool,
}

/// Rules saying which object pairs are of no interest; everything else is tested.
#[derive(Debug, Clone, Default)]
pub struct InterestMatrix {
    /// Row-major `group_count × group_count`, symmetric: true where a group pair is ruled out.
    disallowed_groups: Vec<bool>,
    group_count: usize,
    /// Ruled-out object pairs, smaller id first.
    disallowed_objects: FxHashSet<(ObjectId, ObjectId)>,
}

impl InterestMatrix {
    /// A matrix that rules out only static-static pairs.
    pub fn new() -> Self {
        Self::default()
    }

    /// Rules out every pair with one object in group `a` and the other in group `b` (`a == b`
    /// rules out pairs within the group).
    pub fn disallow_groups(&mut self, a: GroupId, b: GroupId) {
        self.set_groups(a, b, true);
    }

    /// Undoes [`InterestMatrix::disallow_groups`].
    pub fn allow_groups(&mut self, a: GroupId, b: GroupId) {
        self.set_groups(a, b, false);
    }

    fn set_groups(&mut self, a: GroupId, b: GroupId, disallowed: bool) {
        let needed = usize::from(a.0.max(b.0)) + 1;
        if needed > self.group_count {
            let mut grown = vec![false; needed * needed];
            for row in 0..self.group_count {
                for column in 0..self.group_count {
                    grown[row * needed + column] =
                        self.disallowed_groups[row * self.group_count + column];
                }
            }
            self.disallowed_groups = grown;
            self.group_count = needed;
        }
        let (a, b) = (usize::from(a.0), usize::from(b.0));
        self.disallowed_groups[a * self.group_count + b] = disallowed;
        self.disallowed_groups[b * self.group_count + a] = disallowed;
    }

    /// Rules out the pair of objects `a` and `b`.
    pub fn disallow_objects(&mut self, a: ObjectId, b: ObjectId) {
        self.disallowed_objects.insert(ordered(a, b));
    }

    /// Drops every rule naming `object` (called when it leaves the scene).
    pub fn forget_object(&mut self, object: ObjectId) {
        self.disallowed_objects
            .retain(|&(a, b)| a != object && b != object);
    }

    /// How many groups the matrix has rows for: one more than the highest group id of a rule.
    pub fn group_count(&self) -> usize {
        self.group_count
    }

    /// True when the pair must be tested.
    pub fn is_interesting(&self, a: &InterestKey, b: &InterestKey) -> bool {
        if a.is_static && b.is_static {
            return false;
        }
        let (ga, gb) = (usize::from(a.group.0), usize::from(b.group.0));
        if ga < self.group_count
            && gb < self.group_count
            && self.disallowed_groups[ga * self.group_count + gb]
        {
            return false;
        }
        self.disallowed_objects.is_empty()
            || !self
                .disallowed_objects
                .contains(&ordered(a.object, b.object))
    }
}

fn ordered(a: ObjectId, b: ObjectId) -> (ObjectId, ObjectId) {
    if a <= b { (a, b) } else { (b, a) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(index: u32, group: u16, is_static: bool) -> InterestKey {
        InterestKey {
            object: ObjectId::from_parts(index, 0),
            group: GroupId(group),
            is_static,
        }
    }

    #[test]
    fn static_pairs_are_never_interesting_and_dynamic_ones_are_by_default() {
        let matrix = InterestMatrix::new();
        assert!(!matrix.is_interesting(&key(0, 0, true), &key(1, 0, true)));
        assert!(matrix.is_interesting(&key(0, 0, true), &key(1, 0, false)));
        assert!(matrix.is_interesting(&key(0, 3, false), &key(1, 7, false)));
    }

    #[test]
    fn group_and_object_rules_apply_symmetrically_and_can_be_undone() {
        let mut matrix = InterestMatrix::new();
        matrix.disallow_groups(GroupId(2), GroupId(5));
        matrix.disallow_groups(GroupId(1), GroupId(1));
        assert!(!matrix.is_interesting(&key(0, 5, false), &key(1, 2, false)));
        assert!(!matrix.is_interesting(&key(0, 2, false), &key(1, 5, true)));
        assert!(!matrix.is_interesting(&key(0, 1, false), &key(1, 1, false)));
        assert!(matrix.is_interesting(&key(0, 2, false), &key(1, 2, false)));
        assert!(matrix.is_interesting(&key(0, 9, false), &key(1, 1, false)));
        matrix.allow_groups(GroupId(5), GroupId(2));
        assert!(matrix.is_interesting(&key(0, 5, false), &key(1, 2, false)));

        matrix.disallow_objects(ObjectId::from_parts(4, 0), ObjectId::from_parts(3, 0));
        assert!(!matrix.is_interesting(&key(3, 0, false), &key(4, 0, false)));
        assert!(matrix.is_interesting(&key(3, 0, false), &key(5, 0, false)));
        matrix.forget_object(ObjectId::from_parts(3, 0));
        assert!(matrix.is_interesting(&key(4, 0, false), &key(3, 0, false)));
    }
}
