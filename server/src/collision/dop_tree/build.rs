//! Top-down construction of a [`DopTree`], with a binned surface heuristic
//! ([`TreeBuilder::partition`]), on all of rayon's threads.
//!
//! Two passes. The first ([`TreeBuilder::plan`]) splits the triangles recursively and records
//! the tree's shape; the second ([`TreeBuilder::fill`]) lays the nodes out (children adjacent,
//! depth first) and computes each node's bounds bottom-up: a node's DOP is the merge of its
//! children's, so each level costs O(k) per node rather than a pass over its triangles. Both
//! passes run the two halves of a large node in parallel; the result does not depend on the
//! number of threads.
//!
//! Every node's offsets are the extremes of its triangles, so every plane touches the geometry (no
//! completely redundant half-space, the condition of the affine re-alignment).

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Point3;
use rayon::prelude::*;

use super::node_bounds::{NodeBox, NodeSphere};
use super::separation::BOX_TEST_MAX_TRIANGLES;
use super::tree::{Arrays, DopTree, Node};
use crate::collision::orientation::OrientationSet;
use crate::collision::triangle::Triangle;
use crate::geometry::TriMesh;

/// Source of tree ids (0 is never given out: it marks an empty memory slot).
static NEXT_TREE_ID: AtomicU64 = AtomicU64::new(1);

/// A tree id never given out before.
pub(super) fn next_tree_id() -> u64 {
    NEXT_TREE_ID.fetch_add(1, Ordering::Relaxed)
}

/// Nodes of at least this many triangles build their two halves in parallel: below it, the
/// work of a half is too small to pay for handing it to another thread.
const PARALLEL_MIN_TRIANGLES: usize = 4096;

/// Number of bins per axis of the split heuristic.
const SPLIT_BINS: usize = 16;

/// What the builder reads: the mesh's triangles with their DOPs and centroids.
pub(super) struct TreeBuilder<'a> {
    set: &'a OrientationSet,
    leaf_size: usize,
    k: usize,
    triangles: Vec<Triangle>,
    /// `k` support values per triangle, in mesh order, rounded up to `f32`.
    triangle_dops: Vec<f32>,
    /// Centroid of each triangle, in mesh order.
    centroids: Vec<Point3<f64>>,
}

/// The shape of a subtree in depth-first order (node, then its left subtree, then its right):
/// per node, for an inner node the triangles and the nodes of its left subtree, for a leaf
/// `[0, 0]`.
type Plan = Vec<[u32; 2]>;

/// The arrays of the tree, per node, for a run of consecutive node indices: the second pass
/// writes disjoint runs from different threads.
struct Slots<'s> {
    /// Index of the run's first node.
    first: usize,
    k: usize,
    nodes: &'s mut [Node],
    parents: &'s mut [u32],
    triangle_ranges: &'s mut [[u32; 2]],
    offsets: &'s mut [f32],
    boxes: &'s mut [NodeBox],
}

impl<'s> Slots<'s> {
    /// The first `count` nodes of the run and the rest.
    fn split_at(self, count: usize) -> (Slots<'s>, Slots<'s>) {
        let (nodes, nodes_rest) = self.nodes.split_at_mut(count);
        let (parents, parents_rest) = self.parents.split_at_mut(count);
        let (ranges, ranges_rest) = self.triangle_ranges.split_at_mut(count);
        let (offsets, offsets_rest) = self.offsets.split_at_mut(count * self.k);
        let (boxes, boxes_rest) = self.boxes.split_at_mut(count);
        (
            Slots {
                first: self.first,
                k: self.k,
                nodes,
                parents,
                triangle_ranges: ranges,
                offsets,
                boxes,
            },
            Slots {
                first: self.first + count,
                k: self.k,
                nodes: nodes_rest,
                parents: parents_rest,
                triangle_ranges: ranges_rest,
                offsets: offsets_rest,
                boxes: boxes_rest,
            },
        )
    }
}

