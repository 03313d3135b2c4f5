//! Exact intersection test of two closed triangles in 3-space.
//!
//! Every decision is the sign of an orientation determinant, evaluated exactly by adaptive
//! precision arithmetic (the `robust` crate), so the answer is exact for the `f64` coordinates
//! given: no epsilon, no tolerance.
//!
//! **Touching convention**: triangles are closed sets. Two triangles that share only a point or a
//! segment (a vertex on a face, an edge crossing an edge, a common edge, coplanar triangles that
//! touch at their borders) *intersect*. This is what sliding contact needs: a part resting on
//! another one is in contact. The only inexactness left is upstream: the second triangle's corners
//! are rounded when they are moved into the first one's frame, so poses that are exactly touching
//! in real numbers may come out either way.
//!
//! The method: if one triangle lies strictly on one side of the other's plane they are disjoint.
//! Otherwise each triangle meets the other's plane in a segment on the common line of the two
//! planes; the vertices are relabelled so that one vertex of each triangle is alone on its side,
//! and two orientation signs then decide whether the two segments overlap. Coplanar triangles
//! are projected to the coordinate plane where they are largest and tested in 2-D.

use nalgebra::Point3;
use robust::{Coord, Coord3D};

/// A triangle as its three corners.
pub type Triangle = [Point3<f64>; 3];

/// Exact sign of `((b - a) x (c - a)) . (d - a)`: positive when `d` lies on the side of the plane
/// through `a`, `b`, `c` that the normal `(b - a) x (c - a)` points to.
fn orient3d(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>, d: &Point3<f64>) -> i8 {
    let coord = |p: &Point3<f64>| Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    // `robust::orient3d` is positive when `d` is *below* the counter-clockwise plane: the opposite.
    sign(-robust::orient3d(coord(a), coord(b), coord(c), coord(d)))
}

/// Exact sides of the corners of `points` with respect to the plane of `plane`: for each corner
/// `v`, the sign of `orient3d(plane[0], plane[1], plane[2], v)`.
///
/// A floating-point filter shares the plane's cross product between the three corners and
/// decides whenever the determinant exceeds its rounding-error bound (Shewchuk's bound for this
/// triple product, with margin); only near-zero cases go to the exact predicate.
#[inline]
fn plane_sides(plane: &Triangle, points: &Triangle) -> [i8; 3] {
    let [p, q, r] = plane;
    let (a, b) = (q - p, r - p);
    let n = a.cross(&b);
    // |a_y b_z| + |a_z b_y| etc.: the permanent of the cross product.
    let m = nalgebra::Vector3::new(
        (a.y * b.z).abs() + (a.z * b.y).abs(),
        (a.z * b.x).abs() + (a.x * b.z).abs(),
        (a.x * b.y).abs() + (a.y * b.x).abs(),
    );
    points.map(|v| {
        let w = v - p;
        let det = n.dot(&w);
        let bound = 1e-15 * m.dot(&w.abs());
        if det > bound {
            1
        } else if det < -bound {
            -1
        } else {
            orient3d(p, q, r, &v)
        }
    })
}

/// Exact sign of the 2-D orientation of `(a, b, c)`: positive when counter-clockwise.
fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let coord = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    sign(robust::orient2d(coord(a), coord(b), coord(c)))
}

fn sign(value: f64) -> i8 {
    (value > 0.0) as i8 - (value < 0.0) as i8
}

