//! The DOP-tree: a bounding-volume tree of k-DOPs over a triangle mesh, and the simultaneous
//! traversal of two such trees with lazy O(k) re-alignment (the paper's §2.1).
//!
//! Layout, chosen for the traversal's memory traffic: node offsets are `f32`, `k` contiguous per
//! node (so the interval test is one vectorised pass); the two children of a node are adjacent;
//! nodes are numbered depth first; leaves hold a few triangles stored by value, in leaf order.
//! Offsets are rounded outwards to `f32`, and every re-aligned offset gets a margin that bounds
//! its `f32` rounding, so no overlap is ever missed; the triangle test is exact in `f64`.
//!
//! Build: top-down, splitting at the median of the triangle centroids along the orientation axis
//! of largest centroid spread. Every node's offsets are the extremes of its triangles, so every
//! plane touches the geometry (no completely redundant half-space).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::orientation::OrientationSet;
use super::triangle::{Triangle, triangles_intersect};
use super::{MeshCollider, QueryStats};
use crate::geometry::TriMesh;

/// Default number of triangles per leaf (the fastest in the tumbling benchmark).
pub const DEFAULT_LEAF_SIZE: usize = 2;

/// Depth to which the parallel traversal splits the node-pair tree into rayon tasks.
const PARALLEL_DEPTH: u32 = 10;

/// One tree node: a leaf (`count > 0`) owns triangles `first..first + count`; an inner node
/// (`count == 0`) has children `first` and `first + 1`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    first: u32,
    count: u32,
    /// Largest slab width of the node's DOP: the traversal descends the larger node.
    size: f32,
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A DOP-tree over one mesh: built once, shared read-only (it is `Send + Sync`).
#[derive(Debug, Clone)]
pub struct DopTree {
    set: OrientationSet,
    k: usize,
    nodes: Vec<Node>,
    /// `k` offsets per node: `offsets[node * k + i] >= max over the node's triangles of n_i . x`.
    offsets: Vec<f32>,
    /// Triangles in leaf order.
    triangles: Vec<Triangle>,
    /// Original index (in the mesh) of each triangle in leaf order.
    triangle_ids: Vec<u32>,
    /// Largest absolute offset in the tree (bounds rounding errors of re-alignment).
    max_abs_offset: f32,
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

    /// Heap bytes used by the tree (nodes, offsets, triangles and their ids).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + self.offsets.len() * size_of::<f32>()
            + self.triangles.len() * (size_of::<Triangle>() + size_of::<u32>())
    }

    /// The `k` offsets of node `index`.
    pub(crate) fn node_offsets(&self, index: usize) -> &[f32] {
        &self.offsets[index * self.k..(index + 1) * self.k]
    }

    /// Largest absolute offset of any node.
    pub(crate) fn max_abs_offset(&self) -> f32 {
        self.max_abs_offset
    }

    /// Like [`MeshCollider::intersects`], with the traversal split across rayon's threads
    /// (dynamic load balancing by work stealing); worth it when one pair dominates.
    pub fn intersects_parallel(
        &self,
        other: &DopTree,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
    ) -> bool {
        let mut unused = Vec::new();
        with_affine::<false>(self, other, b_to_a, stats, &mut unused, true)
    }

    /// Like [`MeshCollider::intersecting_pairs`], split across rayon's threads; the pairs come
    /// out in no particular order.
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
        let pair = TreePair::new(a, b, b_to_a, |rotation, translation| {
            AffineRealign::<K>::new(a, b, rotation, translation)
        });
        pair.run::<ALL, K>(stats, out, parallel)
    }
    match a.k {
        6 => run::<6, ALL>(a, b, b_to_a, stats, out, parallel),
        14 => run::<14, ALL>(a, b, b_to_a, stats, out, parallel),
        18 => run::<18, ALL>(a, b, b_to_a, stats, out, parallel),
        24 => run::<24, ALL>(a, b, b_to_a, stats, out, parallel),
        26 => run::<26, ALL>(a, b, b_to_a, stats, out, parallel),
        k => unreachable!("orientation sets have a supported k, not {k}"),
    }
}

