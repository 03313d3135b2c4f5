//! New directions (the paper's §3.2): the remaining motion projected onto the free space that the
//! contacts leave.
//!
//! Every contact point `p` with normal `n` (pointing away from the obstacle) forbids motions that
//! move `p` against `n`: `n · (d + ω × r) ≥ 0`, with `d` the pivot translation, `ω` the rotation
//! vector and `r = p - pivot`. In the scaled motion space `x = (d, radius * ω)` (metres throughout)
//! that is one linear inequality `a · x ≥ 0` with `a = (n, (r × n) / radius)`; metaphors without
//! rotation use `a = (n, 0)`. The new direction is the point of the cone `{x : a_i · x ≥ 0}`
//! nearest to the desired motion `y`. For translations this is exactly the paper's case split: one
//! contact leaves a plane to slide in, two a crease line, three or more a stop; the same projection
//! handles rotations and any number of contact points.
//!
//! The projection is solved through its dual, a non-negative least-squares problem: `x = y + Σ λ_i
//! a_i` with `λ ≥ 0` minimising `|y + A λ|`, by the Lawson–Hanson active-set method. Contacts are
//! few (merged per cluster before they get here), so this takes microseconds.

use nalgebra::{Matrix6, Vector6};

/// What the free space around the contacts allows, judged from the projection's active contacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum FreeSpace {
    /// No contact restricts the desired motion.
    Unconstrained,
    /// One contact is active: the part slides along a surface (for translations, a plane).
    Surface,
    /// Two or more independent contacts are active and motion remains: for translations, a
    /// crease line.
    Crease,
    /// Nothing of the desired motion survives: the part stops.
    Stop,
}

/// The new direction: the projected motion and the contacts that shaped it.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    /// The projected motion in the scaled space `(d, radius * ω)`.
    pub motion: Vector6<f64>,
    /// Indices of the constraints with a positive multiplier: the contacts the part presses on.
    pub active: Vec<usize>,
    /// The classification of the free space.
    pub free_space: FreeSpace,
}

/// Relative size below which a projected motion counts as no motion, and a multiplier as zero.
const RELATIVE_EPSILON: f64 = 1e-10;

/// Projects `desired` onto the cone `{x : row · x ≥ 0 for every row}` (see the module notes).
///
/// Rows need not be unit length or independent; zero rows are ignored.
pub fn project_onto_free_space(desired: &Vector6<f64>, rows: &[Vector6<f64>]) -> Projection {
    let scale = desired.norm();
    let violates =
        |x: &Vector6<f64>, row: &Vector6<f64>| row.dot(x) < -RELATIVE_EPSILON * scale * row.norm();
    if scale == 0.0 || !rows.iter().any(|row| violates(desired, row)) {
        return Projection {
            motion: *desired,
            active: Vec::new(),
            free_space: if scale == 0.0 {
                FreeSpace::Stop
            } else {
                FreeSpace::Unconstrained
            },
        };
    }

    let mut multipliers = vec![0.0; rows.len()];
    let mut passive: Vec<usize> = Vec::with_capacity(6);
    // Rows that turned out dependent on the passive set; they cannot enter it again.
    let mut excluded = vec![false; rows.len()];
    let mut motion = *desired;
    // Lawson–Hanson terminates in finitely many steps; the bound only guards against rounding.
    for _ in 0..(3 * rows.len() + 6) {
        // The most violated constraint outside the passive set enters it.
        let entering = (0..rows.len())
            .filter(|&j| !passive.contains(&j) && !excluded[j] && violates(&motion, &rows[j]))
            .min_by(|&a, &b| {
                (rows[a].dot(&motion) / rows[a].norm())
                    .total_cmp(&(rows[b].dot(&motion) / rows[b].norm()))
            });
        let Some(entering) = entering else { break };
        passive.push(entering);
        loop {
            let Some(solution) = solve_passive(desired, rows, &passive) else {
                // The entering row depends on the passive ones: drop it for good.
                passive.pop();
                excluded[entering] = true;
                break;
            };
            if solution.iter().take(passive.len()).all(|&z| z > 0.0) {
                for (&j, &z) in passive.iter().zip(solution.iter()) {
                    multipliers[j] = z;
                }
                break;
            }
            // Step from the current multipliers towards the solution until one hits zero.
            let alpha = passive
                .iter()
                .zip(solution.iter())
                .filter(|&(_, &z)| z <= 0.0)
                .map(|(&j, &z)| multipliers[j] / (multipliers[j] - z))
                .fold(1.0_f64, f64::min);
            for (&j, &z) in passive.iter().zip(solution.iter()) {
                multipliers[j] += alpha * (z - multipliers[j]);
            }
            passive.retain(|&j| multipliers[j] > RELATIVE_EPSILON * scale);
            for (j, multiplier) in multipliers.iter_mut().enumerate() {
                if !passive.contains(&j) {
                    *multiplier = 0.0;
                }
            }
            if passive.is_empty() {
                break;
            }
        }
        motion = *desired;
        for &j in &passive {
            motion += rows[j] * multipliers[j];
        }
    }

    let free_space = if motion.norm() <= 1e-9 * scale {
        FreeSpace::Stop
    } else {
        match passive.len() {
            0 => FreeSpace::Unconstrained,
            1 => FreeSpace::Surface,
            _ => FreeSpace::Crease,
        }
    };
    passive.sort_unstable();
    Projection {
        motion,
        active: passive,
        free_space,
    }
}

