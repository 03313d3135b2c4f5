//! Top-down construction of a [`DopTree`], with a binned surface heuristic
//! ([`partition`]), on all of rayon's threads.
//!
//! Two passes. The first ([`TreeBuilder::plan`]) splits the triangles recursively and records
//! the tree's shape; the second ([`TreeBuilder::fill`]) lays the nodes out (children adjacent,
//! depth first) and computes each node's bounds bottom-up, from its children's wherever that
//! bounds as well: an inner node's DOP is the merge of its children's, and a small node's box is
//! fitted to the sum of its children's surface moments, so each costs O(k) per node rather than
//! a pass over its triangles. Spheres are the one pass over the triangles a node may take, and
//! only up to [`SPHERE_EXACT_MAX_TRIANGLES`] and at the root; between them a node's sphere is the
//! one around its children's. Both passes run the two halves of a large node in parallel; the
//! result does not depend on the number of threads.
//!
//! The split ranks candidate splits by the triangles' axis-aligned boxes, binned along the three
//! coordinate axes: six numbers a triangle on three axes, where the node DOPs they stand for have
//! `k` on `k / 2` axes. The heuristic only ranks splits, and the split is most of a build's work.
//! What it reads of a triangle ([`Item`]) is moved with it as the triangles are partitioned, so
//! that every node's items lie contiguous in memory and each pass over a node reads memory in
//! order (looking them up by triangle id instead, in an order the partitions have shuffled, makes
//! every read a cache miss on a large mesh).
//!
//! Every node's offsets are the extremes of its triangles, so every plane touches the geometry (no
//! completely redundant half-space, the condition of the affine re-alignment).

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Vector3;
use rayon::prelude::*;

use super::node_bounds::{NodeBox, NodeSphere};
use super::separation::BOX_TEST_MAX_TRIANGLES;
use super::shared;
use super::tree::{Arrays, DopTree, Node};
use crate::collision::orientation::OrientationSet;
use crate::collision::oriented_box::SurfaceMoments;
use crate::collision::triangle::Triangle;
use crate::geometry::{TriMesh, larger, smaller};

/// Source of tree ids (0 is never given out: it marks an empty memory slot).
static NEXT_TREE_ID: AtomicU64 = AtomicU64::new(1);

/// A tree id never given out before.
pub(super) fn next_tree_id() -> u64 {
    NEXT_TREE_ID.fetch_add(1, Ordering::Relaxed)
}

/// Nodes of at least this many triangles build their two halves in parallel: below it, the
/// work of a half is too small to pay for handing it to another thread.
const PARALLEL_MIN_TRIANGLES: usize = 4096;

/// Nodes of at most this many triangles get the sphere around their triangles, centred on their
/// bounding box; larger ones (but the root, whose sphere is every query's first test) the sphere
/// around their children's, which is looser but costs no pass over the triangles.
const SPHERE_EXACT_MAX_TRIANGLES: usize = 1024;

/// Number of bins per axis of the split heuristic.
const SPLIT_BINS: usize = 16;

/// Most triangles of a node the split heuristic reads (see [`best_split`]).
const SPLIT_SAMPLE: usize = 4096;

/// An axis-aligned box as the six offsets of a DOP along x, y, z, -x, -y, -z: boxes merge with
/// [`merge_max`] alone, and the sum of the offsets is the sum of the box's widths.
type Slabs = [f32; 6];

/// What the split reads of a triangle.
#[derive(Debug, Clone, Copy)]
struct Item {
    /// The triangle's bounding box, rounded to `f32` (the split only ranks by it).
    slabs: Slabs,
    centroid: [f32; 3],
    /// The triangle's index in the mesh.
    id: u32,
}

impl Item {
    fn new([p, q, r]: &Triangle, id: u32) -> Self {
        let (lo, hi) = (p.inf(q).inf(r), p.sup(q).sup(r));
        let centroid = (p.coords + q.coords + r.coords) / 3.0;
        Item {
            slabs: [hi.x, hi.y, hi.z, -lo.x, -lo.y, -lo.z].map(|x| x as f32),
            centroid: centroid.map(|x| x as f32).into(),
            id,
        }
    }
}

