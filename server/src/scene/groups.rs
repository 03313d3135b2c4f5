//! The collision groups of a scene and the pairs never tested against each other.

use crate::collision::pipeline::interest::GroupId;

/// The groups of a scene and the pairs of groups whose parts are never tested against each
/// other. Pairs of two static parts are never of interest either.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Groups {
    /// Every group some part belongs to, sorted.
    pub names: Vec<String>,
    /// Pairs of groups that are not of interest, each sorted, as the config lists them.
    pub not_of_interest: Vec<[String; 2]>,
    /// Pairs of parts (indices into [`Scene::parts`](super::Scene::parts), smaller first) that are not of interest:
    /// parts that touch by design, such as a screw and its thread.
    pub parts_not_of_interest: Vec<[usize; 2]>,
}

impl Groups {
    /// The collision group id of a group name: its index in [`Groups::names`].
    pub fn id_of(&self, name: &str) -> GroupId {
        let index = self.names.iter().position(|g| g == name);
        // Loading collects every part's group into `names`; an unknown name gets an id of its own.
        GroupId(
            index
                .and_then(|i| u16::try_from(i).ok())
                .unwrap_or(u16::MAX),
        )
    }

    /// A collision group of no part: the one after the scene's groups (the hand's segments get
    /// it). Loading caps a scene's groups below `u16::MAX`.
    pub fn spare_id(&self) -> GroupId {
        GroupId(u16::try_from(self.names.len()).expect("a scene has fewer than u16::MAX groups"))
    }

    /// True unless the config lists the pair of groups (in either order) as not of interest.
    pub fn of_interest(&self, a: &str, b: &str) -> bool {
        let pair = sorted_pair(a, b);
        !self.not_of_interest.contains(&pair)
    }
}

pub(super) fn sorted_pair(a: &str, b: &str) -> [String; 2] {
    if a <= b {
        [a.to_owned(), b.to_owned()]
    } else {
        [b.to_owned(), a.to_owned()]
    }
}
