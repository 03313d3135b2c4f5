//! The convex-hull stage: a separating-plane search between two hulls (PAPER §2.2).
//!
//! Two convex sets do not meet iff a plane has one on each side. The search is the perceptron rule
//! on the paper's set Z = {(p, -1), (-q, 1)}: while some z is on the wrong side, move the plane
//! w ← w + η z. Here the z used are the most violating ones, the extremal vertex of each hull along
//! the plane normal, found by hill-climbing ([`ConvexHull::extremal_vertex`]), so a step costs a
//! short walk on each hull instead of a scan. With the offset kept midway between the two extremal
//! vertices, the update of the normal is n ← n + η (q − p) (in coordinates centred between the
//! hulls and scaled to their size). η is a temperature (simulated annealing): it starts high and
//! cools whenever a step fails to widen the gap, and the search stops when it is cold or after at
//! most 300 loops.
//!
//! The plane found and the extremal vertices are kept per pair ([`SeparatingPlane`]), so the next
//! frame starts from them (temporal coherence): for coherent motion one check of the cached plane
//! settles the pair. The plane is held in A's frame for the climb on A and mapped into B's frame
//! for the climb on B, so no hull vertex is ever transformed wholesale.
//!
//! "Separated" is answered only when proven: the gap between the two hulls' extremal vertices
//! along the normal exceeds both hulls' [`ConvexHull::tolerance`]. Anything else is "not found",
//! which may be wrong: the exact test follows.

use crate::geometry::ConvexHull;
use nalgebra::{Isometry3, Point3, Vector3};

/// Parameters of the perceptron search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneSearch {
    /// At most this many perceptron loops per check (the paper found 300 sufficient).
    pub max_loops: u32,
    /// The temperature η of the first loop.
    pub initial_temperature: f64,
    /// Factor applied to η after every loop that fails to widen the best gap so far: the search
    /// takes big steps while they pay and anneals when it starts to oscillate.
    pub cooling: f64,
    /// The search gives up when η falls below this: the steps are then too small to matter, and
    /// the pair is touching or intersecting (the exact test decides).
    pub min_temperature: f64,
}

impl Default for PlaneSearch {
    fn default() -> Self {
        PlaneSearch {
            max_loops: 300,
            initial_temperature: 1.0,
            cooling: 0.8,
            min_temperature: 1e-3,
        }
    }
}

/// The outcome of one separating-plane check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlaneCheck {
    /// True when a plane was proven to separate the hulls.
    pub separated: bool,
    /// Perceptron loops run (each loop is one hill-climb on each hull).
    pub loops: u32,
}

/// The separating-plane state of one object pair, kept from frame to frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeparatingPlane {
    /// Unit normal in A's frame, pointing from A towards B, of the plane that separated the pair
    /// in the last check; `None` if it did not (or before the first check).
    normal_in_a: Option<Vector3<f64>>,
    /// A's vertex extremal along the normal, where A's next climb starts.
    vertex_a: u32,
    /// B's vertex extremal against the normal, where B's next climb starts.
    vertex_b: u32,
}

impl Default for SeparatingPlane {
    fn default() -> Self {
        Self::new()
    }
}

impl SeparatingPlane {
    /// A pair that has no plane yet: the first check starts from the line between the hulls'
    /// centres.
    pub fn new() -> Self {
        SeparatingPlane {
            normal_in_a: None,
            vertex_a: 0,
            vertex_b: 0,
        }
    }

    /// The plane of the last check that proved separation, as (unit normal, offset) in A's frame
    /// with A on the side where `normal · x < offset`, for the pose `b_to_a`; `None` if the last
    /// check found no plane.
    pub fn plane_in_a(
        &self,
        a: &ConvexHull,
        b: &ConvexHull,
        b_to_a: &Isometry3<f64>,
    ) -> Option<(Vector3<f64>, f64)> {
        let normal = self.normal_in_a?;
        let (_, max_a) = a.extremal_vertex(&normal, self.vertex_a);
        let normal_in_b = b_to_a.rotation.inverse_transform_vector(&normal);
        let (_, max_b) = b.extremal_vertex(&-normal_in_b, self.vertex_b);
        let min_b = -max_b + normal.dot(&b_to_a.translation.vector);
        Some((normal, 0.5 * (max_a + min_b)))
    }

    /// Checks whether hulls `a` and `b` are separated, B being placed in A's frame by `b_to_a`,
    /// starting from the cached plane and updating it.
    pub fn check(
        &mut self,
        a: &ConvexHull,
        b: &ConvexHull,
        b_to_a: &Isometry3<f64>,
        search: &PlaneSearch,
    ) -> PlaneCheck {
        let cached = self.normal_in_a.is_some();
        let first = self.search(a, b, b_to_a, search, search.max_loops);
        if first.separated || !cached {
            return first;
        }
        // The cached plane led nowhere (the pose moved too far for coherence to help): one more
        // search from scratch, within the same loop budget.
        let second = self.search(a, b, b_to_a, search, search.max_loops - first.loops);
        PlaneCheck {
            separated: second.separated,
            loops: first.loops + second.loops,
        }
    }