impl<'a> TreeBuilder<'a> {
    pub(super) fn new(mesh: &TriMesh, set: &'a OrientationSet, leaf_size: usize) -> Self {
        let k = set.k();
        let triangles: Vec<Triangle> = (0..mesh.triangles().len())
            .into_par_iter()
            .map(|i| mesh.triangle(i))
            .collect();
        let mut triangle_dops = vec![0.0; triangles.len() * k];
        triangle_dops
            .par_chunks_mut(k)
            .zip(&triangles)
            .for_each(|(dop, t)| {
                for (i, d) in dop.iter_mut().enumerate() {
                    let n = set.normal(i);
                    *d = round_up(t.iter().map(|p| n.dot(&p.coords)).fold(f64::MIN, f64::max));
                }
            });
        let centroids = triangles
            .par_iter()
            .map(|t| Point3::from((t[0].coords + t[1].coords + t[2].coords) / 3.0))
            .collect();
        TreeBuilder {
            set,
            leaf_size,
            k,
            triangles,
            triangle_dops,
            centroids,
        }
    }

    pub(super) fn build(self) -> DopTree {
        let k = self.k;
        let mut order: Vec<u32> = (0..self.triangles.len() as u32).collect();
        let plan = self.plan(&mut order);
        let count = plan.len();
        let mut nodes = vec![Node::default(); count];
        let mut parents = vec![0u32; count];
        let mut triangle_ranges = vec![[0u32; 2]; count];
        let mut offsets = vec![0.0f32; count * k];
        let mut boxes = vec![NodeBox::default(); count];
        let (mut root, below) = Slots {
            first: 0,
            k,
            nodes: &mut nodes,
            parents: &mut parents,
            triangle_ranges: &mut triangle_ranges,
            offsets: &mut offsets,
            boxes: &mut boxes,
        }
        .split_at(1);
        self.fill(&plan, &order, 0, 0, &mut root, below);
        DopTree::assemble(
            Arrays {
                set: self.set.clone(),
                nodes,
                parents,
                triangle_ranges,
                offsets,
                boxes,
                triangle_ids: order,
            },
            |i| self.triangles[i],
        )
    }

    /// Splits `order` (triangle indices) recursively until at most `leaf_size` remain, leaving
    /// it in leaf order, and returns the tree's shape.
    fn plan(&self, order: &mut [u32]) -> Plan {
        if order.len() <= self.leaf_size {
            return vec![[0, 0]];
        }
        let parallel = order.len() >= PARALLEL_MIN_TRIANGLES;
        let mid = self.partition(order);
        let (left, right) = order.split_at_mut(mid);
        let (left_plan, right_plan) = if parallel {
            rayon::join(|| self.plan(left), || self.plan(right))
        } else {
            (self.plan(left), self.plan(right))
        };
        let mut plan = Vec::with_capacity(1 + left_plan.len() + right_plan.len());
        plan.push([mid as u32, left_plan.len() as u32]);
        plan.extend(left_plan);
        plan.extend(right_plan);
        plan
    }

    /// Writes the node of `plan[0]` (triangles `order`, which start at `start` in leaf order;
    /// parent `parent`) into `slot`, and its descendants into `below`, the run that follows
    /// it: its two children first, then the left child's descendants, then the right's.
    fn fill(
        &self,
        plan: &[[u32; 2]],
        order: &[u32],
        start: usize,
        parent: usize,
        slot: &mut Slots<'_>,
        below: Slots<'_>,
    ) {
        let k = self.k;
        let index = slot.first;
        let [left_triangles, left_nodes] = plan[0];
        let first = if left_nodes == 0 {
            let dop = &mut slot.offsets[..k];
            dop.fill(f32::MIN);
            for &t in order {
                merge_max(
                    dop,
                    &self.triangle_dops[t as usize * k..(t as usize + 1) * k],
                );
            }
            start
        } else {
            let (left_triangles, left_nodes) = (left_triangles as usize, left_nodes as usize);
            let children = below.first;
            let (pair, descendants) = below.split_at(2);
            let (mut left, mut right) = pair.split_at(1);
            let (left_below, right_below) = descendants.split_at(left_nodes - 1);
            let (left_plan, right_plan) = plan[1..].split_at(left_nodes);
            let (left_order, right_order) = order.split_at(left_triangles);
            let right_start = start + left_triangles;
            let fill_left =
                || self.fill(left_plan, left_order, start, index, &mut left, left_below);
            let fill_right = || {
                self.fill(
                    right_plan,
                    right_order,
                    right_start,
                    index,
                    &mut right,
                    right_below,
                )
            };
            if order.len() >= PARALLEL_MIN_TRIANGLES {
                rayon::join(fill_left, fill_right);
            } else {
                fill_left();
                fill_right();
            }
            let dop = &mut slot.offsets[..k];
            dop.copy_from_slice(&left.offsets[..k]);
            merge_max(dop, &right.offsets[..k]);
            children
        };
        let dop = &slot.offsets[..k];
        let h = k / 2;
        slot.nodes[0] = Node {
            first: first as u32,
            count: if left_nodes == 0 {
                order.len() as u32
            } else {
                0
            },
            size: (0..h).map(|i| dop[i] + dop[i + h]).fold(0.0, f32::max),
            sphere: NodeSphere::around(order.iter().flat_map(|&t| &self.triangles[t as usize])),
        };
        slot.parents[0] = parent as u32;
        slot.triangle_ranges[0] = [start as u32, (start + order.len()) as u32];
        if order.len() <= BOX_TEST_MAX_TRIANGLES {
            slot.boxes[0] = NodeBox::around(&self.triangles, order);
        }
    }

