//! The exact distance between two closed triangles in `f64`, with the closest point on each.
//!
//! Two disjoint convex sets are closest at a pair of boundary features, and for triangles one of
//! those pairs is always an edge and an edge, or a corner and the interior of the other's face.
//! So the distance is the least of the nine edge-edge distances and the six corner-face ones
//! (a corner whose projection falls outside the face is closer to one of the face's edges, which
//! the edge-edge cases cover). Degenerate triangles (a segment or a point) have no face: their
//! edges alone stand for them. Triangles that intersect are 0 apart, which the features do not
//! show when one pierces the other; the exact intersection test of [`triangles_intersect`]
//! decides those, and the point of contact is where an edge of one crosses the other.

use nalgebra::{Point3, Vector3};

use crate::collision::triangle::{Triangle, triangles_intersect};

/// The distance between two triangles and where it is reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleDistance {
    /// The least distance between the two closed triangles (0 when they touch or intersect).
    pub distance: f64,
    /// The closest point on the first triangle.
    pub on_first: Point3<f64>,
    /// The closest point on the second triangle (the same point as `on_first` when they touch).
    pub on_second: Point3<f64>,
}

/// The exact distance between `t1` and `t2` and their closest points.
pub fn triangle_distance(t1: &Triangle, t2: &Triangle) -> TriangleDistance {
    let (sides_1, sides_2) = (Sides::of(t1), Sides::of(t2));
    let mut best = closest_features(&sides_1, &sides_2);
    if best.distance > 0.0 && triangles_intersect(t1, t2) {
        let at = piercing_point(&sides_1, &sides_2);
        best = TriangleDistance {
            distance: 0.0,
            on_first: at,
            on_second: at,
        };
    }
    best
}

/// The exact distance between `t1` and `t2` when they are known apart (a line separates their
/// projections by a clear margin): the features alone, without the intersection test.
pub fn separated_triangle_distance(t1: &Triangle, t2: &Triangle) -> TriangleDistance {
    closest_features(&Sides::of(t1), &Sides::of(t2))
}

/// The least of the edge-edge and corner-face distances: the distance of the two triangles when
/// they do not intersect.
fn closest_features(sides_1: &Sides, sides_2: &Sides) -> TriangleDistance {
    // The squared distance of the nearest features so far, and their points.
    let mut best = nearest_edge_pair(sides_1, sides_2);
    let (t1, t2) = (sides_1.corners, sides_2.corners);
    for (face, corners, face_first) in [(sides_2.face(), t1, false), (sides_1.face(), t2, true)] {
        let Some(face) = face else { continue };
        for corner in corners {
            if let Some(foot) = face.foot_inside(corner) {
                let squared = (corner - foot).norm_squared();
                if squared < best.0 {
                    best = match face_first {
                        true => (squared, foot, *corner),
                        false => (squared, *corner, foot),
                    };
                }
            }
        }
    }
    TriangleDistance {
        distance: best.0.sqrt(),
        on_first: best.1,
        on_second: best.2,
    }
}

/// The edge pairs of two triangles, edge `i` of the first with edge `j` of the second at
/// `3 i + j`.
const EDGE_PAIRS: usize = 9;

/// One quantity of each of the nine edge pairs.
type PerPair = [f64; EDGE_PAIRS];

