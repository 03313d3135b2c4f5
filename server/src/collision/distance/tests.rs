//! The exact triangle distance against hand-computed answers, against a certificate of each
//! answer (its points on the triangles, the triangles separated by it along its line), and
//! against parry (an independent implementation, in `f32`) on random pairs.

use nalgebra::{Point3, Vector3};
use parry3d::query;
use parry3d::shape::Triangle as ParryTriangle;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::triangle_distance;
use crate::collision::triangle::{Triangle, triangles_intersect};

fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
    Point3::new(x, y, z)
}

/// The distance from `point` to the closed triangle: to its plane where the barycentric
/// coordinates of the foot (solved from the normal equations) are all non-negative, else to the
/// nearest edge. Only to check that the answer's points lie on the triangles.
fn gap_to_triangle(point: &Point3<f64>, t: &Triangle) -> f64 {
    let to_segment = |a: &Point3<f64>, b: &Point3<f64>| {
        let ab = b - a;
        let s = if ab.norm_squared() == 0.0 {
            0.0
        } else {
            ((point - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
        };
        (a + ab * s - point).norm()
    };
    let edges = to_segment(&t[0], &t[1])
        .min(to_segment(&t[1], &t[2]))
        .min(to_segment(&t[2], &t[0]));
    let (u, v, w) = (t[1] - t[0], t[2] - t[0], point - t[0]);
    let (uu, uv, vv) = (u.dot(&u), u.dot(&v), v.dot(&v));
    let det = uu * vv - uv * uv;
    if det <= 1e-12 * uu * vv {
        return edges;
    }
    let s = (vv * w.dot(&u) - uv * w.dot(&v)) / det;
    let r = (uu * w.dot(&v) - uv * w.dot(&u)) / det;
    if s >= 0.0 && r >= 0.0 && s + r <= 1.0 {
        edges.min((t[0] + u * s + v * r - point).norm())
    } else {
        edges
    }
}

/// Checks the answer against itself: its points lie on the triangles, as far apart as the
/// distance (so the true distance is no more), and the triangles are no closer than that along
/// the line through the points (so it is no less); a distance of 0 only for triangles that
/// intersect by the exact test.
fn assert_exact(t1: &Triangle, t2: &Triangle) -> f64 {
    let found = triangle_distance(t1, t2);
    let scale = t1
        .iter()
        .chain(t2)
        .map(|c| c.coords.norm())
        .fold(1.0, f64::max);
    let tolerance = 1e-12 * scale;
    assert!(
        ((found.on_first - found.on_second).norm() - found.distance).abs() <= tolerance,
        "{found:?}"
    );
    assert!(
        gap_to_triangle(&found.on_first, t1) <= 1e-9 * scale,
        "{found:?} off {t1:?}"
    );
    assert!(
        gap_to_triangle(&found.on_second, t2) <= 1e-9 * scale,
        "{found:?} off {t2:?}"
    );
    if found.distance == 0.0 {
        assert!(
            triangles_intersect(t1, t2),
            "{t1:?} {t2:?} apart, answered 0"
        );
    } else {
        let direction = (found.on_second - found.on_first) / found.distance;
        let reach = t1
            .iter()
            .map(|c| c.coords.dot(&direction))
            .fold(f64::MIN, f64::max);
        let start = t2
            .iter()
            .map(|c| c.coords.dot(&direction))
            .fold(f64::MAX, f64::min);
        assert!(
            start - reach >= found.distance - 1e-9 * scale,
            "{t1:?} {t2:?}: {found:?} is not the least: the gap along its line is {}",
            start - reach
        );
    }
    found.distance
}

#[test]
fn hand_computed_distances() {
    let base = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
    let cases: [(Triangle, f64); 8] = [
        // Parallel, above the first: face to face.
        ([p(0.1, 0.1, 0.5), p(0.5, 0.1, 0.5), p(0.1, 0.5, 0.5)], 0.5),
        // A corner above the face.
        ([p(0.2, 0.2, 0.3), p(0.2, 0.2, 2.0), p(0.5, 0.4, 2.0)], 0.3),
        // Skew edges: x-axis edge against a segment along y at x = 0.5, z = 2.
        (
            [p(0.5, -1.0, 2.0), p(0.5, -3.0, 2.0), p(0.5, -1.0, 7.0)],
            5.0_f64.sqrt(),
        ),
        // Crossing edges: (0.5, -0.5, 0.25) - (0.5, 0.5, -0.25) passes the x-axis edge.
        (
            [p(0.5, -0.5, 0.25), p(0.5, -0.5, -0.25), p(0.5, 0.5, -0.25)],
            0.0,
        ),
        // Piercing the face through its interior.
        ([p(0.2, 0.2, -1.0), p(0.3, 0.2, 1.0), p(0.2, 0.3, 1.0)], 0.0),
        // Coplanar, apart along x.
        ([p(2.0, 0.0, 0.0), p(3.0, 0.0, 0.0), p(2.0, 1.0, 0.0)], 1.0),
        // A point (degenerate triangle) beyond the hypotenuse.
        (
            [p(1.0, 1.0, 0.0), p(1.0, 1.0, 0.0), p(1.0, 1.0, 0.0)],
            0.5_f64.sqrt(),
        ),
        // A segment (degenerate) above the face, parallel to it.
        (
            [p(0.1, 0.1, 0.25), p(0.3, 0.3, 0.25), p(0.2, 0.2, 0.25)],
            0.25,
        ),
    ];
    for (other, expected) in cases {
        for (t1, t2) in [(&base, &other), (&other, &base)] {
            let d = assert_exact(t1, t2);
            assert!((d - expected).abs() <= 1e-15, "{t2:?}: {d} != {expected}");
        }
    }
}

#[test]
fn touching_and_intersecting_pairs_answer_zero_at_a_shared_point() {
    let base = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
    let others = [
        [p(0.2, 0.2, -1.0), p(0.3, 0.2, 1.0), p(0.2, 0.3, 1.0)],
        [p(0.25, 0.25, 0.0), p(0.25, 0.25, 1.0), p(0.5, 0.25, 1.0)],
        [p(1.0, 0.0, 0.0), p(2.0, 0.0, 0.0), p(2.0, 1.0, 1.0)],
        [p(0.1, 0.1, 0.0), p(0.2, 0.1, 0.0), p(0.1, 0.2, 0.0)],
    ];
    for other in others {
        let found = triangle_distance(&base, &other);
        assert_eq!(found.distance, 0.0, "{other:?}");
        assert!(gap_to_triangle(&found.on_first, &base) <= 1e-9, "{found:?}");
        assert!(
            gap_to_triangle(&found.on_first, &other) <= 1e-9,
            "{found:?}"
        );
    }
}

/// A triangle with corners within `size` of `centre` along each axis; one in eight degenerate.
pub(super) fn random_triangle(rng: &mut ChaCha8Rng, centre: Vector3<f64>, size: f64) -> Triangle {
    let mut corner = || {
        let offset = Vector3::new(
            rng.random_range(-size..size),
            rng.random_range(-size..size),
            rng.random_range(-size..size),
        );
        Point3::from(centre + offset)
    };
    let mut t = [corner(), corner(), corner()];
    // One in eight degenerate: two corners equal, or all three in a line.
    match rng.random_range(0..16) {
        0 => t[1] = t[0],
        1 => t[2] = t[0] + (t[1] - t[0]) * 0.5,
        _ => {}
    }
    t
}

#[test]
fn random_pairs_agree_with_parry_and_are_consistent() {
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    let to_parry = |t: &Triangle| {
        let [a, b, c] = t.map(|x| x.cast::<f32>());
        ParryTriangle::new(a, b, c)
    };
    let identity = nalgebra::Isometry3::identity();
    let mut touching = 0;
    for case in 0..4000 {
        let reach = [0.2, 1.0, 3.0][case % 3];
        let centre = Vector3::new(
            rng.random_range(-reach..reach),
            0.0,
            rng.random_range(-reach..reach),
        );
        let t1 = random_triangle(&mut rng, Vector3::zeros(), 1.0);
        let t2 = random_triangle(&mut rng, centre, 1.0);
        let d = assert_exact(&t1, &t2);
        touching += (d == 0.0) as usize;
        let oracle = query::distance(&identity, &to_parry(&t1), &identity, &to_parry(&t2))
            .expect("triangles are supported");
        // parry's GJK stops within its own tolerance, above the least distance.
        assert!(
            (d - f64::from(oracle)).abs() <= 1e-3 * (1.0 + d),
            "case {case}: {t1:?} {t2:?}: {d} against parry's {oracle}"
        );
    }
    assert!(
        touching > 400 && touching < 3600,
        "{touching} touching pairs"
    );
}
