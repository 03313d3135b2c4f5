//! What the fuzz targets (`tests/targets.rs`) share: the repository's configs, the checks that an
//! accepted input gave a usable value, wire samples made from raw bytes, and the structured input
//! of the collision target.
//!
//! `cargo test` runs every target on its seeds and a second of random input; `.ci/fuzz` runs
//! them under libFuzzer with `cargo bolero`.

use std::path::PathBuf;
use std::sync::OnceLock;

use bolero::generator::TypeGenerator;
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use vas_protocol::{ControlRequest, GloveSample, HandJointsSample, MAX_POSITION_M, TrackerSample};
use vas_server::collision::orientation::{DEFAULT_K, SUPPORTED_K};
use vas_server::collision::{DopTree, MeshCollider, OrientationSet};
use vas_server::geometry::mesh::MAX_COORDINATE;
use vas_server::geometry::{MeshError, TriMesh};
use vas_server::grasping::{FLEX_COUNT, HandModel, VARIABLE_COUNT};

/// The repository's `configs/` folder: the targets resolve relative paths against it, so that
/// seeds naming its meshes and hands load them.
pub fn configs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// Panics unless `mesh` keeps [`TriMesh`]'s promise: triangles left, coordinates finite within
/// [`MAX_COORDINATE`], indices in range.
pub fn check_mesh(mesh: &TriMesh) {
    assert!(!mesh.triangles().is_empty(), "a mesh without triangles");
    for v in mesh.vertices() {
        assert!(
            v.iter().all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE),
            "vertex {v} is not finite within {MAX_COORDINATE}"
        );
    }
    let count = mesh.vertices().len();
    for t in mesh.triangles() {
        assert!(t.iter().all(|&i| (i as usize) < count), "{t:?} of {count}");
    }
}

/// The orientation set of `k` (one of [`SUPPORTED_K`]) directions, made once: making one
/// takes milliseconds, far longer than a small mesh's tree.
pub fn orientations(k: usize) -> &'static OrientationSet {
    static SETS: OnceLock<Vec<OrientationSet>> = OnceLock::new();
    let sets = SETS.get_or_init(|| {
        SUPPORTED_K
            .iter()
            .map(|&k| OrientationSet::new(k).expect("a supported k"))
            .collect()
    });
    let index = SUPPORTED_K.iter().position(|&s| s == k);
    &sets[index.expect("a supported k")]
}

/// Panics unless a DOP-tree over `mesh` builds, holds every triangle and finds the mesh touching
/// itself: what the server does next with a loaded mesh.
pub fn check_tree(mesh: &TriMesh) {
    let tree = DopTree::with_orientations(mesh, orientations(DEFAULT_K));
    assert_eq!(tree.triangle_count(), mesh.triangles().len());
    let mut stats = Default::default();
    assert!(tree.intersects(&tree, &Isometry3::identity(), &mut stats));
}

/// Panics unless `model`'s levers are finite, its joint axes unit vectors, and its segments'
/// poses finite with unit rotations at rest and at both ends of every joint's limits.
pub fn check_hand(model: &HandModel) {
    for variable in 0..VARIABLE_COUNT {
        assert!(model.lever(variable).is_finite(), "lever of {variable}");
    }
    for segment in model.segments() {
        for dof in &segment.dofs {
            assert!((dof.axis.norm() - 1.0).abs() < 1e-9, "{}", segment.name);
        }
    }
    let limits = model.limits();
    let low: [f64; FLEX_COUNT] = std::array::from_fn(|i| limits[i].min);
    let high: [f64; FLEX_COUNT] = std::array::from_fn(|i| limits[i].max);
    for flex in [[0.0; FLEX_COUNT], low, high] {
        for (segment, pose) in model.segment_poses(&flex).iter().enumerate() {
            assert!(is_finite(pose), "segment {segment} at {flex:?}: {pose}");
            let norm = pose.rotation.norm();
            assert!(
                (norm - 1.0).abs() < 1e-9,
                "segment {segment}: rotation of norm {norm}"
            );
        }
    }
}

/// Whether every component of `pose` is finite.
pub fn is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|c| c.is_finite())
        && pose.rotation.coords.iter().all(|c| c.is_finite())
}

/// A wire type of which every bit pattern of its size is a value, so that it can be read from
/// bytes as a corrupt or hostile peer could write them into shared memory.
///
/// # Safety
///
/// Only for `#[repr(C)]` types whose fields are integers, floats or arrays and structs of them,
/// with no invariant that unsafe code relies on.
pub unsafe trait AnyBitPattern: Copy {}

