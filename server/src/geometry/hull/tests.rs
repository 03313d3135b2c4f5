use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn mesh_of(points: Vec<Point>, triangles: Vec<[u32; 3]>) -> TriMesh {
    TriMesh::new(points, triangles).unwrap().0
}

/// A random point cloud turned into a mesh by a fan of triangles (the hull ignores topology).
fn random_cloud(rng: &mut ChaCha8Rng, n: usize, flat: bool) -> TriMesh {
    let points: Vec<Point> = (0..n)
        .map(|_| {
            let z = if flat {
                0.0
            } else {
                rng.random_range(-1.0..1.0)
            };
            Point::new(rng.random_range(-1.0..1.0), rng.random_range(-2.0..2.0), z)
        })
        .collect();
    let triangles = (1..n as u32 - 1).map(|i| [0, i, i + 1]).collect();
    mesh_of(points, triangles)
}

fn random_direction(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize()
}

/// The hull's support (hill-climbed from a random vertex, widened by the tolerance) bounds the
/// support of every mesh vertex, in many random directions.
fn assert_encloses(hull: &ConvexHull, mesh: &TriMesh, rng: &mut ChaCha8Rng) {
    for _ in 0..500 {
        let d = random_direction(rng);
        let start = rng.random_range(0..hull.vertices().len() as u32);
        let (_, climbed) = hull.extremal_vertex(&d, start);
        let mesh_max = mesh
            .vertices()
            .iter()
            .map(|v| v.coords.dot(&d))
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            climbed + hull.tolerance() >= mesh_max,
            "climbed {climbed} + {} < mesh support {mesh_max}",
            hull.tolerance()
        );
        let (_, brute) = hull.brute_force_extremal(&d);
        assert!(
            climbed >= brute - hull.tolerance(),
            "local maximum {climbed} < {brute}"
        );
    }
}

#[test]
fn hull_of_random_clouds_encloses_them_and_climbs_to_the_maximum() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for n in [4, 10, 100, 2000] {
        let mesh = random_cloud(&mut rng, n, false);
        let hull = ConvexHull::of(&mesh);
        assert_eq!(hull.source(), HullSource::ConvexHull);
        assert!(hull.vertices().len() <= n);
        for v in hull.vertices() {
            assert!(
                mesh.vertices().contains(v),
                "hull vertex {v} is not a mesh vertex"
            );
        }
        assert_encloses(&hull, &mesh, &mut rng);
    }
}

#[test]
fn flat_meshes_get_a_flat_hull_that_still_encloses_them() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mesh = random_cloud(&mut rng, 500, true);
    let hull = ConvexHull::of(&mesh);
    assert!(hull.vertices().iter().all(|v| v.z == 0.0));
    assert_encloses(&hull, &mesh, &mut rng);
}

#[test]
fn cube_hull_has_its_corners_and_edge_neighbours() {
    let corners: Vec<Point> = (0..8)
        .map(|c| Point::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64))
        .collect();
    // Two triangles per face of the unit cube.
    let triangles = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 5, 7],
        [4, 7, 6],
        [0, 1, 5],
        [0, 5, 4],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 3, 7],
        [1, 7, 5],
    ];
    let hull = ConvexHull::of(&mesh_of(corners, triangles));
    assert_eq!(hull.vertices().len(), 8);
    for v in 0..8u32 {
        let n = hull.neighbours(v);
        // Three cube edges, plus at most the face diagonals of the hull's triangulation.
        assert!(
            (3..=6).contains(&n.len()),
            "vertex {v} has {} neighbours",
            n.len()
        );
    }
    assert!(hull.tolerance() < 1e-5);
    let (v, value) = hull.extremal_vertex(
        &Vector3::new(1.0, 1.0, 1.0),
        hull.start_vertex(&-Vector3::new(1.0, 1.0, 1.0)),
    );
    assert_eq!(hull.vertices()[v as usize], Point::new(1.0, 1.0, 1.0));
    assert_eq!(value, 3.0);
}

#[test]
fn interior_points_left_out_of_the_hull_need_no_tolerance_but_near_face_ones_do() {
    // A tetrahedron with one point deep inside and one just outside a face (closer than
    // parry's epsilon, so it is dropped from the hull).
    let points = vec![
        Point::new(0.0, 0.0, 0.0),
        Point::new(1.0, 0.0, 0.0),
        Point::new(0.0, 1.0, 0.0),
        Point::new(0.0, 0.0, 1.0),
        Point::new(0.1, 0.1, 0.1),
        Point::new(0.3, 0.3, -1e-7),
    ];
    let triangles = vec![
        [0, 1, 2],
        [0, 1, 3],
        [0, 2, 3],
        [1, 2, 3],
        [4, 0, 1],
        [5, 1, 2],
    ];
    let hull = ConvexHull::of(&mesh_of(points, triangles));
    assert_eq!(hull.vertices().len(), 4);
    assert!(hull.tolerance() >= 1e-7, "tolerance {}", hull.tolerance());
    assert!(hull.tolerance() < 1e-5, "tolerance {}", hull.tolerance());
}

