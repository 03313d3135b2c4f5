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
    let (sides_1, sides_2) = (Sides::of(t1), Sides::of(t2));
    // The squared distance of the nearest features so far, and their points.
    let mut best = (f64::INFINITY, t1[0], t2[0]);
    for ((p0, u), &a) in t1.iter().zip(&sides_1.edges).zip(&sides_1.squared) {
        for ((q0, v), &c) in t2.iter().zip(&sides_2.edges).zip(&sides_2.squared) {
            let (s, t, squared) = closest_parameters((u, a), (v, c), &(p0 - q0));
            if squared < best.0 {
                best = (squared, p0 + u * s, q0 + v * t);
            }
        }
    }
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

    /// The triangle's face; `None` when it is degenerate (no area, or not finite).
    fn face(&self) -> Option<Face<'_>> {
        // (b - a) x (c - a), with c - a the third edge reversed.
        let normal = self.edges[2].cross(&self.edges[0]);
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
    let sides = Sides::of(triangle);
    if let Some(foot) = sides.face().and_then(|face| face.foot_inside(point)) {
        return (point - foot).norm();
    }
    let still = (&Vector3::zeros(), 0.0);
    (0..3)
        .map(|i| {
            let edge = (&sides.edges[i], sides.squared[i]);
            closest_parameters(still, edge, &(point - triangle[i])).2
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}
