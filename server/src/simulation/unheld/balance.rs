//! Whether a settling part rests balanced on what supports it, and if not, about what it tips.
//!
//! Under gravity along the scene's down direction, a part held by friction on its supporting
//! contacts is balanced when the vertical line through its centre of mass passes through the
//! support polygon: the convex hull of the supporting contact points seen from above. Otherwise
//! gravity's torque about the polygon's point nearest that line tips it, about the axis
//! `up × r`, `r` the horizontal offset from that point to the centre of mass.

use nalgebra::{Point2, Unit, Vector2, Vector3};

use crate::geometry::{Point, TriMesh};

/// A centre of mass within this distance (metres) of the support polygon counts as above it:
/// contact points are found to the sliding tolerance, not exactly.
const BALANCE_MARGIN: f64 = 1e-6;

/// A part's centre of mass in its mesh frame: the centroid of the volume its surface encloses,
/// uniform density assumed, so that a bracket or a tool whose material lies to one side of its
/// bounding box tips as the real one would. A mesh enclosing no volume (a sheet, a degenerate
/// mesh) has its bounding-box centre instead.
pub(super) fn centre_of_mass(mesh: &TriMesh) -> Point {
    let (low, high) = mesh.bounding_box();
    let middle = nalgebra::center(&low, &high);
    // Tetrahedra from the box's centre to each triangle: signed volumes and their centroids.
    let (volume, moment) =
        (mesh.triangles().iter()).fold((0.0, Vector3::zeros()), |(volume, moment), &[a, b, c]| {
            let [a, b, c] = [a, b, c].map(|i| mesh.vertices()[i as usize] - middle);
            let tetrahedron = a.dot(&b.cross(&c)) / 6.0;
            (
                volume + tetrahedron,
                moment + (a + b + c) * (tetrahedron / 4.0),
            )
        });
    let box_volume = (high - low)
        .iter()
        .map(|side| side.max(0.0))
        .product::<f64>();
    let centre = middle + moment / volume;
    if volume.abs() > 1e-9 * box_volume && centre.iter().all(|c| c.is_finite()) {
        centre
    } else {
        middle
    }
}

/// How an unbalanced part tips.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Tip {
    /// The point of the support polygon it turns about.
    pub(super) point: Point,
    /// The axis it turns about (right-handed: a positive turn lowers the centre of mass).
    pub(super) axis: Unit<Vector3<f64>>,
}

/// How a part with its centre of mass at `centre` tips on supporting contact points `supports`
/// under gravity against `up`; `None` when it is balanced on them (or there are none).
pub(super) fn tipping(centre: &Point, supports: &[Point], up: &Unit<Vector3<f64>>) -> Option<Tip> {
    let plane = Plane::across(up);
    let flat: Vec<Point2<f64>> = supports.iter().map(|p| plane.project(p)).collect();
    let hull = convex_hull(&flat);
    let above = plane.project(centre);
    if hull.len() >= 3 && contains(&hull, &flat, &above) {
        return None;
    }
    let edges = (0..hull.len()).map(|i| (hull[i], hull[(i + 1) % hull.len()]));
    let (a, b, t) = (edges.map(|(a, b)| (a, b, closest_on_segment(&flat[a], &flat[b], &above))))
        .min_by(|x, y| {
            let distance = |(a, b, t): &(usize, usize, f64)| {
                (flat[*a] + (flat[*b] - flat[*a]) * *t - above).norm()
            };
            distance(x).total_cmp(&distance(y))
        })?;
    let point = supports[a] + (supports[b] - supports[a]) * t;
    let offset = centre - point;
    let horizontal = offset - up.into_inner() * offset.dot(up);
    if horizontal.norm() <= BALANCE_MARGIN {
        return None;
    }
    Some(Tip {
        point,
        axis: Unit::new_normalize(up.cross(&horizontal)),
    })
}

/// The plane across the up direction, with an orthonormal basis: where points are seen from
/// above.
struct Plane {
    u: Vector3<f64>,
    v: Vector3<f64>,
}

impl Plane {
    fn across(up: &Unit<Vector3<f64>>) -> Plane {
        let seed = if up.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (seed - up.into_inner() * seed.dot(up)).normalize();
        Plane { u, v: up.cross(&u) }
    }

    fn project(&self, p: &Point) -> Point2<f64> {
        Point2::new(p.coords.dot(&self.u), p.coords.dot(&self.v))
    }
}

