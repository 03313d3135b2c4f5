//! The tree itself: its layout, its public API and its [`MeshCollider`] implementation.
//!
//! Layout, chosen for the traversal's memory traffic: node offsets are `f32`, `k` contiguous per
//! node (so the interval test is one vectorised pass); the two children of a node are adjacent;
//! nodes are numbered depth first; leaves hold up to [`DEFAULT_LEAF_SIZE`] triangles stored by value.
//! Offsets are rounded outwards to `f32`, and every re-aligned offset gets a margin that bounds
//! its `f32` rounding, so no overlap is ever missed; the triangle test is exact in `f64`.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3};

use super::build::{TreeBuilder, next_tree_id};
use super::node_bounds::{NodeBox, NodeSphere};
use super::query::with_affine;
use crate::collision::orientation::OrientationSet;
use crate::collision::triangle::Triangle;
use crate::collision::{MeshCollider, QueryStats};
use crate::geometry::TriMesh;

/// Default number of triangles per leaf: four keeps the tree near 180 bytes a triangle (one
/// takes 420) at the query times of one in the tumbling and random benchmarks (B1, B2).
pub const DEFAULT_LEAF_SIZE: usize = 4;

/// One tree node: a leaf (`count > 0`) owns triangles `first..first + count`; an inner node
/// (`count == 0`) has children `first` and `first + 1`.
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct Node {
    pub(super) first: u32,
    pub(super) count: u32,
    /// Largest slab width of the node's DOP: the traversal descends the larger node.
    pub(super) size: f32,
    /// A sphere around the node's triangles: how far its points can move when the tree turns
    /// about another point, for the certificates of a [`Front`](super::front::Front). Kept in the
    /// node, which the traversal has just read wherever it records a certificate.
    pub(super) sphere: NodeSphere,
}

impl Node {
    pub(super) fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A DOP-tree over one mesh: built once, shared read-only (it is `Send + Sync`). A clone shares
/// the built tree (its arrays are reference-counted), so every loop that needs a part's tree
/// holds the same one.
#[derive(Debug, Clone)]
pub struct DopTree {
    /// Identifies the tree for the per-thread witness cache (a clone shares it: same content).
    pub(super) id: u64,
    pub(super) set: OrientationSet,
    pub(super) k: usize,
    pub(super) nodes: Arc<[Node]>,
    /// Parent of each node (the root is its own parent).
    pub(super) parents: Arc<[u32]>,
    /// The triangles under each node, `start..end` in leaf order (a subtree's are contiguous).
    pub(super) triangle_ranges: Arc<[[u32; 2]]>,
    /// `k` offsets per node: `offsets[node * k + i] >= max over the node's triangles of n_i . x`.
    pub(super) offsets: Arc<[f32]>,
    /// Triangles in leaf order.
    pub(super) triangles: Arc<[Triangle]>,
    /// Original index (in the mesh) of each triangle in leaf order.
    pub(super) triangle_ids: Arc<[u32]>,
    /// Largest absolute offset in the tree (bounds rounding errors of re-alignment).
    pub(super) max_abs_offset: f32,
    /// An oriented box around the triangles of each node of at most
    /// [`BOX_TEST_MAX_TRIANGLES`](super::separation::BOX_TEST_MAX_TRIANGLES) triangles (see
    /// [`NodeBox`]); larger nodes, whose boxes the traversal never reads, have none.
    pub(super) boxes: Arc<[NodeBox]>,
    /// Centre and radius of a sphere enclosing the mesh (for the cheap first test of a query).
    pub(super) bounding_centre: Point3<f64>,
    pub(super) bounding_radius: f64,
}

/// What a build computes, from which [`DopTree::assemble`] makes the tree; also what the tree
/// cache reads back.
pub(super) struct Arrays {
    pub(super) set: OrientationSet,
    pub(super) nodes: Arc<[Node]>,
    pub(super) parents: Arc<[u32]>,
    pub(super) triangle_ranges: Arc<[[u32; 2]]>,
    pub(super) offsets: Arc<[f32]>,
    pub(super) boxes: Arc<[NodeBox]>,
    /// The mesh's triangle indices in leaf order.
    pub(super) triangle_ids: Arc<[u32]>,
}

impl DopTree {
    /// The tree of `arrays`, with a fresh id, over `triangles` (the mesh's, in leaf order).
    pub(super) fn assemble(arrays: Arrays, triangles: Arc<[Triangle]>) -> Self {
        let k = arrays.set.k();
        let max_abs_offset = arrays.offsets[..k]
            .iter()
            .fold(0.0f32, |m, d| m.max(d.abs()));
        // The root's sphere encloses the mesh.
        let root = arrays.nodes[0].sphere;
        DopTree {
            id: next_tree_id(),
            bounding_centre: Point3::from(root.centre()),
            bounding_radius: root.radius as f64,
            set: arrays.set,
            k,
            nodes: arrays.nodes,
            parents: arrays.parents,
            triangle_ranges: arrays.triangle_ranges,
            offsets: arrays.offsets,
            triangles,
            triangle_ids: arrays.triangle_ids,
            max_abs_offset,
            boxes: arrays.boxes,
        }
    }

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
    pub fn node_offsets(&self, index: usize) -> &[f32] {
        &self.offsets[index * self.k..(index + 1) * self.k]
    }

    /// Every triangle under node `index`.
    pub(super) fn node_triangles(&self, index: u32) -> &[Triangle] {
        let [start, end] = self.triangle_ranges[index as usize];
        &self.triangles[start as usize..end as usize]
    }

    /// The ancestor `levels` above `node` (or the root, if nearer).
    pub(super) fn ancestor(&self, mut node: u32, levels: u32) -> u32 {
        for _ in 0..levels {
            node = self.parents[node as usize];
        }
        node
    }

    /// Largest absolute offset of any node.
    pub fn max_abs_offset(&self) -> f32 {
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
