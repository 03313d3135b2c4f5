//! The scene: parts with their meshes and poses, the collision interest groups, the algorithm
//! parameters and the loop rates, loaded from a TOML config and validated as a whole.
//!
//! A config that is wrong in any way is refused with the file, the key and the reason; a scene is
//! either loaded completely or not at all. The format:
//!
//! ```toml
//! name = "peg in hole"
//! # hand = "hands/right.toml"          # optional hand model, relative to this file
//! # hands = ["hands/right.toml", "hands/left.toml"]  # or two, one of each side; the first
//! #                                    # is the one the tracker and the glove drive
//!
//! [params]                             # all optional, with defaults
//! dop_orientations = 24
//! sliding = { metaphor = "rubber-band", contact_tolerance = 1e-4 }
//! tracking = { lost_after = 0.1, grace = 0.5 }   # seconds of sample time, for hand joints
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

mod assembly;
pub mod hand_over;
mod params;
pub mod script;

use std::collections::{BTreeSet, HashMap};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::Deserialize;
use thiserror::Error;

use crate::collision::dop_tree::{DEFAULT_LEAF_SIZE, Provenance, TreeCache};
use crate::collision::interest::{GroupId, InterestMatrix};
use crate::collision::pipeline::ObjectId;
use crate::collision::{DopTree, OrientationSet};
use crate::geometry::shapes::ShapeSpec;
use crate::geometry::{
    ConvexHull, EdgeAdjacency, FileLimits, GeometryError, Point, TriMesh, describe_toml_error,
    load_mesh_within, read_regular_text,
};
use crate::grasping::{HandModel, PartGeometry};
use params::Problem;
pub use params::{AlgorithmParams, DOP_ORIENTATION_COUNTS, Rates, TrackingParams};

/// How far from 1 a rotation quaternion's norm may be (relative), as a config writes it with a
/// limited number of digits.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-6;

/// Why a scene config was refused; every variant names the file.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("scene {}: cannot read it: {source}", file.display())]
    Read {
        /// The scene file.
        file: PathBuf,
        /// What the operating system said.
        #[source]
        source: io::Error,
    },
    /// The file is not valid TOML, has an unknown key, or a value of the wrong type.
    #[error("scene {}: {message}", file.display())]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// The line, the offending text and the reason.
        message: String,
    },
    /// A value is out of range or inconsistent with the rest of the scene.
    #[error("scene {}: {key}: {reason}", file.display())]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// The key, as in the config (`parts[2].rotation`).
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// A part's mesh file could not be loaded or its shape not built.
    #[error("scene {}: {key}: {source}", file.display())]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// The key, as in the config (`parts[1].mesh`).
        key: String,
        /// Why the mesh failed.
        #[source]
        source: GeometryError,
    },
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene's name.
    pub name: String,
    /// The file it was loaded from.
    pub source: PathBuf,
    /// The parts; a part's id is its index here.
    pub parts: Vec<Part>,
    /// The hand models the scene names (`hand`, or `hands`: at most one of each side), loaded
    /// and validated with it. The first is the hand that tracker and glove samples drive;
    /// hand-joints samples drive the hand of their side.
    pub hands: Vec<SceneHand>,
    /// Parameters of the algorithms.
    pub params: AlgorithmParams,
    /// Rates of the runtime loops.
    pub rates: Rates,
    /// The collision interest groups.
    pub groups: Groups,
}

/// The hand model of a scene: its file, resolved against the scene's folder, and the model.
#[derive(Debug, Clone)]
pub struct SceneHand {
    /// The hand model file.
    pub path: PathBuf,
    /// The model loaded from it.
    pub model: Arc<HandModel>,
}

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

    /// The part as the grasping stage tests it: its shared mesh and tree, not copies.
    pub fn grasp_geometry(&self) -> PartGeometry {
        PartGeometry::with_tree(Arc::clone(&self.mesh), self.tree().clone())
    }
}

/// Parts of at least this many triangles have their preparation logged at info level: they take
/// a noticeable time.
const LARGE_PART_TRIANGLES: usize = 100_000;

/// What [`Scene::prepare_parts`] calls to log `parts` of scene `scene` as they become ready,
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
    hull: Arc<OnceLock<ConvexHull>>,
    adjacency: Arc<OnceLock<Arc<EdgeAdjacency>>>,
}