    /// One perceptron search of at most `max_loops` loops, from the cached plane if there is one,
    /// else from the line between the centres.
    fn search(
        &mut self,
        a: &ConvexHull,
        b: &ConvexHull,
        b_to_a: &Isometry3<f64>,
        search: &PlaneSearch,
        max_loops: u32,
    ) -> PlaneCheck {
        let rotation = &b_to_a.rotation;
        let translation = &b_to_a.translation.vector;
        let centre_b = b_to_a * b.centre();
        // Work in coordinates centred between the hulls and scaled to their size, so that the
        // perceptron's steps mean the same for every pair.
        let scale = 1.0 / (a.radius() + b.radius()).max(f64::MIN_POSITIVE);
        let margin = a.tolerance() + b.tolerance();
        let mut normal = match self.normal_in_a {
            Some(normal) => normal,
            None => {
                let normal = (centre_b - a.centre())
                    .try_normalize(0.0)
                    .unwrap_or_else(Vector3::x);
                self.vertex_a = a.start_vertex(&normal);
                self.vertex_b = b.start_vertex(&-rotation.inverse_transform_vector(&normal));
                normal
            }
        };
        let mut best = Best {
            gap: f64::NEG_INFINITY,
            normal,
            step: Vector3::zeros(),
        };
        let mut temperature = search.initial_temperature;
        let mut loops = 0;
        while loops < max_loops {
            loops += 1;
            let (vertex_a, max_a) = a.extremal_vertex(&normal, self.vertex_a);
            let normal_in_b = rotation.inverse_transform_vector(&normal);
            let (vertex_b, max_b) = b.extremal_vertex(&-normal_in_b, self.vertex_b);
            let min_b = -max_b + normal.dot(translation);
            let gap = min_b - max_a;
            if gap > margin {
                self.normal_in_a = Some(normal);
                self.vertex_a = vertex_a;
                self.vertex_b = vertex_b;
                return PlaneCheck {
                    separated: true,
                    loops,
                };
            }
            // Both extremal vertices violate the plane through the midpoint: the perceptron rule
            // for both, (-p) and (+q), moves the normal along q - p (normalised coordinates).
            let p: &Point3<f64> = &a.vertices()[vertex_a as usize];
            let q = b_to_a * b.vertices()[vertex_b as usize];
            let step = (q - p) * scale;
            let (base, direction) = if gap > best.gap {
                best = Best { gap, normal, step };
                (normal, step)
            } else {
                // The step overshot a ridge where two vertex pairs are extremal: cool, go back to
                // the best plane and step along the shortest convex combination of the two
                // pairs' updates, which widens both their gaps.
                temperature *= search.cooling;
                if temperature < search.min_temperature {
                    break;
                }
                (best.normal, shortest_on_segment(&best.step, &step))
            };
            self.vertex_a = vertex_a;
            self.vertex_b = vertex_b;
            match (base + direction * temperature).try_normalize(0.0) {
                Some(next) => normal = next,
                None => break,
            }
        }
        // Not found: only a plane that separated is worth keeping; the next check starts afresh
        // from the line between the centres.
        self.normal_in_a = None;
        PlaneCheck {
            separated: false,
            loops,
        }
    }
}

/// The widest-gap plane of a search so far, with the perceptron step taken from it.
struct Best {
    gap: f64,
    normal: Vector3<f64>,
    step: Vector3<f64>,
}

