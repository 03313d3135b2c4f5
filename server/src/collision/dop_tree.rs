//! The DOP-tree: a bounding-volume tree of k-DOPs over a triangle mesh, and the simultaneous
//! traversal of two such trees with lazy O(k) re-alignment (the paper's §2.1).
//!
//! Layout, chosen for the traversal's memory traffic: node offsets are `f32`, `k` contiguous per
//! node (so the interval test is one vectorised pass); the two children of a node are adjacent;
//! nodes are numbered depth first; leaves hold one triangle (by default) stored by value.
//! Offsets are rounded outwards to `f32`, and every re-aligned offset gets a margin that bounds
//! its `f32` rounding, so no overlap is ever missed; the triangle test is exact in `f64`.
//!
//! Build: top-down with a binned surface heuristic (see `TreeBuilder::partition`). Every
//! node's offsets are the extremes of its triangles, so every plane touches the geometry (no
//! completely redundant half-space, the condition of the affine re-alignment).
//!
//! Query, in B's pose in A's frame:
//! 0. the bounding spheres are tested (far pairs end here, in about 10 ns); a first-hit query
//!    then uses what the previous queries of the same two trees on this thread left (temporal
//!    coherence, `PairMemory`): the pair of leaves last in contact is tested again, then the
//!    subtrees around it; a traversal starts from the last free query's front (the node pairs
//!    where it ended, each with a directional certificate: a DOP axis or, for a leaf against a
//!    leaf or a small subtree, a face plane of the leaf), taking up again only the pairs whose
//!    gap the motion since may have closed along their direction (bounded with the tree's
//!    sphere, then with the node's own); an all-pairs query (not split) walks from the same
//!    front and leaves its own, which is complete whatever it finds. A first-hit query far from
//!    both the front's pose and the last query's (two trees shared by many pairs of objects,
//!    random poses) walks from the roots without recording a front;
//! 1. the last proof that the roots are apart is checked against the motion since; failing
//!    that, a few of A's root slabs nearest the direction from A to B are tested against B's
//!    bounding sphere and B's root re-aligned along that slab only: far pairs end here, in tens
//!    of ns;
//! 2. otherwise the support cone of each of A's k directions in B's orientation set is found
//!    (first trying last query's vertex: temporal coherence; the opposite direction takes the
//!    opposite normals), giving the affine map from B's offsets to re-aligned ones, stored
//!    densely for vector multiply-adds; a query that the front answers without a test skips it;
//! 3. depth-first traversal: B's nodes are re-aligned lazily, once per query (a small
//!    direct-mapped cache), leaves exactly from their corners; children pairs are tested when
//!    generated and the deeper overlap is visited first; pairs that A's axes barely fail to
//!    separate are also tested along B's axes (A's node re-aligned into B's frame); a leaf's
//!    face planes are tried against an overlapping subtree of up to `PLANE_TEST_MAX_TRIANGLES`
//!    before the subtree is split, and two overlapping nodes of up to `BOX_TEST_MAX_TRIANGLES`
//!    each (`PLAIN_BOX_TEST_MAX_TRIANGLES` in a walk that records no front) are tested with
//!    their oriented boxes (fitted as the OBB-tree fits its own, kept in `f32` beside the DOPs)
//!    before the walk descends: near contact a small patch of a smooth surface is nearly flat,
//!    and its box is thin where a DOP of fixed axes is not, so the walk and its front end
//!    several levels higher.
//!
//! The traversal is compiled twice, portable and with AVX2/FMA, chosen at run time.

use std::cell::RefCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use nalgebra::{Isometry3, Matrix3, Point3, UnitQuaternion, Vector3};

use super::orientation::OrientationSet;
use super::oriented_box::OrientedBox;
use super::triangle::{Triangle, triangles_intersect};
use super::{MeshCollider, QueryStats};
use crate::geometry::{TriMesh, bounding_box_of, bounding_sphere_of};

/// Default number of triangles per leaf (the fastest in the tumbling benchmark).
pub const DEFAULT_LEAF_SIZE: usize = 1;

/// Depth to which the parallel traversal splits the node-pair tree into rayon tasks (up to
/// 2^depth tasks). Measured: a first-hit query of a few microseconds gets slower in parallel
/// (task hand-over costs more than the work); the split pays for long traversals such as all
/// pairs of two meshes in deep contact.
const PARALLEL_DEPTH: u32 = 6;

/// One tree node: a leaf (`count > 0`) owns triangles `first..first + count`; an inner node
/// (`count == 0`) has children `first` and `first + 1`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    first: u32,
    count: u32,
    /// Largest slab width of the node's DOP: the traversal descends the larger node.
    size: f32,
    /// A sphere around the node's triangles: how far its points can move when the tree turns
    /// about another point, for the certificates of a [`Front`]. Kept in the node, which the
    /// traversal has just read wherever it records a certificate.
    sphere: NodeSphere,
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A DOP-tree over one mesh: built once, shared read-only (it is `Send + Sync`). A clone shares
/// the built tree (its arrays are reference-counted), so every loop that needs a part's tree
/// holds the same one.
#[derive(Debug, Clone)]
pub struct DopTree {
    /// Identifies the tree for the per-thread witness cache (a clone shares it: same content).
    id: u64,
    set: OrientationSet,
    k: usize,
    nodes: Arc<[Node]>,
    /// Parent of each node (the root is its own parent).
    parents: Arc<[u32]>,
    /// The triangles under each node, `start..end` in leaf order (a subtree's are contiguous).
    triangle_ranges: Arc<[[u32; 2]]>,
    /// `k` offsets per node: `offsets[node * k + i] >= max over the node's triangles of n_i . x`.
    offsets: Arc<[f32]>,
    /// Triangles in leaf order.
    triangles: Arc<[Triangle]>,
    /// Original index (in the mesh) of each triangle in leaf order.
    triangle_ids: Arc<[u32]>,
    /// Largest absolute offset in the tree (bounds rounding errors of re-alignment).
    max_abs_offset: f32,
    /// An oriented box around each node's triangles (see [`NodeBox`]).
    boxes: Arc<[NodeBox]>,
    /// Centre and radius of a sphere enclosing the mesh (for the cheap first test of a query).
    bounding_centre: Point3<f64>,
    bounding_radius: f64,
}

impl DopTree {
    /// Builds the tree over `mesh` with orientation set `set` and at most `leaf_size` (>= 1)
    /// triangles per leaf.
    pub fn with_options(mesh: &TriMesh, set: &OrientationSet, leaf_size: usize) -> Self {
        TreeBuilder::new(mesh, set, leaf_size.max(1)).build()
    }

    /// Builds the tree with orientation set `set` and the default leaf size.
    pub fn with_orientations(mesh: &TriMesh, set: &OrientationSet) -> Self {
        DopTree::with_options(mesh, set, DEFAULT_LEAF_SIZE)
    }

    /// The orientation set the tree was built with.
    pub fn orientations(&self) -> &OrientationSet {
        &self.set
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Heap bytes used by the tree (nodes, their boxes, offsets, triangles and their ids).
    pub fn bytes(&self) -> usize {
        self.nodes.len()
            * (size_of::<Node>() + size_of::<NodeBox>() + size_of::<u32>() + size_of::<[u32; 2]>())
            + self.offsets.len() * size_of::<f32>()
            + self.triangles.len() * (size_of::<Triangle>() + size_of::<u32>())
    }

    /// The `k` offsets of node `index`.
    pub(crate) fn node_offsets(&self, index: usize) -> &[f32] {
        &self.offsets[index * self.k..(index + 1) * self.k]
    }

    /// Every triangle under node `index`.
    fn node_triangles(&self, index: u32) -> &[Triangle] {
        let [start, end] = self.triangle_ranges[index as usize];
        &self.triangles[start as usize..end as usize]
    }

    /// The ancestor `levels` above `node` (or the root, if nearer).
    fn ancestor(&self, mut node: u32, levels: u32) -> u32 {
        for _ in 0..levels {
            node = self.parents[node as usize];
        }
        node
    }

    /// Largest absolute offset of any node.
    pub(crate) fn max_abs_offset(&self) -> f32 {
        self.max_abs_offset
    }

    /// Like [`MeshCollider::intersects`], with the traversal split across rayon's threads
    /// (dynamic load balancing by work stealing) where it is long: from the roots, or from a
    /// remembered front with many pairs due. Worth it when one pair dominates.
    pub fn intersects_parallel(
        &self,
        other: &DopTree,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
    ) -> bool {
        let mut unused = Vec::new();
        with_affine::<false>(self, other, b_to_a, stats, &mut unused, true)
    }

    /// Like [`MeshCollider::intersecting_pairs`], split across rayon's threads from the roots
    /// (without the remembered front); the pairs come out in no particular order.
    pub fn intersecting_pairs_parallel(
        &self,
        other: &DopTree,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    ) {
        with_affine::<true>(self, other, b_to_a, stats, out, true);
    }
}

impl MeshCollider for DopTree {
    fn build(mesh: &TriMesh) -> Self {
        DopTree::with_orientations(mesh, &OrientationSet::default())
    }

    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, stats: &mut QueryStats) -> bool {
        let mut unused = Vec::new();
        with_affine::<false>(self, other, b_to_a, stats, &mut unused, false)
    }

    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    ) {
        with_affine::<true>(self, other, b_to_a, stats, out, false);
    }
}

/// Runs a query with the O(k) affine re-alignment, dispatching on A's k.
fn with_affine<const ALL: bool>(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    stats: &mut QueryStats,
    out: &mut Vec<[u32; 2]>,
    parallel: bool,
) -> bool {
    fn run<const K: usize, const ALL: bool>(
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
        parallel: bool,
    ) -> bool {
        let centre_b = b_to_a * b.bounding_centre;
        let reach = a.bounding_radius + b.bounding_radius;
        if (centre_b - a.bounding_centre).norm_squared() > reach * reach {
            stats.bv_tests += 1;
            return false;
        }
        if ALL {
            let mut memory = PairMemory::take(a, b);
            let hit = match affine_pair::<K>(a, b, b_to_a, &centre_b, &mut memory.root_separation) {
                None => {
                    stats.bv_tests += 1;
                    false
                }
                Some(pair) if parallel => pair.get().run::<ALL, K>(stats, out, true).is_some(),
                Some(pair) => memory.all_pairs::<K>(&pair, stats, out),
            };
            PairMemory::put_back(memory);
            return hit;
        }
        let Some(mut memory) = PairMemory::take_unless_apart(a, b, b_to_a, &centre_b) else {
            stats.bv_tests += 1;
            return false;
        };
        let hit = memory.first_hit::<K>(a, b, b_to_a, &centre_b, stats, parallel);
        memory.last_query = Some(*b_to_a);
        PairMemory::put_back(memory);
        hit
    }
    assert_eq!(
        a.k, b.k,
        "the two trees of a query must have the same orientation set"
    );
    match a.k {
        6 => run::<6, ALL>(a, b, b_to_a, stats, out, parallel),
        14 => run::<14, ALL>(a, b, b_to_a, stats, out, parallel),
        18 => run::<18, ALL>(a, b, b_to_a, stats, out, parallel),
        24 => run::<24, ALL>(a, b, b_to_a, stats, out, parallel),
        26 => run::<26, ALL>(a, b, b_to_a, stats, out, parallel),
        k => unreachable!("orientation sets have a supported k, not {k}"),
    }
}

/// What the last first-hit or all-pairs query between a pair of trees on this thread leaves to
/// the next one.
/// Poses change little between frames (temporal coherence): a pair in contact usually stays in
/// contact through the same or nearby triangles, and a pair proved apart stays apart at most of
/// the node pairs where the proof ended, by a margin that only motion towards each other can use
/// up.
#[derive(Default)]
struct PairMemory {
    /// A's and B's ids; 0 marks an empty slot.
    ids: (u64, u64),
    /// The pair of leaves whose triangles intersected at the last query that found contact,
    /// kept through one query without (a free pose between two trial poses in contact), and the
    /// queries without contact since.
    witness: Option<[u32; 2]>,
    misses_since_witness: u32,
    /// The last query found the trees apart at its walk from the remembered front, the roots'
    /// probes having failed: the next one walks from the front before it probes the roots.
    apart_by_front: bool,
    /// How [`roots_separated_along_offset`] last proved the roots apart: checked first next time.
    root_separation: Option<RootSeparation>,
    /// B's pose in A's frame at the last traversal that recorded a front, and that front: every
    /// pair of leaves lies under one of its node pairs, proved apart or to be tested again.
    front_pose: Option<(Matrix3<f64>, Vector3<f64>)>,
    front: Front,
    /// B's pose in A's frame at the last query that reached the memory: a query far from it
    /// and from the front's pose follows no coherent motion
    /// ([`PairMemory::far_from_last_query`]).
    last_query: Option<Isometry3<f64>>,
    /// Buffers reused across queries: the pairs to test again, the certificates due among
    /// them and those to renew, and where their tests ended.
    retest: Vec<(u32, u32)>,
    due: [DueCertificates; 2],
    ended: Vec<FrontPair>,
}

/// What [`Front::due`] found in one frame's certificates.
#[derive(Default)]
struct DueCertificates {
    /// Indices of the certificates that may no longer hold: their pairs are tested again.
    indices: Vec<u32>,
    /// Certificates whose tree bound failed but whose node bound held, with the tree bound's
    /// expiry renewed from the node bound (see [`Certificates::flagged`]); applied when the
    /// front settles at this query's pose.
    renewed: Vec<(u32, f64)>,
}

/// The node pairs at which the traversals since the last one from the roots ended.
///
/// A separated pair carries a certificate: a direction, fixed in A's or in B's frame, along which
/// the other tree's triangles lay at least a gap beyond this tree's. Motion changes that gap by at
/// most the other tree's centre moving along the direction plus the turn times its radius, so a
/// certificate is still valid while `gap + direction . (centre now - centre then) - radius *
/// (turn since)` stays positive: sliding along a surface (the peg down its hole) leaves the
/// certificates across the gap intact, however far it goes. The same holds with the moving
/// node's own centre and radius instead of its tree's: that bound costs more to evaluate but
/// survives turning (the tree's radius times even a small turn soon exceeds a small gap), so it
/// is checked wherever the tree's bound fails. A query takes out only the pairs both bounds
/// may have expired (a scan of packed arrays: the fronts hold up to tens of thousands of pairs,
/// where a scan beats a priority queue's scattered accesses).
#[derive(Default)]
struct Front {
    /// Separated pairs, per frame of the certificate's direction (A's, B's).
    separated: [Certificates; 2],
    /// Turn accumulated since the last traversal from the roots: the sum of `|R' - R|` (spectral
    /// norm) over the poses at which the front was advanced.
    turn: f64,
    /// Largest coordinate scale ([`Placement::scale`]) since the last traversal from the roots:
    /// bounds the rounding of the certificates' arithmetic.
    scale: f64,
    /// Pairs of leaves whose triangles no face plane separated: tested again every time.
    leaves: Vec<(u32, u32)>,
    /// Pairs of the first complete front (of a query without a hit) since the last traversal
    /// from the roots; a carried front that grows well beyond (the contact region wandered) is
    /// dropped for a fresh one.
    fresh_len: Option<usize>,
    /// Whether the last query that advanced the front without a hit tested again less than
    /// [`STEADY_DUE_SHARE`] of it: most certificates hold (sliding), so extra pairs cost little
    /// more than their scan and the front may grow further before a fresh one pays off.
    steady: bool,
}

