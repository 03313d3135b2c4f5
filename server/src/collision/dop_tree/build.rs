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
//! What the split reads of a triangle (its DOP and its centroid's projections) is moved with it
//! as the triangles are partitioned, so that every node's triangles lie contiguous in memory and
//! each pass over a node reads memory in order (looking them up by triangle id instead, in an
//! order the partitions have shuffled, makes every read a cache miss on a large mesh).
//!
//! Every node's offsets are the extremes of its triangles, so every plane touches the geometry (no
//! completely redundant half-space, the condition of the affine re-alignment).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::node_bounds::{NodeBox, NodeSphere};
use super::separation::BOX_TEST_MAX_TRIANGLES;
use super::shared;
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

/// Most triangles of a node the split heuristic reads (see [`TreeBuilder::best_split`]).
const SPLIT_SAMPLE: usize = 4096;

/// Builds the tree of one mesh.
pub(super) struct TreeBuilder<'a> {
    mesh: &'a TriMesh,
    set: &'a OrientationSet,
    leaf_size: usize,
    /// Number of DOP offsets, twice the number of axes.
    k: usize,
}

/// What the split reads of a run of triangles, item `i` of each slice being the same triangle:
/// partitioning a node permutes the three together.
struct Items<'s> {
    /// The triangles' indices in the mesh.
    ids: &'s mut [u32],
    /// `k` support values per triangle, rounded up to `f32`.
    dops: &'s mut [f32],
    /// The projection of each triangle's centroid on every axis of the orientation set (`k / 2`
    /// per triangle), rounded to `f32`: the split only needs them to compare.
    centroids: &'s mut [f32],
}

impl<'s> Items<'s> {
    fn len(&self) -> usize {
        self.ids.len()
    }

    /// The first `count` triangles and the rest.
    fn split_at(self, count: usize, k: usize) -> (Items<'s>, Items<'s>) {
        let (ids, ids_rest) = self.ids.split_at_mut(count);
        let (dops, dops_rest) = self.dops.split_at_mut(count * k);
        let (centroids, centroids_rest) = self.centroids.split_at_mut(count * k / 2);
        (
            Items {
                ids,
                dops,
                centroids,
            },
            Items {
                ids: ids_rest,
                dops: dops_rest,
                centroids: centroids_rest,
            },
        )
    }

    /// Exchanges triangles `i < j`.
    fn swap(&mut self, i: usize, j: usize, k: usize) {
        self.ids.swap(i, j);
        swap_strided(self.dops, k, i, j);
        swap_strided(self.centroids, k / 2, i, j);
    }
}

/// Exchanges elements `i < j` of `slice` seen as elements of `stride` values.
fn swap_strided(slice: &mut [f32], stride: usize, i: usize, j: usize) {
    let (low, high) = slice.split_at_mut(j * stride);
    low[i * stride..(i + 1) * stride].swap_with_slice(&mut high[..stride]);
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

/// The triangles in leaf order, and their DOPs in the same order, which the second pass reads.
struct LeafOrder<'t> {
    triangles: &'t [Triangle],
    dops: &'t [f32],
}

impl<'a> TreeBuilder<'a> {
    pub(super) fn new(mesh: &'a TriMesh, set: &'a OrientationSet, leaf_size: usize) -> Self {
        TreeBuilder {
            mesh,
            set,
            leaf_size,
            k: set.k(),
        }
    }