/// The nearest of the nine edge pairs: its points' squared distance and the points. The pairs
/// are solved side by side, each quantity an array over them (vector code), as
/// [`closest_parameters`] solves one, so the answers are the same to the bit; the rare pairs
/// that its other branches decide (a degenerate edge, nearly parallel edges) are solved again
/// by it. Ties go to the first pair.
fn nearest_edge_pair(sides_1: &Sides, sides_2: &Sides) -> (f64, Point3<f64>, Point3<f64>) {
    let u = per_pair(|i, _, x| sides_1.edges[i][x]);
    let v = per_pair(|_, j, x| sides_2.edges[j][x]);
    let w = per_pair(|i, j, x| sides_1.corners[i][x] - sides_2.corners[j][x]);
    let a: PerPair = std::array::from_fn(|k| sides_1.squared[k / 3]);
    let c: PerPair = std::array::from_fn(|k| sides_2.squared[k % 3]);
    let dot = |p: &[PerPair; 3], q: &[PerPair; 3]| -> PerPair {
        std::array::from_fn(|k| p[0][k] * q[0][k] + p[1][k] * q[1][k] + p[2][k] * q[2][k])
    };
    let (b, d, e) = (dot(&u, &v), dot(&u, &w), dot(&v, &w));
    let (mut s, mut t) = ([0.0; EDGE_PAIRS], [0.0; EDGE_PAIRS]);
    let mut regular = [true; EDGE_PAIRS];
    for k in 0..EDGE_PAIRS {
        let denominator = a[k] * c[k] - b[k] * b[k];
        let interior = if denominator > 0.0 {
            ((b[k] * e[k] - c[k] * d[k]) / denominator).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let t_interior = (b[k] * interior + e[k]) / c[k];
        let at_low = (-d[k] / a[k]).clamp(0.0, 1.0);
        let at_high = ((b[k] - d[k]) / a[k]).clamp(0.0, 1.0);
        s[k] = if t_interior < 0.0 {
            at_low
        } else if t_interior > 1.0 {
            at_high
        } else {
            interior
        };
        t[k] = t_interior.clamp(0.0, 1.0);
        regular[k] = a[k] != 0.0 && c[k] != 0.0 && denominator > PARALLEL * a[k] * c[k];
    }
    for k in (0..EDGE_PAIRS).filter(|&k| !regular[k]) {
        let at = |x: &[PerPair; 3]| Vector3::new(x[0][k], x[1][k], x[2][k]);
        (s[k], t[k], _) = closest_parameters((&at(&u), a[k]), (&at(&v), c[k]), &at(&w));
    }
    let squared: PerPair = std::array::from_fn(|k| {
        let gap = |x: usize| w[x][k] + u[x][k] * s[k] - v[x][k] * t[k];
        gap(0) * gap(0) + gap(1) * gap(1) + gap(2) * gap(2)
    });
    let nearest = (1..EDGE_PAIRS).fold(
        0,
        |best, k| if squared[k] < squared[best] { k } else { best },
    );
    let (i, j) = (nearest / 3, nearest % 3);
    (
        squared[nearest],
        sides_1.corners[i] + sides_1.edges[i] * s[nearest],
        sides_2.corners[j] + sides_2.edges[j] * t[nearest],
    )
}

/// The three coordinates of a quantity `f(i, j, x)` of each edge pair (`x` the coordinate).
fn per_pair(f: impl Fn(usize, usize, usize) -> f64) -> [PerPair; 3] {
    std::array::from_fn(|x| std::array::from_fn(|k| f(k / 3, k % 3, x)))
}

/// A triangle's edges (corner `i` to corner `i + 1`) and their squared lengths, worked out once
/// for its nine edge pairs and its face.
struct Sides<'t> {
    corners: &'t Triangle,
    edges: [Vector3<f64>; 3],
    squared: [f64; 3],
}

impl<'t> Sides<'t> {
    fn of(corners: &'t Triangle) -> Self {
        let edges: [Vector3<f64>; 3] = std::array::from_fn(|i| corners[(i + 1) % 3] - corners[i]);
        let squared = edges.map(|e| e.norm_squared());
        Sides {
            corners,
            edges,
            squared,
        }
    }

    /// The normal `(b - a) x (c - a)` (`c - a` is the third edge reversed), of length twice the
    /// area; zero for a degenerate triangle.
    fn normal(&self) -> Vector3<f64> {
        self.edges[2].cross(&self.edges[0])
    }