/// Separated node pairs and their certificates, in parallel arrays.
#[derive(Default)]
struct Certificates {
    /// `gap - direction . centre - radius * turn` when the pair was found (rounding guard
    /// subtracted): the certificate holds while this plus `direction . centre - radius * turn`
    /// now stays above the guard.
    expiry: Vec<f64>,
    /// Unit direction (to f32 rounding) beyond which the other tree lies, in this frame, by
    /// component (so that the scan of [`Certificates::flagged`] runs in vector registers).
    directions: [Vec<f32>; 3],
    /// The same bound for the moving node alone (B's in A's frame, A's in B's), fixed when the
    /// pair was found: `gap - guard - direction . centre - radius * turn` with the node's own
    /// sphere. A node turns with its tree about the tree's centre, but only its own radius
    /// widens the bound: when the tree's bound has expired (a turning tree), this one often
    /// still holds.
    anchors: Vec<f64>,
    /// The moving node's sphere: its centre in its own tree's frame, by component, and radius.
    node_centres: [Vec<f32>; 3],
    node_radii: Vec<f32>,
    pairs: Vec<(u32, u32)>,
}

/// Where the two trees are at a query, for the certificates of a [`Front`].
struct Placement {
    /// B's bounding centre in A's frame, and A's in B's frame.
    centres: [Vector3<f64>; 2],
    /// The radius of the tree that moves in each frame: B's in A's frame, A's in B's.
    radii: [f64; 2],
    /// A bound on every coordinate involved: `|t| + |c_A| + |c_B| + r_A + r_B`.
    scale: f64,
    /// B's pose in A's frame.
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
}

/// The node bound of a [`Front`]'s certificates in one frame: the moving tree's pose there, the
/// turn accumulated since the front's restart, and the rounding guard.
struct NodeBound {
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
    turn: f64,
    guard: f64,
}

/// Relative rounding guard of the certificates: covers the `f32` rounding of their directions and
/// of the DOP slacks they come from (both a few 1e-8 of the coordinates' scale).
const CERTIFICATE_ROUNDING: f64 = 1e-6;

impl Placement {
    fn new(a: &DopTree, b: &DopTree, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Self {
        Placement {
            centres: [
                rotation * b.bounding_centre.coords + translation,
                rotation.transpose() * (a.bounding_centre.coords - translation),
            ],
            radii: [
                b.bounding_radius * (1.0 + CERTIFICATE_ROUNDING),
                a.bounding_radius * (1.0 + CERTIFICATE_ROUNDING),
            ],
            scale: translation.norm()
                + a.bounding_centre.coords.norm()
                + b.bounding_centre.coords.norm()
                + a.bounding_radius
                + b.bounding_radius,
            rotation: *rotation,
            translation: *translation,
        }
    }

    /// The pose of the tree that moves in `frame` (B in A's frame, A in B's).
    fn motion(&self, frame: usize) -> (Matrix3<f64>, Vector3<f64>) {
        if frame == 0 {
            (self.rotation, self.translation)
        } else {
            let inverse = self.rotation.transpose();
            (inverse, -(inverse * self.translation))
        }
    }
}

impl Certificates {
    fn clear(&mut self) {
        self.expiry.clear();
        self.directions.iter_mut().for_each(Vec::clear);
        self.anchors.clear();
        self.node_centres.iter_mut().for_each(Vec::clear);
        self.node_radii.clear();
        self.pairs.clear();
    }

    fn push(
        &mut self,
        (expiry, anchor): (f64, f64),
        direction: [f32; 3],
        sphere: &NodeSphere,
        pair: (u32, u32),
    ) {
        self.expiry.push(expiry);
        self.anchors.push(anchor);
        for (component, value) in self.directions.iter_mut().zip(direction) {
            component.push(value);
        }
        for (component, value) in self.node_centres.iter_mut().zip(sphere.centre) {
            component.push(value);
        }
        self.node_radii.push(sphere.radius);
        self.pairs.push(pair);
    }

    /// Appends to `due.indices` the certificates that may no longer hold: those whose tree
    /// bound (`expiry + direction . centre`, with the other tree's centre at `centre`) is at
    /// most `threshold` and whose node bound (`anchor + direction . (rotation c + translation)
    /// - radius * turn`, with the moving node's sphere) is at most `guard`.
    ///
    /// Both bounds are lower bounds on the gap now (less the guard). Where the node bound holds
    /// and the tree bound does not, the node bound's value renews the tree bound's expiry
    /// (`due.renewed`), as if the pair had been found apart by that gap at this pose: under
    /// steady turning the tree bound fails soon after each pair was found, and without renewal
    /// every later query would pay for the node bound of most pairs. The renewal is valid only
    /// from this pose on, so it is applied only when the front settles here (where its turn is
    /// counted from).
    ///
    /// The tree bound is checked for every pair, the node bound only where the tree bound fails
    /// (a few pairs per query: on B1's bunny at d = 1.5, about 6 of a front of 120).
    fn flagged(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            return unsafe { self.flagged_avx2(centre, threshold, nodes, due) };
        }
        self.flagged_scalar(centre, threshold, nodes, due, 0);
    }

    /// The tree bound of pair `j` with the other tree's centre at `centre`:
    /// `expiry + direction . centre`.
    #[inline(always)]
    fn tree_bound(&self, j: usize, centre: &Vector3<f64>) -> f64 {
        let [dx, dy, dz] = &self.directions;
        self.expiry[j]
            + f64::from(dx[j]) * centre.x
            + f64::from(dy[j]) * centre.y
            + f64::from(dz[j]) * centre.z
    }

    /// [`Self::flagged`] over the pairs from `first` on, one at a time.
    fn flagged_scalar(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
        first: usize,
    ) {
        for j in first..self.expiry.len() {
            let tree = self.tree_bound(j, centre);
            if tree <= threshold {
                self.flag(j, tree, threshold, nodes, due);
            }
        }
    }

    /// [`Self::flagged`] with the tree bounds of four pairs at a time in AVX2 registers, and
    /// their comparisons packed into a bit mask: with the node bounds only where needed, half the
    /// instructions of bounds computed into arrays for chunks of 32 pairs and compared there
    /// (callgrind, B1's bunny at d = 1.5: 720 against 1,400 a scan).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn flagged_avx2(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        use std::arch::x86_64::{
            _CMP_LE_OQ, _mm_loadu_ps, _mm256_cmp_pd, _mm256_cvtps_pd, _mm256_fmadd_pd,
            _mm256_loadu_pd, _mm256_movemask_pd, _mm256_set1_pd, _mm256_storeu_pd,
        };
        let [dx, dy, dz] = &self.directions;
        let len = self.expiry.len();
        assert!(dx.len() == len && dy.len() == len && dz.len() == len);
        let whole = len - len % 4;
        let (cx, cy, cz) = (
            _mm256_set1_pd(centre.x),
            _mm256_set1_pd(centre.y),
            _mm256_set1_pd(centre.z),
        );
        let limit = _mm256_set1_pd(threshold);
        let mut lanes = [0.0f64; 4];
        for start in (0..whole).step_by(4) {
            // SAFETY: `start + 4 <= len`, the length of each of the four arrays read.
            let tree = unsafe {
                let x = _mm256_cvtps_pd(_mm_loadu_ps(dx.as_ptr().add(start)));
                let y = _mm256_cvtps_pd(_mm_loadu_ps(dy.as_ptr().add(start)));
                let z = _mm256_cvtps_pd(_mm_loadu_ps(dz.as_ptr().add(start)));
                let expiry = _mm256_loadu_pd(self.expiry.as_ptr().add(start));
                _mm256_fmadd_pd(
                    z,
                    cz,
                    _mm256_fmadd_pd(y, cy, _mm256_fmadd_pd(x, cx, expiry)),
                )
            };
            let mut mask = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(tree, limit)) as u32;
            if mask == 0 {
                continue;
            }
            // SAFETY: `lanes` holds four f64.
            unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), tree) };
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                self.flag(start + lane, lanes[lane], threshold, nodes, due);
                mask &= mask - 1;
            }
        }
        self.flagged_scalar(centre, threshold, nodes, due, whole);
    }

    /// Pair `j`, whose tree bound `tree` failed (at most `threshold`): due if its node bound
    /// fails too, else renewed from the node bound.
    #[inline(always)]
    fn flag(
        &self,
        j: usize,
        tree: f64,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        let [dx, dy, dz] = &self.directions;
        let [cx, cy, cz] = &self.node_centres;
        let centre = Vector3::new(f64::from(cx[j]), f64::from(cy[j]), f64::from(cz[j]));
        let moved = nodes.rotation * centre + nodes.translation;
        let node = self.anchors[j]
            + f64::from(dx[j]) * moved.x
            + f64::from(dy[j]) * moved.y
            + f64::from(dz[j]) * moved.z
            - f64::from(self.node_radii[j]) * nodes.turn;
        if node <= nodes.guard {
            due.indices.push(j as u32);
        } else {
            // The tree bound's gap now is `tree - (threshold - guard)`; the node bound's is
            // `node`, larger here: the expiry grows by the difference.
            let renewed = self.expiry[j] + node - tree + (threshold - nodes.guard);
            due.renewed.push((j as u32, renewed));
        }
    }

    /// Renews the expiries that [`Certificates::flagged`] computed, then removes the pairs it
    /// flagged.
    fn settle(&mut self, due: &DueCertificates) {
        for &(i, expiry) in &due.renewed {
            self.expiry[i as usize] = expiry;
        }
        self.remove(&due.indices);
    }

    /// Removes the pairs at `indices` (ascending).
    fn remove(&mut self, indices: &[u32]) {
        // Descending, each swap brings in a pair that stays.
        for &i in indices.iter().rev() {
            self.expiry.swap_remove(i as usize);
            for component in &mut self.directions {
                component.swap_remove(i as usize);
            }
            self.anchors.swap_remove(i as usize);
            for component in &mut self.node_centres {
                component.swap_remove(i as usize);
            }
            self.node_radii.swap_remove(i as usize);
            self.pairs.swap_remove(i as usize);
        }
    }
}

impl Front {
    fn len(&self) -> usize {
        self.separated[0].pairs.len() + self.separated[1].pairs.len() + self.leaves.len()
    }

    /// Empties the front for a traversal from the roots.
    fn restart(&mut self) {
        self.separated.iter_mut().for_each(Certificates::clear);
        self.turn = 0.0;
        self.scale = 0.0;
        self.leaves.clear();
        self.steady = false;
    }

    /// The pairs to test at `placement`, after a further `turn`: the pairs of leaves and every
    /// pair whose certificate may have expired (their indices go to `due`). The front itself is
    /// unchanged until [`Front::settle`]: a query that finds contact leaves it as it was, since
    /// its pose (a trial pose inside an obstacle) says nothing of the next free one.
    fn due(
        &self,
        turn: f64,
        placement: &Placement,
        retest: &mut Vec<(u32, u32)>,
        due: &mut [DueCertificates; 2],
    ) {
        retest.clear();
        retest.extend_from_slice(&self.leaves);
        let turn = self.turn + turn;
        let guard = CERTIFICATE_ROUNDING * self.scale.max(placement.scale);
        for (frame, certificates) in self.separated.iter().enumerate() {
            due[frame].indices.clear();
            due[frame].renewed.clear();
            let threshold = guard + placement.radii[frame] * turn;
            let centre = &placement.centres[frame];
            let (rotation, translation) = placement.motion(frame);
            let nodes = NodeBound {
                rotation,
                translation,
                turn,
                guard,
            };
            certificates.flagged(centre, threshold, &nodes, &mut due[frame]);
            retest.extend(
                due[frame]
                    .indices
                    .iter()
                    .map(|&i| certificates.pairs[i as usize]),
            );
        }
    }

    /// Replaces the pairs [`Front::due`] gave by where their new tests ended.
    fn settle(
        &mut self,
        trees: [&DopTree; 2],
        turn: f64,
        due: &[DueCertificates; 2],
        ended: &[FrontPair],
        placement: &Placement,
    ) {
        self.leaves.clear();
        for (certificates, due) in self.separated.iter_mut().zip(due) {
            certificates.settle(due);
        }
        self.turn += turn;
        self.add(trees, ended, placement);
    }

    /// Adds where a traversal at `placement` ended.
    fn add(&mut self, trees: [&DopTree; 2], ended: &[FrontPair], placement: &Placement) {
        self.scale = self.scale.max(placement.scale);
        let guard = CERTIFICATE_ROUNDING * self.scale;
        let motions = [placement.motion(0), placement.motion(1)];
        for &FrontPair { pair, ending } in ended {
            match ending {
                Ending::Separated {
                    gap,
                    direction,
                    along_b,
                } => {
                    let frame = along_b as usize;
                    let [x, y, z] = direction.map(f64::from);
                    // `gap - guard - direction . centre + radius * turn`, for the moving tree
                    // and for the moving node.
                    let bound = |centre: &Vector3<f64>, radius: f64| {
                        gap - guard - (x * centre.x + y * centre.y + z * centre.z)
                            + radius * self.turn
                    };
                    let expiry = bound(&placement.centres[frame], placement.radii[frame]);
                    let node = if along_b { pair.0 } else { pair.1 };
                    let sphere = &trees[1 - frame].nodes[node as usize].sphere;
                    let (rotation, translation) = &motions[frame];
                    let anchor = bound(
                        &(rotation * sphere.centre() + translation),
                        f64::from(sphere.radius),
                    );
                    self.separated[frame].push((expiry, anchor), direction, sphere, pair);
                }
                Ending::Retest => self.leaves.push(pair),
            }
        }
    }
}

/// Tree pairs remembered per thread (a power of two).
const MEMORY_SLOTS: usize = 64;

/// Levels above the old witness's leaves at which a first-hit query searches first when the
/// witness no longer intersects (subtrees of up to 2^levels triangles each).
const WITNESS_SEARCH_LEVELS: u32 = 4;

/// Queries without contact through which the last witness is kept: sliding alternates trial
/// poses in contact with the free pose found between them, and the next trial pose usually
/// touches where the last one did.
const WITNESS_KEPT_MISSES: u32 = 1;

/// Largest front walked before the roots' probes when it proved the last query apart: scanning
/// it costs about what the probes cost (on the 50k torus of B1, whose fronts hold hundreds to
/// thousands of pairs, walking them first made the queries at d = 1.5 and 1.75, most of them far
/// apart, 40-75 % slower).
const FRONT_FIRST_MAX_PAIRS: usize = 128;

