//! The cheap start of a query: a proof that the two roots are apart along one of A's
//! orientations, from B's bounding sphere or from B's root re-aligned along that orientation
//! alone, kept to be checked first against the motion at the next query.

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};

use super::front::CERTIFICATE_ROUNDING;
use super::realign::{ConeHints, rounding_margin};
use super::tree::DopTree;

/// How two roots were proved apart: B's points lay at least `gap` beyond A's root along A's
/// orientation `slot` (`normal`, A's frame), with B's centre at `centre` and B's rotation
/// `rotation` (both in A's frame).
#[derive(Debug, Clone, Copy)]
pub(super) struct RootSeparation {
    slot: u8,
    normal: Vector3<f64>,
    gap: f64,
    centre: Vector3<f64>,
    rotation: UnitQuaternion<f64>,
}

impl RootSeparation {
    /// Whether the last proof, if any, still holds with B at `b_to_a` (its centre at
    /// `centre_b`): B's points moved along the normal by at least the centre's move less B's
    /// radius times `|R - R0|`, which is `2 sin(θ / 2)` for the angle θ between the rotations, so
    /// its square is `4 (1 - (q . q0)^2)`: compared in squares, without a square root.
    pub(super) fn still_holds(
        proof: &Option<Self>,
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
    ) -> bool {
        let Some(proof) = proof else {
            return false;
        };
        let scale = root_scale(a, b_to_a) + b.bounding_radius;
        let gap = proof.gap + proof.normal.dot(&(centre_b.coords - proof.centre))
            - CERTIFICATE_ROUNDING * scale;
        let cos_half = proof.rotation.coords.dot(&b_to_a.rotation.coords);
        // The small term covers the rounding of 1 - cos² for nearly equal rotations.
        let turn_squared = 4.0 * (1.0 - cos_half * cos_half) + 1e-15;
        gap > 0.0 && gap * gap > b.bounding_radius * b.bounding_radius * turn_squared
    }
}

/// A bound on the coordinates of a root test at `b_to_a`, for its rounding margins: `|t|`
/// (bounded by its 1-norm, which needs no square root) plus A's largest offset.
fn root_scale(a: &DopTree, b_to_a: &Isometry3<f64>) -> f64 {
    b_to_a.translation.vector.abs().sum() + a.max_abs_offset() as f64
}

/// Cheap start of a query, once the bounding spheres overlap and the last proof that the roots
/// are apart (`root_separation`) no longer holds: along that proof's orientation, then along
/// the few orientations of A closest to the direction from A's centre
/// to B's (`centre_b`, in A's frame), B's bounding sphere and then B's root re-aligned along that
/// orientation only (one support cone instead of k) are tested against A's root. Pairs far
/// apart end here; `root_separation` keeps the proof found.
pub(super) fn roots_separated_along_offset(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    centre_b: &Point3<f64>,
    hints: &mut ConeHints,
    root_separation: &mut Option<RootSeparation>,
) -> bool {
    let translation = &b_to_a.translation.vector;
    // The offsets are f32: the same margin as in the traversal covers their rounding.
    let scale = root_scale(a, b_to_a);
    let d = b.node_offsets(0);
    // The gap by which B lies beyond A's root along orientation `slot`, if it does.
    let gap_along = |slot: usize, hint: &mut u8| {
        let a_max = a.node_offsets(0)[slot] as f64;
        let normal = a.set.normal(slot);
        let sphere_gap = normal.dot(&centre_b.coords) - b.bounding_radius - a_max;
        if sphere_gap > 0.0 {
            return Some(sphere_gap);
        }
        let cone = b
            .set
            .support_cone_hinted(&b_to_a.rotation.inverse_transform_vector(&-normal), hint);
        let b_support = (0..3)
            .map(|l| cone.lambda[l] * d[cone.planes[l] as usize] as f64)
            .sum::<f64>()
            - normal.dot(translation);
        let margin =
            rounding_margin(cone.lambda.iter().sum::<f64>() * b.max_abs_offset() as f64 + scale)
                as f64;
        let gap = -(a_max + b_support + margin);
        (gap > 0.0).then_some(gap)
    };
    let last = root_separation.map(|proof| usize::from(proof.slot));
    let mut prove = |slot: usize| {
        let gap = gap_along(slot, &mut hints[slot])?;
        *root_separation = Some(RootSeparation {
            slot: slot as u8,
            normal: a.set.normal(slot),
            gap,
            centre: centre_b.coords,
            rotation: b_to_a.rotation,
        });
        Some(())
    };
    if let Some(last) = last
        && prove(last).is_some()
    {
        return true;
    }
    let offset = centre_b - a.bounding_centre;
    // Slot i compares A's maximum along n_i with B's minimum along n_i: promising when B lies
    // far along n_i.
    let mut probes = [(f64::MIN, 0usize); ROOT_PROBES];
    for i in 0..a.k {
        let score = a.set.normal(i).dot(&offset);
        if score > probes[ROOT_PROBES - 1].0 {
            probes[ROOT_PROBES - 1] = (score, i);
            probes.sort_by(|x, y| y.0.total_cmp(&x.0));
        }
    }
    probes
        .iter()
        .any(|&(_, slot)| Some(slot) != last && prove(slot).is_some())
}

/// Number of orientations tried by [`roots_separated_along_offset`] before a full query.
const ROOT_PROBES: usize = 3;