/// Builds the tree of one mesh.
pub(super) struct TreeBuilder<'a> {
    mesh: &'a TriMesh,
    set: &'a OrientationSet,
    leaf_size: usize,
    /// Number of DOP offsets, twice the number of axes.
    k: usize,
    /// Whether the orientations begin with x, y and z, so that a node's DOP holds its bounding
    /// box (every supported set but k = 24).
    dop_has_box: bool,
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
    pub(super) fn new(mesh: &'a TriMesh, set: &'a OrientationSet, leaf_size: usize) -> Self {
        let coordinate = [Vector3::x(), Vector3::y(), Vector3::z()];
        TreeBuilder {
            mesh,
            set,
            leaf_size,
            k: set.k(),
            dop_has_box: set.axes().get(..3) == Some(&coordinate[..]),
        }
    }

    pub(super) fn build(self) -> DopTree {
        let k = self.k;
        let count = self.mesh.triangles().len();
        let mut items: Vec<Item> = (0..count)
            .into_par_iter()
            .map(|i| Item::new(&self.mesh.triangle(i), i as u32))
            .collect();
        let plan = self.plan(&mut items);
        let triangle_ids = shared::from_fn(count, |i| items[i].id);
        drop(items);
        let triangles = shared::from_fn(count, |i| self.mesh.triangle(triangle_ids[i] as usize));
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
        self.fill(&plan, &triangles, 0..count, 0, &mut root, below);
        DopTree::assemble(
            Arrays {
                set: self.set.clone(),
                nodes,
                parents,
                triangle_ranges,
                offsets,
                boxes,
                triangle_ids,
            },
            triangles,
        )
    }

    /// Splits `items` recursively until at most `leaf_size` remain, leaving them in leaf order,
    /// and returns the tree's shape.
    fn plan(&self, items: &mut [Item]) -> Plan {
        if items.len() <= self.leaf_size {
            return vec![[0, 0]];
        }
        let parallel = items.len() >= PARALLEL_MIN_TRIANGLES;
        let mid = partition(items);
        let (left, right) = items.split_at_mut(mid);
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

    /// Writes the node of `plan[0]` (the triangles `range` of `triangles`, the mesh's in leaf
    /// order; parent `parent`) into `slot`, and its descendants into `below`, the run that
    /// follows it: its two children first, then the left child's descendants, then the right's.
    /// Returns the node's surface moments if it is small enough to get a box (a parent's box is
    /// fitted to the sum of its children's).
    fn fill(
        &self,
        plan: &[[u32; 2]],
        triangles: &[Triangle],
        range: std::ops::Range<usize>,
        parent: usize,
        slot: &mut Slots<'_>,
        below: Slots<'_>,
    ) -> Option<SurfaceMoments> {
        let (k, h) = (self.k, self.k / 2);
        let index = slot.first;
        let [left_triangles, left_nodes] = plan[0];
        let own = &triangles[range.clone()];
        let small = own.len() <= BOX_TEST_MAX_TRIANGLES;
        let (first, count, moments, merged_sphere) = if left_nodes == 0 {
            let dop = &mut slot.offsets[..k];
            for (i, axis) in self.set.axes().iter().enumerate() {
                let (low, high) = (own.iter().flatten())
                    .map(|p| axis.dot(&p.coords))
                    .fold((f64::MAX, f64::MIN), |(low, high), x| {
                        (smaller(low, x), larger(high, x))
                    });
                dop[i] = round_up(high);
                dop[i + h] = round_up(-low);
            }
            let moments = small.then(|| SurfaceMoments::of(own));
            (range.start, own.len() as u32, moments, None)
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
                self.fill(left_plan, triangles, range, index, &mut left, left_below)
            };
            let fill_right = || {
                let range = middle..range.end;
                self.fill(right_plan, triangles, range, index, &mut right, right_below)
            };
            let (left_moments, right_moments) = if range.len() >= PARALLEL_MIN_TRIANGLES {
                rayon::join(fill_left, fill_right)
            } else {
                (fill_left(), fill_right())
            };
            let dop = &mut slot.offsets[..k];
            dop.copy_from_slice(&left.offsets[..k]);
            merge_max(dop, &right.offsets[..k]);
            let moments = small.then(|| {
                let halves = left_moments.zip(right_moments);
                halves
                    .map(|(left, right)| left + right)
                    .expect("the children of a node small enough for a box are too")
            });
            let sphere = NodeSphere::enclosing(&left.nodes[0].sphere, &right.nodes[0].sphere);
            (children, 0, moments, Some(sphere))
        };
        let dop = &slot.offsets[..k];
        slot.nodes[0] = Node {
            first: first as u32,
            count,
            size: (0..h).map(|i| dop[i] + dop[i + h]).fold(0.0, f32::max),
            sphere: match merged_sphere {
                Some(sphere) if own.len() > SPHERE_EXACT_MAX_TRIANGLES && index != 0 => sphere,
                _ if self.dop_has_box => {
                    let centre =
                        Vector3::from_fn(|i, _| (f64::from(dop[i]) - f64::from(dop[i + h])) / 2.0);
                    NodeSphere::centred(centre, own.iter().flatten())
                }
                _ => NodeSphere::around(own.iter().flatten()),
            },
        };
        slot.parents[0] = parent as u32;
        slot.triangle_ranges[0] = [range.start as u32, range.end as u32];
        if let Some(moments) = &moments {
            slot.boxes[0] = NodeBox::fitted(moments, own);
        }
        moments
    }
}