/// True when the closed triangles `t1` and `t2` share at least one point (see the module's
/// touching convention).
pub fn triangles_intersect(t1: &Triangle, t2: &Triangle) -> bool {
    // Sides of t1's corners with respect to t2's plane, and of t2's with respect to t1's.
    let side1 = plane_sides(t2, t1);
    if strictly_one_side(side1) {
        return false;
    }
    let mut side2 = plane_sides(t1, t2);
    if strictly_one_side(side2) {
        return false;
    }
    if side1 == [0; 3] || side2 == [0; 3] {
        // In one plane, or one triangle is degenerate (it puts every point on its "plane").
        return match (collinear(t1), collinear(t2)) {
            (false, false) => coplanar_intersect(t1, t2),
            (true, false) => edges_meet_triangle(t1, t2),
            (false, true) => edges_meet_triangle(t2, t1),
            (true, true) => (0..3).any(|i| (0..3).any(|j| segments_meet(edge(t1, i), edge(t2, j)))),
        };
    }
    let mut a = *t1;
    let mut b = *t2;
    // Rotate t1 so that its first corner is alone on its side of t2's plane; flipping t2's
    // orientation (swapping its last two corners) negates those sides.
    let (shift1, flip2) = arrangement(side1);
    a = rotated(a, shift1);
    if flip2 {
        b.swap(1, 2);
        side2.swap(1, 2);
    }
    // The same for t2 with respect to t1's plane. Swapping t1's last two corners keeps t1's
    // arrangement, whose last two corners are on the same side.
    let (shift2, flip1) = arrangement(side2);
    b = rotated(b, shift2);
    if flip1 {
        a.swap(1, 2);
    }
    // Now a[0] is on the non-negative side of b's plane and a[1], a[2] on the non-positive one,
    // and likewise for b. The segments a ∩ plane(b) and b ∩ plane(a) lie on the planes' common
    // line; they overlap exactly when these two orientations have the signs below.
    orient3d(&a[0], &a[1], &b[0], &b[1]) <= 0 && orient3d(&a[0], &a[2], &b[0], &b[2]) >= 0
}

/// Edge `i` of `t`: from corner `i` to the next.
fn edge(t: &Triangle, i: usize) -> [&Point3<f64>; 2] {
    [&t[i], &t[(i + 1) % 3]]
}

/// Exactly whether the corners of `t` lie on one line (or coincide): its cross product vanishes
/// exactly when all three of its projections on the coordinate planes are degenerate.
fn collinear(t: &Triangle) -> bool {
    (0..3).all(|drop| {
        let project = |p: &Point3<f64>| [p[(drop + 1) % 3], p[(drop + 2) % 3]];
        orient2d(project(&t[0]), project(&t[1]), project(&t[2])) == 0
    })
}

/// Whether some edge of the degenerate triangle `degenerate` meets the proper triangle `t`.
fn edges_meet_triangle(degenerate: &Triangle, t: &Triangle) -> bool {
    (0..3).any(|i| {
        let [p, q] = edge(degenerate, i);
        let (sp, sq) = (
            orient3d(&t[0], &t[1], &t[2], p),
            orient3d(&t[0], &t[1], &t[2], q),
        );
        if sp * sq > 0 {
            return false;
        }
        if sp == 0 && sq == 0 {
            return coplanar_intersect(&[*p, *q, *q], t);
        }
        // The segment crosses the plane at one point, inside the closed triangle exactly when
        // the segment turns the same way (or not at all) around each of its edges.
        let turns = [0, 1, 2].map(|j| orient3d(p, q, &t[j], &t[(j + 1) % 3]));
        turns.iter().all(|&o| o >= 0) || turns.iter().all(|&o| o <= 0)
    })
}

/// Whether two segments of 3-space share a point: they must lie in one plane, and then their
/// projections meet on every coordinate plane (at least one of which maps that plane one to one).
fn segments_meet([p, q]: [&Point3<f64>; 2], [r, s]: [&Point3<f64>; 2]) -> bool {
    orient3d(p, q, r, s) == 0
        && (0..3).all(|drop| {
            let project = |x: &Point3<f64>| [x[(drop + 1) % 3], x[(drop + 2) % 3]];
            segments_intersect(project(p), project(q), project(r), project(s))
        })
}

/// `corners` rotated left by `shift` (< 3): written out, since the slice method is a call to a
/// general routine, costly on this hot path.
fn rotated<T: Copy>(corners: [T; 3], shift: usize) -> [T; 3] {
    [
        corners[shift],
        corners[(shift + 1) % 3],
        corners[(shift + 2) % 3],
    ]
}