    pub(super) fn build(self) -> DopTree {
        let (k, h) = (self.k, self.k / 2);
        let count = self.mesh.triangles().len();
        let mut ids = shared::from_fn(count, |i| i as u32);
        let mut dops = vec![0.0f32; count * k];
        let mut centroids = vec![0.0f32; count * h];
        dops.par_chunks_mut(k)
            .zip(centroids.par_chunks_mut(h))
            .enumerate()
            .for_each(|(i, (dop, centroid))| {
                let t = self.mesh.triangle(i);
                for (j, axis) in self.set.axes().iter().enumerate() {
                    let [x, y, z] = t.map(|p| axis.dot(&p.coords));
                    dop[j] = round_up(x.max(y).max(z));
                    dop[j + h] = round_up(-x.min(y).min(z));
                    centroid[j] = ((x + y + z) / 3.0) as f32;
                }
            });
        let plan = self.plan(Items {
            ids: shared::unshared(&mut ids),
            dops: &mut dops,
            centroids: &mut centroids,
        });
        drop(centroids);
        let triangles = shared::from_fn(count, |i| self.mesh.triangle(ids[i] as usize));
        let node_count = plan.len();
        let mut nodes = shared::zeroed(node_count);
        let mut parents = shared::zeroed(node_count);
        let mut triangle_ranges = shared::zeroed(node_count);
        let mut offsets = shared::zeroed(node_count * k);
        let mut boxes = shared::zeroed(node_count);
        let (mut root, below) = Slots {
            first: 0,
            k,
            nodes: shared::unshared(&mut nodes),
            parents: shared::unshared(&mut parents),
            triangle_ranges: shared::unshared(&mut triangle_ranges),
            offsets: shared::unshared(&mut offsets),
            boxes: shared::unshared(&mut boxes),
        }
        .split_at(1);
        let leaves = LeafOrder {
            triangles: &triangles,
            dops: &dops,
        };
        self.fill(&plan, &leaves, 0..count, 0, &mut root, below);
        DopTree::assemble(
            Arrays {
                set: self.set.clone(),
                nodes,
                parents,
                triangle_ranges,
                offsets,
                boxes,
                triangle_ids: ids,
            },
            triangles,
        )
    }

    /// Splits `items` recursively until at most `leaf_size` remain, leaving them in leaf order,
    /// and returns the tree's shape.
    fn plan(&self, mut items: Items<'_>) -> Plan {
        if items.len() <= self.leaf_size {
            return vec![[0, 0]];
        }
        let parallel = items.len() >= PARALLEL_MIN_TRIANGLES;
        let mid = self.partition(&mut items);
        let (left, right) = items.split_at(mid, self.k);
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

    /// Writes the node of `plan[0]` (the triangles `range` of the leaf order; parent `parent`)
    /// into `slot`, and its descendants into `below`, the run that follows it: its two children
    /// first, then the left child's descendants, then the right's.
    fn fill(
        &self,
        plan: &[[u32; 2]],
        leaves: &LeafOrder<'_>,
        range: std::ops::Range<usize>,
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
            for support in leaves.dops[range.start * k..range.end * k].chunks_exact(k) {
                merge_max(dop, support);
            }
            range.start
        } else {
            let left_nodes = left_nodes as usize;
            let children = below.first;
            let (pair, descendants) = below.split_at(2);
            let (mut left, mut right) = pair.split_at(1);
            let (left_below, right_below) = descendants.split_at(left_nodes - 1);
            let (left_plan, right_plan) = plan[1..].split_at(left_nodes);
            let middle = range.start + left_triangles as usize;
            let fill_left = || {
                let range = range.start..middle;
                self.fill(left_plan, leaves, range, index, &mut left, left_below)
            };
            let fill_right = || {
                let range = middle..range.end;
                self.fill(right_plan, leaves, range, index, &mut right, right_below)
            };
            if range.len() >= PARALLEL_MIN_TRIANGLES {
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
        let triangles = &leaves.triangles[range.clone()];
        slot.nodes[0] = Node {
            first: first as u32,
            count: if left_nodes == 0 {
                triangles.len() as u32
            } else {
                0
            },
            size: (0..h).map(|i| dop[i] + dop[i + h]).fold(0.0, f32::max),
            sphere: NodeSphere::around(triangles.iter().flatten()),
        };
        slot.parents[0] = parent as u32;
        slot.triangle_ranges[0] = [range.start as u32, range.end as u32];
        if triangles.len() <= BOX_TEST_MAX_TRIANGLES {
            slot.boxes[0] = NodeBox::around(triangles);
        }
    }

    /// Splits `items` in two non-empty halves and returns where the second begins.
    ///
    /// Binned surface heuristic: along each orientation axis the centroids are put in
    /// [`SPLIT_BINS`] bins, and the split between bins minimising
    /// `size(left) * count(left) + size(right) * count(right)` is taken, where `size` is the sum of
    /// the child DOP's slab widths (proportional to its mean width, hence to how often a node of
    /// the other tree overlaps it); ties go to the first axis. When all centroids coincide, any
    /// split is as good: the middle is taken.
    fn partition(&self, items: &mut Items<'_>) -> usize {
        // Few triangles: as many bins as triangles keeps the cost linear in their number.
        let bins = SPLIT_BINS.min(items.len());
        let Some(split) = self.best_split(items, bins) else {
            return items.len() / 2;
        };
        let (k, h) = (self.k, self.k / 2);
        let range = split.range;
        let goes_left = |items: &Items<'_>, i: usize| {
            bin_of(items.centroids[i * h + split.axis], range, bins) < split.bin
        };
        // Hoare's scheme: swap only the pairs on the wrong sides.
        let (mut low, mut high) = (0, items.len());
        loop {
            while low < high && goes_left(items, low) {
                low += 1;
            }
            while low < high && !goes_left(items, high - 1) {
                high -= 1;
            }
            if low + 1 >= high {
                break;
            }
            items.swap(low, high - 1, k);
            low += 1;
            high -= 1;
        }
        low
    }

    /// The cheapest split of `items` over all axes, or `None` when their centroids spread
    /// along none.
    ///
    /// A large node is judged on an evenly spread sample of [`SPLIT_SAMPLE`] of its triangles:
    /// the bins of a few thousand triangles place the split about where those of all of them
    /// would, and the node's one full pass is then the partition's.
    fn best_split(&self, items: &Items<'_>, bins: usize) -> Option<Split> {
        let (k, h) = (self.k, self.k / 2);
        let step = items.len().div_ceil(SPLIT_SAMPLE);
        let sample = || {
            (0..items.len()).step_by(step).map(|i| {
                (
                    &items.centroids[i * h..(i + 1) * h],
                    &items.dops[i * k..(i + 1) * k],
                )
            })
        };
        let mut spreads = vec![(f32::MAX, f32::MIN); h];
        for (centroid, _) in sample() {
            for ((lo, hi), &x) in spreads.iter_mut().zip(centroid) {
                *lo = lo.min(x);
                *hi = hi.max(x);
            }
        }
        let axes: Vec<(usize, AxisRange)> = (spreads.iter().enumerate())
            .filter_map(|(axis, &(lo, hi))| {
                let scale = bins as f32 / (hi - lo);
                (hi > lo && scale.is_finite()).then_some((axis, AxisRange { lo, scale }))
            })
            .collect();
        let mut binned = Bins::new(axes.len(), bins, k);
        let mut sampled = 0;
        for (centroid, support) in sample() {
            for (slot, &(axis, range)) in axes.iter().enumerate() {
                binned.add(slot, bin_of(centroid[axis], range, bins), support);
            }
            sampled += 1;
        }
        let mut best: Option<Split> = None;
        for (slot, &(axis, range)) in axes.iter().enumerate() {
            if let Some((cost, bin)) = binned.cheapest_split(slot, sampled)
                && best.as_ref().is_none_or(|b| cost < b.cost)
            {
                best = Some(Split {
                    cost,
                    axis,
                    range,
                    bin,
                });
            }
        }
        best
    }
}

/// Where the centroids of a node lie along one axis, for binning.
#[derive(Debug, Clone, Copy)]
struct AxisRange {
    /// The lowest centroid projection.
    lo: f32,
    /// Bins per unit length.
    scale: f32,
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