    /// The triangle's face; `None` when it is degenerate (no area, or not finite).
    fn face(&self) -> Option<Face<'_>> {
        let normal = self.normal();
        let area2 = normal.norm_squared();
        (area2 != 0.0 && area2.is_finite()).then_some(Face {
            sides: self,
            normal,
            area2,
        })
    }
}

/// The parameters `(s, t)` of the closest points `p0 + u s` and `q0 + v t` of two segments
/// (either may be a single point), from their directions and squared lengths `(u, a)`, `(v, c)`
/// and `w = p0 - q0`, with the points' squared distance: the minimum of the convex quadratic
/// over the unit square.
fn closest_parameters(
    (u, a): (&Vector3<f64>, f64),
    (v, c): (&Vector3<f64>, f64),
    w: &Vector3<f64>,
) -> (f64, f64, f64) {
    let gap = |s: f64, t: f64| (w + u * s - v * t).norm_squared();
    let with_gap = |(s, t): (f64, f64)| (s, t, gap(s, t));
    let (b, d, e) = (u.dot(v), u.dot(w), v.dot(w));
    if a == 0.0 && c == 0.0 {
        return with_gap((0.0, 0.0));
    }
    if a == 0.0 {
        return with_gap((0.0, (e / c).clamp(0.0, 1.0)));
    }
    if c == 0.0 {
        return with_gap(((-d / a).clamp(0.0, 1.0), 0.0));
    }
    // The unclamped minimiser over s (for the best t), clamped; then t for that s, clamped, and
    // s again for that t: exact for the convex quadratic when the segments are not parallel.
    let denominator = a * c - b * b;
    let mut s = if denominator > 0.0 {
        ((b * e - c * d) / denominator).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + e) / c;
    if t < 0.0 {
        t = 0.0;
        s = (-d / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - d) / a).clamp(0.0, 1.0);
    }
    let interior = with_gap((s, t));
    if denominator > PARALLEL * a * c {
        return interior;
    }
    // Nearly parallel: the division above loses its digits, but the minimum is then on the
    // square's border too (to within the rounding), at one of the four one-sided minimisers.
    [
        (0.0, (e / c).clamp(0.0, 1.0)),
        (1.0, ((b + e) / c).clamp(0.0, 1.0)),
        ((-d / a).clamp(0.0, 1.0), 0.0),
        (((b - d) / a).clamp(0.0, 1.0), 1.0),
    ]
    .into_iter()
    .map(with_gap)
    .fold(
        interior,
        |best, other| if other.2 < best.2 { other } else { best },
    )
}

/// Relative size of `a c - b²` (the sine² of the segments' angle) below which they count as
/// parallel: the interior minimiser's division would lose most of its digits.
const PARALLEL: f64 = 1e-12;

/// A triangle with a face: its normal (not unit) computed once for the feet of several points.
struct Face<'s> {
    sides: &'s Sides<'s>,
    normal: Vector3<f64>,
    /// The normal's squared length: twice the area, squared.
    area2: f64,
}

impl Face<'_> {
    /// The foot of `point` on the face's plane when it falls inside the triangle (closed).
    fn foot_inside(&self, point: &Point3<f64>) -> Option<Point3<f64>> {
        let Sides { corners, edges, .. } = self.sides;
        let normal = &self.normal;
        let foot = point - normal * (normal.dot(&(point - corners[0])) / self.area2);
        let inside = |i: usize| edges[i].cross(&(foot - corners[i])).dot(normal) >= 0.0;
        (inside(0) && inside(1) && inside(2)).then_some(foot)
    }
}