/// Splits `items` in two non-empty halves and returns where the second begins.
///
/// Binned surface heuristic: along each coordinate axis the centroids are put in [`SPLIT_BINS`]
/// bins, and the split between bins minimising
/// `size(left) * count(left) + size(right) * count(right)` is taken, where `size` is the sum of
/// the widths of the box around a side (proportional to its mean width, hence to how often a
/// node of the other tree overlaps it); ties go to the first axis. When all centroids coincide,
/// any split is as good: the middle is taken.
fn partition(items: &mut [Item]) -> usize {
    // Few triangles: as many bins as triangles keeps the cost linear in their number.
    let bins = SPLIT_BINS.min(items.len());
    let Some(split) = best_split(items, bins) else {
        return items.len() / 2;
    };
    // In the bin's terms `bin_of(x) < split.bin`, compared before rounding to a bin.
    let (range, first_right) = (split.range, split.bin as f32);
    let goes_left =
        |item: &Item| (item.centroid[split.axis] - range.lo) * range.scale < first_right;
    // Hoare's scheme: swap only the pairs on the wrong sides.
    let (mut low, mut high) = (0, items.len());
    loop {
        while low < high && goes_left(&items[low]) {
            low += 1;
        }
        while low < high && !goes_left(&items[high - 1]) {
            high -= 1;
        }
        if low + 1 >= high {
            break;
        }
        items.swap(low, high - 1);
        low += 1;
        high -= 1;
    }
    low
}

/// The cheapest split of `items` over the three axes, or `None` when their centroids spread
/// along none.
///
/// A large node is judged on an evenly spread sample of [`SPLIT_SAMPLE`] of its triangles: the
/// bins of a few thousand triangles place the split about where those of all of them would, and
/// the node's one full pass is then the partition's.
fn best_split(items: &[Item], bins: usize) -> Option<Split> {
    let sample = || items.iter().step_by(items.len().div_ceil(SPLIT_SAMPLE));
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for item in sample() {
        for axis in 0..3 {
            let x = item.centroid[axis];
            lo[axis] = if x < lo[axis] { x } else { lo[axis] };
            hi[axis] = if x > hi[axis] { x } else { hi[axis] };
        }
    }
    // An axis along which the centroids do not spread gets scale 0: all in one bin, no split.
    let ranges = std::array::from_fn::<_, 3, _>(|axis| {
        let scale = bins as f32 / (hi[axis] - lo[axis]);
        AxisRange {
            lo: lo[axis],
            scale: if hi[axis] > lo[axis] && scale.is_finite() {
                scale
            } else {
                0.0
            },
        }
    });
    let mut binned = Bins::new(bins);
    let mut sampled = 0;
    for item in sample() {
        for (axis, &range) in ranges.iter().enumerate() {
            binned.add(axis, bin_of(item.centroid[axis], range, bins), &item.slabs);
        }
        sampled += 1;
    }
    let mut best: Option<Split> = None;
    for (axis, &range) in ranges.iter().enumerate() {
        if let Some((cost, bin)) = binned.cheapest_split(axis, sampled)
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

/// Where the centroids of a node lie along one axis, for binning.
#[derive(Debug, Clone, Copy)]
struct AxisRange {
    /// The lowest centroid coordinate.
    lo: f32,
    /// Bins per unit length.
    scale: f32,
}

/// Per axis and bin, how many triangles fell in it and the box around them.
struct Bins {
    bins: usize,
    counts: [[usize; SPLIT_BINS]; 3],
    slabs: [[Slabs; SPLIT_BINS]; 3],
}

impl Bins {
    fn new(bins: usize) -> Bins {
        Bins {
            bins,
            counts: [[0; SPLIT_BINS]; 3],
            slabs: [[[f32::MIN; 6]; SPLIT_BINS]; 3],
        }
    }

    fn add(&mut self, axis: usize, bin: usize, slabs: &Slabs) {
        self.counts[axis][bin] += 1;
        merge_max(&mut self.slabs[axis][bin], slabs);
    }

    /// The cheapest split between bins along `axis` of a node of `total` triangles: its cost
    /// and the first bin of the right side, or `None` if every split leaves a side empty.
    fn cheapest_split(&self, axis: usize, total: usize) -> Option<(f64, usize)> {
        let (bins, slabs) = (self.bins, &self.slabs[axis]);
        let size = |box_: &Slabs| box_.iter().sum::<f32>() as f64;
        // The sizes of the prefixes from the left, then a sweep from the right.
        let mut left_sizes = [0.0; SPLIT_BINS];
        let mut running = [f32::MIN; 6];
        for (bin, left_size) in left_sizes.iter_mut().enumerate().take(bins) {
            merge_max(&mut running, &slabs[bin]);
            *left_size = size(&running);
        }
        running = [f32::MIN; 6];
        let mut right_count = 0;
        let mut best: Option<(f64, usize)> = None;
        for bin in (1..bins).rev() {
            merge_max(&mut running, &slabs[bin]);
            right_count += self.counts[axis][bin];
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

/// A candidate split of a node: centroids in bins `< bin` along coordinate axis `axis` go left.
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

/// The bin of a centroid coordinate `x` on an axis binned as `range`.
fn bin_of(x: f32, range: AxisRange, bins: usize) -> usize {
    (((x - range.lo) * range.scale) as usize).min(bins - 1)
}

/// The smallest `f32` not below `x`.
pub(super) fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}
