//! The scene: parts with their meshes and poses, the collision interest groups, the algorithm
//! parameters and the loop rates, loaded from a TOML config and validated as a whole.
//!
//! A config that is wrong in any way is refused with the file, the key and the reason; a scene is
//! either loaded completely or not at all. The format:
//!
//! ```toml
//! name = "peg in hole"
//! # hand = "hands/right.toml"          # optional hand model, relative to this file
//! # hands = ["hands/right.toml", "hands/left.toml"]  # or two, one of each side: one user's,
//! #                                    # named "user"
//! # [[users]]                          # or up to four users, each with one or two hands
//! # name = "anna"                      # (instead of hand or hands)
//! # hands = ["hands/right.toml", "hands/left.toml"]
//!
//! [params]                             # all optional, with defaults
//! dop_orientations = 24
//! sliding = { metaphor = "rubber-band", contact_tolerance = 1e-4 }
//! tracking = { lost_after = 0.1, grace = 0.5 }   # seconds of sample time, for hand joints
//! clearance = { threshold = 0.005, parts = "held" }  # report pairs closer than 5 mm; off
//!                                    # without a threshold; "held" (default) or "movable"
//! push = { enabled = true }            # a touching hand pushes movable parts (unheld.rs)
//! release = { mode = "settle", floor = 0.0 }  # released parts settle down ("stay": they float)
//!
//! [rates]                              # optional, hertz
//! publish_hz = 60
//!
//! [groups]                             # optional: pairs never tested against each other
//! not_of_interest = [["fixtures", "fixtures"]]   # by group
//! parts_not_of_interest = [["block", "bunny"]]   # by part (touching by design)
//!
//! [[parts]]
//! name = "block"
//! shape = { kind = "box-with-hole", width = 0.08, height = 0.05, hole_radius = 0.01, triangles = 2000 }
//! position = [0.0, 0.0, 0.025]         # metres; default the origin
//! rotation = [0.0, 0.0, 0.0, 1.0]      # unit quaternion x, y, z, w; default identity
//! movable = false                      # default false (static)
//! group = "fixtures"                   # default "default"
//!
//! [[parts]]
//! name = "bunny"
//! mesh = "meshes/low_poly_bunny.obj"   # OBJ, STL, PLY, glTF or GLB, relative to this file
//! scale = 0.05                         # optional uniform scale of a mesh file
//! movable = true
//! push = false                         # optional: over [params.push]
//! release = "stay"                     # optional: over [params.release]
//!
//! [[assemblies]]                       # every mesh node of a glTF file as a part (assembly.rs)
//! file = "cad/gearbox.glb"             # .gltf or .glb, relative to this file
//! up = "y"                             # the file's up axis, turned to z; default "z"
//! position = [0.0, 0.0, 0.75]          # of the whole assembly; default the origin
//! rotation = [0.0, 0.0, 0.0, 1.0]      # of the whole assembly; default identity
//! movable = ["shaft", "gear#2"]        # parts by name, or true / false for all; default false
//! group = "gearbox"                    # default "default"
//! ```
//!
//! Parts are numbered in the order of `[[parts]]`, then of each assembly's parts.

mod clearance;
mod error;
mod file;
mod groups;
mod loader;
mod overlaps;
mod params;
mod part;
mod part_tree;
mod summary;
mod unheld;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::collision::pipeline::ObjectId;
use crate::collision::pipeline::interest::{GroupId, InterestMatrix};
use crate::grasping::HandModel;

pub use clearance::{ClearanceParams, ClearanceParts};
pub use error::SceneError;
pub use groups::Groups;
pub use loader::LoadOptions;
pub use params::{AlgorithmParams, DOP_ORIENTATION_COUNTS, Rates, TrackingParams};
pub use part::{Part, log_prepared};
pub use part_tree::PartTree;
pub use unheld::{PushParams, ReleaseMode, ReleaseParams, UnheldParams};

/// How far from 1 a rotation quaternion's norm may be (relative), as a config writes it with a
/// limited number of digits.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-6;

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene's name.
    pub name: String,
    /// The file it was loaded from.
    pub source: PathBuf,
    /// The parts; a part's id is its index here.
    pub parts: Vec<Part>,
    /// The names of the scene's users, by index: those of `[[users]]`, or [`DEFAULT_USER`]
    /// alone for a scene that gives `hand` or `hands` (or no hand at all).
    pub users: Vec<String>,
    /// The hand models of every user (at most one of each side per user), grouped by user in
    /// the users' order, loaded and validated with the scene. Every input sample names the user
    /// and side of the hand it drives.
    pub hands: Vec<SceneHand>,
    /// Parameters of the algorithms.
    pub params: AlgorithmParams,
    /// Rates of the runtime loops.
    pub rates: Rates,
    /// The collision interest groups.
    pub groups: Groups,
}