// SAFETY: `u64`, `u64`, two `WirePose`s (`[f64; 3]`, `[f64; 4]`) and a `u32`; the padding after
// the `u32` may hold anything.
unsafe impl AnyBitPattern for TrackerSample {}
// SAFETY: `u64`, `u64` and `[f32; 22]`.
unsafe impl AnyBitPattern for GloveSample {}
// SAFETY: `u64`, `u64`, 26 `JointLocation`s (`[f64; 3]`, `[f64; 4]`, `f32`, `u32`) and a `u32`;
// the padding after it may hold anything.
unsafe impl AnyBitPattern for HandJointsSample {}
// SAFETY: `u32`, `u32` and a `WireText` (a `u32` length and bytes); the length is checked on
// every read (`WireText::as_str`), nothing unsafe relies on it.
unsafe impl AnyBitPattern for ControlRequest {}

/// The values `bytes` holds, one per `size_of::<T>()` bytes, the last one padded with zeros.
pub fn values_from_bytes<T: AnyBitPattern>(bytes: &[u8]) -> Vec<T> {
    bytes
        .chunks(size_of::<T>())
        .map(|chunk| {
            let mut buffer = vec![0u8; size_of::<T>()];
            buffer[..chunk.len()].copy_from_slice(chunk);
            // SAFETY: the buffer holds `size_of::<T>()` initialised bytes, and every bit pattern
            // is a `T` (`AnyBitPattern`); the read does not need alignment.
            unsafe { std::ptr::read_unaligned(buffer.as_ptr().cast::<T>()) }
        })
        .collect()
}

/// A fuzzed coordinate: on a grid of sixteenths (so that vertices coincide and triangles are
/// coplanar or touch exactly, where rounding decides), or any `f64` (NaN and infinities too)
/// brought within [-8, 8] by a remainder, so that it rarely makes the mesh too large to accept.
#[derive(Debug, Clone, Copy, TypeGenerator)]
pub enum Coordinate {
    /// `n / 16`.
    Grid(i8),
    /// `x % 8`.
    Any(f64),
}

impl Coordinate {
    /// The value.
    pub fn value(self) -> f64 {
        match self {
            Coordinate::Grid(n) => f64::from(n) / 16.0,
            Coordinate::Any(x) => x % 8.0,
        }
    }
}

/// A small fuzzed triangle soup, before validation.
#[derive(Debug, Clone, TypeGenerator)]
pub struct SmallMesh {
    /// Vertex coordinates.
    #[generator(bolero::produce::<Vec<[Coordinate; 3]>>().with().len(0usize..=96))]
    pub vertices: Vec<[Coordinate; 3]>,
    /// Triangles as vertex indices, taken modulo the vertex count.
    #[generator(bolero::produce::<Vec<[u8; 3]>>().with().len(0usize..=64))]
    pub triangles: Vec<[u8; 3]>,
}

impl SmallMesh {
    /// The mesh as [`TriMesh::new`] validates it.
    pub fn validate(&self) -> Result<TriMesh, MeshError> {
        let vertices: Vec<_> = self
            .vertices
            .iter()
            .map(|v| Point3::from(v.map(Coordinate::value)))
            .collect();
        let count = vertices.len().max(1) as u32;
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|i| u32::from(i) % count))
            .collect();
        TriMesh::new(vertices, triangles).map(|(mesh, _)| mesh)
    }
}

/// A fuzzed relative pose: a quaternion (normalised) and a translation.
#[derive(Debug, Clone, Copy, TypeGenerator)]
pub struct FuzzPose {
    /// `[x, y, z, w]`, of any norm.
    pub rotation: [Coordinate; 4],
    /// Metres.
    pub translation: [Coordinate; 3],
}

impl FuzzPose {
    /// The pose as the server makes relative poses of parts: a unit rotation and a translation
    /// within twice [`MAX_POSITION_M`]; `None` for a quaternion too short to normalise or a
    /// translation beyond that.
    pub fn isometry(&self) -> Option<Isometry3<f64>> {
        let [x, y, z, w] = self.rotation.map(Coordinate::value);
        let quaternion = Quaternion::new(w, x, y, z);
        let norm = quaternion.norm();
        if !(norm.is_finite() && norm > 1e-6) {
            return None;
        }
        let rotation = UnitQuaternion::new_normalize(quaternion);
        let translation = Vector3::from(self.translation.map(Coordinate::value));
        let within = translation
            .iter()
            .all(|c| c.is_finite() && c.abs() <= 2.0 * MAX_POSITION_M);
        within.then(|| Isometry3::from_parts(Translation3::from(translation), rotation))
    }
}

/// The input of the collision target: a small mesh, where it is queried against the fixed mesh
/// (up to three poses in a row, so that what a query leaves for the next is used), and the
/// trees' parameters.
#[derive(Debug, Clone, TypeGenerator)]
pub struct CollisionCase {
    /// The fuzzed mesh.
    pub mesh: SmallMesh,
    /// Its poses in the fixed mesh's frame, queried in order.
    #[generator(bolero::produce::<Vec<FuzzPose>>().with().len(1usize..=3))]
    pub poses: Vec<FuzzPose>,
    /// Picks the orientation set (of `SUPPORTED_K`).
    pub orientations: u8,
    /// Picks the fuzzed mesh's tree leaf size, 1 to 4.
    pub leaf_size: u8,
}