    /// Splits `order` in two non-empty halves and returns where the second begins.
    ///
    /// Binned surface heuristic: along each orientation axis the centroids are put in
    /// [`SPLIT_BINS`] bins, and the split between bins minimising
    /// `size(left) * count(left) + size(right) * count(right)` is taken, where `size` is the sum of
    /// the child DOP's slab widths (proportional to its mean width, hence to how often a node of
    /// the other tree overlaps it); ties go to the first axis. Falls back to the median when all
    /// centroids share a bin.
    fn partition(&self, order: &mut [u32]) -> usize {
        // Few triangles: as many bins as triangles keeps the cost linear in their number.
        let bins = SPLIT_BINS.min(order.len());
        let Some(split) = self.best_split(order, bins) else {
            let mid = order.len() / 2;
            let axis = self.set.axes()[0];
            let centroids = &self.centroids;
            order.select_nth_unstable_by(mid, |a, b| {
                axis.dot(&centroids[*a as usize].coords)
                    .total_cmp(&axis.dot(&centroids[*b as usize].coords))
            });
            return mid;
        };
        let axis = self.set.axes()[split.axis];
        let mut boundary = 0;
        for i in 0..order.len() {
            let t = order[i];
            let x = axis.dot(&self.centroids[t as usize].coords);
            if bin_of(x, split.ranges[split.axis], bins) < split.bin {
                order.swap(i, boundary);
                boundary += 1;
            }
        }
        boundary
    }

    /// The cheapest split of `order` over all axes, or `None` when the centroids spread along
    /// none. Two passes over the triangles, each serving every axis at once (the triangles'
    /// data is read once a pass, not once an axis); a large node's passes run in parallel over
    /// chunks of its triangles.
    fn best_split(&self, order: &[u32], bins: usize) -> Option<Split> {
        let h = self.set.axes().len();
        let parallel = order.len() >= PARALLEL_MIN_TRIANGLES;
        let spread = |chunk: &[u32]| {
            let mut range = vec![(f64::MAX, f64::MIN); h];
            for &t in chunk {
                let c = &self.centroids[t as usize].coords;
                for (axis, (lo, hi)) in self.set.axes().iter().zip(&mut range) {
                    let x = axis.dot(c);
                    *lo = lo.min(x);
                    *hi = hi.max(x);
                }
            }
            range
        };
        let widen = |mut a: Vec<(f64, f64)>, b: Vec<(f64, f64)>| {
            for ((lo, hi), (l, h)) in a.iter_mut().zip(b) {
                *lo = lo.min(l);
                *hi = hi.max(h);
            }
            a
        };
        let spreads = if parallel {
            order
                .par_chunks(PARALLEL_MIN_TRIANGLES)
                .map(spread)
                .reduce_with(widen)?
        } else {
            spread(order)
        };
        let ranges: Vec<Option<AxisRange>> = spreads
            .iter()
            .map(|&(lo, hi)| {
                (hi - lo > 1e-12 * (hi.abs() + lo.abs() + 1.0)).then(|| AxisRange {
                    lo,
                    scale: bins as f64 / (hi - lo),
                })
            })
            .collect();
        let binned = if parallel {
            order
                .par_chunks(PARALLEL_MIN_TRIANGLES)
                .map(|chunk| self.bin(chunk, &ranges, bins))
                .reduce_with(Bins::merge)?
        } else {
            self.bin(order, &ranges, bins)
        };
        let mut best: Option<Split> = None;
        for (axis, range) in ranges.iter().enumerate() {
            if range.is_none() {
                continue;
            }
            if let Some((cost, bin)) = binned.cheapest_split(axis, order.len())
                && best.as_ref().is_none_or(|b| cost < b.cost)
            {
                best = Some(Split {
                    cost,
                    axis,
                    ranges: ranges.iter().map(|r| r.unwrap_or_default()).collect(),
                    bin,
                });
            }
        }
        best
    }

