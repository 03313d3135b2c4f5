//! Baseline: the k-DOP tree re-aligned by brute force (QuickCD's method, [KHM+98]).
//!
//! Same tree, same traversal and same triangle test as [`DopTree`]; only the re-alignment
//! differs: each B node's DOP vertices are computed from its offsets, transformed into A's frame
//! and projected on A's axes, O(k²) per node instead of O(k). The vertices are those of the
//! generic DOP's combinatorial structure (every vertex solves three plane equations); their hull
//! contains the node's DOP whatever its offsets, so the result is conservative, and exact when
//! the node has the generic structure.

use nalgebra::{Isometry3, Matrix3, Vector3};

use vas_server::collision::dop_tree::{DopTree, Realign, TreePair, rounding_margin};
use vas_server::collision::orientation::OrientationSet;
use vas_server::collision::{MeshCollider, QueryStats};
use vas_server::geometry::TriMesh;

/// A DOP-tree queried with brute-force (vertex transform) re-alignment.
#[derive(Debug, Clone)]
pub struct KdopBruteForceTree {
    tree: DopTree,
}

impl KdopBruteForceTree {
    /// Wraps a built DOP-tree.
    pub fn new(tree: DopTree) -> Self {
        KdopBruteForceTree { tree }
    }

    /// Builds the tree with orientation set `set` and the default leaf size.
    pub fn with_orientations(mesh: &TriMesh, set: &OrientationSet) -> Self {
        KdopBruteForceTree::new(DopTree::with_orientations(mesh, set))
    }

    /// The underlying tree.
    pub fn tree(&self) -> &DopTree {
        &self.tree
    }

    fn query<const ALL: bool>(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        fn run<const K: usize, const ALL: bool>(
            a: &DopTree,
            b: &DopTree,
            b_to_a: &Isometry3<f64>,
            stats: &mut QueryStats,
            out: &mut Vec<[u32; 2]>,
        ) -> bool {
            let pair = TreePair::new(a, b, b_to_a, |rotation, translation| {
                VertexRealign::<K>::new(a, b, rotation, translation)
            });
            pair.run::<ALL, K>(stats, out, false).is_some()
        }
        let (a, b) = (&self.tree, &other.tree);
        match a.orientations().k() {
            6 => run::<6, ALL>(a, b, b_to_a, stats, out),
            14 => run::<14, ALL>(a, b, b_to_a, stats, out),
            18 => run::<18, ALL>(a, b, b_to_a, stats, out),
            24 => run::<24, ALL>(a, b, b_to_a, stats, out),
            26 => run::<26, ALL>(a, b, b_to_a, stats, out),
            k => unreachable!("orientation sets have a supported k, not {k}"),
        }
    }
}

impl MeshCollider for KdopBruteForceTree {
    fn build(mesh: &TriMesh) -> Self {
        KdopBruteForceTree::with_orientations(mesh, &OrientationSet::default())
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

/// Per-query data of the brute-force re-alignment: vertex solvers of B's set, the pose, A's axes.
struct VertexRealign<const K: usize> {
    /// Per generic vertex: its three planes and the matrix giving its position from their offsets.
    solvers: Vec<([u8; 3], Matrix3<f32>)>,
    rotation: Matrix3<f32>,
    translation: Vector3<f32>,
    /// A's k/2 axes.
    axes: Vec<Vector3<f32>>,
    margin: f32,
}

impl<const K: usize> VertexRealign<K> {
    fn new(a: &DopTree, b: &DopTree, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Self {
        let solvers: Vec<([u8; 3], Matrix3<f32>)> = b
            .orientations()
            .vertex_solvers()
            .into_iter()
            .map(|(planes, m)| (planes, m.cast::<f32>()))
            .collect();
        let solver_norm = solvers
            .iter()
            .map(|(_, m)| m.abs().row_sum().max() as f64)
            .fold(0.0, f64::max);
        let margin = rounding_margin(
            solver_norm * b.max_abs_offset() as f64
                + translation.norm()
                + a.max_abs_offset() as f64,
        );
        VertexRealign {
            solvers,
            rotation: rotation.cast(),
            translation: translation.cast(),
            axes: a.orientations().axes().iter().map(|v| v.cast()).collect(),
            margin,
        }
    }
}

impl<const K: usize> Realign<K> for VertexRealign<K> {
    fn realign<const FUSED: bool>(&self, b: &DopTree, node: usize, out: &mut [f32; K]) {
        let h = K / 2;
        let d = b.node_offsets(node);
        let mut lo = [f32::MAX; K];
        let mut hi = [f32::MIN; K];
        for (planes, solver) in &self.solvers {
            let offsets = Vector3::new(
                d[planes[0] as usize],
                d[planes[1] as usize],
                d[planes[2] as usize],
            );
            let vertex = self.rotation * (solver * offsets) + self.translation;
            for j in 0..h {
                let p = self.axes[j].dot(&vertex);
                lo[j] = lo[j].min(p);
                hi[j] = hi[j].max(p);
            }
        }
        // Opposite storage: slot j < h holds the support along -axis j, slot j + h along +axis j.
        for j in 0..h {
            out[j] = -lo[j] + self.margin;
            out[j + h] = hi[j] + self.margin;
        }
    }
}
