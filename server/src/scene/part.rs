//! One part of a scene: its mesh, pose and collision data, and how their preparation is logged.

use std::sync::Arc;

use nalgebra::Isometry3;

use super::part_tree::PartTree;
use super::unheld::{PushParams, ReleaseMode, ReleaseParams};
use crate::collision::DopTree;
use crate::collision::dop_tree::Provenance;
use crate::geometry::{ConvexHull, EdgeAdjacency, TriMesh};
use crate::grasping::PartGeometry;

/// One part of a scene.
#[derive(Debug, Clone)]
pub struct Part {
    /// Unique name within the scene.
    pub name: String,
    /// The geometry in the part's own frame (shared between parts that use the same source).
    pub mesh: Arc<TriMesh>,
    /// Where the mesh came from: the resolved file path, `<file>#/nodes/<index>` for a node of
    /// an assembly, or `shape:KIND:...` for a procedural shape.
    pub mesh_source: String,
    /// The uniform scale the config applies to a mesh file (1 for shapes, and for an
    /// assembly's parts, whose scales from the file are baked in), already applied to
    /// [`Part::mesh`].
    pub scale: f64,
    /// Initial pose of the part's frame in the world.
    pub pose: Isometry3<f64>,
    /// Whether the part can be grasped and moved; static parts never move.
    pub movable: bool,
    /// The part's group in the collision interest matrix.
    pub group: String,
    /// The part's own `push` key: whether hands push it, over the scene's `[params.push]`.
    pub push: Option<bool>,
    /// The part's own `release` key: what it does when released, over `[params.release]`.
    pub release: Option<ReleaseMode>,
    /// The DOP-tree, convex hull and edge adjacency of [`Part::mesh`], built on first use
    /// ([`Part::tree`], [`Part::hull`], [`Part::adjacency`]).
    pub tree: PartTree,
}

impl Part {
    /// The DOP-tree over the part's mesh, with the scene's orientations: built by the first
    /// caller (concurrent callers wait for it), then shared by every loop and every part with
    /// the same mesh.
    pub fn tree(&self) -> &DopTree {
        self.tree.get(&self.mesh)
    }

    /// The convex hull of the part's mesh, for the collision pipeline's separating-plane
    /// pre-check: built by the first caller, then shared like [`Part::tree`].
    pub fn hull(&self) -> &ConvexHull {
        self.tree.hull.get_or_init(|| ConvexHull::of(&self.mesh))
    }

    /// The edge adjacency of the part's mesh, which sliding classifies contacts with: built by
    /// the first caller, then shared like [`Part::tree`].
    pub fn adjacency(&self) -> &Arc<EdgeAdjacency> {
        (self.tree.adjacency).get_or_init(|| Arc::new(EdgeAdjacency::new(&self.mesh)))
    }

    /// Whether a hand touching the part without holding it moves it: a movable part, unless
    /// its own key or the scene's `push` table says not.
    pub fn pushable(&self, scene: &PushParams) -> bool {
        scene.pushes(self.movable, self.push)
    }

    /// What the part does when released: its own key, else the scene's; a static part stays.
    pub fn release_mode(&self, scene: &ReleaseParams) -> ReleaseMode {
        scene.mode_of(self.movable, self.release)
    }

    /// The part as the grasping stage tests it: its shared mesh and tree, not copies.
    pub fn grasp_geometry(&self) -> PartGeometry {
        PartGeometry::with_tree(Arc::clone(&self.mesh), self.tree().clone())
    }
}

/// Parts of at least this many triangles have their preparation logged at info level: they take
/// a noticeable time.
const LARGE_PART_TRIANGLES: usize = 100_000;

/// What [`Scene::prepare_parts`](super::Scene::prepare_parts) calls to log `parts` of scene `scene` as they become ready,
/// with how many are and the percentage of their triangles done: large parts at info level, so
/// that a long start-up says where it is, the others at debug level.
pub fn log_prepared<'a>(scene: &'a str, parts: &[Part]) -> impl Fn(&Part, f64) + Sync + use<'a> {
    let total_parts = parts.len();
    let total_triangles: usize = parts.iter().map(|p| p.mesh.triangles().len()).sum();
    let done = std::sync::Mutex::new((0usize, 0usize));
    move |part, seconds| {
        let triangles = part.mesh.triangles().len();
        let (done_parts, done_triangles) = {
            let mut done = done
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            *done = (done.0 + 1, done.1 + triangles);
            *done
        };
        let percent = (100 * done_triangles)
            .checked_div(total_triangles)
            .unwrap_or(100);
        let tree = match part.tree.provenance() {
            Some(Provenance::Read) => "read from the cache",
            Some(Provenance::Built) => "built",
            None => "not built",
        };
        if triangles >= LARGE_PART_TRIANGLES {
            tracing::info!(
                scene,
                part = part.name,
                triangles,
                tree,
                seconds,
                "part ready ({done_parts} of {total_parts}, {percent}% of the triangles)"
            );
        } else {
            tracing::debug!(
                scene,
                part = part.name,
                triangles,
                tree,
                seconds,
                "part ready ({done_parts} of {total_parts}, {percent}% of the triangles)"
            );
        }
    }
}
