//! Re-alignment: B's node DOPs mapped onto A's orientations for one query, in O(k) per node with
//! the paper's affine map ([`AffineRealign`]), and cached per query on each thread
//! ([`RealignCache`] over the buffers of [`Scratch`]).

use std::cell::RefCell;

use nalgebra::{Matrix3, Vector3};

use super::tree::DopTree;
use crate::collision::QueryStats;

/// Re-aligns a node of tree B to A's orientations, for one query.
///
/// The result is stored *opposite*: `out[i]` is the support of B's node along `-n_i`, so that the
/// nodes are disjoint along axis i exactly when `a[i] + out[i] < 0`.
pub trait Realign<const K: usize>: Sync {
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
    pub(super) fn new(
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
pub fn rounding_margin(scale: f64) -> f32 {
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

/// Per orientation slot of A, the generic vertex of B's set that supported it at the previous
/// query on this thread: the first candidate tried (temporal coherence of poses).
pub(super) type ConeHints = [u8; MAX_K];

/// The largest supported k.
pub(super) const MAX_K: usize = 26;

thread_local! {
    pub(super) static CONE_HINTS: std::cell::Cell<ConeHints> =
        const { std::cell::Cell::new([u8::MAX; MAX_K]) };
    static REVERSE_CONE_HINTS: std::cell::Cell<ConeHints> =
        const { std::cell::Cell::new([u8::MAX; MAX_K]) };
}

/// Runs `f` with this thread's cone hints in `hints` (one of the two above), keeping what it
/// leaves in them for the next query.
pub(super) fn with_cone_hints<T>(
    hints: &'static std::thread::LocalKey<std::cell::Cell<ConeHints>>,
    f: impl FnOnce(&mut ConeHints) -> T,
) -> T {
    let mut current = hints.get();
    let result = f(&mut current);
    hints.set(current);
    result
}

/// This query's view of the per-thread re-alignment cache.
pub(super) struct RealignCache<'a> {
    pub(super) stamp: u32,
    pub(super) tags: &'a mut [(u32, u32)],
    pub(super) realigned: &'a mut [f32],
}

impl RealignCache<'_> {
    /// The re-aligned offsets of node `node` of `tree`, computed unless cached in this query.
    #[inline(always)]
    pub(super) fn get<const K: usize, const FUSED: bool, R: Realign<K>>(
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
pub(super) struct Scratch {
    pub(super) stamp: u32,
    /// Per slot: (stamp of the query that filled it, B node it holds).
    pub(super) tags: Vec<(u32, u32)>,
    pub(super) realigned: Vec<f32>,
    /// The same for A's nodes re-aligned into B's frame.
    pub(super) reverse_tags: Vec<(u32, u32)>,
    pub(super) reverse_realigned: Vec<f32>,
    pub(super) stack: Vec<(u32, u32)>,
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
    pub(super) fn begin(&mut self) {
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
pub(super) fn with_scratch<T>(f: impl FnOnce(&mut Scratch) -> T) -> T {
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scratch) => f(&mut scratch),
        Err(_) => f(&mut Scratch::default()),
    })
}