/// A carried front is used while B moved by at most this fraction of the smaller bounding radius
/// since the previous query; beyond, most of it would be tested again and the roots are cheaper.
const FRONT_MAX_MOTION: f64 = 0.05;

/// A carried front is dropped when it holds more than this many times the pairs of a fresh one
/// (plus [`FRONT_SLACK_PAIRS`]).
const FRONT_MAX_GROWTH: usize = 2;

/// The growth bound of a steady front ([`Front::steady`]).
const FRONT_MAX_GROWTH_STEADY: usize = 4;

/// Share of a front re-tested by a query below which the front is steady.
const STEADY_DUE_SHARE: f64 = 0.1;

/// Pairs a carried front may exceed its growth bound by (small fronts grow fast in relative terms).
const FRONT_SLACK_PAIRS: usize = 64;

/// A split query walks the remembered front in parallel only from this many due pairs: below,
/// handing the work to other threads costs more than it saves.
const PARALLEL_MIN_STARTS: usize = 256;

/// Pairs a split walk of a remembered front tests on the calling thread before it splits: the
/// pairs of leaves that no plane separated come first, a query that finds contact usually finds
/// it among them, and then it never pays for the split.
const SEQUENTIAL_PREFIX_STARTS: usize = 64;

/// Chunks per thread of a split walk: several, so that threads that finish early steal work.
const PARALLEL_CHUNKS_PER_THREAD: usize = 4;

/// Largest subtree, in triangles, whose pair with a leaf of the other tree is tested against the
/// leaf's face planes before it is split (a test costs a projection of the subtree's corners).
const PLANE_TEST_MAX_TRIANGLES: usize = 16;

/// Largest node, in triangles, whose pair with another such node is tested with their oriented
/// boxes when their DOPs overlap, in walks that record a front. Near contact a small patch of a
/// smooth surface is nearly flat, and its box is thin across it where any DOP of fixed axes
/// is as wide as the patch along most of them: on the 50k torus of B1 the first query after a
/// contact phase opened 1,100-1,200 node pairs down to the leaves with the DOPs alone. Above
/// this size a box test (about 30 ns) rarely separates what the DOPs did not.
const BOX_TEST_MAX_TRIANGLES: usize = 64;

/// The same bound in walks that record no front (a detached query's, the search around an old
/// witness): there a box test only prunes, and most of these walks end on a hit, where the boxes
/// on the way down overlap. On B4's scene the exact stage ran 140 million instructions with boxes
/// of up to 64 triangles in such walks, 127 million with this bound and 115 million with none
/// (callgrind, 210 frames); with none, the worst query of B2 (fcl_env against fcl_rob) doubled.
const PLAIN_BOX_TEST_MAX_TRIANGLES: usize = 8;

/// Depth of the cut through the larger tree where a split query from the roots starts: up to
/// 2^depth pairs, enough for work stealing to balance two to eight threads.
const PARALLEL_CUT_DEPTH: u32 = 5;

/// The starts of a split query from the roots: the nodes of the larger tree at
/// [`PARALLEL_CUT_DEPTH`] (or leaves above it), each paired with the other tree's root. Like the
/// root pair, they cover every pair of leaves exactly once.
fn top_starts(a: &DopTree, b: &DopTree) -> Vec<(u32, u32)> {
    let cut_a = a.nodes.len() >= b.nodes.len();
    let tree = if cut_a { a } else { b };
    let mut cut = vec![0u32];
    for _ in 0..PARALLEL_CUT_DEPTH {
        cut = cut
            .iter()
            .flat_map(|&node| {
                let n = tree.nodes[node as usize];
                if n.is_leaf() {
                    vec![node]
                } else {
                    vec![n.first, n.first + 1]
                }
            })
            .collect();
    }
    cut.into_iter()
        .map(|node| if cut_a { (node, 0) } else { (0, node) })
        .collect()
}

thread_local! {
    /// Boxed, so that taking a memory out of its slot and putting it back moves a pointer, not
    /// the memory's few hundred bytes (a query far apart costs tens of nanoseconds in all).
    static PAIR_MEMORIES: RefCell<Vec<Option<Box<PairMemory>>>> =
        const { RefCell::new(Vec::new()) };
}

/// Whether and how a query can start from the remembered front.
enum Carry {
    /// From the front, after a further `turn`: its due pairs are in `retest` and `due`.
    Advanced { turn: f64 },
    /// From the roots; with `keep_on_hit`, the old front is kept when the query finds contact
    /// (a far excursion, such as a trial pose deep inside an obstacle, between poses near the
    /// front's own).
    Restart { keep_on_hit: bool },
}

impl PairMemory {
    /// The slot of the tree pair with ids `(a, b)`.
    fn slot((a, b): (u64, u64)) -> usize {
        (a.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ b) as usize % MEMORY_SLOTS
    }

    /// Takes this thread's memory of the pair `(a, b)` out of its slot (a blank one, keeping the
    /// slot's buffers, if the slot remembers another pair; a new one if a query of this thread
    /// already holds it).
    fn take(a: &DopTree, b: &DopTree) -> Box<PairMemory> {
        PAIR_MEMORIES.with_borrow_mut(|memories| Self::claim(Self::slot_of(memories, a, b), a, b))
    }

    /// Takes the memory as [`Self::take`] does, unless the remembered proof that the roots are
    /// apart still holds with B at `b_to_a` (its bounding centre at `centre_b`): then the memory
    /// records the query as [`Self::first_hit`] would have, in its slot, and `None` says the
    /// trees are apart. A query far apart then costs the bounding-sphere test and the proof's
    /// check (a few nanoseconds), not the memory's trip out of its slot and back. Where the
    /// proof fails, [`Self::first_hit`] checks it once more: a few nanoseconds on a query that
    /// goes on to test nodes.
    fn take_unless_apart(
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
    ) -> Option<Box<PairMemory>> {
        PAIR_MEMORIES.with_borrow_mut(|memories| {
            let slot = Self::slot_of(memories, a, b);
            if let Some(memory) = slot.as_deref_mut()
                && memory.ids == (a.id, b.id)
                && memory.witness.is_none()
                && RootSeparation::still_holds(&memory.root_separation, a, b, b_to_a, centre_b)
            {
                memory.remember_roots_apart();
                memory.last_query = Some(*b_to_a);
                return None;
            }
            Some(Self::claim(slot, a, b))
        })
    }

    /// This thread's slot for the pair `(a, b)` (the slots made on first use).
    fn slot_of<'m>(
        memories: &'m mut Vec<Option<Box<PairMemory>>>,
        a: &DopTree,
        b: &DopTree,
    ) -> &'m mut Option<Box<PairMemory>> {
        if memories.is_empty() {
            memories.resize_with(MEMORY_SLOTS, || Some(Box::default()));
        }
        &mut memories[Self::slot((a.id, b.id))]
    }

    /// Takes the memory out of `slot` for the pair `(a, b)`: a blank one (keeping the slot's
    /// buffers) if the slot remembers another pair, a new one if the slot is empty.
    fn claim(slot: &mut Option<Box<PairMemory>>, a: &DopTree, b: &DopTree) -> Box<PairMemory> {
        let mut memory = slot.take().unwrap_or_default();
        if memory.ids != (a.id, b.id) {
            memory.ids = (a.id, b.id);
            memory.witness = None;
            memory.root_separation = None;
            memory.front_pose = None;
            memory.apart_by_front = false;
            memory.last_query = None;
        }
        memory
    }

    /// Puts the memory back in its slot.
    fn put_back(memory: Box<PairMemory>) {
        PAIR_MEMORIES.with_borrow_mut(|memories| {
            let slot = Self::slot(memory.ids);
            memories[slot] = Some(memory);
        });
    }

    /// A first-hit query that starts from what the previous ones left: the old witness, the
    /// subtrees around it, the old front where the motion may have closed its gaps; the roots
    /// only when there is nothing usable. Remembers what this query found.
    fn first_hit<const K: usize>(
        &mut self,
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
        stats: &mut QueryStats,
        parallel: bool,
    ) -> bool {
        if let Some(leaves) = self.witness
            && witness_still_intersects(a, b, b_to_a, leaves, stats)
        {
            return true;
        }
        // Near a pair apart, the probes of the roots usually fail again where they failed last
        // time, and the front settles the query alone (on the bunny at d = 2.0 of B1, the failed
        // probes took about 40 % of a query's time).
        if self.apart_by_front
            && self.front.len() <= FRONT_FIRST_MAX_PAIRS
            && self.witness.is_none()
            && !RootSeparation::still_holds(&self.root_separation, a, b, b_to_a, centre_b)
        {
            let pair = LazyPair::<K>::new(a, b, b_to_a);
            let (carry, placement) = self.carry_front(&pair);
            if let Carry::Advanced { .. } = carry {
                let hit = self.search_carried::<K>(&pair, carry, placement, stats, parallel);
                return self.remember_walk(hit);
            }
        }
        let Some(pair) = affine_pair::<K>(a, b, b_to_a, centre_b, &mut self.root_separation) else {
            stats.bv_tests += 1;
            self.remember_roots_apart();
            return false;
        };
        // The contact usually moved only a few triangles along: search the subtrees around the
        // old witness before the whole trees.
        let near = self.witness.and_then(|[leaf_a, leaf_b]| {
            let start = (
                a.ancestor(leaf_a, WITNESS_SEARCH_LEVELS),
                b.ancestor(leaf_b, WITNESS_SEARCH_LEVELS),
            );
            pair.get().run_walk::<K>(Walk::from(&[start]), stats)
        });
        let mut detached = false;
        let hit = near.or_else(|| {
            let (carry, placement) = self.carry_front(&pair);
            // A restart that keeps the front on a hit: B moved too far from the front's pose.
            if let Carry::Restart { keep_on_hit: true } = carry
                && self.far_from_last_query(&pair)
            {
                detached = true;
                return pair.get().run::<false, K>(stats, &mut Vec::new(), parallel);
            }
            self.search_carried::<K>(&pair, carry, placement, stats, parallel)
        });
        let found = self.remember_walk(hit);
        // A detached walk proved nothing about the front: the next query must not start there.
        self.apart_by_front &= !detached;
        found
    }

    /// Remembers a query that the roots' test proved apart. The front, if any, stays valid: its
    /// pose is kept with it.
    fn remember_roots_apart(&mut self) {
        self.apart_by_front = false;
        self.remember_witness(None);
    }

    /// Remembers what a query's walk found (its hit, if any) and returns whether it found
    /// contact: the witness, and whether the walk proved the trees apart, which sends the next
    /// query to the front first.
    fn remember_walk(&mut self, hit: Option<[u32; 2]>) -> bool {
        self.apart_by_front = hit.is_none();
        self.remember_witness(hit);
        hit.is_some()
    }

    /// Keeps a query's witness, or the old one through [`WITNESS_KEPT_MISSES`] queries without.
    fn remember_witness(&mut self, hit: Option<[u32; 2]>) {
        if hit.is_some() {
            self.witness = hit;
            self.misses_since_witness = 0;
        } else {
            self.misses_since_witness += 1;
            if self.misses_since_witness > WITNESS_KEPT_MISSES {
                self.witness = None;
            }
        }
    }

    /// The traversal of a first-hit query from the remembered front (or from the roots), as
    /// [`PairMemory::carry_front`] decided, split across rayon's threads when `parallel` and
    /// long. A query without a hit leaves the front where it ended; one with a hit leaves the
    /// front as it was when it came from it.
    fn search_carried<const K: usize>(
        &mut self,
        pair: &LazyPair<'_, K>,
        carry: Carry,
        placement: Placement,
        stats: &mut QueryStats,
        parallel: bool,
    ) -> Option<[u32; 2]> {
        let (a, b) = (pair.a, pair.b);
        // A restart costs about as much as the last complete front was large.
        let split = parallel
            && rayon::current_num_threads() > 1
            && match carry {
                Carry::Advanced { .. } => self.retest.len() >= PARALLEL_MIN_STARTS,
                Carry::Restart { .. } => self.front.fresh_len.unwrap_or(0) >= PARALLEL_MIN_STARTS,
            };
        let top_cut;
        let (starts, sequential): (&[(u32, u32)], usize) = match carry {
            Carry::Advanced { .. } => (&self.retest, SEQUENTIAL_PREFIX_STARTS),
            Carry::Restart { .. } if split => {
                top_cut = top_starts(a, b);
                (&top_cut, 0)
            }
            Carry::Restart { .. } => (&[(0, 0)], 0),
        };
        // Nothing due: the front proves the trees apart without a test (nor the set-up of one).
        let hit = if starts.is_empty() {
            None
        } else if split {
            pair.get()
                .run_walk_parallel::<K>(starts, sequential, &mut self.ended, stats)
        } else {
            let walk = Walk {
                starts,
                stop: None,
                front: Some(&mut self.ended),
            };
            pair.get().run_walk::<K>(walk, stats)
        };
        match carry {
            Carry::Advanced { .. } | Carry::Restart { keep_on_hit: true } if hit.is_some() => {
                return hit;
            }
            // A split walk stopped by a hit leaves no complete front: the next query restarts.
            Carry::Restart { .. } if split && hit.is_some() => {
                self.front_pose = None;
                return hit;
            }
            // A first hit leaves unexplored pairs high up in the trees, so its front
            // understates a complete one: the measure is the first front since the restart
            // that has no hit.
            _ => self.keep_front(&carry, &placement, hit.is_none(), pair),
        }
        hit
    }

    /// An all-pairs query from the remembered front (or from the roots): every pair of leaves
    /// the front holds without a certificate, or whose certificate the motion may have expired,
    /// is walked again; the pairs of intersecting triangles go to `out`. The walk is complete
    /// whatever it finds, so its front is kept. Returns whether any pair intersects.
    fn all_pairs<const K: usize>(
        &mut self,
        pair: &LazyPair<'_, K>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        let (carry, placement) = self.carry_front(pair);
        let starts: &[(u32, u32)] = match carry {
            Carry::Advanced { .. } => &self.retest,
            Carry::Restart { .. } => &[(0, 0)],
        };
        let walk = Walk {
            starts,
            stop: None,
            front: Some(&mut self.ended),
        };
        let found = out.len();
        if !starts.is_empty() {
            pair.get().sequential::<true, K>(walk, stats, out);
        }
        self.keep_front(&carry, &placement, true, pair);
        out.len() > found
    }

    /// Makes the front where this query's walk ended (`ended`): settled into the old one when
    /// the walk came from it, a new one after a restart. `complete`: the walk covered every pair
    /// of leaves, so its front measures the fresh size if none is known since the restart.
    fn keep_front<const K: usize>(
        &mut self,
        carry: &Carry,
        placement: &Placement,
        complete: bool,
        pair: &LazyPair<'_, K>,
    ) {
        match *carry {
            Carry::Advanced { turn } => {
                self.front.steady =
                    (self.retest.len() as f64) < STEADY_DUE_SHARE * self.front.len() as f64;
                self.front
                    .settle([pair.a, pair.b], turn, &self.due, &self.ended, placement);
            }
            Carry::Restart { .. } => {
                self.front.restart();
                self.front.add([pair.a, pair.b], &self.ended, placement);
                self.front.fresh_len = None;
            }
        }
        if complete && self.front.fresh_len.is_none() {
            self.front.fresh_len = Some(self.front.len());
        }
        self.front_pose = Some((pair.rotation, pair.translation));
    }

    /// Whether the old front is usable at `pair`'s pose, and if so its due pairs in `retest`
    /// and `due`; also where the trees are for the certificates, and `ended` emptied for the
    /// walk. Says to restart when there is no front, B moved too far (beyond a fraction of the
    /// smaller radius), or the front grew too large.
    fn carry_front<const K: usize>(&mut self, pair: &LazyPair<'_, K>) -> (Carry, Placement) {
        let (a, b) = (pair.a, pair.b);
        let placement = Placement::new(a, b, &pair.rotation, &pair.translation);
        self.ended.clear();
        let Some((old_rotation, old_translation)) = &self.front_pose else {
            return (Carry::Restart { keep_on_hit: false }, placement);
        };
        let growth = if self.front.steady {
            FRONT_MAX_GROWTH_STEADY
        } else {
            FRONT_MAX_GROWTH
        };
        if let Some(fresh_len) = self.front.fresh_len
            && self.front.len() > growth * fresh_len + FRONT_SLACK_PAIRS
        {
            return (Carry::Restart { keep_on_hit: false }, placement);
        }
        let (turn, far) = motion_since(pair, old_rotation, old_translation);
        if far {
            return (Carry::Restart { keep_on_hit: true }, placement);
        }
        self.front
            .due(turn, &placement, &mut self.retest, &mut self.due);
        (Carry::Advanced { turn }, placement)
    }

    /// Whether a query at `pair`'s pose is far ([`motion_since`]) from the last query's. A
    /// first-hit query far from both the front's pose and the last query's is detached: no
    /// motion connects it to the queries before, nor likely to the next one (the trees are
    /// shared by several pairs of objects, as in a scene of many copies of a few parts, or the
    /// poses are random). It walks from the roots without recording a front and leaves the old
    /// one as it is: on B4's scene, recording the front, with the box tests that tighten it, was
    /// about a quarter of the exact stage's instructions (callgrind).
    fn far_from_last_query<const K: usize>(&self, pair: &LazyPair<'_, K>) -> bool {
        self.last_query.is_some_and(|last| {
            let rotation = last.rotation.to_rotation_matrix();
            motion_since(pair, rotation.matrix(), &last.translation.vector).1
        })
    }
}

