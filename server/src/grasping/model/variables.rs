//! Sets of the hand's variables: the flex values and the root.

use super::VARIABLE_COUNT;

/// A set of clasp variables as a bit mask: bit `v` is flex value `v`, bit [`ROOT_VARIABLE`](super::ROOT_VARIABLE) the
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