impl PartTree {
    /// A tree of `orientations` directions (one of [`DOP_ORIENTATION_COUNTS`]), not built yet;
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
    fn get(&self, mesh: &TriMesh) -> &DopTree {
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

/// How a scene is loaded: the largest files it may read, and where its trees are cached.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// The largest files read.
    pub limits: FileLimits,
    /// The folder of built trees (`--tree-cache`), if any.
    pub tree_cache: Option<Arc<TreeCache>>,
}

impl From<FileLimits> for LoadOptions {
    fn from(limits: FileLimits) -> Self {
        LoadOptions {
            limits,
            tree_cache: None,
        }
    }
}

/// The groups of a scene and the pairs of groups whose parts are never tested against each
/// other. Pairs of two static parts are never of interest either.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Groups {
    /// Every group some part belongs to, sorted.
    pub names: Vec<String>,
    /// Pairs of groups that are not of interest, each sorted, as the config lists them.
    pub not_of_interest: Vec<[String; 2]>,
    /// Pairs of parts (indices into [`Scene::parts`], smaller first) that are not of interest:
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

fn sorted_pair(a: &str, b: &str) -> [String; 2] {
    if a <= b {
        [a.to_owned(), b.to_owned()]
    } else {
        [b.to_owned(), a.to_owned()]
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

/// The config as written, before validation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    hand: Option<PathBuf>,
    hands: Option<Vec<PathBuf>>,
    #[serde(default)]
    params: AlgorithmParams,
    #[serde(default)]
    rates: Rates,
    #[serde(default)]
    groups: GroupsFile,
    #[serde(default)]
    parts: Vec<PartFile>,
    #[serde(default)]
    assemblies: Vec<assembly::AssemblyFile>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct GroupsFile {
    #[serde(default)]
    not_of_interest: Vec<[String; 2]>,
    #[serde(default)]
    parts_not_of_interest: Vec<[String; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PartFile {
    name: String,
    mesh: Option<PathBuf>,
    scale: Option<f64>,
    shape: Option<ShapeSpec>,
    #[serde(default)]
    position: [f64; 3],
    rotation: Option<[f64; 4]>,
    #[serde(default)]
    movable: bool,
    #[serde(default = "default_group")]
    group: String,
}

fn default_group() -> String {
    "default".to_owned()
}

impl Scene {
    /// Loads and validates the scene config at `path`. Mesh paths (and the hand model) are
    /// relative to the config's folder. Each file may have the [default](FileLimits::default)
    /// size at most.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] of files (config, meshes, hand model) within `options`' limits, with its
    /// trees in `options`' cache.
    pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
        let text = read_regular_text(path, options.limits.config_bytes).map_err(|source| {
            SceneError::Read {
                file: path.to_owned(),
                source,
            }
        })?;
        Scene::from_toml(path, &text, options)
    }

    /// [`Scene::load_with`] on a config's text already read from `path`: errors name `path`,
    /// and mesh and hand paths are relative to its folder.
    pub fn from_toml(path: &Path, text: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
            file: path.to_owned(),
            message: describe_toml_error(text, &e),
        })?;
        Loader {
            path,
            folder: path.parent().unwrap_or(Path::new("")),
            limits: &options.limits,
            tree_cache: options.tree_cache.clone(),
            meshes: HashMap::new(),
            by_content: HashMap::new(),
            read_ahead: HashMap::new(),
            orientations: file.params.dop_orientations,
            triangles: 0,
        }
        .scene(file)
    }

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

    /// The triangles of all parts (a mesh shared by several parts counts for each).
    pub fn triangle_count(&self) -> usize {
        self.parts.iter().map(|p| p.mesh.triangles().len()).sum()
    }

    /// A human-readable summary: parts, triangles, groups, parameters and rates.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let triangles = self.triangle_count();
        let _ = writeln!(s, "scene {:?} ({})", self.name, self.source.display());
        let _ = writeln!(
            s,
            "parts: {} ({} movable), {triangles} triangles",
            self.parts.len(),
            self.parts.iter().filter(|p| p.movable).count()
        );
        for (id, part) in self.parts.iter().enumerate() {
            let t = part.pose.translation.vector;
            let (roll, pitch, yaw) = part.pose.rotation.euler_angles();
            let _ = writeln!(
                s,
                "  {id:>3} {:<16} {:<7} group {:<10} {:>7} triangles  at [{:.4}, {:.4}, {:.4}] m, \
                 rpy [{:.1}, {:.1}, {:.1}]°  {}",
                part.name,
                if part.movable { "movable" } else { "static" },
                part.group,
                part.mesh.triangles().len(),
                t.x,
                t.y,
                t.z,
                // Adding zero turns -0.0 into 0.0 for display.
                roll.to_degrees() + 0.0,
                pitch.to_degrees() + 0.0,
                yaw.to_degrees() + 0.0,
                part.mesh_source
            );
        }
        let ignored: Vec<String> = self
            .groups
            .not_of_interest
            .iter()
            .map(|[a, b]| format!("{a}/{b}"))
            .collect();
        let _ = writeln!(
            s,
            "groups: {}; not of interest: {} (and every static/static pair)",
            self.groups.names.join(", "),
            if ignored.is_empty() {
                "none".to_owned()
            } else {
                ignored.join(", ")
            }
        );
        let (p, sl, cl) = (&self.params, &self.params.sliding, &self.params.clasp);
        let contact_tolerance = sl
            .contact_tolerance
            .map_or("1e-4 of the part's size".to_owned(), |t| format!("{t} m"));
        let _ = writeln!(
            s,
            "params: {}-DOPs; sliding {} (contact tolerance {contact_tolerance}, lift {}, \
             {} iterations, {} stall cycles, cluster angle {} rad, {} slide-in units); \
             clasp (flex tolerance {} rad, root tolerance {} m, {} steps, max motion {} m); \
             tracking (lost after {} s, grace {} s)",
            p.dop_orientations,
            sl.metaphor,
            sl.lift,
            sl.max_iterations,
            sl.stall_cycles,
            sl.cluster_angle,
            sl.allowances.len(),
            cl.flex_tolerance,
            cl.root_tolerance,
            cl.max_steps,
            cl.max_motion,
            p.tracking.lost_after,
            p.tracking.grace
        );
        let r = &self.rates;
        let _ = writeln!(
            s,
            "rates: publish {} Hz, collision {} Hz, sliding {} Hz, grasping {} Hz",
            r.publish_hz, r.collision_hz, r.sliding_hz, r.grasping_hz
        );
        let hands: Vec<String> = (self.hands.iter())
            .map(|hand| hand.path.display().to_string())
            .collect();
        let _ = write!(
            s,
            "hands: {}",
            if hands.is_empty() {
                "none".to_owned()
            } else {
                hands.join(", ")
            }
        );
        s
    }
}

/// Validation state while loading one scene.
struct Loader<'a> {
    path: &'a Path,
    folder: &'a Path,
    /// The largest files read.
    limits: &'a FileLimits,
    /// Where the parts' trees are cached.
    tree_cache: Option<Arc<TreeCache>>,
    /// Meshes already loaded or built, with their trees, by source, so that parts sharing one
    /// are loaded once and share its tree.
    meshes: HashMap<String, (Arc<TriMesh>, PartTree)>,
    /// The same meshes by [content hash](TriMesh::content_hash) (several for a collision).
    by_content: HashMap<u64, Vec<(Arc<TriMesh>, PartTree)>>,
    /// Mesh files read ahead of their parts ([`Loader::read_ahead`]), by path, until a part
    /// takes its file.
    read_ahead: HashMap<PathBuf, Result<TriMesh, GeometryError>>,
    /// The scene's DOP orientation count, for the parts' trees.
    orientations: usize,
    /// The triangles of the parts so far, against [`FileLimits::scene_triangles`].
    triangles: u64,
}