/// Top-down construction state.
struct TreeBuilder<'a> {
    set: &'a OrientationSet,
    leaf_size: usize,
    k: usize,
    triangles: Vec<Triangle>,
    /// `k` support values (f64) per triangle, in mesh order.
    triangle_dops: Vec<f64>,
    /// Centroid of each triangle, in mesh order.
    centroids: Vec<Point3<f64>>,
    order: Vec<u32>,
    nodes: Vec<Node>,
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
                t.iter().map(|p| n.dot(&p.coords)).fold(f64::MIN, f64::max)
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
            offsets: Vec::new(),
        }
    }

    fn build(mut self) -> DopTree {
        self.push_nodes(1);
        self.build_node(0, 0, self.triangles.len());
        let max_abs_offset = self.offsets[..self.k]
            .iter()
            .fold(0.0f32, |m, d| m.max(d.abs()));
        DopTree {
            set: self.set.clone(),
            k: self.k,
            nodes: self.nodes,
            offsets: self.offsets,
            triangles: self
                .order
                .iter()
                .map(|&i| self.triangles[i as usize])
                .collect(),
            triangle_ids: self.order,
            max_abs_offset,
        }
    }

    fn push_nodes(&mut self, count: usize) -> usize {
        let first = self.nodes.len();
        for _ in 0..count {
            self.nodes.push(Node {
                first: 0,
                count: 0,
                size: 0.0,
            });
        }
        self.offsets.resize(self.nodes.len() * self.k, 0.0);
        first
    }

    fn build_node(&mut self, index: usize, start: usize, end: usize) {
        let k = self.k;
        let h = k / 2;
        let mut dop = vec![f64::MIN; k];
        for &t in &self.order[start..end] {
            let support = &self.triangle_dops[t as usize * k..(t as usize + 1) * k];
            for (d, s) in dop.iter_mut().zip(support) {
                *d = d.max(*s);
            }
        }
        for (o, d) in self.offsets[index * k..(index + 1) * k]
            .iter_mut()
            .zip(&dop)
        {
            *o = round_up(*d);
        }
        let size = (0..h).map(|i| dop[i] + dop[i + h]).fold(0.0, f64::max) as f32;
        let count = end - start;
        if count <= self.leaf_size {
            self.nodes[index] = Node {
                first: start as u32,
                count: count as u32,
                size,
            };
            return;
        }
        let axis = self.split_axis(start, end);
        let centroids = &self.centroids;
        let key = |t: &u32| axis.dot(&centroids[*t as usize].coords);
        let mid = start + count / 2;
        self.order[start..end].select_nth_unstable_by(count / 2, |a, b| key(a).total_cmp(&key(b)));
        let children = self.push_nodes(2);
        self.nodes[index] = Node {
            first: children as u32,
            count: 0,
            size,
        };
        self.build_node(children, start, mid);
        self.build_node(children + 1, mid, end);
    }

    /// The orientation axis along which the centroids of `order[start..end]` spread most.
    fn split_axis(&self, start: usize, end: usize) -> Vector3<f64> {
        let mut best = (f64::MIN, Vector3::x());
        for axis in self.set.axes() {
            let (lo, hi) = self.order[start..end]
                .iter()
                .map(|&t| axis.dot(&self.centroids[t as usize].coords))
                .fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
            if hi - lo > best.0 {
                best = (hi - lo, *axis);
            }
        }
        best.1
    }
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
    fn realign(&self, b: &DopTree, node: usize, out: &mut [f32; K]);
}

/// The paper's O(k) re-alignment: each new offset is `Σ λ d_j + n . t` over the three planes of
/// the generic vertex that supports the rotated direction.
pub(crate) struct AffineRealign<const K: usize> {
    planes: [[u8; K]; 3],
    lambda: [[f32; K]; 3],
    base: [f32; K],
}

