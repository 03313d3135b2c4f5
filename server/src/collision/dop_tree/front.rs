//! The front: the node pairs at which the walks since the last one from the roots ended, each
//! separated pair with a certificate that stays valid until the motion may have closed its gap.
//!
//! A certificate is a direction, fixed in A's or in B's frame, along which the other tree's
//! triangles lay at least a gap beyond this tree's. Motion changes that gap by at most the other
//! tree's centre moving along the direction plus the turn times its radius, so the certificate
//! holds while `gap + direction . (centre now - centre then) - radius * (turn since)` stays
//! positive: sliding along a surface (a peg down its hole) leaves the certificates across the gap
//! intact, however far it goes. The same holds with the moving node's own centre and radius: that
//! bound costs more but survives turning (the tree's radius times even a small turn soon exceeds
//! a small gap), so it is checked wherever the tree's bound fails. A query takes out only the
//! pairs both bounds may have expired, by a scan of packed arrays ([`Certificates`]): fronts hold
//! up to tens of thousands of pairs, where a scan beats a priority queue's scattered accesses.

use nalgebra::{Matrix3, Vector3};

use super::certificates::{Certificates, DueCertificates, NodeBound};
use super::separation::Ending;
use super::traverse::FrontPair;
use super::tree::DopTree;

/// The node pairs at which the traversals since the last one from the roots ended: the separated
/// ones with their certificates (see the module's doc), and the pairs of leaves to test again.
#[derive(Default)]
pub(super) struct Front {
    /// Separated pairs, per frame of the certificate's direction (A's, B's).
    pub(super) separated: [Certificates; 2],
    /// Turn accumulated since the last traversal from the roots: the sum of `|R' - R|` (spectral
    /// norm) over the poses at which the front was advanced.
    turn: f64,
    /// Largest coordinate scale ([`Placement::scale`]) since the last traversal from the roots:
    /// bounds the rounding of the certificates' arithmetic.
    scale: f64,
    /// Pairs of leaves whose triangles no face plane separated: tested again every time.
    leaves: Vec<(u32, u32)>,
    /// Pairs of the first complete front (of a query without a hit) since the last traversal
    /// from the roots; a carried front that grows well beyond (the contact region wandered) is
    /// dropped for a fresh one.
    pub(super) fresh_len: Option<usize>,
    /// Whether the last query that advanced the front without a hit tested again less than
    /// `STEADY_DUE_SHARE` of it (see `pair_memory`): most certificates hold (sliding), so extra
    /// pairs cost little more than their scan and the front may grow further before a fresh one
    /// pays off.
    pub(super) steady: bool,
}

/// Where the two trees are at a query, for the certificates of a [`Front`].
pub(super) struct Placement {
    /// B's bounding centre in A's frame, and A's in B's frame.
    centres: [Vector3<f64>; 2],
    /// The radius of the tree that moves in each frame: B's in A's frame, A's in B's.
    radii: [f64; 2],
    /// A bound on every coordinate involved: `|t| + |c_A| + |c_B| + r_A + r_B`.
    scale: f64,
    /// B's pose in A's frame.
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
}

/// Relative rounding guard of the certificates: covers the `f32` rounding of their directions and
/// of the DOP slacks they come from (both a few 1e-8 of the coordinates' scale).
pub(super) const CERTIFICATE_ROUNDING: f64 = 1e-6;

impl Placement {
    pub(super) fn new(
        a: &DopTree,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
    ) -> Self {
        Placement {
            centres: [
                rotation * b.bounding_centre.coords + translation,
                rotation.transpose() * (a.bounding_centre.coords - translation),
            ],
            radii: [
                b.bounding_radius * (1.0 + CERTIFICATE_ROUNDING),
                a.bounding_radius * (1.0 + CERTIFICATE_ROUNDING),
            ],
            scale: translation.norm()
                + a.bounding_centre.coords.norm()
                + b.bounding_centre.coords.norm()
                + a.bounding_radius
                + b.bounding_radius,
            rotation: *rotation,
            translation: *translation,
        }
    }

