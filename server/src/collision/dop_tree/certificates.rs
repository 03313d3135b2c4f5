//! The certificates of a front's separated node pairs, in packed arrays, and the scan that finds
//! those the motion since may have expired (four at a time with AVX2 where the CPU has it).

use nalgebra::{Matrix3, Vector3};

use super::node_bounds::NodeSphere;

/// Separated node pairs and their certificates, in parallel arrays.
#[derive(Default)]
pub(super) struct Certificates {
    /// `gap - direction . centre - radius * turn` when the pair was found (rounding guard
    /// subtracted): the certificate holds while this plus `direction . centre - radius * turn`
    /// now stays above the guard.
    pub(super) expiry: Vec<f64>,
    /// Unit direction (to f32 rounding) beyond which the other tree lies, in this frame, by
    /// component (so that the scan of [`Certificates::flagged`] runs in vector registers).
    pub(super) directions: [Vec<f32>; 3],
    /// The same bound for the moving node alone (B's in A's frame, A's in B's), fixed when the
    /// pair was found: `gap - guard - direction . centre - radius * turn` with the node's own
    /// sphere. A node turns with its tree about the tree's centre, but only its own radius
    /// widens the bound: when the tree's bound has expired (a turning tree), this one often
    /// still holds.
    anchors: Vec<f64>,
    /// The moving node's sphere: its centre in its own tree's frame, by component, and radius.
    node_centres: [Vec<f32>; 3],
    node_radii: Vec<f32>,
    pub(super) pairs: Vec<(u32, u32)>,
}

/// What [`Front::due`](super::front::Front::due) found in one frame's certificates.
#[derive(Default)]
pub(super) struct DueCertificates {
    /// Indices of the certificates that may no longer hold: their pairs are tested again.
    pub(super) indices: Vec<u32>,
    /// Certificates whose tree bound failed but whose node bound held, with the tree bound's
    /// expiry renewed from the node bound (see [`Certificates::flagged`]); applied when the
    /// front settles at this query's pose.
    pub(super) renewed: Vec<(u32, f64)>,
}

/// The node bound of a [`Front`](super::front::Front)'s certificates in one frame: the moving
/// tree's pose there, the turn accumulated since the front's restart, and the rounding guard.
pub(super) struct NodeBound {
    pub(super) rotation: Matrix3<f64>,
    pub(super) translation: Vector3<f64>,
    pub(super) turn: f64,
    pub(super) guard: f64,
}

impl Certificates {
    pub(super) fn clear(&mut self) {
        self.expiry.clear();
        self.directions.iter_mut().for_each(Vec::clear);
        self.anchors.clear();
        self.node_centres.iter_mut().for_each(Vec::clear);
        self.node_radii.clear();
        self.pairs.clear();
    }

    pub(super) fn push(
        &mut self,
        (expiry, anchor): (f64, f64),
        direction: [f32; 3],
        sphere: &NodeSphere,
        pair: (u32, u32),
    ) {
        self.expiry.push(expiry);
        self.anchors.push(anchor);
        for (component, value) in self.directions.iter_mut().zip(direction) {
            component.push(value);
        }
        for (component, value) in self.node_centres.iter_mut().zip(sphere.centre) {
            component.push(value);
        }
        self.node_radii.push(sphere.radius);
        self.pairs.push(pair);
    }

