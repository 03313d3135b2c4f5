//! Pushing: how far a hand's motion into a part it touches without holding it (a push by the
//! analysis) would carry the part.
//!
//! The clasp stops the hand at the part's surface; what the tracked hand wanted beyond it is the
//! push. Each contact of a pushing segment is followed as the hand's root moves from the visible
//! to the target root, and the part must move along the contact's normal as far as that point
//! went into it. Only the root pushes: fingers closing on a part (their glove values far inside
//! it) are a grasp in the making, and taking their motion would shove a part out of every grasp. The displacement satisfying every contact is found by projecting onto one
//! contact's constraint after another (a few sweeps: contacts of a flat palm agree, those of
//! fingers on two faces of a corner combine).

use nalgebra::{Isometry3, Vector3};

use super::collider::PartId;
use super::hand::SegmentContact;

/// A part the hand pushes this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    /// The part.
    pub part: PartId,
    /// How far the hand's motion into the part would carry it, in the world (metres; zero while
    /// the hand rests on it).
    pub displacement: Vector3<f64>,
}

/// Sweeps over the contacts when combining their constraints: two or three faces of a corner
/// agree within a few.
const SWEEPS: usize = 4;

/// The pushes of `parts` (the parts the analysis found pushed) by the hand's root moving from
/// `visible` to `target`, from the segments' contacts at the visible hand (`touching`, per
/// segment).
pub fn pushes(
    visible: &Isometry3<f64>,
    target: &Isometry3<f64>,
    touching: &[Vec<SegmentContact>],
    parts: impl IntoIterator<Item = PartId>,
) -> Vec<Push> {
    let motion: Isometry3<f64> = target * visible.inverse();
    parts
        .into_iter()
        .map(|part| {
            // Per contact: its normal and how far its point went along it.
            let constraints: Vec<(Vector3<f64>, f64)> = (touching.iter())
                .flat_map(|contacts| {
                    (contacts.iter())
                        .filter(move |contact| contact.part == part)
                        .map(move |contact| {
                            let moved = motion * contact.point - contact.point;
                            (contact.normal.into_inner(), moved.dot(&contact.normal))
                        })
                })
                .filter(|(_, depth)| depth.is_finite() && *depth > 0.0)
                .collect();
            Push {
                part,
                displacement: satisfy(&constraints),
            }
        })
        .collect()
}

/// The displacement `d` that carries every constraint's surface at least its depth along its
/// normal (`d · n ≥ depth`), by projecting onto each unmet constraint in turn.
fn satisfy(constraints: &[(Vector3<f64>, f64)]) -> Vector3<f64> {
    let mut displacement = Vector3::zeros();
    for _ in 0..SWEEPS {
        for (normal, depth) in constraints {
            let short = depth - displacement.dot(normal);
            if short > 0.0 {
                displacement += normal * short;
            }
        }
    }
    displacement
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_face_is_pushed_as_deep_as_the_hand_went() {
        let d = satisfy(&[(Vector3::x(), 0.02), (Vector3::x(), 0.015)]);
        assert!((d - Vector3::new(0.02, 0.0, 0.0)).norm() < 1e-12, "{d:?}");
    }

    #[test]
    fn two_faces_of_a_corner_combine() {
        let d = satisfy(&[(Vector3::x(), 0.01), (Vector3::y(), 0.02)]);
        assert!((d - Vector3::new(0.01, 0.02, 0.0)).norm() < 1e-12, "{d:?}");
        assert_eq!(satisfy(&[]), Vector3::zeros());
    }
}