/// The one user of a scene that names its hands with `hand` or `hands` rather than `[[users]]`.
pub const DEFAULT_USER: &str = "user";

/// A hand model of a scene: whose it is, its file, resolved against the scene's folder, and the
/// model.
#[derive(Debug, Clone)]
pub struct SceneHand {
    /// The user's index in [`Scene::users`].
    pub user: u32,
    /// The hand model file.
    pub path: PathBuf,
    /// The model loaded from it.
    pub model: Arc<HandModel>,
}

impl Scene {
    /// True when parts `a` and `b` must be tested for collision: different parts, at least one
    /// movable, and their groups of interest to each other.
    pub fn pair_of_interest(&self, a: usize, b: usize) -> bool {
        let (p, q) = (&self.parts[a], &self.parts[b]);
        a != b
            && (p.movable || q.movable)
            && self.groups.of_interest(&p.group, &q.group)
            && !self
                .groups
                .parts_not_of_interest
                .contains(&[a.min(b), a.max(b)])
    }

    /// The collision group of part `part`: its group's index in [`Groups::names`].
    pub fn group_id(&self, part: usize) -> GroupId {
        self.groups.id_of(&self.parts[part].group)
    }

    /// The collision interest matrix of the scene's group and part rules, for a collision pipeline
    /// in which `objects[i]` is part `i` (static pairs need no rule: the pipeline skips them).
    pub fn interest_matrix(&self, objects: &[ObjectId]) -> InterestMatrix {
        let mut matrix = InterestMatrix::new();
        for [a, b] in &self.groups.not_of_interest {
            matrix.disallow_groups(self.groups.id_of(a), self.groups.id_of(b));
        }
        for &[a, b] in &self.groups.parts_not_of_interest {
            if let (Some(&a), Some(&b)) = (objects.get(a), objects.get(b)) {
                matrix.disallow_objects(a, b);
            }
        }
        matrix
    }

    /// Builds every part's DOP-tree, convex hull and edge adjacency now
    /// ([`Scene::prepare_parts`]): a scene loaded while another is served is made ready before
    /// it replaces it.
    pub fn prepare(&self) {
        Scene::prepare_parts(&self.parts, &log_prepared(&self.name, &self.parts));
    }

    /// Builds the DOP-tree, convex hull and edge adjacency of each of `parts`, the parts in
    /// parallel, rather than on the loops' first use, and calls `ready` with each part and the
    /// seconds it took as it is done (in no particular order).
    ///
    /// The largest parts start first, each a task of its own: an assembly's few large panels then
    /// go to different threads at once, instead of waiting one after another at the end of a
    /// thread's share.
    pub fn prepare_parts(parts: &[Part], ready: &(dyn Fn(&Part, f64) + Sync)) {
        use rayon::prelude::*;
        let mut largest_first: Vec<&Part> = parts.iter().collect();
        largest_first.sort_by_key(|part| std::cmp::Reverse(part.mesh.triangles().len()));
        largest_first.par_iter().with_max_len(1).for_each(|part| {
            let started = std::time::Instant::now();
            part.tree();
            part.hull();
            part.adjacency();
            ready(part, started.elapsed().as_secs_f64());
        });
    }

    /// Each hand's model with its user's index, in the scene's order.
    pub fn hand_models(&self) -> impl Iterator<Item = (u32, &HandModel)> {
        (self.hands.iter()).map(|hand| (hand.user, hand.model.as_ref()))
    }

    /// The triangles of all parts (a mesh shared by several parts counts for each).
    pub fn triangle_count(&self) -> usize {
        self.parts.iter().map(|p| p.mesh.triangles().len()).sum()
    }
}

/// The default demo scene, `configs/default.toml`: found relative to the working directory
/// (running from the repository root), else in the source tree the binary was built from.
pub fn default_scene_path() -> PathBuf {
    let relative = Path::new("configs").join("default.toml");
    if relative.is_file() {
        relative
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(relative)
    }
}
