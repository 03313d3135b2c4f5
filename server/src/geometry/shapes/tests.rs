use std::collections::HashMap;
use std::f64::consts::PI;

use super::*;
use serde::Deserialize;

use super::resolution::torus_resolution;
use crate::geometry::adjacency::EdgeAdjacency;
use crate::geometry::mesh::Point;
use crate::geometry::weld::weld;

const ALL: [ShapeKind; 8] = ShapeKind::ALL;

fn is_open(kind: ShapeKind) -> bool {
    matches!(kind, ShapeKind::Hyperboloid | ShapeKind::SheetWithHole)
}

/// Genus-0 closed shapes have Euler characteristic 2; rings (torus, pipe, block with a hole)
/// and open annuli (hyperboloid, sheet with a hole) have 0.
fn expected_euler_characteristic(kind: ShapeKind) -> i64 {
    match kind {
        ShapeKind::Sphere | ShapeKind::Box | ShapeKind::Cylinder => 2,
        _ => 0,
    }
}

fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles().len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            a.coords.dot(&b.coords.cross(&c.coords)) / 6.0
        })
        .sum()
}

fn area(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles().len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            (b - a).cross(&(c - a)).norm() / 2.0
        })
        .sum()
}

/// The area-weighted centroid of the surface.
fn surface_centroid(mesh: &TriMesh) -> Vector3<f64> {
    let weighted: Vector3<f64> = (0..mesh.triangles().len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            (b - a).cross(&(c - a)).norm() / 2.0 * (a.coords + b.coords + c.coords) / 3.0
        })
        .sum();
    weighted / area(mesh)
}

fn relative_error(value: f64, expected: f64) -> f64 {
    (value - expected).abs() / expected.abs()
}

#[test]
fn kind_names_agree_between_cli_config_and_display() {
    for kind in ALL {
        let name = kind.to_string();
        assert_eq!(name.parse::<ShapeKind>(), Ok(kind));
        let quoted = serde_json::to_string(&kind).unwrap();
        assert_eq!(quoted, format!("\"{name}\""));
        assert_eq!(serde_json::from_str::<ShapeKind>(&quoted).unwrap(), kind);
    }
    assert_eq!(ShapeKind::BoxWithHole.to_string(), "box-with-hole");
    let error = "donut".parse::<ShapeKind>().unwrap_err().to_string();
    assert!(
        error.contains("donut") && error.contains("sheet-with-hole"),
        "{error}"
    );
}

#[test]
fn unit_shapes_meet_the_requested_count_and_fit_the_unit_box() {
    for kind in ALL {
        for target in [300, 1_000, 5_000, 10_000, 50_000] {
            let mesh = build(kind, target);
            let count = mesh.triangles().len();
            assert!(
                relative_error(count as f64, target as f64) <= 0.1,
                "{kind} asked for {target} triangles, got {count}"
            );
            let (lo, hi) = mesh.bounding_box();
            assert!(
                lo.iter().chain(hi.iter()).all(|c| c.abs() <= 1.0 + 1e-12),
                "{kind} does not fit in [-1, 1]^3: {lo} .. {hi}"
            );
            let centroid = surface_centroid(&mesh);
            assert!(centroid.norm() < 1e-9, "{kind} is centred at {centroid}");
        }
    }
}

#[test]
fn tiny_and_huge_requests_are_served() {
    for kind in ALL {
        assert!(!build(kind, 0).triangles().is_empty(), "{kind}");
        assert!(build(kind, 1).triangles().len() < 200, "{kind}");
    }
    // Above the maximum the request is clamped; the count stays bounded (not built here, as
    // that would take too long: check the resolution chosen instead).
    let (nu, nv) = torus_resolution(MAX_TRIANGLES);
    assert!(2 * nu * nv <= MAX_TRIANGLES + MAX_TRIANGLES / 50);
}

#[test]
fn the_b1_torus_is_the_250_by_100_grid() {
    assert_eq!(torus_resolution(50_000), (250, 100));
    let built = build(ShapeKind::Torus, 50_000);
    assert_eq!(built.triangles().len(), 50_000);
    let reference = torus(1.0, 0.35, 250, 100);
    assert_eq!(reference.triangles().len(), 50_000);
    assert_eq!(reference.vertices().len(), 25_000);
    let (a, b) = (
        built.normalized_to_unit_box(),
        reference.normalized_to_unit_box(),
    );
    assert_eq!(a.triangles(), b.triangles());
    for (p, q) in a.vertices().iter().zip(b.vertices()) {
        assert!((p - q).norm() < 1e-12);
    }
}

#[test]
fn the_papers_sphere_counts_are_met_exactly() {
    assert_eq!(sphere(1.0, 132).triangles().len(), 132);
    assert_eq!(sphere(1.0, 2_652).triangles().len(), 2_652);
}