/// A point shared by two intersecting triangles: where an edge of one meets the other (some edge
/// does, unless they are coplanar, when the closest features already touch); of the crossings of
/// the planes, the one nearest to the other triangle, so rounding picks the best candidate.
fn piercing_point(sides_1: &Sides, sides_2: &Sides) -> Point3<f64> {
    let mut best = (f64::INFINITY, sides_1.corners[0]);
    for (edges, other) in [(sides_1, sides_2), (sides_2, sides_1)] {
        let normal = other.normal();
        for i in 0..3 {
            let (p, q) = (edges.corners[i], edges.corners[(i + 1) % 3]);
            let Some(crossing) = plane_crossing(&p, &q, &other.corners[0], &normal) else {
                continue;
            };
            let gap = point_triangle_distance(&crossing, other);
            if gap < best.0 {
                best = (gap, crossing);
            }
        }
    }
    best.1
}

/// Where segment `p q` crosses the plane through `origin` with `normal`, if its ends are on
/// different sides (or on the plane).
fn plane_crossing(
    p: &Point3<f64>,
    q: &Point3<f64>,
    origin: &Point3<f64>,
    normal: &Vector3<f64>,
) -> Option<Point3<f64>> {
    let (sp, sq) = (normal.dot(&(p - origin)), normal.dot(&(q - origin)));
    if (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) {
        return None;
    }
    let span = sp - sq;
    Some(if span == 0.0 {
        *p
    } else {
        p + (q - p) * (sp / span)
    })
}

/// Distance from `point` to the closed triangle of `sides`.
fn point_triangle_distance(point: &Point3<f64>, sides: &Sides) -> f64 {
    if let Some(foot) = sides.face().and_then(|face| face.foot_inside(point)) {
        return (point - foot).norm();
    }
    let still = (&Vector3::zeros(), 0.0);
    (0..3)
        .map(|i| {
            let edge = (&sides.edges[i], sides.squared[i]);
            closest_parameters(still, edge, &(point - sides.corners[i])).2
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::super::tests::random_triangle;
    use super::{Sides, Triangle, closest_parameters, nearest_edge_pair};

    /// The edge pairs solved one at a time, in order, the first nearest kept.
    fn nearest_one_by_one(t1: &Triangle, t2: &Triangle) -> (f64, Point3<f64>, Point3<f64>) {
        let (sides_1, sides_2) = (Sides::of(t1), Sides::of(t2));
        let mut best = (f64::INFINITY, t1[0], t2[0]);
        for ((p0, u), &a) in t1.iter().zip(&sides_1.edges).zip(&sides_1.squared) {
            for ((q0, v), &c) in t2.iter().zip(&sides_2.edges).zip(&sides_2.squared) {
                let (s, t, squared) = closest_parameters((u, a), (v, c), &(p0 - q0));
                if squared < best.0 {
                    best = (squared, p0 + u * s, q0 + v * t);
                }
            }
        }
        best
    }

    /// The side-by-side solver answers exactly as the one-pair solver, on random pairs and on
    /// the cases its other branches decide: degenerate edges and parallel ones.
    #[test]
    fn edge_pairs_side_by_side_answer_as_one_by_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for case in 0..20_000 {
            let t1 = random_triangle(&mut rng, Vector3::zeros(), 1.0);
            let mut t2 = random_triangle(&mut rng, Vector3::zeros(), 1.5);
            let shift = Vector3::new(0.0, 0.0, [0.0, 0.1, 2.0][case % 3]);
            match case % 8 {
                // A copy moved: every edge parallel to its counterpart.
                0 => t2 = t1.map(|p| p + shift + Vector3::new(0.3, 0.0, 0.0)),
                // An edge of no length, or a triangle that is a point.
                1 => t2[1] = t2[0],
                2 => t2 = [t2[0]; 3],
                // Corners in a line.
                3 => t2[2] = t2[0] + (t2[1] - t2[0]) * 0.25,
                _ => {}
            }
            let (side_by_side, one_by_one) = (
                nearest_edge_pair(&Sides::of(&t1), &Sides::of(&t2)),
                nearest_one_by_one(&t1, &t2),
            );
            assert_eq!(side_by_side, one_by_one, "case {case}: {t1:?} {t2:?}");
        }
    }
}