    /// The pose of the tree that moves in `frame` (B in A's frame, A in B's).
    fn motion(&self, frame: usize) -> (Matrix3<f64>, Vector3<f64>) {
        if frame == 0 {
            (self.rotation, self.translation)
        } else {
            let inverse = self.rotation.transpose();
            (inverse, -(inverse * self.translation))
        }
    }
}

impl Front {
    pub(super) fn len(&self) -> usize {
        self.separated[0].pairs.len() + self.separated[1].pairs.len() + self.leaves.len()
    }

    /// Empties the front for a traversal from the roots.
    pub(super) fn restart(&mut self) {
        self.separated.iter_mut().for_each(Certificates::clear);
        self.turn = 0.0;
        self.scale = 0.0;
        self.leaves.clear();
        self.steady = false;
    }

    /// The pairs to test at `placement`, after a further `turn`: the pairs of leaves and every
    /// pair whose certificate may have expired (their indices go to `due`). The front itself is
    /// unchanged until [`Front::settle`]: a query that finds contact leaves it as it was, since
    /// its pose (a trial pose inside an obstacle) says nothing of the next free one.
    pub(super) fn due(
        &self,
        turn: f64,
        placement: &Placement,
        retest: &mut Vec<(u32, u32)>,
        due: &mut [DueCertificates; 2],
    ) {
        retest.clear();
        retest.extend_from_slice(&self.leaves);
        let turn = self.turn + turn;
        let guard = CERTIFICATE_ROUNDING * self.scale.max(placement.scale);
        for (frame, certificates) in self.separated.iter().enumerate() {
            due[frame].indices.clear();
            due[frame].renewed.clear();
            let threshold = guard + placement.radii[frame] * turn;
            let centre = &placement.centres[frame];
            let (rotation, translation) = placement.motion(frame);
            let nodes = NodeBound {
                rotation,
                translation,
                turn,
                guard,
            };
            certificates.flagged(centre, threshold, &nodes, &mut due[frame]);
            retest.extend(
                due[frame]
                    .indices
                    .iter()
                    .map(|&i| certificates.pairs[i as usize]),
            );
        }
    }

    /// Replaces the pairs [`Front::due`] gave by where their new tests ended.
    pub(super) fn settle(
        &mut self,
        trees: [&DopTree; 2],
        turn: f64,
        due: &[DueCertificates; 2],
        ended: &[FrontPair],
        placement: &Placement,
    ) {
        self.leaves.clear();
        for (certificates, due) in self.separated.iter_mut().zip(due) {
            certificates.settle(due);
        }
        self.turn += turn;
        self.add(trees, ended, placement);
    }

    /// Adds where a traversal at `placement` ended.
    pub(super) fn add(&mut self, trees: [&DopTree; 2], ended: &[FrontPair], placement: &Placement) {
        self.scale = self.scale.max(placement.scale);
        let guard = CERTIFICATE_ROUNDING * self.scale;
        let motions = [placement.motion(0), placement.motion(1)];
        for &FrontPair { pair, ending } in ended {
            match ending {
                Ending::Separated {
                    gap,
                    direction,
                    along_b,
                } => {
                    let frame = along_b as usize;
                    let [x, y, z] = direction.map(f64::from);
                    // `gap - guard - direction . centre + radius * turn`, for the moving tree
                    // and for the moving node.
                    let bound = |centre: &Vector3<f64>, radius: f64| {
                        gap - guard - (x * centre.x + y * centre.y + z * centre.z)
                            + radius * self.turn
                    };
                    let expiry = bound(&placement.centres[frame], placement.radii[frame]);
                    let node = if along_b { pair.0 } else { pair.1 };
                    let sphere = &trees[1 - frame].nodes[node as usize].sphere;
                    let (rotation, translation) = &motions[frame];
                    let anchor = bound(
                        &(rotation * sphere.centre() + translation),
                        f64::from(sphere.radius),
                    );
                    self.separated[frame].push((expiry, anchor), direction, sphere, pair);
                }
                Ending::Retest => self.leaves.push(pair),
            }
        }
    }
}