/// How far B turned since it was at `(rotation, translation)` in A's frame (a bound on `|R' - R|`
/// in the spectral norm), and whether it moved too far since for a front kept there to pay off
/// ([`FRONT_MAX_MOTION`]).
fn motion_since<const K: usize>(
    pair: &LazyPair<'_, K>,
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
) -> (f64, bool) {
    let (a, b) = (pair.a, pair.b);
    // |R' - R| in the spectral norm is at most the Frobenius norm over sqrt 2 (twice the sine of
    // half the angle between them); the small term covers matrices that are orthogonal only to
    // rounding.
    let turn = (pair.rotation - rotation).norm() * std::f64::consts::FRAC_1_SQRT_2 + 1e-12;
    // How far any point of B moved in A's frame.
    let shift = (pair.translation - translation).norm();
    let reach_b = b.bounding_centre.coords.norm() + b.bounding_radius;
    let far = turn * reach_b + shift > FRONT_MAX_MOTION * a.bounding_radius.min(b.bounding_radius);
    (turn, far)
}

/// True when the pair of leaves that proved two trees in contact at the previous query still has
/// intersecting triangles at `b_to_a`.
fn witness_still_intersects(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    [leaf_a, leaf_b]: [u32; 2],
    stats: &mut QueryStats,
) -> bool {
    if leaf_a as usize >= a.nodes.len() || leaf_b as usize >= b.nodes.len() {
        return false;
    }
    // Moved exactly as the traversal moves B's triangles, so both give the same answer.
    let rotation = b_to_a.rotation.to_rotation_matrix();
    let translation = b_to_a.translation.vector;
    let (triangles_a, triangles_b) = (a.node_triangles(leaf_a), b.node_triangles(leaf_b));
    triangles_b.iter().any(|tb| {
        let tb = tb.map(|p| Point3::from(rotation.matrix() * p.coords + translation));
        triangles_a.iter().any(|ta| {
            stats.tri_tests += 1;
            triangles_intersect(ta, &tb)
        })
    })
}

/// Source of tree ids (0 is never given out: it marks an empty memory slot).
static NEXT_TREE_ID: AtomicU64 = AtomicU64::new(1);

/// The query of `b` posed at `b_to_a` against `a` with the O(k) re-alignment, or `None` when
/// [`roots_separated_along_offset`] already proves them apart (`centre_b`: B's centre in A's
/// frame; `root_separation`: how the roots were last proved apart, updated).
fn affine_pair<'a, const K: usize>(
    a: &'a DopTree,
    b: &'a DopTree,
    b_to_a: &Isometry3<f64>,
    centre_b: &Point3<f64>,
    root_separation: &mut Option<RootSeparation>,
) -> Option<LazyPair<'a, K>> {
    let separated = RootSeparation::still_holds(root_separation, a, b, b_to_a, centre_b) || {
        with_cone_hints(&CONE_HINTS, |hints| {
            roots_separated_along_offset(a, b, b_to_a, centre_b, hints, root_separation)
        })
    };
    (!separated).then(|| LazyPair::new(a, b, b_to_a))
}

/// A query's two trees and B's pose in A's frame, with the traversal's set-up (the support cones
/// of the O(k) re-alignment) made on first use: a query that the remembered front answers alone
/// never pays for it.
struct LazyPair<'a, const K: usize> {
    a: &'a DopTree,
    b: &'a DopTree,
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
    pair: std::cell::OnceCell<TreePair<'a, AffineRealign<K>>>,
}

impl<'a, const K: usize> LazyPair<'a, K> {
    /// The query of `b` posed at `b_to_a` against `a`, set up on first use.
    fn new(a: &'a DopTree, b: &'a DopTree, b_to_a: &Isometry3<f64>) -> Self {
        LazyPair {
            a,
            b,
            rotation: *b_to_a.rotation.to_rotation_matrix().matrix(),
            translation: b_to_a.translation.vector,
            pair: std::cell::OnceCell::new(),
        }
    }

    /// The traversal's set-up, made now if not yet.
    fn get(&self) -> &TreePair<'a, AffineRealign<K>> {
        self.pair.get_or_init(|| {
            let realigner = with_cone_hints(&CONE_HINTS, |hints| {
                AffineRealign::<K>::new(self.a, self.b, &self.rotation, &self.translation, hints)
            });
            TreePair {
                a: self.a,
                b: self.b,
                rotation: self.rotation,
                translation: self.translation,
                realigner,
            }
        })
    }
}

/// How two roots were proved apart: B's points lay at least `gap` beyond A's root along A's
/// orientation `slot` (`normal`, A's frame), with B's centre at `centre` and B's rotation
/// `rotation` (both in A's frame).
#[derive(Debug, Clone, Copy)]
struct RootSeparation {
    slot: u8,
    normal: Vector3<f64>,
    gap: f64,
    centre: Vector3<f64>,
    rotation: UnitQuaternion<f64>,
}

impl RootSeparation {
    /// Whether the last proof, if any, still holds with B at `b_to_a` (its centre at
    /// `centre_b`): B's points moved along the normal by at least the centre's move less B's
    /// radius times `|R - R0|`, which is `2 sin(θ / 2)` for the angle θ between the rotations, so
    /// its square is `4 (1 - (q . q0)^2)`: compared in squares, without a square root.
    fn still_holds(
        proof: &Option<Self>,
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
    ) -> bool {
        let Some(proof) = proof else {
            return false;
        };
        let scale = root_scale(a, b_to_a) + b.bounding_radius;
        let gap = proof.gap + proof.normal.dot(&(centre_b.coords - proof.centre))
            - CERTIFICATE_ROUNDING * scale;
        let cos_half = proof.rotation.coords.dot(&b_to_a.rotation.coords);
        // The small term covers the rounding of 1 - cos² for nearly equal rotations.
        let turn_squared = 4.0 * (1.0 - cos_half * cos_half) + 1e-15;
        gap > 0.0 && gap * gap > b.bounding_radius * b.bounding_radius * turn_squared
    }
}

/// A bound on the coordinates of a root test at `b_to_a`, for its rounding margins: `|t|`
/// (bounded by its 1-norm, which needs no square root) plus A's largest offset.
fn root_scale(a: &DopTree, b_to_a: &Isometry3<f64>) -> f64 {
    b_to_a.translation.vector.abs().sum() + a.max_abs_offset() as f64
}

/// Cheap start of a query, once the bounding spheres overlap and the last proof that the roots
/// are apart (`root_separation`) no longer holds: along that proof's orientation, then along
/// the few orientations of A closest to the direction from A's centre
/// to B's (`centre_b`, in A's frame), B's bounding sphere and then B's root re-aligned along that
/// orientation only (one support cone instead of k) are tested against A's root. Pairs far
/// apart end here; `root_separation` keeps the proof found.
fn roots_separated_along_offset(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    centre_b: &Point3<f64>,
    hints: &mut ConeHints,
    root_separation: &mut Option<RootSeparation>,
) -> bool {
    let translation = &b_to_a.translation.vector;
    // The offsets are f32: the same margin as in the traversal covers their rounding.
    let scale = root_scale(a, b_to_a);
    let d = b.node_offsets(0);
    // The gap by which B lies beyond A's root along orientation `slot`, if it does.
    let gap_along = |slot: usize, hint: &mut u8| {
        let a_max = a.node_offsets(0)[slot] as f64;
        let normal = a.set.normal(slot);
        let sphere_gap = normal.dot(&centre_b.coords) - b.bounding_radius - a_max;
        if sphere_gap > 0.0 {
            return Some(sphere_gap);
        }
        let cone = b
            .set
            .support_cone_hinted(&b_to_a.rotation.inverse_transform_vector(&-normal), hint);
        let b_support = (0..3)
            .map(|l| cone.lambda[l] * d[cone.planes[l] as usize] as f64)
            .sum::<f64>()
            - normal.dot(translation);
        let margin =
            rounding_margin(cone.lambda.iter().sum::<f64>() * b.max_abs_offset() as f64 + scale)
                as f64;
        let gap = -(a_max + b_support + margin);
        (gap > 0.0).then_some(gap)
    };
    let last = root_separation.map(|proof| usize::from(proof.slot));
    let mut prove = |slot: usize| {
        let gap = gap_along(slot, &mut hints[slot])?;
        *root_separation = Some(RootSeparation {
            slot: slot as u8,
            normal: a.set.normal(slot),
            gap,
            centre: centre_b.coords,
            rotation: b_to_a.rotation,
        });
        Some(())
    };
    if let Some(last) = last
        && prove(last).is_some()
    {
        return true;
    }
    let offset = centre_b - a.bounding_centre;
    // Slot i compares A's maximum along n_i with B's minimum along n_i: promising when B lies
    // far along n_i.
    let mut probes = [(f64::MIN, 0usize); ROOT_PROBES];
    for i in 0..a.k {
        let score = a.set.normal(i).dot(&offset);
        if score > probes[ROOT_PROBES - 1].0 {
            probes[ROOT_PROBES - 1] = (score, i);
            probes.sort_by(|x, y| y.0.total_cmp(&x.0));
        }
    }
    probes
        .iter()
        .any(|&(_, slot)| Some(slot) != last && prove(slot).is_some())
}

/// Number of orientations tried by [`roots_separated_along_offset`] before a full query.
const ROOT_PROBES: usize = 3;

/// Per orientation slot of A, the generic vertex of B's set that supported it at the previous
/// query on this thread: the first candidate tried (temporal coherence of poses).
type ConeHints = [u8; MAX_K];

/// The largest supported k.
const MAX_K: usize = 26;

thread_local! {
    static CONE_HINTS: std::cell::Cell<ConeHints> = const { std::cell::Cell::new([u8::MAX; MAX_K]) };
    static REVERSE_CONE_HINTS: std::cell::Cell<ConeHints> =
        const { std::cell::Cell::new([u8::MAX; MAX_K]) };
}

/// Runs `f` with this thread's cone hints in `hints` (one of the two above), keeping what it
/// leaves in them for the next query.
fn with_cone_hints<T>(
    hints: &'static std::thread::LocalKey<std::cell::Cell<ConeHints>>,
    f: impl FnOnce(&mut ConeHints) -> T,
) -> T {
    let mut current = hints.get();
    let result = f(&mut current);
    hints.set(current);
    result
}

/// Top-down construction state.
struct TreeBuilder<'a> {
    set: &'a OrientationSet,
    leaf_size: usize,
    k: usize,
    triangles: Vec<Triangle>,
    /// `k` support values per triangle, in mesh order, rounded up to `f32`.
    triangle_dops: Vec<f32>,
    /// Centroid of each triangle, in mesh order.
    centroids: Vec<Point3<f64>>,
    order: Vec<u32>,
    nodes: Vec<Node>,
    parents: Vec<u32>,
    triangle_ranges: Vec<[u32; 2]>,
    offsets: Vec<f32>,
}

impl<'a> TreeBuilder<'a> {
    fn new(mesh: &TriMesh, set: &'a OrientationSet, leaf_size: usize) -> Self {
        let k = set.k();
        let triangles: Vec<Triangle> = (0..mesh.triangles().len())
            .map(|i| mesh.triangle(i))
            .collect();
        let mut triangle_dops = Vec::with_capacity(triangles.len() * k);
        for t in &triangles {
            triangle_dops.extend((0..k).map(|i| {
                let n = set.normal(i);
                round_up(t.iter().map(|p| n.dot(&p.coords)).fold(f64::MIN, f64::max))
            }));
        }
        let centroids = triangles
            .iter()
            .map(|t| Point3::from((t[0].coords + t[1].coords + t[2].coords) / 3.0))
            .collect();
        TreeBuilder {
            set,
            leaf_size,
            k,
            order: (0..triangles.len() as u32).collect(),
            triangles,
            triangle_dops,
            centroids,
            nodes: Vec::new(),
            parents: Vec::new(),
            triangle_ranges: Vec::new(),
            offsets: Vec::new(),
        }
    }

