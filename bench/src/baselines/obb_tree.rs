//! Baseline: the OBB-tree (RAPID's algorithm, as FCL implements it).
//!
//! Build: each node's box is fitted to its triangles, with axes the eigenvectors of the
//! area-weighted covariance of the triangles (the second moments of the triangles as surfaces),
//! and split along the axis of largest variance at the mean of the triangle centroids (at the
//! median if that leaves one side empty), down to one triangle per leaf.
//! Query: the relative pose of two boxes is computed per node pair from B's pose in A's frame
//! and the 15-axis separating-axis test decides overlap; the larger box is descended. Leaves use
//! the same exact triangle test as the DOP-trees.

use nalgebra::{Isometry3, Point3};

use vas_server::collision::oriented_box::OrientedBox;
use vas_server::collision::triangle::{Triangle, triangles_intersect};
use vas_server::collision::{MeshCollider, QueryStats};
use vas_server::geometry::TriMesh;

/// A node: an oriented box; a leaf (`count > 0`) owns triangles `first..first + count`, an inner
/// node has children `first` and `first + 1`.
#[derive(Debug, Clone, Copy)]
struct ObbNode {
    bounds: OrientedBox,
    first: u32,
    count: u32,
}

impl ObbNode {
    fn is_leaf(&self) -> bool {
        self.count > 0
    }
    fn size(&self) -> f64 {
        self.bounds.extents.max()
    }
}

/// An OBB-tree over one mesh.
#[derive(Debug, Clone)]
pub struct ObbTree {
    nodes: Vec<ObbNode>,
    triangles: Vec<Triangle>,
    triangle_ids: Vec<u32>,
}

impl ObbTree {
    /// Heap bytes used by the tree.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<ObbNode>()
            + self.triangles.len() * (size_of::<Triangle>() + size_of::<u32>())
    }

    fn query<const ALL: bool>(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        let rotation = *b_to_a.rotation.to_rotation_matrix().matrix();
        let translation = b_to_a.translation.vector;
        let mut hit = false;
        let mut stack = vec![(0u32, 0u32)];
        while let Some((ia, ib)) = stack.pop() {
            let (na, nb) = (&self.nodes[ia as usize], &other.nodes[ib as usize]);
            stats.bv_tests += 1;
            stats.realignments += 1;
            if na
                .bounds
                .separating_axis(&nb.bounds, &rotation, &translation)
                .is_some()
            {
                continue;
            }
            stats.nodes_visited += 1;
            match (na.is_leaf(), nb.is_leaf()) {
                (true, true) => {
                    for jb in nb.first..nb.first + nb.count {
                        let tb = other.triangles[jb as usize]
                            .map(|p| Point3::from(rotation * p.coords + translation));
                        for ja in na.first..na.first + na.count {
                            stats.tri_tests += 1;
                            if triangles_intersect(&self.triangles[ja as usize], &tb) {
                                hit = true;
                                if !ALL {
                                    return true;
                                }
                                out.push([
                                    self.triangle_ids[ja as usize],
                                    other.triangle_ids[jb as usize],
                                ]);
                            }
                        }
                    }
                }
                _ if !na.is_leaf() && (nb.is_leaf() || na.size() >= nb.size()) => {
                    stack.push((na.first + 1, ib));
                    stack.push((na.first, ib));
                }
                _ => {
                    stack.push((ia, nb.first + 1));
                    stack.push((ia, nb.first));
                }
            }
        }
        hit
    }
}

impl MeshCollider for ObbTree {
    fn build(mesh: &TriMesh) -> Self {
        let triangles: Vec<Triangle> = (0..mesh.triangles().len())
            .map(|i| mesh.triangle(i))
            .collect();
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = vec![ObbNode::fit(&triangles, &order)];
        build_node(&triangles, &mut order, &mut nodes, 0, 0);
        ObbTree {
            nodes,
            triangles: order.iter().map(|&i| triangles[i as usize]).collect(),
            triangle_ids: order,
        }
    }

    fn intersects(&self, other: &Self, b_to_a: &Isometry3<f64>, stats: &mut QueryStats) -> bool {
        self.query::<false>(other, b_to_a, stats, &mut Vec::new())
    }

    fn intersecting_pairs(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        out: &mut Vec<[u32; 2]>,
        stats: &mut QueryStats,
    ) {
        self.query::<true>(other, b_to_a, stats, out);
    }
}

/// Splits node `index` (whose box is already fitted) covering `order[start..]` of its length.
fn build_node(
    triangles: &[Triangle],
    order: &mut [u32],
    nodes: &mut Vec<ObbNode>,
    index: usize,
    start: usize,
) {
    let count = nodes[index].count as usize;
    if count <= 1 {
        return;
    }
    let range = &mut order[start..start + count];
    let axis = nodes[index].bounds.axes.column(0).into_owned();
    let centroid = |t: u32| {
        let [p, q, r] = &triangles[t as usize];
        axis.dot(&((p.coords + q.coords + r.coords) / 3.0))
    };
    let mean = range.iter().map(|&t| centroid(t)).sum::<f64>() / count as f64;
    // Partition by the mean; fall back to the median when one side would be empty.
    let mut left = 0;
    for i in 0..count {
        if centroid(range[i]) < mean {
            range.swap(i, left);
            left += 1;
        }
    }
    if left == 0 || left == count {
        left = count / 2;
        range.select_nth_unstable_by(left, |&a, &b| centroid(a).total_cmp(&centroid(b)));
    }
    let children = nodes.len();
    let mut first = ObbNode::fit(triangles, &order[start..start + left]);
    let mut second = ObbNode::fit(triangles, &order[start + left..start + count]);
    first.first = start as u32;
    second.first = (start + left) as u32;
    nodes.push(first);
    nodes.push(second);
    nodes[index].first = children as u32;
    nodes[index].count = 0;
    build_node(triangles, order, nodes, children, start);
    build_node(triangles, order, nodes, children + 1, start + left);
}

impl ObbNode {
    /// The node fitted to the triangles `subset`: a leaf covering them until it is split.
    fn fit(triangles: &[Triangle], subset: &[u32]) -> Self {
        ObbNode {
            bounds: OrientedBox::fit(triangles, subset),
            first: 0,
            count: subset.len() as u32,
        }
    }
}