/// The point of segment [a, b] closest to the origin.
fn shortest_on_segment(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let ab = b - a;
    let length_squared = ab.norm_squared();
    if length_squared == 0.0 {
        return *a;
    }
    let t = (-a.dot(&ab) / length_squared).clamp(0.0, 1.0);
    a + ab * t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point, TriMesh};
    use nalgebra::{Translation3, UnitQuaternion};
    use parry3d::shape::ConvexPolyhedron;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random convex-ish body: points on an ellipsoid with random half-axes (plus interior
    /// points), as a fan mesh; its hull is what matters.
    fn random_body(rng: &mut ChaCha8Rng, n: usize) -> (ConvexHull, ConvexPolyhedron) {
        let axes = Vector3::new(
            rng.random_range(0.2..1.0),
            rng.random_range(0.2..1.0),
            rng.random_range(0.2..1.0),
        );
        let points: Vec<Point> = (0..n)
            .map(|_| {
                let d = random_unit(rng);
                let depth = if rng.random_bool(0.8) {
                    1.0
                } else {
                    rng.random_range(0.0..1.0)
                };
                Point::from(d.component_mul(&axes) * depth)
            })
            .collect();
        let triangles = (1..n as u32 - 1).map(|i| [0, i, i + 1]).collect();
        let mesh = TriMesh::new(points, triangles).unwrap().0;
        let hull = ConvexHull::of(&mesh);
        let f32_points: Vec<_> = hull
            .vertices()
            .iter()
            .map(|p| nalgebra::convert(*p))
            .collect();
        let polyhedron = ConvexPolyhedron::from_convex_hull(&f32_points).unwrap();
        (hull, polyhedron)
    }

    fn random_unit(rng: &mut ChaCha8Rng) -> Vector3<f64> {
        loop {
            let v = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if let Some(unit) = v.try_normalize(1e-3) {
                return unit;
            }
        }
    }

    fn random_rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
        UnitQuaternion::from_scaled_axis(
            random_unit(rng) * rng.random_range(0.0..std::f64::consts::PI),
        )
    }

    /// parry's GJK: do the polyhedra intersect, and how far apart are they?
    fn parry_truth(
        a: &ConvexPolyhedron,
        b: &ConvexPolyhedron,
        b_to_a: &Isometry3<f64>,
    ) -> (bool, f64) {
        let pose: Isometry3<f32> = nalgebra::convert(*b_to_a);
        let identity = Isometry3::identity();
        let intersects = parry3d::query::intersection_test(&identity, a, &pose, b).unwrap();
        let distance = parry3d::query::distance(&identity, a, &pose, b).unwrap();
        (intersects, f64::from(distance))
    }

    /// Asserts that a "separated" answer is backed by a plane with every vertex of A below and
    /// every vertex of B above it, and that parry finds no intersection.
    fn assert_sound(
        plane: &SeparatingPlane,
        (a, pa): &(ConvexHull, ConvexPolyhedron),
        (b, pb): &(ConvexHull, ConvexPolyhedron),
        b_to_a: &Isometry3<f64>,
    ) {
        let (intersects, distance) = parry_truth(pa, pb, b_to_a);
        assert!(
            !intersects,
            "separated, but parry finds an intersection (distance {distance})"
        );
        let (normal, offset) = plane.plane_in_a(a, b, b_to_a).unwrap();
        assert!(a.vertices().iter().all(|p| normal.dot(&p.coords) < offset));
        assert!(
            b.vertices()
                .iter()
                .all(|q| normal.dot(&(b_to_a * q).coords) > offset)
        );
    }

    #[test]
    fn never_separated_where_gjk_finds_an_intersection_and_found_when_well_apart() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let search = PlaneSearch::default();
        let (mut separated, mut poses) = (0, 0);
        for _ in 0..12 {
            let (na, nb) = (rng.random_range(4..400), rng.random_range(4..400));
            let a = random_body(&mut rng, na);
            let b = random_body(&mut rng, nb);
            let reach = a.0.radius() + b.0.radius();
            for _ in 0..250 {
                // Centre distances from deep overlap to well apart, most near touching.
                let distance = reach * rng.random_range(0.3f64..1.3).powf(0.5);
                let b_to_a = Isometry3::from_parts(
                    Translation3::from(random_unit(&mut rng) * distance),
                    random_rotation(&mut rng),
                );
                let mut plane = SeparatingPlane::new();
                let check = plane.check(&a.0, &b.0, &b_to_a, &search);
                poses += 1;
                if check.separated {
                    separated += 1;
                    assert_sound(&plane, &a, &b, &b_to_a);
                } else {
                    let (intersects, gap) = parry_truth(&a.1, &b.1, &b_to_a);
                    assert!(
                        intersects || gap < 0.02 * reach,
                        "not found at gap {gap} (reach {reach})"
                    );
                }
            }
        }
        assert!(
            separated > poses / 4,
            "only {separated} of {poses} poses separated"
        );
    }

    #[test]
    fn cached_planes_under_coherent_motion_stay_sound_and_need_few_loops() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let search = PlaneSearch::default();
        let a = random_body(&mut rng, 300);
        let b = random_body(&mut rng, 300);
        let reach = a.0.radius() + b.0.radius();
        let mut plane = SeparatingPlane::new();
        let (mut loops, mut frames, mut separated) = (0, 0, 0);
        let axis = random_unit(&mut rng);
        for step in 0..3000 {
            // Orbit B around A at a distance that swings through touching, spinning it too.
            let angle = f64::from(step) * 0.02;
            let distance = reach * (0.95 + 0.3 * (f64::from(step) * 0.003).sin().abs());
            let orbit = UnitQuaternion::from_scaled_axis(axis * angle);
            let b_to_a = Isometry3::from_parts(
                Translation3::from(orbit * (axis.cross(&Vector3::x()).normalize() * distance)),
                UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 1.0, 0.2) * angle),
            );
            let check = plane.check(&a.0, &b.0, &b_to_a, &search);
            if check.separated {
                assert_sound(&plane, &a, &b, &b_to_a);
                separated += 1;
                loops += check.loops;
                frames += 1;
            }
        }
        assert!(separated > 1000, "only {separated} separated frames");
        let mean_loops = f64::from(loops) / f64::from(frames);
        assert!(mean_loops < 3.0, "{mean_loops} loops per separated frame");
    }
}