/// Solves the unconstrained least-squares problem on the passive rows: the multipliers `z` with
/// `(A_P^T A_P) z = -A_P^T y`. None when the passive rows are (numerically) dependent.
///
/// Independent rows in a 6-space are at most six, so the Gram matrix is padded to 6 x 6 with the
/// identity (zero right-hand side) and factorised without allocating.
fn solve_passive(
    desired: &Vector6<f64>,
    rows: &[Vector6<f64>],
    passive: &[usize],
) -> Option<Vector6<f64>> {
    let k = passive.len();
    if k > 6 {
        return None;
    }
    let gram = Matrix6::from_fn(|a, b| match (a < k, b < k) {
        (true, true) => rows[passive[a]].dot(&rows[passive[b]]),
        _ => f64::from(u8::from(a == b)),
    });
    let rhs = Vector6::from_fn(|a, _| {
        if a < k {
            -rows[passive[a]].dot(desired)
        } else {
            0.0
        }
    });
    // A pivot this small relative to the row lengths means the rows are dependent.
    let largest = gram
        .diagonal()
        .iter()
        .take(k)
        .fold(0.0_f64, |m, &d| m.max(d));
    let smallest_allowed = 1e-12 * largest;
    let cholesky = gram.cholesky()?;
    if cholesky
        .l_dirty()
        .diagonal()
        .iter()
        .take(k)
        .any(|&d| d * d <= smallest_allowed)
    {
        return None;
    }
    Some(cholesky.solve(&rhs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use nalgebra::{DMatrix, DVector};
    use proptest::prelude::*;

    fn translation_row(n: [f64; 3]) -> Vector6<f64> {
        let n = Vector3::from(n).normalize();
        Vector6::new(n.x, n.y, n.z, 0.0, 0.0, 0.0)
    }

    fn motion(d: [f64; 3]) -> Vector6<f64> {
        Vector6::new(d[0], d[1], d[2], 0.0, 0.0, 0.0)
    }

    #[test]
    fn one_contact_leaves_a_plane() {
        let p =
            project_onto_free_space(&motion([1.0, 2.0, -3.0]), &[translation_row([0., 0., 1.])]);
        assert_eq!(p.free_space, FreeSpace::Surface);
        assert_eq!(p.active, vec![0]);
        assert!((p.motion - motion([1.0, 2.0, 0.0])).norm() < 1e-12);
    }

    #[test]
    fn two_contacts_leave_a_crease_and_three_stop() {
        let floor = translation_row([0., 0., 1.]);
        let wall = translation_row([1., 0., 0.]);
        let back = translation_row([0., 1., 0.]);
        let desired = motion([-1.0, -2.0, -3.0]);
        let crease = project_onto_free_space(&desired, &[floor, wall]);
        assert_eq!(crease.free_space, FreeSpace::Crease);
        assert!((crease.motion - motion([0.0, -2.0, 0.0])).norm() < 1e-12);
        let corner = project_onto_free_space(&desired, &[floor, wall, back]);
        assert_eq!(corner.free_space, FreeSpace::Stop);
        assert!(corner.motion.norm() < 1e-12);
    }

    #[test]
    fn contacts_the_motion_leaves_stay_inactive() {
        let p = project_onto_free_space(
            &motion([1.0, 0.0, -1.0]),
            &[
                translation_row([0., 0., 1.]),
                translation_row([-1., 0., 0.]),
            ],
        );
        // The wall at x (normal -x) is pressed, the floor is pressed too: crease along y.
        assert_eq!(p.free_space, FreeSpace::Stop);
        let q = project_onto_free_space(
            &motion([-1.0, 0.5, -1.0]),
            &[
                translation_row([0., 0., 1.]),
                translation_row([-1., 0., 0.]),
            ],
        );
        assert_eq!(q.active, vec![0]);
        assert!((q.motion - motion([-1.0, 0.5, 0.0])).norm() < 1e-12);
    }

    #[test]
    fn duplicate_and_zero_rows_are_harmless() {
        let floor = translation_row([0., 0., 1.]);
        let p = project_onto_free_space(
            &motion([1.0, 0.0, -1.0]),
            &[floor, floor, Vector6::zeros(), floor * 2.0],
        );
        assert_eq!(p.free_space, FreeSpace::Surface);
        assert!((p.motion - motion([1.0, 0.0, 0.0])).norm() < 1e-12);
    }

    /// Brute-force oracle: the nearest point of the cone is the best feasible projection onto the
    /// subspace orthogonal to some subset of the rows.
    fn brute_force(desired: &Vector6<f64>, rows: &[Vector6<f64>]) -> Vector6<f64> {
        let mut best: Option<Vector6<f64>> = None;
        for mask in 0u32..(1 << rows.len()) {
            let chosen: Vec<_> = (0..rows.len()).filter(|i| mask & (1 << i) != 0).collect();
            let a = DMatrix::from_fn(6, chosen.len(), |r, c| rows[chosen[c]][r]);
            let y = DVector::from_column_slice(desired.as_slice());
            // Projection onto the orthogonal complement of span(a) via the pseudo-inverse.
            let x = if chosen.is_empty() {
                y.clone()
            } else {
                let pinv = a.clone().pseudo_inverse(1e-12).unwrap();
                &y - &a * (pinv * &y)
            };
            let x = Vector6::from_column_slice(x.as_slice());
            let feasible = rows.iter().all(|r| r.dot(&x) >= -1e-9);
            if feasible && best.is_none_or(|b| (x - desired).norm() < (b - desired).norm()) {
                best = Some(x);
            }
        }
        best.expect("the zero motion is always feasible")
    }

    proptest! {
        #[test]
        fn matches_brute_force_on_random_cones(
            desired in prop::array::uniform6(-1.0f64..1.0),
            rows in prop::collection::vec(prop::array::uniform6(-1.0f64..1.0), 0..7),
        ) {
            let desired = Vector6::from(desired);
            let rows: Vec<Vector6<f64>> = rows.into_iter().map(Vector6::from).collect();
            let ours = project_onto_free_space(&desired, &rows);
            let oracle = brute_force(&desired, &rows);
            prop_assert!((ours.motion - oracle).norm() < 1e-7, "{} vs {}", ours.motion, oracle);
            for row in &rows {
                prop_assert!(row.dot(&ours.motion) >= -1e-9);
            }
        }
    }
}
