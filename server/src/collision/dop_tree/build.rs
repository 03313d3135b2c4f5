//! Top-down construction of a [`DopTree`], with a binned surface heuristic
//! ([`TreeBuilder::partition`]).
//!
//! Every node's offsets are the extremes of its triangles, so every plane touches the geometry (no
//! completely redundant half-space, the condition of the affine re-alignment).

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Point3;

use super::node_bounds::{NodeBox, NodeSphere};
use super::tree::{DopTree, Node};
use crate::collision::orientation::OrientationSet;
use crate::collision::triangle::Triangle;
use crate::geometry::{TriMesh, bounding_sphere_of};

/// Source of tree ids (0 is never given out: it marks an empty memory slot).
static NEXT_TREE_ID: AtomicU64 = AtomicU64::new(1);

/// Top-down construction state.
pub(super) struct TreeBuilder<'a> {
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
    pub(super) fn new(mesh: &TriMesh, set: &'a OrientationSet, leaf_size: usize) -> Self {
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

    pub(super) fn build(mut self) -> DopTree {
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
pub(super) fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}
