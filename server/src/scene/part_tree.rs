//! A part's collision data, built lazily once and shared by every part with the same mesh.

use std::sync::{Arc, OnceLock};

use crate::collision::dop_tree::{DEFAULT_LEAF_SIZE, Provenance, TreeCache};
use crate::collision::{DopTree, OrientationSet};
use crate::geometry::{ConvexHull, EdgeAdjacency, TriMesh};

/// A part's DOP-tree, convex hull and edge adjacency, built on first use and shared.
///
/// A large part's tree takes a noticeable time and memory to build, and the collision, grasping
/// and sliding loops all test the part: they clone this one (a clone shares the built arrays),
/// parts that share a mesh share its tree, hull and adjacency, a reset builds nothing, and
/// checking a config builds none.
#[derive(Debug, Clone)]
pub struct PartTree {
    orientations: usize,
    /// Where the tree is read from, and stored once built, if anywhere.
    cache: Option<Arc<TreeCache>>,
    tree: Arc<OnceLock<(DopTree, Provenance)>>,
    pub(super) hull: Arc<OnceLock<ConvexHull>>,
    pub(super) adjacency: Arc<OnceLock<Arc<EdgeAdjacency>>>,
}

impl PartTree {
    /// A tree of `orientations` directions (one of [`DOP_ORIENTATION_COUNTS`](super::DOP_ORIENTATION_COUNTS)), not built yet;
    /// `cache` keeps it once built.
    pub fn new(orientations: usize, cache: Option<Arc<TreeCache>>) -> PartTree {
        PartTree {
            orientations,
            cache,
            tree: Arc::default(),
            hull: Arc::default(),
            adjacency: Arc::default(),
        }
    }

    /// The tree over `mesh`, which must be the mesh of every part holding this tree.
    pub(super) fn get(&self, mesh: &TriMesh) -> &DopTree {
        let (tree, _) = self.tree.get_or_init(|| {
            let set = OrientationSet::new(self.orientations)
                .expect("the scene validated its orientation count");
            match &self.cache {
                Some(cache) => cache.tree(mesh, &set, DEFAULT_LEAF_SIZE),
                None => (DopTree::with_orientations(mesh, &set), Provenance::Built),
            }
        });
        tree
    }

    /// Where the tree came from, once it is there.
    pub fn provenance(&self) -> Option<Provenance> {
        self.tree.get().map(|(_, provenance)| *provenance)
    }
}