impl Loader<'_> {
    fn invalid(&self, key: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.path.to_owned(),
            key: key.into(),
            reason: reason.into(),
        }
    }

    fn problem(&self, problem: Problem) -> SceneError {
        self.invalid(problem.key, problem.reason)
    }

    fn scene(mut self, file: SceneFile) -> Result<Scene, SceneError> {
        if file.name.trim().is_empty() {
            return Err(self.invalid("name", "must not be empty"));
        }
        file.params.validate().map_err(|p| self.problem(p))?;
        file.rates.validate().map_err(|p| self.problem(p))?;

        self.read_ahead(&file.parts);
        let mut parts: Vec<Part> = Vec::with_capacity(file.parts.len());
        for (index, part) in file.parts.into_iter().enumerate() {
            let part = self.part(index, part)?;
            if let Some(first) = parts.iter().position(|p| p.name == part.name) {
                return Err(self.invalid(
                    format!("parts[{index}].name"),
                    format!("{:?} is already the name of parts[{first}]", part.name),
                ));
            }
            parts.push(part);
        }
        for (index, assembly) in file.assemblies.into_iter().enumerate() {
            for part in self.assembly(index, assembly)? {
                if let Some(first) = parts.iter().position(|p| p.name == part.name) {
                    return Err(self.invalid(
                        format!("assemblies[{index}]"),
                        format!("its part {:?} has the name of part {first}", part.name),
                    ));
                }
                parts.push(part);
            }
        }

        let names: Vec<String> = parts
            .iter()
            .map(|p| p.group.clone())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        if names.len() >= usize::from(u16::MAX) {
            return Err(self.invalid(
                "parts",
                format!(
                    "name {} collision groups; at most {} fit",
                    names.len(),
                    u16::MAX - 1
                ),
            ));
        }
        let mut not_of_interest = Vec::with_capacity(file.groups.not_of_interest.len());
        for (index, [a, b]) in file.groups.not_of_interest.iter().enumerate() {
            if let Some(unknown) = [a, b].into_iter().find(|g| !names.contains(g)) {
                return Err(self.invalid(
                    format!("groups.not_of_interest[{index}]"),
                    format!(
                        "no part is in group {unknown:?} (groups: {})",
                        names.join(", ")
                    ),
                ));
            }
            not_of_interest.push(sorted_pair(a, b));
        }
        let mut parts_not_of_interest = Vec::with_capacity(file.groups.parts_not_of_interest.len());
        for (index, [a, b]) in file.groups.parts_not_of_interest.iter().enumerate() {
            let key = format!("groups.parts_not_of_interest[{index}]");
            let find = |name: &String| parts.iter().position(|p| &p.name == name);
            match (find(a), find(b)) {
                (Some(i), Some(j)) if i != j => parts_not_of_interest.push([i.min(j), i.max(j)]),
                (Some(_), Some(_)) => {
                    return Err(self.invalid(key, format!("names part {a:?} twice")));
                }
                _ => {
                    let unknown = if find(a).is_none() { a } else { b };
                    return Err(self.invalid(key, format!("there is no part named {unknown:?}")));
                }
            }
        }

        // Loaded here, so that whatever loads a scene (check-scene, run, a load-scene request)
        // refuses a broken hand model the same way.
        let listed = match (file.hand, file.hands) {
            (Some(_), Some(_)) => {
                return Err(self.invalid("hands", "give `hand` or `hands`, not both"));
            }
            (Some(hand), None) => vec![("hand".to_owned(), hand)],
            (None, Some(hands)) => (0..)
                .zip(hands)
                .map(|(index, hand)| (format!("hands[{index}]"), hand))
                .collect(),
            (None, None) => Vec::new(),
        };
        let mut hands: Vec<SceneHand> = Vec::with_capacity(listed.len());
        for (key, hand) in listed {
            let path = self.folder.join(&hand);
            let model = HandModel::load_within(&path, self.limits)
                .map_err(|error| self.invalid(&key, error.to_string()))?;
            if hands.iter().any(|other| other.model.side() == model.side()) {
                return Err(self.invalid(
                    key,
                    format!(
                        "a second {:?} hand: a scene has at most one of each side",
                        model.side()
                    ),
                ));
            }
            hands.push(SceneHand {
                path,
                model: Arc::new(model),
            });
        }

        Ok(Scene {
            name: file.name,
            source: self.path.to_owned(),
            parts,
            hands,
            params: file.params,
            rates: file.rates,
            groups: Groups {
                names,
                not_of_interest,
                parts_not_of_interest,
            },
        })
    }

    fn part(&mut self, index: usize, part: PartFile) -> Result<Part, SceneError> {
        let key = |field: &str| format!("parts[{index}].{field}");
        if part.name.trim().is_empty() {
            return Err(self.invalid(key("name"), "must not be empty"));
        }
        if part.group.trim().is_empty() {
            return Err(self.invalid(key("group"), "must not be empty"));
        }
        let position = self.position(&key("position"), part.position)?;
        let rotation = match part.rotation {
            None => UnitQuaternion::identity(),
            Some(q) => self.rotation(&key("rotation"), q)?,
        };
        let pose = Isometry3::from_parts(position, rotation);
        let (mesh, mesh_source, tree) = match (part.mesh, part.shape) {
            (Some(mesh), None) => self.mesh_file(index, &part.name, &mesh, part.scale)?,
            (None, Some(shape)) if part.scale.is_none() => self.shape(index, &part.name, shape)?,
            (None, Some(_)) => {
                return Err(self.invalid(
                    key("scale"),
                    "applies to mesh files only; give a shape's dimensions instead",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(self.invalid(key("shape"), "give either mesh or shape, not both"));
            }
            (None, None) => {
                return Err(self.invalid(
                    format!("parts[{index}]"),
                    "needs a mesh (a file) or a shape",
                ));
            }
        };
        Ok(Part {
            name: part.name,
            mesh,
            mesh_source,
            scale: part.scale.unwrap_or(1.0),
            pose,
            movable: part.movable,
            group: part.group,
            tree,
        })
    }

    /// A position from a config, refused unless finite and within the bound of tracker input
    /// ([`vas_protocol::MAX_POSITION_M`]), so that every pose derived from a part's stays
    /// finite.
    fn position(&self, key: &str, position: [f64; 3]) -> Result<Translation3<f64>, SceneError> {
        let limit = vas_protocol::MAX_POSITION_M;
        if let Some(c) = position.iter().find(|c| !c.is_finite() || c.abs() > limit) {
            return Err(self.invalid(
                key,
                format!("coordinates must be finite and within {limit} m, not {c}"),
            ));
        }
        Ok(Translation3::from(position))
    }

    /// A unit quaternion from (x, y, z, w), refused unless its norm is 1 within
    /// [`QUATERNION_NORM_TOLERANCE`]; accepted ones are renormalised to full precision.
    fn rotation(
        &self,
        key: &str,
        [x, y, z, w]: [f64; 4],
    ) -> Result<UnitQuaternion<f64>, SceneError> {
        if ![x, y, z, w].iter().all(|c| c.is_finite()) {
            return Err(self.invalid(key, "components must be finite"));
        }
        let quaternion = Quaternion::new(w, x, y, z);
        let norm = quaternion.norm();
        if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(self.invalid(
                key,
                format!(
                    "[{x}, {y}, {z}, {w}] has norm {norm}; a unit quaternion [x, y, z, w] is \
                     required (norm 1 within {QUATERNION_NORM_TOLERANCE})"
                ),
            ));
        }
        Ok(UnitQuaternion::from_quaternion(quaternion))
    }

    fn mesh_file(
        &mut self,
        index: usize,
        name: &str,
        relative: &Path,
        scale: Option<f64>,
    ) -> Result<(Arc<TriMesh>, String, PartTree), SceneError> {
        let scale = scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(self.invalid(
                format!("parts[{index}].scale"),
                format!("must be a positive number, not {scale}"),
            ));
        }
        let path = self.folder.join(relative);
        let source = path.display().to_string();
        let cache_key = format!("{source} x {scale}");
        let key = format!("parts[{index}].mesh");
        if let Some((mesh, tree)) = self.cached(&cache_key) {
            self.count_triangles(&key, name, mesh.triangles().len() as u64)?;
            return Ok((mesh, source, tree));
        }
        let mesh_error = |source| SceneError::Mesh {
            file: self.path.to_owned(),
            key: key.clone(),
            source,
        };
        let within = FileLimits {
            scene_triangles: self.triangles_left(),
            ..*self.limits
        };
        let loaded = match self.read_ahead.remove(&path) {
            // Refused for its share of the limit only: read again with all the parts before
            // it leave.
            Some(Err(GeometryError::TooManyTriangles { .. })) | None => {
                load_mesh_within(&path, &within)
            }
            Some(read) => read,
        };
        let mut mesh = match loaded {
            Err(GeometryError::TooManyTriangles { count, .. }) => {
                return Err(self.too_many_triangles(&key, name, count));
            }
            loaded => loaded.map_err(mesh_error)?,
        };
        if scale != 1.0 {
            // Uniform scaling keeps the triangles' shapes; only extreme scales can make some
            // degenerate, and a mesh with none left is refused.
            mesh = mesh
                .map_vertices(|v| Point::from(v.coords * scale))
                .map_err(|source| {
                    mesh_error(GeometryError::InvalidMesh {
                        path: path.clone(),
                        source,
                    })
                })?;
        }
        self.count_triangles(&key, name, mesh.triangles().len() as u64)?;
        let (mesh, tree) = self.remember(cache_key, mesh);
        Ok((mesh, source, tree))
    }

    fn shape(
        &mut self,
        index: usize,
        name: &str,
        shape: ShapeSpec,
    ) -> Result<(Arc<TriMesh>, String, PartTree), SceneError> {
        let key = format!("parts[{index}].shape");
        let source = shape.to_string();
        if let Some((mesh, tree)) = self.cached(&source) {
            self.count_triangles(&key, name, mesh.triangles().len() as u64)?;
            return Ok((mesh, source, tree));
        }
        // The requested count, before the shape is built (which meets it within a few percent).
        let requested = shape.triangles() as u64;
        if requested > self.triangles_left() {
            return Err(self.too_many_triangles(&key, name, requested));
        }
        let mesh = shape
            .build()
            .map_err(|e| self.invalid(format!("{key}.{}", e.field), e.reason))?;
        self.count_triangles(&key, name, mesh.triangles().len() as u64)?;
        let (mesh, tree) = self.remember(source.clone(), mesh);
        Ok((mesh, source, tree))
    }

    /// Reads the mesh files `parts` name, each once, on all of rayon's threads, ahead of the
    /// parts, which are then made in order: their triangles are counted against the scene's
    /// limit, and the first bad part is reported, as if each file were read in its turn.
    ///
    /// The files read at once share what the limit leaves: each claims, before it is read, its
    /// share (one per thread) of the triangles not claimed yet, and is refused beyond it, so
    /// that all read ahead stay within the limit together; a file refused for its share is read
    /// again in its turn, with all the parts before it leave.
    fn read_ahead(&mut self, parts: &[PartFile]) {
        use rayon::prelude::*;
        let mut paths: Vec<PathBuf> = (parts.iter())
            .filter(|part| part.shape.is_none())
            .filter_map(|part| part.mesh.as_ref().map(|mesh| self.folder.join(mesh)))
            .collect();
        paths.sort_unstable();
        paths.dedup();
        let threads = rayon::current_num_threads().max(1) as u64;
        let limits = *self.limits;
        let claimed = std::sync::Mutex::new(0u64);
        let claims = || {
            claimed
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        self.read_ahead = (paths.into_par_iter().with_max_len(1))
            .map(|path| {
                let share = {
                    let mut claimed = claims();
                    let share = limits.scene_triangles.saturating_sub(*claimed) / threads;
                    *claimed += share;
                    share
                };
                let within = FileLimits {
                    scene_triangles: share,
                    ..limits
                };
                let read = load_mesh_within(&path, &within);
                let used = read
                    .as_ref()
                    .map_or(0, |mesh| mesh.triangles().len() as u64);
                *claims() -= share - used.min(share);
                (path, read)
            })
            .collect();
    }

    /// How many triangles the next part may have within the scene's limit.
    fn triangles_left(&self) -> u64 {
        self.limits.scene_triangles.saturating_sub(self.triangles)
    }

    /// Adds part `name`'s `count` triangles to the scene's, refusing the part (at `key`) if the
    /// scene would have more than its limit.
    fn count_triangles(&mut self, key: &str, name: &str, count: u64) -> Result<(), SceneError> {
        if count > self.triangles_left() {
            return Err(self.too_many_triangles(key, name, count));
        }
        self.triangles += count;
        Ok(())
    }

    /// The refusal of part `name`, whose `count` triangles the scene's limit has no room for.
    fn too_many_triangles(&self, key: &str, name: &str, count: u64) -> SceneError {
        self.invalid(
            key,
            format!(
                "part {name:?} needs at least {count} triangles, but the scene's limit of {} \
                 triangles (--max-scene-triangles) leaves {} after the parts before it",
                self.limits.scene_triangles,
                self.triangles_left()
            ),
        )
    }

    /// The mesh loaded or built for `key` before, with its tree.
    fn cached(&self, key: &str) -> Option<(Arc<TriMesh>, PartTree)> {
        self.meshes.get(key).cloned()
    }

    /// Keeps `mesh` for `key`, with a tree for it that every part using it shares. A mesh
    /// equal to one kept before (from another file, shape or node) is that one: its tree is
    /// built once.
    fn remember(&mut self, key: String, mesh: TriMesh) -> (Arc<TriMesh>, PartTree) {
        let same_content = self.by_content.entry(mesh.content_hash()).or_default();
        let entry = match same_content.iter().find(|(kept, _)| **kept == mesh) {
            Some(kept) => kept.clone(),
            None => {
                let entry = (
                    Arc::new(mesh),
                    PartTree::new(self.orientations, self.tree_cache.clone()),
                );
                same_content.push(entry.clone());
                entry
            }
        };
        self.meshes.insert(key, entry.clone());
        entry
    }
}