/// True when all three sides are strictly positive or all strictly negative.
fn strictly_one_side(side: [i8; 3]) -> bool {
    side.iter().all(|&s| s > 0) || side.iter().all(|&s| s < 0)
}

/// For sides that are neither all zero nor all of one strict sign: the left rotation and whether
/// to negate them so that the first corner is on the non-negative side and the other two on the
/// non-positive side, with either the first corner strictly positive or the other two strictly
/// negative (then the plane does not contain an edge through the first corner).
fn arrangement(side: [i8; 3]) -> (usize, bool) {
    for flip in [false, true] {
        for shift in 0..3 {
            let s = |i: usize| {
                let v = side[(shift + i) % 3];
                if flip { -v } else { v }
            };
            let (p, q, r) = (s(0), s(1), s(2));
            if p >= 0 && q <= 0 && r <= 0 && (p > 0 || (q < 0 && r < 0)) {
                return (shift, flip);
            }
        }
    }
    unreachable!("sides {side:?} are all zero or all of one strict sign")
}

/// Intersection of two triangles known to lie in one plane, tested in 2-D after dropping the
/// coordinate along which the plane's normal is largest (the projection keeps every orientation
/// sign, up to one common sign, exactly).
fn coplanar_intersect(t1: &Triangle, t2: &Triangle) -> bool {
    let normal = |t: &Triangle| (t[1] - t[0]).cross(&(t[2] - t[0]));
    let (n1, n2) = (normal(t1), normal(t2));
    let n = if n1.norm_squared() >= n2.norm_squared() {
        n1
    } else {
        n2
    };
    let drop = n.iamax();
    let (u, v) = ((drop + 1) % 3, (drop + 2) % 3);
    let project = |t: &Triangle| t.map(|p| [p[u], p[v]]);
    let (a, b) = (project(t1), project(t2));
    for i in 0..3 {
        for j in 0..3 {
            if segments_intersect(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]) {
                return true;
            }
        }
    }
    // No edges cross: either one triangle contains the other or they are disjoint.
    point_in_triangle(a[0], &b) || point_in_triangle(b[0], &a)
}

/// True when the closed 2-D segments `[a, b]` and `[c, d]` share a point.
fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient2d(a, b, c), orient2d(a, b, d));
    let (o3, o4) = (orient2d(c, d, a), orient2d(c, d, b));
    if o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0 {
        // Collinear (all four signs vanish: a segment reduced to a point is collinear with
        // another only when it lies on its line): compare the intervals on the coordinate along
        // which the line extends.
        let (from, to) = if a != b { (a, b) } else { (c, d) };
        let axis = if (to[0] - from[0]).abs() >= (to[1] - from[1]).abs() {
            0
        } else {
            1
        };
        let (lo1, hi1) = (a[axis].min(b[axis]), a[axis].max(b[axis]));
        let (lo2, hi2) = (c[axis].min(d[axis]), c[axis].max(d[axis]));
        return lo1 <= hi2 && lo2 <= hi1;
    }
    o1 * o2 <= 0 && o3 * o4 <= 0
}