impl<const K: usize> AffineRealign<K> {
    /// Finds, for each of A's directions, its support cone in B's orientation set.
    fn new(a: &DopTree, b: &DopTree, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Self {
        let mut planes = [[0u8; K]; 3];
        let mut lambda = [[0f32; K]; 3];
        let mut base = [0f32; K];
        let mut lambda_sum_max = 0.0f64;
        for i in 0..K {
            let direction = -a.set.normal(i);
            let cone = b.set.support_cone(&(rotation.transpose() * direction));
            for l in 0..3 {
                planes[l][i] = cone.planes[l];
                lambda[l][i] = cone.lambda[l] as f32;
            }
            lambda_sum_max = lambda_sum_max.max(cone.lambda.iter().sum());
            base[i] = direction.dot(translation) as f32;
        }
        let margin = rounding_margin(
            lambda_sum_max * b.max_abs_offset() as f64
                + translation.norm()
                + a.max_abs_offset() as f64,
        );
        for x in &mut base {
            *x += margin;
        }
        AffineRealign {
            planes,
            lambda,
            base,
        }
    }
}

/// A margin that bounds the `f32` rounding of re-aligned offsets of magnitude up to `scale`.
pub(crate) fn rounding_margin(scale: f64) -> f32 {
    (scale * 64.0 * f32::EPSILON as f64) as f32
}

impl<const K: usize> Realign<K> for AffineRealign<K> {
    #[inline]
    fn realign(&self, b: &DopTree, node: usize, out: &mut [f32; K]) {
        let d = b.node_offsets(node);
        *out = self.base;
        for l in 0..3 {
            for i in 0..K {
                out[i] += self.lambda[l][i] * d[self.planes[l][i] as usize];
            }
        }
    }
}

/// True when A's node offsets `a` and B's re-aligned opposite offsets `e` overlap on every axis.
#[inline]
fn dops_overlap<const K: usize>(a: &[f32; K], e: &[f32; K]) -> bool {
    let mut overlap = true;
    for i in 0..K {
        overlap &= a[i] + e[i] >= 0.0;
    }
    overlap
}

/// Per-thread buffers reused across queries: the re-alignment cache (stamped per query) and the
/// traversal stack.
#[derive(Default)]
struct Scratch {
    stamp: u32,
    stamps: Vec<u32>,
    realigned: Vec<f32>,
    stack: Vec<(u32, u32)>,
}

impl Scratch {
    /// Starts a query over a B tree of `nodes` nodes with re-aligned DOPs of `k` offsets.
    fn begin(&mut self, nodes: usize, k: usize) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.fill(0);
            self.stamp = 1;
        }
        if self.stamps.len() < nodes {
            self.stamps.resize(nodes, 0);
        }
        if self.realigned.len() < nodes * k {
            self.realigned.resize(nodes * k, 0.0);
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

/// What a traversal found.
#[derive(Default)]
struct Found {
    stats: QueryStats,
    pairs: Vec<[u32; 2]>,
    hit: bool,
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
    /// Runs the query from the root pair, sequentially or split across threads.
    pub(crate) fn run<const ALL: bool, const K: usize>(
        &self,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
        parallel: bool,
    ) -> bool
    where
        R: Realign<K>,
    {
        let found = if parallel {
            let stop = AtomicBool::new(false);
            self.parallel::<ALL, K>(0, 0, PARALLEL_DEPTH, &stop)
        } else {
            let mut found = Found::default();
            found.hit = self.sequential::<ALL, K>((0, 0), &mut found.stats, &mut found.pairs, None);
            found
        };
        *stats += found.stats;
        out.extend_from_slice(&found.pairs);
        found.hit
    }

    /// Depth-first traversal from one node pair with this thread's re-alignment cache.
    fn sequential<const ALL: bool, const K: usize>(
        &self,
        start: (u32, u32),
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
        stop: Option<&AtomicBool>,
    ) -> bool
    where
        R: Realign<K>,
    {
        with_scratch(|scratch| {
            scratch.begin(self.b.nodes.len(), K);
            let stamp = scratch.stamp;
            let Scratch {
                stamps,
                realigned,
                stack,
                ..
            } = scratch;
            let mut hit = false;
            stack.push(start);
            while let Some((ia, ib)) = stack.pop() {
                if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                    break;
                }
                let slot = ib as usize * K;
                let e: &mut [f32; K] = (&mut realigned[slot..slot + K]).try_into().unwrap();
                if stamps[ib as usize] != stamp {
                    stamps[ib as usize] = stamp;
                    self.realigner.realign(self.b, ib as usize, e);
                    stats.realignments += 1;
                }
                stats.bv_tests += 1;
                let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
                if !dops_overlap(da, e) {
                    continue;
                }
                stats.nodes_visited += 1;
                let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
                if na.is_leaf() && nb.is_leaf() {
                    if self.leaf_pair::<ALL>(na, nb, stats, out) {
                        hit = true;
                        if !ALL {
                            if let Some(stop) = stop {
                                stop.store(true, Ordering::Relaxed);
                            }
                            break;
                        }
                    }
                    continue;
                }
                let [first, second] = self.children(ia, ib);
                stack.push(second);
                stack.push(first);
            }
            hit
        })
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
            found.hit =
                self.sequential::<ALL, K>((ia, ib), &mut found.stats, &mut found.pairs, Some(stop));
            return found;
        }
        let mut e = [0f32; K];
        self.realigner.realign(self.b, ib as usize, &mut e);
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
        found.hit = x.hit || y.hit;
        found.pairs = x.pairs;
        found.pairs.extend_from_slice(&y.pairs);
        found
    }
}