    fn build(mut self) -> DopTree {
        self.push_nodes(1, 0);
        self.build_node(0, 0, self.triangles.len());
        let max_abs_offset = self.offsets[..self.k]
            .iter()
            .fold(0.0f32, |m, d| m.max(d.abs()));
        let (bounding_centre, radius) = bounding_sphere_of(self.triangles.iter().flatten());
        let boxes = self
            .triangle_ranges
            .iter()
            .map(|&[start, end]| {
                NodeBox::around(&self.triangles, &self.order[start as usize..end as usize])
            })
            .collect();
        DopTree {
            id: NEXT_TREE_ID.fetch_add(1, Ordering::Relaxed),
            bounding_centre,
            bounding_radius: radius * (1.0 + 1e-9) + 1e-12,
            set: self.set.clone(),
            k: self.k,
            nodes: self.nodes.into(),
            parents: self.parents.into(),
            triangle_ranges: self.triangle_ranges.into(),
            offsets: self.offsets.into(),
            triangles: self
                .order
                .iter()
                .map(|&i| self.triangles[i as usize])
                .collect(),
            triangle_ids: self.order.into(),
            max_abs_offset,
            boxes,
        }
    }

    /// Appends `count` nodes, children of `parent`; returns the index of the first.
    fn push_nodes(&mut self, count: usize, parent: usize) -> usize {
        let first = self.nodes.len();
        for _ in 0..count {
            self.parents.push(parent as u32);
            self.triangle_ranges.push([0, 0]);
            self.nodes.push(Node {
                first: 0,
                count: 0,
                size: 0.0,
                sphere: NodeSphere::default(),
            });
        }
        self.offsets.resize(self.nodes.len() * self.k, 0.0);
        first
    }

    fn build_node(&mut self, index: usize, start: usize, end: usize) {
        let k = self.k;
        let h = k / 2;
        let mut dop = vec![f32::MIN; k];
        for &t in &self.order[start..end] {
            let support = &self.triangle_dops[t as usize * k..(t as usize + 1) * k];
            merge_max(&mut dop, support);
        }
        self.offsets[index * k..(index + 1) * k].copy_from_slice(&dop);
        self.triangle_ranges[index] = [start as u32, end as u32];
        let sphere = NodeSphere::around(
            self.order[start..end]
                .iter()
                .flat_map(|&t| &self.triangles[t as usize]),
        );
        let size = (0..h).map(|i| dop[i] + dop[i + h]).fold(0.0, f32::max);
        let count = end - start;
        if count <= self.leaf_size {
            self.nodes[index] = Node {
                first: start as u32,
                count: count as u32,
                size,
                sphere,
            };
            return;
        }
        let mid = self.partition(start, end);
        let children = self.push_nodes(2, index);
        self.nodes[index] = Node {
            first: children as u32,
            count: 0,
            size,
            sphere,
        };
        self.build_node(children, start, mid);
        self.build_node(children + 1, mid, end);
    }

    /// Splits `order[start..end]` in two non-empty halves and returns where the second begins.
    ///
    /// Binned surface heuristic: along each orientation axis the centroids are put in
    /// [`SPLIT_BINS`] bins, and the split between bins minimising
    /// `size(left) * count(left) + size(right) * count(right)` is taken, where `size` is the sum of
    /// the child DOP's slab widths (proportional to its mean width, hence to how often a node of
    /// the other tree overlaps it). Falls back to the median when all centroids share a bin.
    fn partition(&mut self, start: usize, end: usize) -> usize {
        let k = self.k;
        let h = k / 2;
        // (cost, axis, lowest projection, bins per unit length, first bin of the right side)
        let mut best: Option<(f64, usize, f64, f64, usize)> = None;
        let mut bin_dops = vec![f32::MIN; SPLIT_BINS * k];
        let mut bin_counts = [0usize; SPLIT_BINS];
        let mut left_dops = vec![f32::MIN; SPLIT_BINS * k];
        // Centroid extent along every axis.
        let spreads: Vec<(usize, f64, f64)> = self
            .set
            .axes()
            .iter()
            .enumerate()
            .map(|(i, axis)| {
                let (lo, hi) = self.order[start..end]
                    .iter()
                    .map(|&t| axis.dot(&self.centroids[t as usize].coords))
                    .fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
                (i, lo, hi)
            })
            .collect();
        // Few triangles: as many bins as triangles keeps the cost linear in their number.
        let bins = SPLIT_BINS.min(end - start);
        for &(axis_index, lo, hi) in &spreads {
            let axis = self.set.axes()[axis_index];
            if hi - lo <= 1e-12 * (hi.abs() + lo.abs() + 1.0) {
                continue;
            }
            let scale = bins as f64 / (hi - lo);
            bin_dops[..bins * k].fill(f32::MIN);
            bin_counts.fill(0);
            for &t in &self.order[start..end] {
                let bin = bin_of(
                    axis.dot(&self.centroids[t as usize].coords),
                    lo,
                    scale,
                    bins,
                );
                bin_counts[bin] += 1;
                let support = &self.triangle_dops[t as usize * k..(t as usize + 1) * k];
                merge_max(&mut bin_dops[bin * k..(bin + 1) * k], support);
            }
            // Prefix DOPs from the left, then sweep from the right.
            let mut running = vec![f32::MIN; k];
            for bin in 0..bins {
                merge_max(&mut running, &bin_dops[bin * k..(bin + 1) * k]);
                left_dops[bin * k..(bin + 1) * k].copy_from_slice(&running);
            }
            let size = |dop: &[f32]| (0..h).map(|i| (dop[i] + dop[i + h]) as f64).sum::<f64>();
            running.fill(f32::MIN);
            let mut right_count = 0;
            for bin in (1..bins).rev() {
                merge_max(&mut running, &bin_dops[bin * k..(bin + 1) * k]);
                right_count += bin_counts[bin];
                let left_count = (end - start) - right_count;
                if left_count == 0 || right_count == 0 {
                    continue;
                }
                let cost = size(&left_dops[(bin - 1) * k..bin * k]) * left_count as f64
                    + size(&running) * right_count as f64;
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis_index, lo, scale, bin));
                }
            }
        }
        let Some((_, axis_index, lo, scale, split_bin)) = best else {
            let mid = start + (end - start) / 2;
            let axis = self.set.axes()[0];
            let centroids = &self.centroids;
            self.order[start..end].select_nth_unstable_by(mid - start, |a, b| {
                axis.dot(&centroids[*a as usize].coords)
                    .total_cmp(&axis.dot(&centroids[*b as usize].coords))
            });
            return mid;
        };
        let axis = self.set.axes()[axis_index];
        let mut boundary = start;
        for i in start..end {
            let t = self.order[i];
            if bin_of(
                axis.dot(&self.centroids[t as usize].coords),
                lo,
                scale,
                bins,
            ) < split_bin
            {
                self.order.swap(i, boundary);
                boundary += 1;
            }
        }
        boundary
    }
}

/// A sphere enclosing a node's triangles, in its tree's frame.
#[derive(Debug, Clone, Copy, Default)]
struct NodeSphere {
    centre: [f32; 3],
    radius: f32,
}

impl NodeSphere {
    /// The sphere centred on the bounding box of `points`, with the radius rounded up so that
    /// every point lies within it from the `f32` centre, widened by the certificates' rounding
    /// guard (their directions are unit only to `f32` rounding).
    fn around<'a>(points: impl Iterator<Item = &'a Point3<f64>> + Clone) -> Self {
        let (lo, hi) = bounding_box_of(points.clone());
        let centre = nalgebra::center(&lo, &hi).coords.map(|x| x as f32);
        let radius = points
            .map(|p| (p.coords - centre.cast::<f64>()).norm())
            .fold(0.0, f64::max);
        NodeSphere {
            centre: centre.into(),
            radius: round_up(radius * (1.0 + CERTIFICATE_ROUNDING)),
        }
    }

    fn centre(&self) -> Vector3<f64> {
        Vector3::from(self.centre).cast::<f64>()
    }
}

/// An oriented box around a node's triangles, in its tree's frame and in `f32` (the box tests of
/// [`TreePair::box_separation`] read it beside the DOPs, so it is kept as small as they are).
#[derive(Debug, Clone, Copy, Default)]
struct NodeBox {
    /// Axes as columns, unit and orthogonal to `f32` rounding.
    axes: [[f32; 3]; 3],
    centre: [f32; 3],
    /// Half side lengths, padded so that every triangle corner `p` is `centre + sum of u_i
    /// axes_i` with `|u_i| <= extents[i]`, in spite of the rounded axes and centre.
    extents: [f32; 3],
}

/// Relative pad of a [`NodeBox`]'s extents, of the box's distance from the origin plus its half
/// sides: covers axes orthonormal only to `f32` rounding (a few 1e-7) and the `f32` centre.
const BOX_ROUNDING: f64 = 1e-5;

impl NodeBox {
    /// The box fitted (as the OBB-tree fits its boxes) to the triangles `subset` of
    /// `triangles`, rounded to `f32` outwards.
    fn around(triangles: &[Triangle], subset: &[u32]) -> Self {
        let axes = OrientedBox::fitted_axes(triangles, subset)
            .map(|x| x as f32)
            .cast::<f64>();
        let (lo, hi) = OrientedBox::local_range(&axes, triangles, subset);
        let centre = axes * ((lo + hi) * 0.5);
        let half = (hi - lo) * 0.5;
        let pad = BOX_ROUNDING * (centre.norm() + half.sum());
        NodeBox {
            axes: axes.map(|x| x as f32).into(),
            centre: centre.map(|x| x as f32).into(),
            extents: half.map(|x| round_up(x + pad)).into(),
        }
    }

    /// The box in `f64`, for the separating-axis test and projections.
    fn oriented(&self) -> OrientedBox {
        OrientedBox {
            axes: Matrix3::from(self.axes).cast::<f64>(),
            center: Vector3::from(self.centre).cast::<f64>(),
            extents: Vector3::from(self.extents).cast::<f64>(),
        }
    }
}

/// `into[i] = max(into[i], from[i])`, written so that it compiles to vector max instructions.
fn merge_max(into: &mut [f32], from: &[f32]) {
    for (d, &s) in into.iter_mut().zip(from) {
        *d = if s > *d { s } else { *d };
    }
}

/// Number of bins per axis of the split heuristic.
const SPLIT_BINS: usize = 16;

/// The bin of a centroid projection `x` on an axis whose projections start at `lo`.
fn bin_of(x: f64, lo: f64, scale: f64, bins: usize) -> usize {
    (((x - lo) * scale) as usize).min(bins - 1)
}

/// The smallest `f32` not below `x`.
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}

/// Re-aligns a node of tree B to A's orientations, for one query.
///
/// The result is stored *opposite*: `out[i]` is the support of B's node along `-n_i`, so that the
/// nodes are disjoint along axis i exactly when `a[i] + out[i] < 0`.
pub(crate) trait Realign<const K: usize>: Sync {
    /// Writes the re-aligned offsets of node `node` of `b`.
    /// With `FUSED`, multiply-adds are fused (only where the CPU has FMA, or they become calls).
    fn realign<const FUSED: bool>(&self, b: &DopTree, node: usize, out: &mut [f32; K]);

    /// The re-alignment of A's nodes into B's frame (made on first use), when the method also
    /// tests B's axes.
    fn reverse(&self, _a: &DopTree, _b: &DopTree) -> Option<&Self> {
        None
    }
}

/// The paper's O(k) re-alignment: each new offset is `Σ λ d_j + n . t` over the three planes of
/// the generic vertex that supports the rotated direction.
///
/// Stored densely, one column of coefficients per plane of B, so that re-aligning a node is k_B
/// vector multiply-adds of `K` lanes (no gathers; vectorises well).
///
/// Leaves are handled exactly instead: their few triangle corners are moved into A's frame and
/// projected on A's directions, which costs about as much as the affine combination and gives
/// the tightest enclosing DOP (a leaf's DOP is flat, far from the generic structure, so the affine
/// bound is loose there).
pub(crate) struct AffineRealign<const K: usize> {
    /// `columns[j][i]`: coefficient of B's offset j in the re-aligned offset of slot i (on the
    /// heap: a query moves this struct around, and copying k_B x K floats costs more than
    /// allocating them).
    columns: Vec<[f32; K]>,
    base: [f32; K],
    /// Directions of the slots (`-n_i`, A's frame) by component, for projecting leaf corners.
    directions: [[f32; K]; 3],
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
    /// Bound on the f32 rounding of a projected leaf corner.
    leaf_margin: f32,
    /// A's nodes re-aligned into B's frame (same k only): the traversal then tests B's axes
    /// too. The DOP test alone separates only along A's axes; two thin patches crossing at an
    /// angle are usually separated along B's own normals, so testing both ways prunes near-contact
    /// pairs much earlier, as the 15-axis test does for OBBs.
    reverse: std::sync::OnceLock<Box<AffineRealign<K>>>,
}

impl<const K: usize> AffineRealign<K> {
    /// Finds, for each of A's directions, its support cone in B's orientation set.
    fn new(
        a: &DopTree,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
        hints: &mut ConeHints,
    ) -> Self {
        // Both trees have K orientations (checked by `with_affine`).
        debug_assert_eq!(b.k, K);
        let mut columns = vec![[0f32; K]; K];
        let mut base = [0f32; K];
        let mut directions = [[0f32; K]; 3];
        let mut lambda_sum_max = 0.0f64;
        let r = rotation;
        let half = K / 2;
        for (i, hint) in hints.iter_mut().enumerate().take(half) {
            let direction = -a.set.normal(i);
            for (c, component) in directions.iter_mut().enumerate() {
                component[i] = direction[c] as f32;
                component[i + half] = -direction[c] as f32;
            }
            // u = Rᵀ direction, written out: nalgebra's generic product is slower here.
            let u = Vector3::new(
                r[(0, 0)] * direction.x + r[(1, 0)] * direction.y + r[(2, 0)] * direction.z,
                r[(0, 1)] * direction.x + r[(1, 1)] * direction.y + r[(2, 1)] * direction.z,
                r[(0, 2)] * direction.x + r[(1, 2)] * direction.y + r[(2, 2)] * direction.z,
            );
            let cone = b
                .set
                .cone_if_contains(*hint, &u)
                .unwrap_or_else(|| b.set.support_cone_hinted(&u, hint));
            // The opposite direction -u is the same combination of the opposite normals (normal
            // p + k/2 is -n_p): half the cone searches.
            for l in 0..3 {
                let plane = cone.planes[l] as usize;
                let opposite = if plane < half {
                    plane + half
                } else {
                    plane - half
                };
                columns[plane][i] = cone.lambda[l] as f32;
                columns[opposite][i + half] = cone.lambda[l] as f32;
            }
            lambda_sum_max = lambda_sum_max.max(cone.lambda[0] + cone.lambda[1] + cone.lambda[2]);
            let along = direction.dot(translation);
            base[i] = along as f32;
            base[i + half] = -along as f32;
        }
        let shift = translation.norm();
        let margin = rounding_margin(
            lambda_sum_max * b.max_abs_offset() as f64 + shift + a.max_abs_offset() as f64,
        );
        for x in &mut base {
            *x += margin;
        }
        // A moved corner is within |t| + |centre_B| + radius_B of A's origin.
        let reach = shift + b.bounding_centre.coords.norm() + b.bounding_radius;
        AffineRealign {
            columns,
            base,
            directions,
            rotation: *rotation,
            translation: *translation,
            leaf_margin: rounding_margin(reach),
            reverse: std::sync::OnceLock::new(),
        }
    }
}