    /// The cheapest split between bins along `axis` of a node of `total` triangles: its cost
    /// and the first bin of the right side, or `None` if every split leaves a side empty.
    fn cheapest_split(&self, axis: usize, total: usize) -> Option<(f64, usize)> {
        let (bins, k) = (self.bins, self.k);
        let dop = |bin: usize| {
            let slot = axis * bins + bin;
            &self.dops[slot * k..(slot + 1) * k]
        };
        // A DOP's size, the sum of its slab widths, is the sum of its offsets.
        let size = |dop: &[f32]| dop.iter().sum::<f32>() as f64;
        // The sizes of the prefixes from the left, then a sweep from the right.
        let mut left_sizes = [0.0; SPLIT_BINS];
        let mut running = vec![f32::MIN; k];
        for (bin, left_size) in left_sizes.iter_mut().enumerate().take(bins) {
            merge_max(&mut running, dop(bin));
            *left_size = size(&running);
        }
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
            let cost =
                left_sizes[bin - 1] * left_count as f64 + size(&running) * right_count as f64;
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
    /// The binning along the axis.
    range: AxisRange,
    bin: usize,
}

/// `into[i] = max(into[i], from[i])`, written so that it compiles to vector max instructions.
fn merge_max(into: &mut [f32], from: &[f32]) {
    for (d, &s) in into.iter_mut().zip(from) {
        *d = if s > *d { s } else { *d };
    }
}

/// The bin of a centroid projection `x` on an axis binned as `range`.
fn bin_of(x: f32, range: AxisRange, bins: usize) -> usize {
    (((x - range.lo) * range.scale) as usize).min(bins - 1)
}

/// The smallest `f32` not below `x`.
pub(super) fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}