    /// The triangles of `chunk` counted and merged into their bins along every axis that has
    /// a range.
    fn bin(&self, chunk: &[u32], ranges: &[Option<AxisRange>], bins: usize) -> Bins {
        let k = self.k;
        let mut binned = Bins::new(ranges.len(), bins, k);
        for &t in chunk {
            let c = &self.centroids[t as usize].coords;
            let support = &self.triangle_dops[t as usize * k..(t as usize + 1) * k];
            for (axis, range) in ranges.iter().enumerate() {
                let Some(range) = range else { continue };
                let bin = bin_of(self.set.axes()[axis].dot(c), *range, bins);
                binned.add(axis, bin, support);
            }
        }
        binned
    }
}

/// Where the centroids of a node lie along one axis, for binning.
#[derive(Debug, Clone, Copy, Default)]
struct AxisRange {
    /// The lowest centroid projection.
    lo: f64,
    /// Bins per unit length.
    scale: f64,
}

/// Per axis and bin, how many triangles fell in it and the merge of their DOPs.
struct Bins {
    bins: usize,
    k: usize,
    counts: Vec<usize>,
    dops: Vec<f32>,
}

impl Bins {
    fn new(axes: usize, bins: usize, k: usize) -> Bins {
        Bins {
            bins,
            k,
            counts: vec![0; axes * bins],
            dops: vec![f32::MIN; axes * bins * k],
        }
    }

    fn add(&mut self, axis: usize, bin: usize, support: &[f32]) {
        let slot = axis * self.bins + bin;
        self.counts[slot] += 1;
        merge_max(&mut self.dops[slot * self.k..(slot + 1) * self.k], support);
    }

    fn merge(mut self, other: Bins) -> Bins {
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        merge_max(&mut self.dops, &other.dops);
        self
    }

    /// The cheapest split between bins along `axis` of a node of `total` triangles: its cost
    /// and the first bin of the right side, or `None` if every split leaves a side empty.
    fn cheapest_split(&self, axis: usize, total: usize) -> Option<(f64, usize)> {
        let (bins, k) = (self.bins, self.k);
        let h = k / 2;
        let dop = |bin: usize| {
            let slot = axis * bins + bin;
            &self.dops[slot * k..(slot + 1) * k]
        };
        // Prefix DOPs from the left, then sweep from the right.
        let mut left_dops = vec![f32::MIN; bins * k];
        let mut running = vec![f32::MIN; k];
        for bin in 0..bins {
            merge_max(&mut running, dop(bin));
            left_dops[bin * k..(bin + 1) * k].copy_from_slice(&running);
        }
        let size = |dop: &[f32]| (0..h).map(|i| (dop[i] + dop[i + h]) as f64).sum::<f64>();
        running.fill(f32::MIN);
        let mut right_count = 0;
        let mut best: Option<(f64, usize)> = None;
        for bin in (1..bins).rev() {
            merge_max(&mut running, dop(bin));
            right_count += self.counts[axis * bins + bin];
            let left_count = total - right_count;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = size(&left_dops[(bin - 1) * k..bin * k]) * left_count as f64
                + size(&running) * right_count as f64;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, bin));
            }
        }
        best
    }
}

/// A candidate split of a node: centroids in bins `< bin` along orientation axis `axis` go
/// left.
#[derive(Debug, Clone)]
struct Split {
    cost: f64,
    axis: usize,
    /// The binning of every axis (default where the centroids do not spread).
    ranges: Vec<AxisRange>,
    bin: usize,
}

/// `into[i] = max(into[i], from[i])`, written so that it compiles to vector max instructions.
fn merge_max(into: &mut [f32], from: &[f32]) {
    for (d, &s) in into.iter_mut().zip(from) {
        *d = if s > *d { s } else { *d };
    }
}

/// The bin of a centroid projection `x` on an axis binned as `range`.
fn bin_of(x: f64, range: AxisRange, bins: usize) -> usize {
    (((x - range.lo) * range.scale) as usize).min(bins - 1)
}

/// The smallest `f32` not below `x`.
pub(super) fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}
