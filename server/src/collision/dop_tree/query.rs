//! A query's entry, and the stages it goes through, with B posed in A's frame:
//!
//! 0. the bounding spheres are tested (far pairs end here); a first-hit query then uses what the
//!    previous queries of the same two trees on this thread left (`pair_memory`): the pair of
//!    leaves last in contact is tested again, then the subtrees around it; a traversal starts
//!    from the last free query's front (the node pairs where it ended, each with a directional
//!    certificate), taking up again only the pairs whose gap the motion since may have closed.
//!    An all-pairs query (not split) walks from the same front and leaves its own, which is
//!    complete whatever it finds. A first-hit query far from both the front's pose and the last
//!    query's (two trees shared by many pairs of objects, random poses) walks from the roots
//!    without recording a front;
//! 1. the last proof that the roots are apart is checked against the motion since; failing that,
//!    a few of A's root slabs are tried (`root_separation`): far pairs end here;
//! 2. otherwise the affine map from B's offsets to re-aligned ones is set up (`realign`), on
//!    first use only ([`LazyPair`]): a query that the front answers without a test skips it;
//! 3. the depth-first traversal (`traverse`, `separation`, `parallel`).

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::pair_memory::PairMemory;
use super::realign::{AffineRealign, CONE_HINTS, with_cone_hints};
use super::root_separation::{RootSeparation, roots_separated_along_offset};
use super::traverse::TreePair;
use super::tree::DopTree;
use crate::collision::QueryStats;

/// Runs a query with the O(k) affine re-alignment, dispatching on A's k.
pub(super) fn with_affine<const ALL: bool>(
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

/// The query of `b` posed at `b_to_a` against `a` with the O(k) re-alignment, or `None` when
/// [`roots_separated_along_offset`] already proves them apart (`centre_b`: B's centre in A's
/// frame; `root_separation`: how the roots were last proved apart, updated).
pub(super) fn affine_pair<'a, const K: usize>(
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
pub(super) struct LazyPair<'a, const K: usize> {
    pub(super) a: &'a DopTree,
    pub(super) b: &'a DopTree,
    pub(super) rotation: Matrix3<f64>,
    pub(super) translation: Vector3<f64>,
    pair: std::cell::OnceCell<TreePair<'a, AffineRealign<K>>>,
}

impl<'a, const K: usize> LazyPair<'a, K> {
    /// The query of `b` posed at `b_to_a` against `a`, set up on first use.
    pub(super) fn new(a: &'a DopTree, b: &'a DopTree, b_to_a: &Isometry3<f64>) -> Self {
        LazyPair {
            a,
            b,
            rotation: *b_to_a.rotation.to_rotation_matrix().matrix(),
            translation: b_to_a.translation.vector,
            pair: std::cell::OnceCell::new(),
        }
    }

    /// The traversal's set-up, made now if not yet.
    pub(super) fn get(&self) -> &TreePair<'a, AffineRealign<K>> {
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