/// `a × b` in the plane.
fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The indices of `points` on their convex hull, counter-clockwise (Andrew's monotone chain);
/// collinear and coincident points are left out, so a hull of collinear points is its two ends.
fn convex_hull(points: &[Point2<f64>]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    if order.len() < 2 {
        return order;
    }
    order.sort_by(|&i, &j| {
        (points[i].x.total_cmp(&points[j].x)).then(points[i].y.total_cmp(&points[j].y))
    });
    let turns_left = |hull: &[usize], next: usize| {
        let [a, b] = [hull[hull.len() - 2], hull[hull.len() - 1]].map(|i| points[i]);
        cross(&(b - a), &(points[next] - a)) > 0.0
    };
    let mut hull: Vec<usize> = Vec::with_capacity(2 * order.len());
    for pass in [order.clone(), order.into_iter().rev().collect()] {
        let start = hull.len();
        for i in pass {
            while hull.len() >= start + 2 && !turns_left(&hull, i) {
                hull.pop();
            }
            hull.push(i);
        }
        // The last point of each chain starts the next one.
        hull.pop();
    }
    hull.dedup_by(|a, b| (points[*a] - points[*b]).norm() == 0.0);
    if hull.len() == 2 && points[hull[0]] == points[hull[1]] {
        hull.pop();
    }
    hull
}

/// Whether `q` lies inside counter-clockwise `hull` of `points`, or within the margin of it.
fn contains(hull: &[usize], points: &[Point2<f64>], q: &Point2<f64>) -> bool {
    (0..hull.len()).all(|i| {
        let [a, b] = [hull[i], hull[(i + 1) % hull.len()]].map(|k| points[k]);
        let edge = b - a;
        cross(&edge, &(q - a)) >= -BALANCE_MARGIN * edge.norm()
    })
}

/// The parameter in `[0, 1]` of the point of segment `a`–`b` closest to `q`.
fn closest_on_segment(a: &Point2<f64>, b: &Point2<f64>, q: &Point2<f64>) -> f64 {
    let edge = b - a;
    let length = edge.norm_squared();
    if length == 0.0 {
        return 0.0;
    }
    ((q - a).dot(&edge) / length).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;

    fn up() -> Unit<Vector3<f64>> {
        Vector3::z_axis()
    }

    #[test]
    fn a_centre_over_the_supports_balances_and_one_beside_an_edge_tips_towards_its_side() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]]
            .map(|[x, y]| Point::new(x, y, 0.0));
        assert_eq!(tipping(&Point::new(0.3, 0.7, 2.0), &square, &up()), None);
        let tip = tipping(&Point::new(1.5, 0.5, 1.0), &square, &up()).expect("tips");
        assert!(
            (tip.point - Point::new(1.0, 0.5, 0.0)).norm() < 1e-12,
            "{tip:?}"
        );
        // A positive turn about the axis carries the centre down.
        let turned = tip.axis.cross(&(Point::new(1.5, 0.5, 1.0) - tip.point));
        assert!(turned.z < 0.0, "{turned:?}");
    }

    #[test]
    fn an_edge_supports_only_what_is_above_it_and_a_corner_tips_about_itself() {
        let edge = [Point::new(0.0, 0.0, 0.0), Point::new(0.0, 1.0, 0.0)];
        assert_eq!(tipping(&Point::new(0.0, 0.4, 1.0), &edge, &up()), None);
        let tip = tipping(&Point::new(0.2, 0.4, 1.0), &edge, &up()).expect("tips");
        assert!(
            (tip.axis.into_inner() - Vector3::y()).norm() < 1e-12,
            "{tip:?}"
        );
        for corner in [
            &[Point::new(0.0, 0.0, 0.0)][..],
            &[Point::new(0.0, 0.0, 0.0); 3],
        ] {
            let tip = tipping(&Point::new(0.1, 0.1, 1.0), corner, &up()).expect("tips");
            assert_eq!(tip.point, corner[0]);
        }
        assert_eq!(tipping(&Point::new(0.0, 0.0, 1.0), &[], &up()), None);
    }

    #[test]
    fn the_centre_of_mass_is_the_volume_centroid_or_else_the_box_centre() {
        let block = shapes::cuboid(Vector3::new(0.04, 0.02, 0.01), 10);
        let shifted = block
            .map_vertices(|p| p + Vector3::new(0.1, -0.2, 0.3))
            .expect("valid");
        let centre = centre_of_mass(&shifted);
        assert!(
            (centre - Point::new(0.1, -0.2, 0.3)).norm() < 1e-12,
            "{centre:?}"
        );
        // An L of two unit cubes and a third beside one of them: the volume centroid lies
        // towards the heavier side, unlike the box centre.
        let cube = |x: f64, y: f64| {
            (shapes::cuboid(Vector3::repeat(1.0), 1).map_vertices(|p| p + Vector3::new(x, y, 0.0)))
                .expect("valid")
        };
        let parts = [cube(0.5, 0.5), cube(1.5, 0.5), cube(0.5, 1.5)];
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for part in &parts {
            let base = vertices.len() as u32;
            vertices.extend_from_slice(part.vertices());
            triangles.extend(part.triangles().iter().map(|t| t.map(|i| i + base)));
        }
        let (l, _) = TriMesh::new(vertices, triangles).expect("valid");
        let centre = centre_of_mass(&l);
        let expected = Point::new(2.5 / 3.0, 2.5 / 3.0, 0.0);
        assert!((centre - expected).norm() < 1e-12, "{centre:?}");
        let (sheet, _) = TriMesh::new(
            vec![
                Point::new(0.0, 0.0, 0.0),
                Point::new(1.0, 0.0, 0.0),
                Point::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2]],
        )
        .expect("valid");
        assert_eq!(centre_of_mass(&sheet), Point::new(0.5, 0.5, 0.0));
    }
}