    /// Appends to `due.indices` the certificates that may no longer hold: those whose tree
    /// bound (`expiry + direction . centre`, with the other tree's centre at `centre`) is at
    /// most `threshold` and whose node bound (`anchor + direction . (rotation c + translation)
    /// - radius * turn`, with the moving node's sphere) is at most `guard`.
    ///
    /// Both bounds are lower bounds on the gap now (less the guard). Where the node bound holds
    /// and the tree bound does not, the node bound's value renews the tree bound's expiry
    /// (`due.renewed`), as if the pair had been found apart by that gap at this pose: under
    /// steady turning the tree bound fails soon after each pair was found, and without renewal
    /// every later query would pay for the node bound of most pairs. The renewal is valid only
    /// from this pose on, so it is applied only when the front settles here (where its turn is
    /// counted from).
    ///
    /// The tree bound is checked for every pair, the node bound only where the tree bound fails
    /// (usually a few pairs per query).
    pub(super) fn flagged(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            return unsafe { self.flagged_avx2(centre, threshold, nodes, due) };
        }
        self.flagged_scalar(centre, threshold, nodes, due, 0);
    }

    /// The tree bound of pair `j` with the other tree's centre at `centre`:
    /// `expiry + direction . centre`.
    #[inline(always)]
    fn tree_bound(&self, j: usize, centre: &Vector3<f64>) -> f64 {
        let [dx, dy, dz] = &self.directions;
        self.expiry[j]
            + f64::from(dx[j]) * centre.x
            + f64::from(dy[j]) * centre.y
            + f64::from(dz[j]) * centre.z
    }

    /// [`Self::flagged`] over the pairs from `first` on, one at a time.
    pub(super) fn flagged_scalar(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
        first: usize,
    ) {
        for j in first..self.expiry.len() {
            let tree = self.tree_bound(j, centre);
            if tree <= threshold {
                self.flag(j, tree, threshold, nodes, due);
            }
        }
    }

    /// [`Self::flagged`] with the tree bounds of four pairs at a time in AVX2 registers and their
    /// comparisons packed into a bit mask, so that the node bounds, computed one at a time, are
    /// reached only for the lanes that failed.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn flagged_avx2(
        &self,
        centre: &Vector3<f64>,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        use std::arch::x86_64::{
            _CMP_LE_OQ, _mm_loadu_ps, _mm256_cmp_pd, _mm256_cvtps_pd, _mm256_fmadd_pd,
            _mm256_loadu_pd, _mm256_movemask_pd, _mm256_set1_pd, _mm256_storeu_pd,
        };
        let [dx, dy, dz] = &self.directions;
        let len = self.expiry.len();
        assert!(dx.len() == len && dy.len() == len && dz.len() == len);
        let whole = len - len % 4;
        let (cx, cy, cz) = (
            _mm256_set1_pd(centre.x),
            _mm256_set1_pd(centre.y),
            _mm256_set1_pd(centre.z),
        );
        let limit = _mm256_set1_pd(threshold);
        let mut lanes = [0.0f64; 4];
        for start in (0..whole).step_by(4) {
            // SAFETY: `start + 4 <= len`, the length of each of the four arrays read.
            let tree = unsafe {
                let x = _mm256_cvtps_pd(_mm_loadu_ps(dx.as_ptr().add(start)));
                let y = _mm256_cvtps_pd(_mm_loadu_ps(dy.as_ptr().add(start)));
                let z = _mm256_cvtps_pd(_mm_loadu_ps(dz.as_ptr().add(start)));
                let expiry = _mm256_loadu_pd(self.expiry.as_ptr().add(start));
                _mm256_fmadd_pd(
                    z,
                    cz,
                    _mm256_fmadd_pd(y, cy, _mm256_fmadd_pd(x, cx, expiry)),
                )
            };
            let mut mask = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(tree, limit)) as u32;
            if mask == 0 {
                continue;
            }
            // SAFETY: `lanes` holds four f64.
            unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), tree) };
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                self.flag(start + lane, lanes[lane], threshold, nodes, due);
                mask &= mask - 1;
            }
        }
        self.flagged_scalar(centre, threshold, nodes, due, whole);
    }

    /// Pair `j`, whose tree bound `tree` failed (at most `threshold`): due if its node bound
    /// fails too, else renewed from the node bound.
    #[inline(always)]
    fn flag(
        &self,
        j: usize,
        tree: f64,
        threshold: f64,
        nodes: &NodeBound,
        due: &mut DueCertificates,
    ) {
        let [dx, dy, dz] = &self.directions;
        let [cx, cy, cz] = &self.node_centres;
        let centre = Vector3::new(f64::from(cx[j]), f64::from(cy[j]), f64::from(cz[j]));
        let moved = nodes.rotation * centre + nodes.translation;
        let node = self.anchors[j]
            + f64::from(dx[j]) * moved.x
            + f64::from(dy[j]) * moved.y
            + f64::from(dz[j]) * moved.z
            - f64::from(self.node_radii[j]) * nodes.turn;
        if node <= nodes.guard {
            due.indices.push(j as u32);
        } else {
            // The tree bound's gap now is `tree - (threshold - guard)`; the node bound's is
            // `node`, larger here: the expiry grows by the difference.
            let renewed = self.expiry[j] + node - tree + (threshold - nodes.guard);
            due.renewed.push((j as u32, renewed));
        }
    }

    /// Renews the expiries that [`Certificates::flagged`] computed, then removes the pairs it
    /// flagged.
    pub(super) fn settle(&mut self, due: &DueCertificates) {
        for &(i, expiry) in &due.renewed {
            self.expiry[i as usize] = expiry;
        }
        self.remove(&due.indices);
    }

    /// Removes the pairs at `indices` (ascending).
    fn remove(&mut self, indices: &[u32]) {
        // Descending, each swap brings in a pair that stays.
        for &i in indices.iter().rev() {
            self.expiry.swap_remove(i as usize);
            for component in &mut self.directions {
                component.swap_remove(i as usize);
            }
            self.anchors.swap_remove(i as usize);
            for component in &mut self.node_centres {
                component.swap_remove(i as usize);
            }
            self.node_radii.swap_remove(i as usize);
            self.pairs.swap_remove(i as usize);
        }
    }
}