/// A margin that bounds the `f32` rounding of re-aligned offsets of magnitude up to `scale`.
pub(crate) fn rounding_margin(scale: f64) -> f32 {
    (scale * 64.0 * f32::EPSILON as f64) as f32
}

impl<const K: usize> Realign<K> for AffineRealign<K> {
    fn reverse(&self, a: &DopTree, b: &DopTree) -> Option<&Self> {
        if a.k != b.k {
            return None;
        }
        let reverse = self.reverse.get_or_init(|| {
            // A's nodes in B's frame: rotation Rᵀ, translation -Rᵀ t.
            let inverse = self.rotation.transpose();
            Box::new(with_cone_hints(&REVERSE_CONE_HINTS, |hints| {
                AffineRealign::new(b, a, &inverse, &-(inverse * self.translation), hints)
            }))
        });
        Some(reverse)
    }

    #[inline(always)]
    fn realign<const FUSED: bool>(&self, b: &DopTree, node: usize, out: &mut [f32; K]) {
        let leaf = &b.nodes[node];
        if leaf.is_leaf() {
            *out = [f32::MIN; K];
            for triangle in &b.triangles[leaf.first as usize..(leaf.first + leaf.count) as usize] {
                for corner in triangle {
                    let y = (self.rotation * corner.coords + self.translation).cast::<f32>();
                    let [dx, dy, dz] = &self.directions;
                    for (i, o) in out.iter_mut().enumerate() {
                        let p = dx[i] * y.x + dy[i] * y.y + dz[i] * y.z;
                        *o = if p > *o { p } else { *o };
                    }
                }
            }
            for x in out.iter_mut() {
                *x += self.leaf_margin;
            }
            return;
        }
        // Four independent accumulators: one chain of k multiply-adds would be latency bound.
        let mut acc = [self.base, [0.0; K], [0.0; K], [0.0; K]];
        let columns = &self.columns[..];
        let d = b.node_offsets(node);
        let mut groups = columns.chunks_exact(4).zip(d.chunks_exact(4));
        for (group, offsets) in &mut groups {
            for lane in 0..4 {
                multiply_add::<K, FUSED>(&mut acc[lane], &group[lane], offsets[lane]);
            }
        }
        let done = columns.len() - columns.len() % 4;
        for (column, &offset) in columns[done..].iter().zip(&d[done..]) {
            multiply_add::<K, FUSED>(&mut acc[0], column, offset);
        }
        for i in 0..K {
            out[i] = (acc[0][i] + acc[1][i]) + (acc[2][i] + acc[3][i]);
        }
    }
}

/// `acc += column * d`, lane by lane (fused where `FUSED`).
#[inline(always)]
fn multiply_add<const K: usize, const FUSED: bool>(acc: &mut [f32; K], column: &[f32; K], d: f32) {
    for i in 0..K {
        acc[i] = if FUSED {
            column[i].mul_add(d, acc[i])
        } else {
            acc[i] + column[i] * d
        };
    }
}

/// True when A's node offsets `a` and B's re-aligned opposite offsets `e` overlap on every axis.
#[inline(always)]
fn dops_overlap<const K: usize>(a: &[f32; K], e: &[f32; K]) -> bool {
    overlap_slack(a, e) >= 0.0
}

/// The least `a_i + e_i`: how deeply the DOPs overlap along their tightest axis (negative when
/// they are disjoint).
#[inline(always)]
fn overlap_slack<const K: usize>(a: &[f32; K], e: &[f32; K]) -> f32 {
    let mut least = f32::INFINITY;
    for i in 0..K {
        let s = a[i] + e[i];
        least = if s < least { s } else { least };
    }
    least
}

/// The unit normal of a triangle, if it is not degenerate.
fn face_normal(t: &Triangle) -> Option<Vector3<f64>> {
    let normal = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let length = normal.norm();
    (length > 0.0 && length.is_finite()).then(|| normal / length)
}

/// The least and greatest of `direction . p + offset` over the triangles' corners `p`.
fn projection_range(triangles: &[Triangle], direction: &Vector3<f64>, offset: f64) -> (f64, f64) {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in triangles.iter().flatten() {
        let x = direction.x * p.x + direction.y * p.y + direction.z * p.z + offset;
        low = low.min(x);
        high = high.max(x);
    }
    (low, high)
}

/// Fraction of the two nodes' sizes below which an overlap along A's axes is checked along B's.
const REVERSE_TEST_SLACK: f32 = 0.05;

/// This query's view of the per-thread re-alignment cache.
struct RealignCache<'a> {
    stamp: u32,
    tags: &'a mut [(u32, u32)],
    realigned: &'a mut [f32],
}

impl RealignCache<'_> {
    /// The re-aligned offsets of node `node` of `tree`, computed unless cached in this query.
    #[inline(always)]
    fn get<const K: usize, const FUSED: bool, R: Realign<K>>(
        &mut self,
        realigner: &R,
        tree: &DopTree,
        node: u32,
        stats: &mut QueryStats,
    ) -> &[f32; K] {
        let slot = node as usize % CACHE_SLOTS;
        let e: &mut [f32; K] = (&mut self.realigned[slot * K..(slot + 1) * K])
            .try_into()
            .unwrap();
        if self.tags[slot] != (self.stamp, node) {
            self.tags[slot] = (self.stamp, node);
            realigner.realign::<FUSED>(tree, node as usize, e);
            stats.realignments += 1;
        }
        e
    }
}

/// Per-thread buffers reused across queries: the re-alignment cache (stamped per query) and the
/// traversal stack.
///
/// The cache is direct-mapped with [`CACHE_SLOTS`] entries (B node `n` goes to slot
/// `n % CACHE_SLOTS`), small enough to stay in the core's L2 cache whatever the tree size; an
/// entry is valid when its tag holds this query's stamp and the node.
struct Scratch {
    stamp: u32,
    /// Per slot: (stamp of the query that filled it, B node it holds).
    tags: Vec<(u32, u32)>,
    realigned: Vec<f32>,
    /// The same for A's nodes re-aligned into B's frame.
    reverse_tags: Vec<(u32, u32)>,
    reverse_realigned: Vec<f32>,
    stack: Vec<(u32, u32)>,
}

/// Entries of the per-thread re-alignment cache (a power of two).
const CACHE_SLOTS: usize = 4096;

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            stamp: 0,
            tags: vec![(0, 0); CACHE_SLOTS],
            realigned: vec![0.0; CACHE_SLOTS * MAX_K],
            reverse_tags: vec![(0, 0); CACHE_SLOTS],
            reverse_realigned: vec![0.0; CACHE_SLOTS * MAX_K],
            stack: Vec::new(),
        }
    }
}

impl Scratch {
    /// Starts a query: a new stamp invalidates every cache entry.
    fn begin(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.tags.fill((0, 0));
            self.reverse_tags.fill((0, 0));
            self.stamp = 1;
        }
        self.stack.clear();
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Runs `f` with this thread's scratch buffers (or fresh ones if they are already in use).
fn with_scratch<T>(f: impl FnOnce(&mut Scratch) -> T) -> T {
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scratch) => f(&mut scratch),
        Err(_) => f(&mut Scratch::default()),
    })
}

/// One query between two DOP-trees: B's pose in A's frame and the re-alignment method.
pub(crate) struct TreePair<'a, R> {
    a: &'a DopTree,
    b: &'a DopTree,
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
    realigner: R,
}

/// Where a sequential traversal starts and what it records besides its answer.
struct Walk<'w> {
    /// Node pairs to test first (the root pair for a whole query).
    starts: &'w [(u32, u32)],
    /// Set by the first task of a parallel query that finds a hit; stops the others.
    stop: Option<&'w AtomicBool>,
    /// Receives every node pair at which the traversal ended without a hit, with its slack: a
    /// complete traversal's front covers every pair of leaves exactly once.
    front: Option<&'w mut Vec<FrontPair>>,
}

impl<'w> Walk<'w> {
    /// A traversal from `starts` that records nothing.
    fn from(starts: &'w [(u32, u32)]) -> Self {
        Walk {
            starts,
            stop: None,
            front: None,
        }
    }
}

/// A node pair at which a traversal ended, and how.
#[derive(Debug, Clone, Copy)]
struct FrontPair {
    pair: (u32, u32),
    ending: Ending,
}

/// How [`TreePair::face_separation`] measures the extent of an inner node along a leaf's face
/// normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Extent {
    /// Projecting every corner of its triangles: exact, for small subtrees.
    Exact,
    /// From its bounding sphere: a bound, in constant time, for large subtrees.
    Sphere,
}

/// How a traversal ended at a node pair.
#[derive(Debug, Clone, Copy)]
enum Ending {
    /// Proved apart: the other tree's triangles lie at least `gap` beyond this tree's along
    /// `direction` (unit to f32 rounding), in A's frame, or in B's when `along_b`.
    Separated {
        gap: f64,
        direction: [f32; 3],
        along_b: bool,
    },
    /// To be tested again: a pair of leaves that no face plane separates, or a pair left
    /// unexplored when a first hit stopped the traversal.
    Retest,
}

/// How deeply two nodes' DOPs overlap along their tightest axis: negative when they are
/// disjoint, and then the subtrees' triangles are at least `-value` apart along that axis.
#[derive(Debug, Clone, Copy, Default)]
struct Slack {
    value: f32,
    /// The axis is one of B's (A's node re-aligned into B's frame), not one of A's.
    along_b: bool,
}

/// What a traversal found.
#[derive(Default)]
struct Found {
    stats: QueryStats,
    pairs: Vec<[u32; 2]>,
    /// The first pair of leaves found with intersecting triangles (node indices of A and B).
    hit: Option<[u32; 2]>,
}

impl<'a, R> TreePair<'a, R> {
    /// Prepares a query of `b` posed at `b_to_a` in `a`'s frame; `realigner` is made from the
    /// rotation and translation.
    pub(crate) fn new(
        a: &'a DopTree,
        b: &'a DopTree,
        b_to_a: &Isometry3<f64>,
        realigner: impl FnOnce(&Matrix3<f64>, &Vector3<f64>) -> R,
    ) -> Self {
        let rotation = *b_to_a.rotation.to_rotation_matrix().matrix();
        let translation = b_to_a.translation.vector;
        let realigner = realigner(&rotation, &translation);
        TreePair {
            a,
            b,
            rotation,
            translation,
            realigner,
        }
    }

    /// B's leaf triangle `index` (leaf order) moved into A's frame.
    fn b_triangle_in_a(&self, index: usize) -> Triangle {
        self.b.triangles[index].map(|p| Point3::from(self.rotation * p.coords + self.translation))
    }

    /// Tests every triangle pair of two leaves; records pairs when `ALL`, else stops at a hit.
    fn leaf_pair<const ALL: bool>(
        &self,
        leaf_a: &Node,
        leaf_b: &Node,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        let mut hit = false;
        let range_a = leaf_a.first as usize..(leaf_a.first + leaf_a.count) as usize;
        for ib in leaf_b.first as usize..(leaf_b.first + leaf_b.count) as usize {
            let tb = self.b_triangle_in_a(ib);
            for ia in range_a.clone() {
                stats.tri_tests += 1;
                if triangles_intersect(&self.a.triangles[ia], &tb) {
                    hit = true;
                    if !ALL {
                        return true;
                    }
                    out.push([self.a.triangle_ids[ia], self.b.triangle_ids[ib]]);
                }
            }
        }
        hit
    }

    /// The certificate of node pair `(ia, ib)`, whose DOPs overlap, from their oriented boxes:
    /// the separating axis the 15-axis test finds, in A's frame, rounded to `f32`, with the gap
    /// between the boxes' projections on it; `None` when the boxes overlap too, or when either
    /// node has more than `max_triangles` (untested).
    fn box_separation(
        &self,
        (ia, ib): (u32, u32),
        max_triangles: usize,
        stats: &mut QueryStats,
    ) -> Option<Ending> {
        if self.a.node_triangles(ia).len() > max_triangles
            || self.b.node_triangles(ib).len() > max_triangles
        {
            return None;
        }
        stats.bv_tests += 1;
        let box_a = self.a.boxes[ia as usize].oriented();
        let box_b = self.b.boxes[ib as usize].oriented();
        let axis = box_a.separating_axis(&box_b, &self.rotation, &self.translation)?;
        let direction = axis.try_normalize(f64::MIN_POSITIVE)?.cast::<f32>();
        let exact = direction.cast::<f64>();
        // B's box projected in B's frame: n . (R q + t) = (Rᵀ n) . q + n . t.
        let (low_a, high_a) = box_a.projection(&exact, 0.0);
        let (low_b, high_b) = box_b.projection(
            &(self.rotation.transpose() * exact),
            exact.dot(&self.translation),
        );
        let (gap, sign) = if low_b > high_a {
            (low_b - high_a, 1.0)
        } else if low_a > high_b {
            (low_a - high_b, -1.0)
        } else {
            return None;
        };
        Some(Ending::Separated {
            gap,
            direction: (direction * sign).into(),
            along_b: false,
        })
    }

    /// The two node pairs to visit after `(ia, ib)` overlapped: the larger node is split.
    fn children(&self, ia: u32, ib: u32) -> [(u32, u32); 2] {
        let (na, nb) = (self.a.nodes[ia as usize], self.b.nodes[ib as usize]);
        let split_a = !na.is_leaf() && (nb.is_leaf() || na.size >= nb.size);
        if split_a {
            [(na.first, ib), (na.first + 1, ib)]
        } else {
            [(ia, nb.first), (ia, nb.first + 1)]
        }
    }
}