#[test]
fn closed_shapes_are_closed_and_open_shapes_have_their_rims() {
    for kind in ALL {
        let mesh = build(kind, 4_000);
        let adjacency = EdgeAdjacency::new(&mesh);
        assert_eq!(adjacency.non_manifold_edges().count(), 0, "{kind}");
        let euler = mesh.vertices().len() as i64 - adjacency.edge_count() as i64
            + mesh.triangles().len() as i64;
        assert_eq!(euler, expected_euler_characteristic(kind), "{kind}");
        assert_eq!(adjacency.is_closed(), !is_open(kind), "{kind}");
        let rim: Vec<[u32; 2]> = adjacency.open_edges().map(|e| adjacency.edge(e)).collect();
        let rim_radii = |mesh: &TriMesh| -> Vec<f64> {
            rim.iter()
                .flat_map(|e| e.map(|v| mesh.vertices()[v as usize].xy().coords.norm()))
                .collect()
        };
        match kind {
            ShapeKind::Hyperboloid => {
                // Two rims, at the ends, on the end radius.
                assert!(rim_radii(&mesh).iter().all(|r| (r - 1.0).abs() < 1e-12));
                assert!(rim.iter().all(|e| {
                    e.iter()
                        .all(|&v| (mesh.vertices()[v as usize].z.abs() - 1.0).abs() < 1e-12)
                }));
            }
            ShapeKind::SheetWithHole => {
                // Rims: the hole (radius 0.5) and the square's border (|x| or |y| = 1).
                for e in &rim {
                    let points = e.map(|v| mesh.vertices()[v as usize]);
                    let on_hole = points
                        .iter()
                        .all(|p| (p.xy().coords.norm() - 0.5).abs() < 1e-12);
                    let on_border = points
                        .iter()
                        .all(|p| (p.x.abs().max(p.y.abs()) - 1.0).abs() < 1e-12);
                    assert!(on_hole != on_border, "rim edge {points:?}");
                }
            }
            _ => assert!(rim.is_empty()),
        }
    }
}