/// True when `p` lies in the closed 2-D triangle `t`, which must not be degenerate.
fn point_in_triangle(p: [f64; 2], t: &[[f64; 2]; 3]) -> bool {
    let turn = orient2d(t[0], t[1], t[2]);
    if turn == 0 {
        // A degenerate triangle is the union of its edges, already tested against.
        return false;
    }
    (0..3).all(|i| orient2d(t[i], t[(i + 1) % 3], p) * turn >= 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    #[test]
    fn orientation_sign_convention() {
        let (a, b, c) = (p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.));
        assert_eq!(orient3d(&a, &b, &c, &p(0.2, 0.2, 1.0)), 1);
        assert_eq!(orient3d(&a, &b, &c, &p(0.2, 0.2, -1.0)), -1);
        assert_eq!(orient3d(&a, &b, &c, &p(5.0, -3.0, 0.0)), 0);
    }

    #[test]
    fn touching_cases_follow_the_convention() {
        let base = [p(0., 0., 0.), p(2., 0., 0.), p(0., 2., 0.)];
        // A vertex resting on the face.
        assert!(triangles_intersect(
            &base,
            &[p(0.5, 0.5, 0.), p(1., 1., 1.), p(0., 1., 1.)]
        ));
        // The same, lifted by a tiny gap.
        assert!(!triangles_intersect(
            &base,
            &[p(0.5, 0.5, 1e-300), p(1., 1., 1.), p(0., 1., 1.)]
        ));
        // A shared edge, the other triangle folded up.
        assert!(triangles_intersect(
            &base,
            &[p(0., 0., 0.), p(2., 0., 0.), p(1., 0., 3.)]
        ));
        // Coplanar, touching at one corner only.
        assert!(triangles_intersect(
            &base,
            &[p(2., 0., 0.), p(3., 0., 0.), p(3., 1., 0.)]
        ));
        // Coplanar, contained.
        assert!(triangles_intersect(
            &base,
            &[p(0.1, 0.1, 0.), p(0.5, 0.1, 0.), p(0.1, 0.5, 0.)]
        ));
        // Coplanar, disjoint.
        assert!(!triangles_intersect(
            &base,
            &[p(2., 2., 0.), p(3., 2., 0.), p(3., 3., 0.)]
        ));
        // Edge crossing edge at a single point, otherwise apart.
        assert!(triangles_intersect(
            &base,
            &[p(1., -1., 0.), p(1., 1., 0.), p(1., 0., 2.)]
        ));
        // Piercing through the interior.
        assert!(triangles_intersect(
            &base,
            &[p(0.5, 0.5, -1.), p(0.5, 0.5, 1.), p(3., 3., 0.5)]
        ));
    }

    /// Exact integer reference: closed triangles intersect iff an edge of one meets the other
    /// (or, when coplanar, a corner of one lies in the other).
    mod reference {
        type P = [i64; 3];

        fn sub(a: P, b: P) -> P {
            [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
        }
        fn orient(a: P, b: P, c: P, d: P) -> i64 {
            let (u, v, w) = (sub(b, a), sub(c, a), sub(d, a));
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            (cross[0] * w[0] + cross[1] * w[1] + cross[2] * w[2]).signum()
        }
        /// Orientation of three points of the plane (a, b, c) seen along that plane's normal.
        fn orient_in_plane(n: P, a: P, b: P, c: P) -> i64 {
            let (u, v) = (sub(b, a), sub(c, a));
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            (cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2]).signum()
        }
        fn normal(t: [P; 3]) -> P {
            let (u, v) = (sub(t[1], t[0]), sub(t[2], t[0]));
            [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ]
        }
        fn dot(a: P, b: P) -> i64 {
            a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
        }
        /// Closed segments [a, b] and [c, d], all four in a plane with normal n.
        fn coplanar_segments(n: P, a: P, b: P, c: P, d: P) -> bool {
            let (o1, o2) = (orient_in_plane(n, a, b, c), orient_in_plane(n, a, b, d));
            let (o3, o4) = (orient_in_plane(n, c, d, a), orient_in_plane(n, c, d, b));
            if o1 == 0 && o2 == 0 {
                let dir = sub(b, a);
                let (ta, tb) = (0, dot(dir, dir));
                let (tc, td) = (dot(dir, sub(c, a)), dot(dir, sub(d, a)));
                return tc.min(td) <= tb && ta <= tc.max(td);
            }
            o1 * o2 <= 0 && o3 * o4 <= 0
        }
        fn in_triangle(n: P, t: [P; 3], x: P) -> bool {
            (0..3).all(|i| orient_in_plane(n, t[i], t[(i + 1) % 3], x) >= 0)
        }
        /// Closed segment [d, e] against closed triangle t (non-degenerate).
        fn segment_triangle(d: P, e: P, t: [P; 3]) -> bool {
            let (sd, se) = (orient(t[0], t[1], t[2], d), orient(t[0], t[1], t[2], e));
            if sd * se > 0 {
                return false;
            }
            let n = normal(t);
            if sd == 0 && se == 0 {
                return (0..3).any(|i| coplanar_segments(n, d, e, t[i], t[(i + 1) % 3]))
                    || in_triangle(n, t, d);
            }
            // The line pierces the plane inside the segment: inside the triangle iff it passes
            // on the same side of (or through) every edge.
            let s: Vec<i64> = (0..3).map(|i| orient(d, e, t[i], t[(i + 1) % 3])).collect();
            s.iter().all(|&v| v >= 0) || s.iter().all(|&v| v <= 0)
        }
        pub fn intersect(t1: [P; 3], t2: [P; 3]) -> bool {
            (0..3).any(|i| segment_triangle(t1[i], t1[(i + 1) % 3], t2))
                || (0..3).any(|i| segment_triangle(t2[i], t2[(i + 1) % 3], t1))
        }
        pub fn degenerate(t: [P; 3]) -> bool {
            normal(t) == [0, 0, 0]
        }
    }

    #[test]
    fn agrees_with_exact_integer_reference_on_many_degenerate_configurations() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut hits = 0;
        let mut coplanar = 0;
        for _ in 0..200_000 {
            // A third of the samples are flat, so that the coplanar branch is well exercised.
            let flat = rng.random_bool(0.3);
            let mut corner = || {
                let mut c = [0; 3].map(|_: i64| rng.random_range(-3..=3i64));
                if flat {
                    c[2] = 0;
                }
                c
            };
            let t1 = [corner(), corner(), corner()];
            let t2 = [corner(), corner(), corner()];
            if reference::degenerate(t1) || reference::degenerate(t2) {
                continue;
            }
            let to_f = |t: [[i64; 3]; 3]| t.map(|c| p(c[0] as f64, c[1] as f64, c[2] as f64));
            let expected = reference::intersect(t1, t2);
            let got = triangles_intersect(&to_f(t1), &to_f(t2));
            assert_eq!(got, expected, "t1 {t1:?} t2 {t2:?}");
            assert_eq!(
                triangles_intersect(&to_f(t2), &to_f(t1)),
                expected,
                "swapped"
            );
            hits += expected as u32;
            let n = (to_f(t1)[1] - to_f(t1)[0]).cross(&(to_f(t1)[2] - to_f(t1)[0]));
            coplanar += to_f(t2).iter().all(|q| (q - to_f(t1)[0]).dot(&n) == 0.0) as u32;
        }
        // The sample must exercise both answers and the coplanar branch.
        assert!(
            hits > 10_000 && coplanar > 500,
            "{hits} hits, {coplanar} coplanar"
        );
    }

    #[test]
    fn agrees_with_parry_on_random_generic_triangles() {
        use parry3d::math::Isometry;
        use parry3d::query::intersection_test;
        use parry3d::shape::Triangle as ParryTriangle;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut checked = 0;
        for _ in 0..20_000 {
            let mut corner = || p(rng.random(), rng.random(), rng.random());
            let t1 = [corner(), corner(), corner()];
            let t2 = [corner(), corner(), corner()];
            let to_parry = |t: &Triangle| {
                let f =
                    |q: &Point3<f64>| parry3d::math::Point::new(q.x as f32, q.y as f32, q.z as f32);
                ParryTriangle::new(f(&t[0]), f(&t[1]), f(&t[2]))
            };
            let id = Isometry::identity();
            let expected = intersection_test(&id, &to_parry(&t1), &id, &to_parry(&t2)).unwrap();
            // Random triangles almost never touch; skip the rare near-touching pairs where parry's
            // f32 tolerance may decide differently.
            let moved = |t: &Triangle, dz: f64| t.map(|q| p(q.x, q.y, q.z + dz));
            let robust_answer = triangles_intersect(&t1, &moved(&t2, 1e-4))
                == triangles_intersect(&t1, &moved(&t2, -1e-4));
            if robust_answer {
                assert_eq!(triangles_intersect(&t1, &t2), expected, "{t1:?} {t2:?}");
                checked += 1;
            }
        }
        assert!(checked > 19_000, "{checked}");
    }
}