#[test]
fn hulls_of_procedural_shapes_and_real_meshes_enclose_them() {
    use crate::geometry::shapes::{self, ShapeKind};
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for kind in &ShapeKind::ALL {
        for triangles in [100, 3000] {
            let mesh = shapes::build(*kind, triangles);
            let hull = ConvexHull::of(&mesh);
            assert_eq!(hull.source(), HullSource::ConvexHull, "{kind}");
            assert!(
                hull.tolerance() < 1e-4 * hull.radius(),
                "{kind}: {}",
                hull.tolerance()
            );
            assert_encloses(&hull, &mesh, &mut rng);
        }
    }
    let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/meshes");
    for name in [
        "fcl_env",
        "fcl_rob",
        "low_poly_bunny",
        "ur5e_wrist3",
        "ur5e_base",
    ] {
        let path = std::path::Path::new(meshes).join(format!("{name}.obj"));
        let mesh = crate::geometry::load_mesh(&path).unwrap();
        let hull = ConvexHull::of(&mesh);
        assert_eq!(hull.source(), HullSource::ConvexHull, "{name}");
        assert_encloses(&hull, &mesh, &mut rng);
    }
}

/// The face climb's tolerance is at least how far any point lies beyond a face plane (a lower
/// bound of its distance to the hull) and near the exhaustive scan's (the oracle's), on
/// random clouds and on procedural shapes.
#[test]
fn the_face_climb_tolerance_is_at_least_the_exhaustive_one_and_close_to_it() {
    use crate::geometry::shapes::{self, ShapeKind};
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut meshes: Vec<TriMesh> = [10, 300, 5000]
        .into_iter()
        .map(|n| random_cloud(&mut rng, n, false))
        .collect();
    for kind in &ShapeKind::ALL {
        meshes.push(shapes::build(*kind, 20_000));
    }
    let mut climbed_some = false;
    for mesh in &meshes {
        let points = referenced_vertices(mesh);
        let (lo, hi) = bounds(&points);
        let centre = nalgebra::center(&lo, &hi);
        let (vertices, faces) = parry_hull(&points, &CubeFrame::new(lo, hi)).unwrap();
        let centroid = centroid_of(&vertices);
        let planes = face_planes(&vertices, &faces, centroid);
        climbed_some |= FaceClimb::new(&planes, &faces, centroid, &vertices).is_some();
        let climbed = containment_tolerance(&points, &vertices, &faces, centre).unwrap();
        let exhaustive = exhaustive_tolerance(&points, &vertices, &faces, centre);
        let radius = (hi - lo).norm() / 2.0;
        // A point's distance to the hull is at least how far it is beyond any face plane
        // (exact in `f64`, unlike the scan's `f32` distances).
        let beyond = face_planes(&vertices, &faces, centroid)
            .into_iter()
            .flatten()
            .flat_map(|(n, d)| points.iter().map(move |p| n.dot(&p.coords) - d))
            .fold(0.0, f64::max);
        assert!(
            climbed >= beyond - 1e-12 * radius,
            "climbed {climbed} < {beyond}, how far a point is beyond a face plane"
        );
        assert!(
            climbed <= exhaustive + 1e-5 * radius,
            "climbed {climbed} is far above exhaustive {exhaustive}"
        );
    }
    assert!(climbed_some, "every hull fell back to the exhaustive scan");
}

/// Meshes of more vertices than the sample keeps get the hull of the sample: bounded in size,
/// enclosing every vertex with its tolerance, and tight (the tolerance a small fraction of the
/// radius) on a sphere, an elongated cylinder, a thin plate and a random cloud.
#[test]
fn sampled_hulls_of_large_meshes_are_bounded_enclosing_and_tight() {
    use crate::geometry::shapes::ShapeSpec;
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let specs = [
        ShapeSpec::Sphere {
            radius: 1.0,
            triangles: 200_000,
        },
        ShapeSpec::Cylinder {
            radius: 0.01,
            height: 1.0,
            triangles: 100_000,
        },
        ShapeSpec::Box {
            size: [1.0, 0.6, 0.01],
            triangles: 100_000,
        },
    ];
    let mut meshes: Vec<(String, TriMesh)> = specs
        .into_iter()
        .map(|spec| (format!("{spec:?}"), spec.build().unwrap()))
        .collect();
    meshes.push(("cloud".into(), random_cloud(&mut rng, 50_000, false)));
    for (name, mesh) in &meshes {
        assert!(mesh.vertices().len() > SAMPLE_CELLS, "{name}");
        let hull = ConvexHull::of(mesh);
        assert_eq!(hull.source(), HullSource::ConvexHull, "{name}");
        assert!(hull.vertices().len() <= SAMPLE_CELLS, "{name}");
        assert!(
            hull.tolerance() < 1e-2 * hull.radius(),
            "{name}: tolerance {} of radius {}",
            hull.tolerance(),
            hull.radius()
        );
        assert_encloses(&hull, mesh, &mut rng);
    }
}

#[test]
fn failed_hull_falls_back_to_the_bounding_box() {
    let boxed = ConvexHull::bounding_box(Point::new(-1.0, -2.0, 0.0), Point::new(1.0, 2.0, 0.0));
    assert_eq!(boxed.source(), HullSource::BoundingBox);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..200 {
        let d = random_direction(&mut rng);
        let (_, climbed) = boxed.extremal_vertex(&d, rng.random_range(0..8));
        assert!((climbed - (d.x.abs() + 2.0 * d.y.abs())).abs() < 1e-12);
    }
}