#[test]
fn winding_is_consistent_and_closed_shapes_face_outwards() {
    for kind in ALL {
        let mesh = build(kind, 3_000);
        // Each directed edge is used at most once: neighbours traverse a shared edge in
        // opposite directions.
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in mesh.triangles() {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(directed.values().all(|&n| n == 1), "{kind}");
        if !is_open(kind) {
            assert!(signed_volume(&mesh) > 0.0, "{kind} faces inwards");
        }
    }
}

#[test]
fn volumes_and_areas_match_the_analytic_values() {
    let n = 20_000;
    let tolerance = 0.01;
    let cases: [(TriMesh, f64, &str); 6] = [
        (sphere(0.3, n), 4.0 / 3.0 * PI * 0.3f64.powi(3), "sphere"),
        (
            torus(1.0, 0.35, 250, 100),
            2.0 * PI * PI * 0.35 * 0.35,
            "torus",
        ),
        (
            cuboid(Vector3::new(0.2, 0.3, 0.5), n),
            0.2 * 0.3 * 0.5,
            "box",
        ),
        (cylinder(0.1, 0.4, n), PI * 0.01 * 0.4, "cylinder"),
        (
            box_with_hole(0.08, 0.05, 0.01, n),
            (0.08 * 0.08 - PI * 0.01 * 0.01) * 0.05,
            "box with hole",
        ),
        (
            pipe(0.02, 0.025, 0.3, n),
            PI * (0.025f64.powi(2) - 0.02f64.powi(2)) * 0.3,
            "pipe",
        ),
    ];
    for (mesh, expected, name) in cases {
        let volume = signed_volume(&mesh);
        assert!(
            relative_error(volume, expected) < tolerance,
            "{name}: volume {volume}, expected {expected}"
        );
    }
    // A box's faces are flat, so its volume and area are exact.
    let block = cuboid(Vector3::new(0.2, 0.3, 0.5), 500);
    assert!(relative_error(signed_volume(&block), 0.03) < 1e-12);
    assert!(relative_error(area(&block), 2.0 * (0.06 + 0.15 + 0.1)) < 1e-12);

    let sheet = sheet_with_hole(0.3, 0.05, n);
    let expected = 0.09 - PI * 0.05 * 0.05;
    assert!(relative_error(area(&sheet), expected) < tolerance);
    assert!(sheet.vertices().iter().all(|v| v.z == 0.0));
}

#[test]
fn the_hyperboloid_lies_on_its_surface_and_has_its_area() {
    let (waist, end, height) = (0.3, 0.5, 0.8);
    let mesh = hyperboloid(waist, end, height, 20_000);
    let c = (height / 2.0) / ((end / waist) * (end / waist) - 1.0f64).sqrt();
    for v in mesh.vertices() {
        let implicit = (v.x * v.x + v.y * v.y) / (waist * waist) - (v.z * v.z) / (c * c);
        assert!((implicit - 1.0).abs() < 1e-9, "{v} is off the surface");
        assert!(v.z.abs() <= height / 2.0 + 1e-12);
    }
    // Surface of revolution: A = integral of 2 pi r(z) sqrt(1 + r'(z)^2) dz, by Simpson's rule.
    let integrand = |z: f64| {
        let s = (1.0 + z * z / (c * c)).sqrt();
        let (r, dr) = (waist * s, waist * z / (c * c * s));
        2.0 * PI * r * (1.0 + dr * dr).sqrt()
    };
    let steps = 2_000;
    let h = height / steps as f64;
    let simpson: f64 = (0..=steps)
        .map(|i| {
            let weight = if i == 0 || i == steps {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            weight * integrand(-height / 2.0 + i as f64 * h)
        })
        .sum::<f64>()
        * h
        / 3.0;
    assert!(relative_error(area(&mesh), simpson) < 0.01);
}

#[test]
fn welding_a_soup_of_a_shape_restores_it() {
    for kind in ALL {
        let mesh = build(kind, 2_000);
        let soup_vertices: Vec<Point> = (0..mesh.triangles().len())
            .flat_map(|t| mesh.triangle(t))
            .collect();
        let soup_triangles = (0..mesh.triangles().len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let soup = TriMesh::new(soup_vertices, soup_triangles).unwrap().0;
        assert_eq!(
            EdgeAdjacency::new(&soup).open_edges().count(),
            3 * soup.triangles().len()
        );
        let welded = weld(&soup, 1e-9);
        assert_eq!(welded.vertices().len(), mesh.vertices().len(), "{kind}");
        assert_eq!(welded.triangles().len(), mesh.triangles().len(), "{kind}");
        assert_eq!(
            EdgeAdjacency::new(&welded).is_closed(),
            !is_open(kind),
            "{kind}"
        );
    }
}

#[test]
fn the_hole_is_a_regular_polygon_with_a_vertex_at_angle_zero() {
    let (width, height, hole) = (0.08, 0.05, 0.01);
    let block = box_with_hole(width, height, hole, 4_000);
    assert!(
        block
            .vertices()
            .iter()
            .all(|v| v.xy().coords.norm() >= hole - 1e-12),
        "nothing reaches into the hole"
    );
    let mut angles: Vec<f64> = block
        .vertices()
        .iter()
        .filter(|v| v.z == height / 2.0 && (v.xy().coords.norm() - hole).abs() < 1e-12)
        .map(|v| v.y.atan2(v.x))
        .collect();
    angles.sort_by(f64::total_cmp);
    let step = 2.0 * PI / angles.len() as f64;
    assert!(angles.len() >= 16);
    assert!(angles.windows(2).all(|w| (w[1] - w[0] - step).abs() < 1e-9));
    assert!(angles.iter().any(|a| a.abs() < 1e-12));
}

#[test]
fn specs_are_validated_field_by_field() {
    let cases = [
        (
            ShapeSpec::Sphere {
                radius: -1.0,
                triangles: 100,
            },
            "radius",
        ),
        (
            ShapeSpec::Cylinder {
                radius: 0.1,
                height: f64::NAN,
                triangles: 100,
            },
            "height",
        ),
        (
            ShapeSpec::SheetWithHole {
                width: 1.0,
                hole_radius: 0.5,
                triangles: 100,
            },
            "hole_radius",
        ),
        (
            ShapeSpec::Pipe {
                inner_radius: 0.3,
                outer_radius: 0.2,
                length: 1.0,
                triangles: 100,
            },
            "inner_radius",
        ),
        (
            ShapeSpec::Hyperboloid {
                waist_radius: 1.0,
                end_radius: 0.5,
                height: 1.0,
                triangles: 100,
            },
            "waist_radius",
        ),
        (
            ShapeSpec::Box {
                size: [1.0, 1.0, 1.0],
                triangles: 0,
            },
            "triangles",
        ),
        (
            ShapeSpec::Torus {
                major_radius: 1.0,
                minor_radius: 1e9,
                triangles: 100,
            },
            "minor_radius",
        ),
    ];
    for (spec, field) in cases {
        let error = spec.build().unwrap_err();
        assert_eq!(error.field, field, "{spec}: {error}");
    }
}

#[test]
fn specs_read_from_toml_by_kind() {
    #[derive(Deserialize)]
    struct Holder {
        shape: ShapeSpec,
    }
    let parsed: Holder = toml::from_str(
        r#"shape = { kind = "box-with-hole", width = 0.08, height = 0.05, hole_radius = 0.01, triangles = 900 }"#,
    )
    .unwrap();
    assert_eq!(
        parsed.shape,
        ShapeSpec::BoxWithHole {
            width: 0.08,
            height: 0.05,
            hole_radius: 0.01,
            triangles: 900
        }
    );
    assert_eq!(
        parsed.shape.to_string(),
        "shape:box-with-hole:width=0.08,height=0.05,hole_radius=0.01,triangles=900"
    );
    let unknown = toml::from_str::<Holder>(
        r#"shape = { kind = "sphere", radius = 1.0, triangles = 10, colour = "red" }"#,
    );
    let message = unknown.err().unwrap().to_string();
    assert!(message.contains("colour"), "{message}");
    let wrong_kind = toml::from_str::<Holder>(r#"shape = { kind = "cone", triangles = 10 }"#);
    assert!(wrong_kind.err().unwrap().to_string().contains("cone"));
}