impl<R> TreePair<'_, R> {
    /// Runs the query from the root pair, sequentially or split across threads. Returns the
    /// first pair of leaves found with intersecting triangles (node indices of A and B), if any.
    pub(crate) fn run<const ALL: bool, const K: usize>(
        &self,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
        parallel: bool,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        let found = if parallel {
            let stop = AtomicBool::new(false);
            self.parallel::<ALL, K>(0, 0, PARALLEL_DEPTH, &stop)
        } else {
            let mut found = Found::default();
            found.hit = self.sequential::<ALL, K>(
                Walk::from(&[(0, 0)]),
                &mut found.stats,
                &mut found.pairs,
            );
            found
        };
        *stats += found.stats;
        out.extend_from_slice(&found.pairs);
        found.hit
    }

    /// A first-hit traversal as `walk` says; returns the pair of leaves found with intersecting
    /// triangles, if any.
    fn run_walk<const K: usize>(&self, walk: Walk<'_>, stats: &mut QueryStats) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        self.sequential::<false, K>(walk, stats, &mut Vec::new())
    }

    /// A first-hit traversal from `starts` that records its front in `front`: the first
    /// `sequential` starts on this thread, the rest split into chunks across rayon's threads.
    /// Without a hit, the front comes out complete, in the order of `starts`; a hit stops the
    /// other chunks, and the front they leave is incomplete (callers drop it).
    fn run_walk_parallel<const K: usize>(
        &self,
        starts: &[(u32, u32)],
        sequential: usize,
        front: &mut Vec<FrontPair>,
        stats: &mut QueryStats,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        use rayon::prelude::*;
        let (prefix, starts) = starts.split_at(sequential.min(starts.len()));
        let walk = Walk {
            starts: prefix,
            stop: None,
            front: Some(front),
        };
        if let Some(hit) = self.run_walk::<K>(walk, stats) {
            return Some(hit);
        }
        let chunk = starts
            .len()
            .div_ceil(PARALLEL_CHUNKS_PER_THREAD * rayon::current_num_threads())
            .max(1);
        let stop = AtomicBool::new(false);
        let walks: Vec<(Option<[u32; 2]>, Vec<FrontPair>, QueryStats)> = starts
            .par_chunks(chunk)
            .map(|chunk| {
                let (mut ended, mut chunk_stats) = (Vec::new(), QueryStats::default());
                let walk = Walk {
                    starts: chunk,
                    stop: Some(&stop),
                    front: Some(&mut ended),
                };
                let hit = self.run_walk::<K>(walk, &mut chunk_stats);
                (hit, ended, chunk_stats)
            })
            .collect();
        stats.split_walks += 1;
        let mut hit = None;
        for (chunk_hit, ended, chunk_stats) in walks {
            hit = hit.or(chunk_hit);
            front.extend_from_slice(&ended);
            *stats += chunk_stats;
        }
        hit
    }

    /// Depth-first traversal from one node pair with this thread's re-alignment cache, compiled
    /// for AVX2 and FMA where the CPU has them (the interval tests and re-alignments are vector
    /// code).
    fn sequential<const ALL: bool, const K: usize>(
        &self,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        with_scratch(|scratch| {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX2 and FMA, checked just above.
                return unsafe { self.traverse_avx2::<ALL, K>(scratch, walk, stats, out) };
            }
            self.traverse::<ALL, K, false>(scratch, walk, stats, out)
        })
    }

    /// [`Self::traverse`] compiled with AVX2 and FMA enabled.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn traverse_avx2<const ALL: bool, const K: usize>(
        &self,
        scratch: &mut Scratch,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        self.traverse::<ALL, K, true>(scratch, walk, stats, out)
    }

    /// The traversal itself: a stack of node pairs, B's nodes re-aligned once per query.
    #[inline(always)]
    fn traverse<const ALL: bool, const K: usize, const FUSED: bool>(
        &self,
        scratch: &mut Scratch,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        scratch.begin();
        let stamp = scratch.stamp;
        let Scratch {
            tags,
            realigned,
            reverse_tags,
            reverse_realigned,
            stack,
            ..
        } = scratch;
        let mut cache = RealignCache {
            stamp,
            tags,
            realigned,
        };
        let mut reverse_cache = RealignCache {
            stamp,
            tags: reverse_tags,
            realigned: reverse_realigned,
        };
        let Walk {
            starts,
            stop,
            mut front,
        } = walk;
        let box_max_triangles = if front.is_some() {
            BOX_TEST_MAX_TRIANGLES
        } else {
            PLAIN_BOX_TEST_MAX_TRIANGLES
        };
        let mut hit = None;
        // Each start is explored to the end before the next one, so a first hit leaves the
        // later starts untested. The stack holds node pairs already known to overlap. Children
        // pairs are tested when generated and the one overlapping more deeply is visited first:
        // a first hit is found sooner.
        'starts: for (index, &start) in starts.iter().enumerate() {
            let slack = self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, start, stats);
            if slack.value < 0.0 {
                let front = front.as_deref_mut();
                self.record_separation::<K, FUSED>(
                    front,
                    &mut cache,
                    &mut reverse_cache,
                    start,
                    slack,
                );
                continue;
            }
            stack.push(start);
            while let Some((ia, ib)) = stack.pop() {
                if let Some(stop) = stop
                    && stop.load(Ordering::Relaxed)
                {
                    break 'starts;
                }
                stats.nodes_visited += 1;
                let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
                if na.is_leaf() && nb.is_leaf() {
                    let found = self.leaf_pair::<ALL>(na, nb, stats, out);
                    if let Some(front) = front.as_deref_mut() {
                        let ending = if found {
                            Ending::Retest
                        } else {
                            self.face_separation(ia, ib, Extent::Exact)
                        };
                        front.push(FrontPair {
                            pair: (ia, ib),
                            ending,
                        });
                        if found && !ALL {
                            // Every pair left unexplored is tested again next time: the front
                            // then still covers every pair of leaves.
                            let unexplored = stack.iter().chain(&starts[index + 1..]);
                            front.extend(unexplored.map(|&pair| FrontPair {
                                pair,
                                ending: Ending::Retest,
                            }));
                        }
                    }
                    if found {
                        hit = hit.or(Some([ia, ib]));
                        if !ALL {
                            if let Some(stop) = stop {
                                stop.store(true, Ordering::Relaxed);
                            }
                            break 'starts;
                        }
                    }
                    continue;
                }
                // A subtree against one triangle: the triangle's plane often separates them
                // where their DOPs overlap, and it stays a valid certificate along motion in
                // that plane (a peg sliding down its hole's wall), where the DOP axis that would
                // separate their descendants is often the direction of motion. Against a large
                // triangle at a slant it is what ends the descent at all: the triangle's
                // re-aligned DOP is as wide as the triangle along every axis, and would overlap
                // most of the other tree's nodes (a table top under a fine part).
                if let Some(extent) = self.plane_test_extent(na, nb, ia, ib) {
                    stats.bv_tests += 1;
                    let ending = self.face_separation(ia, ib, extent);
                    if let Ending::Separated { .. } = ending {
                        if let Some(front) = front.as_deref_mut() {
                            front.push(FrontPair {
                                pair: (ia, ib),
                                ending,
                            });
                        }
                        continue;
                    }
                }
                let [first, second] = self.children(ia, ib);
                let first_slack =
                    self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, first, stats);
                let second_slack =
                    self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, second, stats);
                // Relative depth: overlap over the size of the pair's smaller node.
                let relative = |(ia, ib): (u32, u32), slack: f32| {
                    let size = self.a.nodes[ia as usize]
                        .size
                        .min(self.b.nodes[ib as usize].size);
                    slack / size.max(f32::MIN_POSITIVE)
                };
                let (deeper, shallower) =
                    if relative(first, first_slack.value) >= relative(second, second_slack.value) {
                        ((first, first_slack), (second, second_slack))
                    } else {
                        ((second, second_slack), (first, first_slack))
                    };
                for (pair, slack) in [shallower, deeper] {
                    if slack.value >= 0.0 {
                        if let Some(ending) = self.box_separation(pair, box_max_triangles, stats) {
                            if let Some(front) = front.as_deref_mut() {
                                front.push(FrontPair { pair, ending });
                            }
                        } else {
                            stack.push(pair);
                        }
                    } else {
                        let front = front.as_deref_mut();
                        self.record_separation::<K, FUSED>(
                            front,
                            &mut cache,
                            &mut reverse_cache,
                            pair,
                            slack,
                        );
                    }
                }
            }
        }
        stack.clear();
        hit
    }

    /// Adds to `front`, when the traversal records one, the node pair that `slack` (negative)
    /// separates with its certificate: the axis the slack came from (found again among the
    /// cached offsets) and the gap along it.
    fn record_separation<const K: usize, const FUSED: bool>(
        &self,
        front: Option<&mut Vec<FrontPair>>,
        cache: &mut RealignCache<'_>,
        reverse_cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        slack: Slack,
    ) where
        R: Realign<K>,
    {
        let Some(front) = front else {
            return;
        };
        let mut unused = QueryStats::default();
        let (own, moved, set) = if slack.along_b {
            // A slack along B's axes comes from a reverse test, so there is a reverse method.
            let Some(reverse) = self.realigner.reverse(self.a, self.b) else {
                front.push(FrontPair {
                    pair: (ia, ib),
                    ending: Ending::Retest,
                });
                return;
            };
            (
                self.b.node_offsets(ib as usize),
                reverse_cache.get::<K, FUSED, R>(reverse, self.a, ia, &mut unused),
                &self.b.set,
            )
        } else {
            (
                self.a.node_offsets(ia as usize),
                cache.get::<K, FUSED, R>(&self.realigner, self.b, ib, &mut unused),
                &self.a.set,
            )
        };
        // The first axis whose sum is the slack (the overlap test's own sums over the same
        // offsets), compared all at once (a bit mask) rather than one branch per axis.
        let mut mask = 0u32;
        for i in 0..K {
            mask |= u32::from(own[i] + moved[i] <= slack.value) << i;
        }
        let axis = (mask.trailing_zeros() as usize).min(K - 1);
        front.push(FrontPair {
            pair: (ia, ib),
            ending: Ending::Separated {
                gap: -slack.value as f64,
                direction: set.normal(axis).cast::<f32>().into(),
                along_b: slack.along_b,
            },
        });
    }

    /// How the leaf's face planes are tried against the other node of a pair of a leaf and an
    /// inner node, one in each tree: against the inner node's triangles when it has at most
    /// [`PLANE_TEST_MAX_TRIANGLES`]; against its bounding sphere when it is smaller than the
    /// leaf (the traversal would otherwise descend the inner node alone under a large
    /// triangle); not at all for other pairs (a small triangle's plane rarely clears a larger
    /// subtree, and the descent splits that subtree anyway).
    fn plane_test_extent(&self, na: &Node, nb: &Node, ia: u32, ib: u32) -> Option<Extent> {
        let extent = |tree: &DopTree, index: u32, inner: &Node, leaf: &Node| {
            if tree.node_triangles(index).len() <= PLANE_TEST_MAX_TRIANGLES {
                Some(Extent::Exact)
            } else {
                (inner.size < leaf.size).then_some(Extent::Sphere)
            }
        };
        match (na.is_leaf(), nb.is_leaf()) {
            (true, false) => extent(self.b, ib, nb, na),
            (false, true) => extent(self.a, ia, na, nb),
            _ => None,
        }
    }

    /// The certificate of node pair `(ia, ib)` where at least one is a leaf: the plane of one
    /// of the leaves' triangles with all of the other node's corners (or, by `extent`, its
    /// bounding sphere) strictly beyond it, the widest gap of them; [`Ending::Retest`] when no
    /// such plane separates them.
    fn face_separation(&self, ia: u32, ib: u32, extent: Extent) -> Ending {
        let (node_a, node_b) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        let triangles_a = self.a.node_triangles(ia);
        let triangles_b = self.b.node_triangles(ib);
        let planes = |node: &Node, triangles| if node.is_leaf() { triangles } else { &[][..] };
        let planes_a = planes(node_a, triangles_a);
        let planes_b = planes(node_b, triangles_b);
        // A node's projections on `direction` (in its tree's frame) plus `offset`.
        let range = |node: &Node, triangles, direction: &Vector3<f64>, offset: f64| {
            if node.is_leaf() || extent == Extent::Exact {
                projection_range(triangles, direction, offset)
            } else {
                let centre = direction.dot(&node.sphere.centre()) + offset;
                let radius = f64::from(node.sphere.radius);
                (centre - radius, centre + radius)
            }
        };
        let mut best = Ending::Retest;
        let mut widest = 0.0;
        // A's normals in A's frame, B's in B's own; each rounded to f32 (as stored) before the
        // gap along it is measured. B's corners are projected in B's frame: n . (R q + t) =
        // (Rᵀ n) . q + n . t.
        let candidates = planes_a
            .iter()
            .map(|t| (t, false))
            .chain(planes_b.iter().map(|t| (t, true)));
        for (triangle, along_b) in candidates {
            let Some(normal) = face_normal(triangle) else {
                continue;
            };
            let direction = normal.cast::<f32>();
            let exact = direction.cast::<f64>();
            let (in_a, in_b) = if along_b {
                (self.rotation * exact, exact)
            } else {
                (exact, self.rotation.transpose() * exact)
            };
            let (low_a, high_a) = range(node_a, triangles_a, &in_a, 0.0);
            let (low_b, high_b) = range(node_b, triangles_b, &in_b, in_a.dot(&self.translation));
            // In A's frame the other tree is B (beyond along +normal when B is above); in B's
            // frame it is A.
            let (gap, sign) = if low_b - high_a > widest {
                (low_b - high_a, if along_b { -1.0 } else { 1.0 })
            } else if low_a - high_b > widest {
                (low_a - high_b, if along_b { 1.0 } else { -1.0 })
            } else {
                continue;
            };
            widest = gap;
            best = Ending::Separated {
                gap,
                direction: (direction * sign).into(),
                along_b,
            };
        }
        best
    }

    /// The overlap slack of a node pair: the least `a_i + e_i` over the axes, negative exactly
    /// when some axis separates them (and then minus a lower bound on their distance). B's node is re-aligned unless cached for this query; when
    /// the method tests both ways and A's axes do not separate, A's node re-aligned into B's
    /// frame is tested against B's axes too.
    #[inline(always)]
    fn slack<const K: usize, const FUSED: bool>(
        &self,
        cache: &mut RealignCache<'_>,
        reverse_cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        stats: &mut QueryStats,
    ) -> Slack
    where
        R: Realign<K>,
    {
        let forward = |value| Slack {
            value,
            along_b: false,
        };
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        let e = cache.get::<K, FUSED, R>(&self.realigner, self.b, ib, stats);
        stats.bv_tests += 1;
        let along_a = overlap_slack(da, e);
        // Only pairs that A's axes barely fail to separate are worth B's axes: deep overlaps
        // are rarely separated by them (measured).
        let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        if along_a < 0.0 || along_a > REVERSE_TEST_SLACK * (na.size + nb.size) {
            return forward(along_a);
        }
        let Some(reverse) = self.realigner.reverse(self.a, self.b) else {
            return forward(along_a);
        };
        let db: &[f32; K] = self.b.node_offsets(ib as usize).try_into().unwrap();
        let e = reverse_cache.get::<K, FUSED, R>(reverse, self.a, ia, stats);
        stats.bv_tests += 1;
        let along_b = overlap_slack(db, e);
        if along_b < along_a {
            Slack {
                value: along_b,
                along_b: true,
            }
        } else {
            forward(along_a)
        }
    }

    /// Splits the traversal into rayon tasks down to `depth`, then traverses sequentially.
    fn parallel<const ALL: bool, const K: usize>(
        &self,
        ia: u32,
        ib: u32,
        depth: u32,
        stop: &AtomicBool,
    ) -> Found
    where
        R: Realign<K>,
    {
        let mut found = Found::default();
        if stop.load(Ordering::Relaxed) {
            return found;
        }
        let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        if depth == 0 || (na.is_leaf() && nb.is_leaf()) {
            found.hit = self.sequential::<ALL, K>(
                Walk {
                    stop: Some(stop),
                    ..Walk::from(&[(ia, ib)])
                },
                &mut found.stats,
                &mut found.pairs,
            );
            return found;
        }
        let mut e = [0f32; K];
        self.realigner.realign::<false>(self.b, ib as usize, &mut e);
        found.stats.realignments += 1;
        found.stats.bv_tests += 1;
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        if !dops_overlap(da, &e) {
            return found;
        }
        found.stats.nodes_visited += 1;
        let [first, second] = self.children(ia, ib);
        let (x, y) = rayon::join(
            || self.parallel::<ALL, K>(first.0, first.1, depth - 1, stop),
            || self.parallel::<ALL, K>(second.0, second.1, depth - 1, stop),
        );
        found.stats += x.stats;
        found.stats += y.stats;
        found.hit = x.hit.or(y.hit);
        found.pairs = x.pairs;
        found.pairs.extend_from_slice(&y.pairs);
        found
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::collision::ObbTree;
    use crate::collision::oracle_tests::{random_pose, random_soup, torus};
    use crate::collision::tumble::tumble_pose;

    /// Every corner of every node's triangles, with the node.
    fn node_corners(tree: &DopTree) -> impl Iterator<Item = (usize, Point3<f64>)> + '_ {
        (0..tree.node_count()).flat_map(move |node| {
            tree.node_triangles(node as u32)
                .iter()
                .flatten()
                .map(move |&corner| (node, corner))
        })
    }

    /// Every corner of node `node`'s triangles, placed by `pose`.
    fn corners_at(tree: &DopTree, node: u32, pose: &Isometry3<f64>) -> Vec<Vector3<f64>> {
        tree.node_triangles(node)
            .iter()
            .flatten()
            .map(|corner| (pose * corner).coords)
            .collect()
    }

    /// How far every point of `far` lies beyond every point of `near` along `direction`
    /// (negative where their projections overlap).
    fn separation_along(
        near: &[Vector3<f64>],
        far: &[Vector3<f64>],
        direction: &Vector3<f64>,
    ) -> f64 {
        let top = near
            .iter()
            .map(|p| p.dot(direction))
            .fold(f64::MIN, f64::max);
        let bottom = far
            .iter()
            .map(|q| q.dot(direction))
            .fold(f64::MAX, f64::min);
        bottom - top
    }

    #[test]
    fn a_remembered_proof_answers_only_for_its_own_pair() {
        // Thin rings, long along y: their bounding spheres overlap 1 apart along x, so the
        // query proves their roots apart and remembers the proof.
        let ring = torus(0.3, 24, 8)
            .map_vertices(|v| Point3::new(0.1 * v.x, 2.0 * v.y, 0.1 * v.z))
            .unwrap();
        let (a, b) = (DopTree::build(&ring), DopTree::build(&ring));
        // Whole tori, which intersect at the same pose, in a pair whose memory takes the same
        // slot of this thread's table.
        let whole = torus(0.3, 24, 8);
        let c = DopTree::build(&whole);
        let slot = PairMemory::slot((a.id, b.id));
        let d = std::iter::repeat_with(|| DopTree::build(&whole))
            .take(100 * MEMORY_SLOTS)
            .find(|d| PairMemory::slot((c.id, d.id)) == slot)
            .expect("some tree's pair with c shares the slot");
        let pose = Isometry3::translation(1.0, 0.0, 0.0);
        let mut stats = QueryStats::default();
        assert!(!a.intersects(&b, &pose, &mut stats), "the rings are apart");
        assert!(
            ObbTree::build(&whole).intersects(&ObbTree::build(&whole), &pose, &mut stats),
            "the oracle: the tori intersect"
        );
        assert!(
            c.intersects(&d, &pose, &mut stats),
            "the rings' proof must not answer for the tori"
        );
    }

    #[test]
    fn node_spheres_hold_their_triangles() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for mesh in [torus(0.3, 20, 10), random_soup(&mut rng, 300, 0.2)] {
            let tree = DopTree::build(&mesh);
            for (node, corner) in node_corners(&tree) {
                let sphere = &tree.nodes[node].sphere;
                let distance = (corner.coords - sphere.centre()).norm();
                assert!(
                    distance <= f64::from(sphere.radius),
                    "node {node}: corner at {distance} from a sphere of radius {}",
                    sphere.radius
                );
            }
            // Not the tree's sphere everywhere: a leaf's is about its triangle's size.
            let leaf = tree.nodes.iter().position(Node::is_leaf).unwrap();
            assert!(f64::from(tree.nodes[leaf].sphere.radius) < 0.5 * tree.bounding_radius);
        }
    }

    #[test]
    fn node_boxes_hold_their_triangles() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for mesh in [torus(0.3, 20, 10), random_soup(&mut rng, 300, 0.2)] {
            let tree = DopTree::build(&mesh);
            let directions: Vec<Vector3<f64>> = (0..16)
                .map(|_| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize())
                .collect();
            for (node, corner) in node_corners(&tree) {
                for direction in &directions {
                    let (low, high) = tree.boxes[node].oriented().projection(direction, 0.0);
                    let along = corner.coords.dot(direction);
                    assert!(
                        (low..=high).contains(&along),
                        "node {node}: corner at {along} outside [{low}, {high}]"
                    );
                }
            }
            // Fitted, not merely enclosing: a leaf's box is flat across its triangle.
            let leaf = tree.nodes.iter().position(Node::is_leaf).unwrap();
            let extents = tree.boxes[leaf].extents;
            assert!(extents[2] < 0.01 * extents[0], "leaf box {extents:?}");
        }
    }

    #[test]
    fn box_certificates_hold_at_their_pose() {
        // Wherever the boxes of a node pair give a certificate, every corner of B's node lies at
        // least the gap beyond every corner of A's node along its direction.
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let a = DopTree::build(&torus(0.3, 12, 6));
        let b = DopTree::build(&random_soup(&mut rng, 120, 0.3));
        let mut certified = 0;
        for _ in 0..20 {
            let pose = random_pose(&mut rng, 1.0);
            let pair = TreePair::new(&a, &b, &pose, |_, _| ());
            for ia in 0..a.node_count() as u32 {
                for ib in 0..b.node_count() as u32 {
                    let mut stats = QueryStats::default();
                    let Some(Ending::Separated { gap, direction, .. }) =
                        pair.box_separation((ia, ib), BOX_TEST_MAX_TRIANGLES, &mut stats)
                    else {
                        continue;
                    };
                    certified += 1;
                    let direction = Vector3::from(direction).cast::<f64>();
                    let apart = separation_along(
                        &corners_at(&a, ia, &Isometry3::identity()),
                        &corners_at(&b, ib, &pose),
                        &direction,
                    );
                    assert!(
                        apart >= gap - 1e-12,
                        "pair ({ia}, {ib}): corners {apart} apart, certificate {gap}"
                    );
                }
            }
        }
        assert!(certified > 1000, "only {certified} certificates");
    }

    #[test]
    fn front_certificates_not_due_still_separate() {
        // Along a tumble, every certificate of the remembered front that the next pose does not
        // put due (its tree bound, its node bound, or the renewal of one by the other) must
        // still separate its pair there: B's corners beyond A's along its direction.
        let a = DopTree::build(&torus(0.35, 20, 10));
        let b = DopTree::build(&torus(0.35, 20, 10));
        let (mut checked, mut renewed) = (0, 0);
        for d in [2.8, 2.5, 2.3] {
            for s in 0..240 {
                let pose = tumble_pose(d, s, 1200);
                let mut memory = PairMemory::take(&a, &b);
                let pair = LazyPair::<18>::new(&a, &b, &pose);
                if let (Carry::Advanced { .. }, _) = memory.carry_front(&pair) {
                    let inverse = pose.inverse();
                    for (frame, certificates) in memory.front.separated.iter().enumerate() {
                        let due = &memory.due[frame];
                        renewed += due.renewed.len();
                        for (i, &(ia, ib)) in certificates.pairs.iter().enumerate() {
                            if due.indices.contains(&(i as u32)) {
                                continue;
                            }
                            let direction =
                                Vector3::from_fn(|c, _| f64::from(certificates.directions[c][i]));
                            // In A's frame B lies beyond; in B's frame A does.
                            let (near, far) = if frame == 0 {
                                (
                                    corners_at(&a, ia, &Isometry3::identity()),
                                    corners_at(&b, ib, &pose),
                                )
                            } else {
                                (
                                    corners_at(&b, ib, &Isometry3::identity()),
                                    corners_at(&a, ia, &inverse),
                                )
                            };
                            let apart = separation_along(&near, &far, &direction);
                            assert!(
                                apart > 0.0,
                                "d {d} step {s}: pair ({ia}, {ib}) overlaps by {} along its certificate",
                                -apart
                            );
                            checked += 1;
                        }
                    }
                }
                PairMemory::put_back(memory);
                a.intersects(&b, &pose, &mut QueryStats::default());
            }
        }
        assert!(checked > 10_000, "only {checked} certificates checked");
        assert!(renewed > 1_000, "only {renewed} certificates renewed");
    }

    #[test]
    fn the_vector_scan_flags_what_the_scalar_scan_flags() {
        // Random fronts of every length up to 40 (whole groups of four and tails), with
        // bounds spread around the thresholds so that every outcome occurs: not flagged, due,
        // renewed.
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let (mut due_seen, mut renewed_seen) = (0, 0);
        for round in 0..2000u32 {
            let mut certificates = Certificates::default();
            for j in 0..round % 41 {
                let d = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
                let sphere = NodeSphere {
                    centre: std::array::from_fn(|_| rng.random_range(-1.0..1.0)),
                    radius: rng.random_range(0.0..0.5),
                };
                let bounds = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let direction = [d.x as f32, d.y as f32, d.z as f32];
                certificates.push(bounds, direction, &sphere, (j, j));
            }
            let centre = Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
            let rotation = UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| {
                rng.random_range(-0.3..0.3)
            }));
            let nodes = NodeBound {
                rotation: *rotation.to_rotation_matrix().matrix(),
                translation: Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5)),
                turn: rng.random_range(0.0..0.3),
                guard: 1e-6,
            };
            let threshold = rng.random_range(0.0..0.2);
            let mut scalar = DueCertificates::default();
            certificates.flagged_scalar(&centre, threshold, &nodes, &mut scalar, 0);
            let mut fast = DueCertificates::default();
            certificates.flagged(&centre, threshold, &nodes, &mut fast);
            // Fused and unfused arithmetic round differently: compare with a tolerance far
            // below the bounds' spread, and only away from a tie at the threshold.
            let near_tie = (0..certificates.expiry.len())
                .any(|j| (certificates.tree_bound(j, &centre) - threshold).abs() < 1e-12);
            if near_tie {
                continue;
            }
            assert_eq!(fast.indices, scalar.indices, "round {round}");
            assert_eq!(fast.renewed.len(), scalar.renewed.len(), "round {round}");
            for ((i, x), (j, y)) in fast.renewed.iter().zip(&scalar.renewed) {
                assert_eq!(i, j, "round {round}");
                assert!((x - y).abs() < 1e-12, "round {round}: {x} against {y}");
            }
            due_seen += scalar.indices.len();
            renewed_seen += scalar.renewed.len();
        }
        assert!(
            due_seen > 1000 && renewed_seen > 1000,
            "{due_seen} due, {renewed_seen} renewed"
        );
    }

    #[test]
    fn a_detached_query_leaves_the_front_to_the_coherent_ones() {
        let mesh = torus(0.35, 20, 10);
        let (a, b) = (DopTree::build(&mesh), DopTree::build(&mesh));
        let (oracle_a, oracle_b) = (ObbTree::build(&mesh), ObbTree::build(&mesh));
        // The front's pose and size, and whether a query at `next` would start from it.
        let front_at = |next: &Isometry3<f64>| {
            let mut memory = PairMemory::take(&a, &b);
            let carry = memory.carry_front(&LazyPair::<18>::new(&a, &b, next)).0;
            let state = (
                memory.front_pose,
                memory.front.len(),
                matches!(carry, Carry::Advanced { .. }),
            );
            PairMemory::put_back(memory);
            state
        };
        let check = |pose: &Isometry3<f64>| {
            let hit = a.intersects(&b, pose, &mut QueryStats::default());
            let expected = oracle_a.intersects(&oracle_b, pose, &mut QueryStats::default());
            assert_eq!(hit, expected, "at {pose:?}");
        };
        let d = 2.0;
        // A tumble near contact leaves a front.
        for s in 0..20 {
            check(&tumble_pose(d, s, 1200));
        }
        let next = tumble_pose(d, 20, 1200);
        let kept = front_at(&next);
        assert!(kept.0.is_some() && kept.1 > 0, "the tumble left no front");
        // Poses far from it and from each other (random ones, in contact or not) leave it as
        // it is, and the tumble can go on from it as before.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20 {
            check(&random_pose(&mut rng, 1.5));
        }
        assert_eq!(front_at(&next), kept, "a detached query changed the front");
        check(&next);
        // Queries that follow one another far from the front make a front of their own: B
        // linked through A like two links of a chain (the tubes 0.3 apart), sliding along.
        let linked = |s: usize| {
            Isometry3::from_parts(
                Translation3::new(1.0, 0.001 * s as f64, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
            )
        };
        for s in 0..3 {
            check(&linked(s));
        }
        let (pose, len, _) = front_at(&linked(3));
        assert_ne!(
            pose, kept.0,
            "coherent queries far from the front kept the old one"
        );
        assert!(len > 0, "the linked pair left no front");
    }

    #[test]
    fn affine_realignment_encloses_every_moved_node() {
        // Support cones are searched for half of A's directions and mirrored for the other
        // half: each re-aligned node must still bound its corners moved into A's frame.
        const K: usize = 18;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let a = DopTree::build(&torus(0.3, 12, 6));
        let b = DopTree::build(&random_soup(&mut rng, 200, 0.3));
        for _ in 0..50 {
            let axis =
                nalgebra::Unit::new_normalize(Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)));
            let pose = Isometry3::from_parts(
                Translation3::from(Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0))),
                UnitQuaternion::from_axis_angle(&axis, rng.random_range(-3.0..3.0)),
            );
            let rotation = *pose.rotation.to_rotation_matrix().matrix();
            let translation = pose.translation.vector;
            let mut hints = [u8::MAX; MAX_K];
            let realigner = AffineRealign::<K>::new(&a, &b, &rotation, &translation, &mut hints);
            let mut realigned = vec![[0f32; K]; b.node_count()];
            for (node, out) in realigned.iter_mut().enumerate() {
                realigner.realign::<false>(&b, node, out);
            }
            for (node, corner) in node_corners(&b) {
                let moved = pose * corner;
                for (i, &offset) in realigned[node].iter().enumerate() {
                    // Stored opposite: slot i bounds B along -n_i.
                    let support = -a.set.normal(i).dot(&moved.coords);
                    assert!(
                        support <= f64::from(offset) + 1e-9,
                        "node {node} slot {i}: {support} beyond {offset}"
                    );
                }
            }
        }
    }
}
