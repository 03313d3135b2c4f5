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
    let mut best = closest_features(t1, t2);
    if best.distance > 0.0 && triangles_intersect(t1, t2) {
        let at = piercing_point(t1, t2);
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
    closest_features(t1, t2)
}

/// The least of the edge-edge and corner-face distances: the distance of the two triangles when
/// they do not intersect.
fn closest_features(t1: &Triangle, t2: &Triangle) -> TriangleDistance {
    let mut best = TriangleDistance {
        distance: f64::INFINITY,
        on_first: t1[0],
        on_second: t2[0],
    };
    let mut consider = |p: Point3<f64>, q: Point3<f64>| {
        let d = (p - q).norm_squared();
        if d < best.distance {
            best = TriangleDistance {
                distance: d,
                on_first: p,
                on_second: q,
            };
        }
    };
    for i in 0..3 {
        for j in 0..3 {
            let (p, q) = closest_on_segments(&t1[i], &t1[(i + 1) % 3], &t2[j], &t2[(j + 1) % 3]);
            consider(p, q);
        }
    }
    if let Some(face) = Face::of(t2) {
        for corner in t1 {
            if let Some(q) = face.foot_inside(corner) {
                consider(*corner, q);
            }
        }
    }
    if let Some(face) = Face::of(t1) {
        for corner in t2 {
            if let Some(p) = face.foot_inside(corner) {
                consider(p, *corner);
            }
        }
    }
    best.distance = best.distance.sqrt();
    best
}

/// The closest points of segments `p0 p1` and `q0 q1` (either may be a single point): the
/// minimum of the squared distance over both parameters, clamped to the segments.
fn closest_on_segments(
    p0: &Point3<f64>,
    p1: &Point3<f64>,
    q0: &Point3<f64>,
    q1: &Point3<f64>,
) -> (Point3<f64>, Point3<f64>) {
    let u = p1 - p0;
    let v = q1 - q0;
    let w = p0 - q0;
    let (a, b, c) = (u.dot(&u), u.dot(&v), v.dot(&v));
    let (d, e) = (u.dot(&w), v.dot(&w));
    let at = |s: f64, t: f64| (p0 + u * s, q0 + v * t);
    if a == 0.0 && c == 0.0 {
        return at(0.0, 0.0);
    }
    if a == 0.0 {
        return at(0.0, (e / c).clamp(0.0, 1.0));
    }
    if c == 0.0 {
        return at((-d / a).clamp(0.0, 1.0), 0.0);
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
    let interior = at(s, t);
    if denominator > PARALLEL * a * c {
        return interior;
    }
    // Nearly parallel: the division above loses its digits, but the minimum is then on the
    // square's border too (to within the rounding), at one of the four one-sided minimisers.
    let gap = |pair: &(Point3<f64>, Point3<f64>)| (pair.0 - pair.1).norm_squared();
    [
        at(0.0, (e / c).clamp(0.0, 1.0)),
        at(1.0, ((b + e) / c).clamp(0.0, 1.0)),
        at((-d / a).clamp(0.0, 1.0), 0.0),
        at(((b - d) / a).clamp(0.0, 1.0), 1.0),
    ]
    .into_iter()
    .fold(
        interior,
        |best, pair| if gap(&pair) < gap(&best) { pair } else { best },
    )
}

/// Relative size of `a c - b²` (the sine² of the segments' angle) below which they count as
/// parallel: the interior minimiser's division would lose most of its digits.
const PARALLEL: f64 = 1e-12;

/// The foot of `point` on the plane of `triangle` when it falls inside the triangle (closed);
/// `None` outside or for a degenerate triangle.
fn projection_inside(point: &Point3<f64>, triangle: &Triangle) -> Option<Point3<f64>> {
    Face::of(triangle)?.foot_inside(point)
}

/// A triangle with a face: its normal (not unit) computed once for the feet of several points.
struct Face<'t> {
    corners: &'t Triangle,
    normal: Vector3<f64>,
    /// The normal's squared length: twice the area, squared.
    area2: f64,
}

impl<'t> Face<'t> {
    /// The face of `triangle`; `None` when it is degenerate (no area, or not finite).
    fn of(triangle: &'t Triangle) -> Option<Self> {
        let [a, b, c] = triangle;
        let normal = (b - a).cross(&(c - a));
        let area2 = normal.norm_squared();
        (area2 != 0.0 && area2.is_finite()).then_some(Face {
            corners: triangle,
            normal,
            area2,
        })
    }

    /// The foot of `point` on the face's plane when it falls inside the triangle (closed).
    fn foot_inside(&self, point: &Point3<f64>) -> Option<Point3<f64>> {
        let [a, b, c] = self.corners;
        let normal = &self.normal;
        let foot = point - normal * (normal.dot(&(point - a)) / self.area2);
        let inside = |from: &Point3<f64>, to: &Point3<f64>| {
            (to - from).cross(&(foot - from)).dot(normal) >= 0.0
        };
        (inside(a, b) && inside(b, c) && inside(c, a)).then_some(foot)
    }
}

/// A point shared by two intersecting triangles: where an edge of one meets the other (some edge
/// does, unless they are coplanar, when the closest features already touch); of the crossings of
/// the planes, the one nearest to the other triangle, so rounding picks the best candidate.
fn piercing_point(t1: &Triangle, t2: &Triangle) -> Point3<f64> {
    let mut best = (f64::INFINITY, t1[0]);
    for (edges, other) in [(t1, t2), (t2, t1)] {
        let normal = (other[1] - other[0]).cross(&(other[2] - other[0]));
        for i in 0..3 {
            let (p, q) = (edges[i], edges[(i + 1) % 3]);
            let Some(crossing) = plane_crossing(&p, &q, &other[0], &normal) else {
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

/// Distance from `point` to the closed triangle.
fn point_triangle_distance(point: &Point3<f64>, triangle: &Triangle) -> f64 {
    if let Some(foot) = projection_inside(point, triangle) {
        return (point - foot).norm();
    }
    (0..3)
        .map(|i| {
            let (p, q) = closest_on_segments(point, point, &triangle[i], &triangle[(i + 1) % 3]);
            (p - q).norm()
        })
        .fold(f64::INFINITY, f64::min)
}
