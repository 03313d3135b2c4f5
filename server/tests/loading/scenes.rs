//! Scene configs: the shipped scenes load and make physical sense, meshes are resolved and
//! shared, the interest matrix follows the config, the tree cache serves the next start, and the
//! `check-scene` and `shape` commands behave. Bad configs are `scene_refusals`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use nalgebra::{Point2, Point3};
use vas_server::geometry::{TriMesh, load_mesh};
use vas_server::scene::{Scene, default_scene_path};
use vas_server::sliding::SlidingMetaphor;

pub(crate) fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// A fresh folder for one test's files.
pub(crate) fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scenes")
        .join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(crate) fn write(dir: &Path, name: &str, contents: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, contents).unwrap();
    path
}

/// A valid part to build scenes around.
pub(crate) const PEG: &str = r#"
[[parts]]
name = "peg"
shape = { kind = "cylinder", radius = 0.01, height = 0.05, triangles = 200 }
movable = true
group = "parts"
"#;

/// The world-space bounding box of a part.
fn world_box(scene: &Scene, id: usize) -> (Point3<f64>, Point3<f64>) {
    let part = &scene.parts[id];
    let world = part
        .mesh
        .map_vertices(|v| part.pose.transform_point(v))
        .unwrap();
    world.bounding_box()
}

#[test]
fn every_shipped_scene_loads_with_movable_parts_clear_of_the_rest() {
    let mut count = 0;
    for entry in std::fs::read_dir(configs()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        count += 1;
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!scene.parts.is_empty(), "{}", path.display());
        assert!(scene.parts.iter().any(|p| p.movable), "{}", path.display());
        // No movable part starts touching another part: their boxes are apart.
        for a in 0..scene.parts.len() {
            for b in 0..scene.parts.len() {
                if a == b || !scene.parts[a].movable {
                    continue;
                }
                let ((lo_a, hi_a), (lo_b, hi_b)) = (world_box(&scene, a), world_box(&scene, b));
                let apart = (0..3).any(|i| hi_a[i] < lo_b[i] || hi_b[i] < lo_a[i]);
                assert!(
                    apart,
                    "{}: {} starts in contact with {}",
                    path.display(),
                    scene.parts[a].name,
                    scene.parts[b].name
                );
            }
        }
    }
    assert!(count >= 4, "configs/ holds the four scenes");
}

#[test]
fn the_default_scene_is_found_and_loads() {
    let path = default_scene_path();
    assert!(path.ends_with("configs/default.toml"), "{}", path.display());
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.name, "demo");
    for name in ["table", "block", "peg"] {
        assert!(scene.parts.iter().any(|p| p.name == name), "{name}");
    }
}

/// Distance from the origin to a triangle projected onto the xy plane (0 if it covers the
/// origin): for the vertical walls of a bore, the distance from the axis.
fn axis_distance(mesh: &TriMesh, triangle: usize) -> f64 {
    let [a, b, c] = mesh.triangle(triangle).map(|p| Point2::new(p.x, p.y));
    let cross = |p: Point2<f64>, q: Point2<f64>| p.x * q.y - p.y * q.x;
    let sides = [cross(a, b), cross(b, c), cross(c, a)];
    if sides.iter().all(|&s| s > 0.0) || sides.iter().all(|&s| s < 0.0) {
        return 0.0;
    }
    let to_segment = |p: Point2<f64>, q: Point2<f64>| {
        let d = q - p;
        let t = if d.norm_squared() > 0.0 {
            (-p.coords.dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p + d * t).coords.norm()
    };
    to_segment(a, b).min(to_segment(b, c)).min(to_segment(c, a))
}

/// The radius of the largest coaxial cylinder that passes through the part's hole.
fn bore_radius(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles().len())
        .map(|t| axis_distance(mesh, t))
        .fold(f64::INFINITY, f64::min)
}

/// The largest distance of the part's surface from its axis.
fn outer_radius(mesh: &TriMesh) -> f64 {
    mesh.vertices()
        .iter()
        .map(|v| v.xy().coords.norm())
        .fold(0.0, f64::max)
}

#[test]
fn the_peg_fits_its_hole_with_about_one_percent_clearance() {
    let scene = Scene::load(&configs().join("peg_in_hole.toml")).unwrap();
    let part = |name: &str| scene.parts.iter().find(|p| p.name == name).unwrap();
    let (block, peg) = (part("block"), part("peg"));
    let (hole, pin) = (bore_radius(&block.mesh), outer_radius(&peg.mesh));
    let clearance = (hole - pin) / hole;
    assert!(
        (0.005..0.015).contains(&clearance),
        "hole {hole}, peg {pin}, clearance {clearance}"
    );
    // Coaxial: the same x and y.
    let offset = peg.pose.translation.vector - block.pose.translation.vector;
    assert!(offset.xy().norm() < 1e-12);
}

#[test]
fn the_pipe_passes_through_the_sheets_hole() {
    let scene = Scene::load(&configs().join("pipe_through_sheet.toml")).unwrap();
    let (sheet, pipe) = (&scene.parts[0], &scene.parts[1]);
    assert_eq!((sheet.name.as_str(), pipe.name.as_str()), ("sheet", "pipe"));
    assert!(!sheet.movable && pipe.movable);
    assert!(outer_radius(&pipe.mesh) < bore_radius(&sheet.mesh));
    let (lo, hi) = sheet.mesh.bounding_box();
    assert_eq!((lo.z, hi.z), (0.0, 0.0), "the sheet has no thickness");
}

/// Parts whose meshes are equal share one mesh and one tree whatever their sources: two copies
/// of a file under other names, and an OBJ written from a shape beside that shape.
#[test]
fn meshes_of_equal_content_share_one_mesh_and_tree() {
    let dir = scratch_dir("content");
    let bunny = configs().join("meshes/low_poly_bunny.obj");
    std::fs::copy(&bunny, dir.join("first.obj")).unwrap();
    std::fs::copy(&bunny, dir.join("second.obj")).unwrap();
    let path = write(
        &dir,
        "scene.toml",
        r#"
name = "copies"

[[parts]]
name = "one"
mesh = "first.obj"

[[parts]]
name = "two"
mesh = "second.obj"
position = [1.0, 0.0, 0.0]

[[parts]]
name = "three"
mesh = "second.obj"
scale = 2.0
position = [2.0, 0.0, 0.0]
"#,
    );
    let scene = Scene::load(&path).unwrap();
    let [one, two, three] = [0, 1, 2].map(|i| &scene.parts[i]);
    assert_ne!(one.mesh_source, two.mesh_source, "each part names its file");
    assert!(Arc::ptr_eq(&one.mesh, &two.mesh), "equal content: one mesh");
    assert!(std::ptr::eq(one.tree(), two.tree()), "and one tree");
    assert!(
        !Arc::ptr_eq(&one.mesh, &three.mesh),
        "another scale: another mesh"
    );
    assert!(!std::ptr::eq(one.tree(), three.tree()));
}

#[test]
fn meshes_are_resolved_scaled_and_shared() {
    let dir = scratch_dir("meshes");
    let bunny = configs().join("meshes/low_poly_bunny.obj");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::copy(&bunny, dir.join("models/bunny.obj")).unwrap();
    let path = write(
        &dir,
        "scene.toml",
        r#"
name = "bunnies"
hand = "hand.toml"
params = { dop_orientations = 26, sliding = { metaphor = "spiral-spring" } }
rates = { publish_hz = 30 }
groups = { not_of_interest = [["b", "a"]] }

[[parts]]
name = "one"
mesh = "models/bunny.obj"
scale = 0.5
group = "a"

[[parts]]
name = "two"
mesh = "models/bunny.obj"
scale = 0.5
position = [1.0, 0.0, 0.0]
rotation = [0.0, 0.0, 0.7071068, 0.7071068]
movable = true
group = "b"

[[parts]]
name = "three"
mesh = "models/bunny.obj"
movable = true
"#,
    );
    std::fs::copy(configs().join("hands/right.toml"), dir.join("hand.toml")).unwrap();
    let scene = Scene::load(&path).unwrap();
    let original = load_mesh(&bunny).unwrap();
    let [one, two, three] = [0, 1, 2].map(|i| &scene.parts[i]);
    assert!(
        Arc::ptr_eq(&one.mesh, &two.mesh),
        "same file and scale: one mesh"
    );
    assert!(!Arc::ptr_eq(&one.mesh, &three.mesh));
    assert_eq!(*three.mesh, original);
    assert_eq!(one.mesh.vertices()[7], original.vertices()[7] * 0.5);
    assert_eq!(
        one.mesh_source,
        dir.join("models/bunny.obj").display().to_string()
    );
    // The rotation is a quarter turn about z, renormalised to full precision.
    assert!((two.pose.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
    assert!((two.pose.rotation.quaternion().norm() - 1.0).abs() < 1e-15);
    assert_eq!(three.group, "default");
    assert_eq!(
        scene
            .hands
            .iter()
            .map(|hand| hand.path.clone())
            .collect::<Vec<_>>(),
        [dir.join("hand.toml")]
    );
    assert_eq!(scene.params.dop_orientations, 26);
    // Parts with one mesh share one tree (built once, on first use), with the scene's
    // orientations.
    assert!(std::ptr::eq(one.tree(), two.tree()));
    assert!(!std::ptr::eq(one.tree(), three.tree()));
    assert_eq!(one.tree().orientations().k(), 26);
    assert_eq!(three.tree().triangle_count(), original.triangles().len());
    assert_eq!(scene.params.sliding.metaphor, SlidingMetaphor::SpiralSpring);
    assert_eq!(scene.params.sliding.contact_tolerance, None, "default kept");
    assert_eq!(
        (scene.rates.publish_hz, scene.rates.collision_hz),
        (30.0, 500.0)
    );
    assert_eq!(scene.groups.names, ["a", "b", "default"]);
    // Interest: a/b is excluded by the config, and parts are never tested against themselves.
    assert!(!scene.pair_of_interest(0, 1));
    assert!(scene.pair_of_interest(0, 2) && scene.pair_of_interest(1, 2));
    assert!(!scene.pair_of_interest(2, 2));
    let summary = scene.summary();
    for needle in [
        "bunnies",
        "parts: 3 (2 movable)",
        "26-DOPs",
        "spiral-spring",
        "a/b",
    ] {
        assert!(
            summary.contains(needle),
            "{needle} missing from:\n{summary}"
        );
    }
}

#[test]
fn static_pairs_are_never_of_interest() {
    let dir = scratch_dir("static_pairs");
    let path = write(
        &dir,
        "scene.toml",
        r#"
name = "fixtures"
[[parts]]
name = "a"
shape = { kind = "sphere", radius = 0.1, triangles = 100 }
[[parts]]
name = "b"
shape = { kind = "sphere", radius = 0.1, triangles = 100 }
position = [1.0, 0.0, 0.0]
"#,
    );
    let scene = Scene::load(&path).unwrap();
    assert!(!scene.pair_of_interest(0, 1));
}

#[test]
fn check_scene_prints_a_summary_or_fails_with_the_error() {
    let binary = env!("CARGO_BIN_EXE_vas-server");
    let ok = Command::new(binary)
        .args(["check-scene"])
        .arg(configs().join("peg_in_hole.toml"))
        .output()
        .unwrap();
    assert!(ok.status.success());
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert!(
        stdout.contains("peg in hole") && stdout.contains("parts: 2 (1 movable)"),
        "{stdout}"
    );
    assert!(
        !stdout.contains("prepared"),
        "nothing built unasked: {stdout}"
    );
    let prepared = Command::new(binary)
        .args(["check-scene", "--prepare"])
        .arg(configs().join("peg_in_hole.toml"))
        .output()
        .unwrap();
    assert!(prepared.status.success());
    let stdout = String::from_utf8_lossy(&prepared.stdout);
    assert!(
        stdout.contains("prepared (DOP-trees, convex hulls and edge adjacency of 2 parts) in "),
        "{stdout}"
    );

    let dir = scratch_dir("cli");
    let bad = write(
        &dir,
        "bad.toml",
        &format!("name = \"s\"\n[params]\ndop_orientations = 7\n{PEG}"),
    );
    let failed = Command::new(binary)
        .arg("check-scene")
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!failed.status.success());
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(stderr.contains("params.dop_orientations"), "{stderr}");
    assert!(failed.stdout.is_empty());
}

#[test]
fn the_shape_command_writes_a_loadable_obj() {
    let out = scratch_dir("cli_shape").join("torus.obj");
    let status = Command::new(env!("CARGO_BIN_EXE_vas-server"))
        .args(["shape", "torus", "--triangles", "50000", "--out"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(load_mesh(&out).unwrap().triangles().len(), 50_000);
}

#[test]
fn the_interest_matrix_follows_the_group_and_part_rules_of_the_config() {
    use vas_server::collision::DopTree;
    use vas_server::collision::MeshCollider;
    use vas_server::collision::pipeline::interest::InterestKey;
    use vas_server::collision::pipeline::{
        CollisionModel, CollisionPipeline, ObjectDesc, PipelineConfig,
    };
    use vas_server::geometry::hull::ConvexHull;

    let dir = scratch_dir("interest_matrix");
    let sphere = "shape = { kind = \"sphere\", radius = 0.1, triangles = 100 }";
    let path = write(
        &dir,
        "scene.toml",
        &format!(
            r#"
name = "interest"
[groups]
not_of_interest = [["tools", "parts"]]
parts_not_of_interest = [["nut", "bolt"]]
[[parts]]
name = "table"
{sphere}
group = "fixtures"
[[parts]]
name = "bolt"
{sphere}
movable = true
group = "parts"
[[parts]]
name = "nut"
{sphere}
movable = true
group = "parts"
[[parts]]
name = "wrench"
{sphere}
movable = true
group = "tools"
[[parts]]
name = "stand"
{sphere}
group = "fixtures"
"#
        ),
    );
    let scene = Scene::load(&path).unwrap();
    let mut pipeline = CollisionPipeline::<DopTree>::new(PipelineConfig::default());
    let objects: Vec<_> = scene
        .parts
        .iter()
        .enumerate()
        .map(|(i, part)| {
            let model = CollisionModel::new(DopTree::build(&part.mesh), ConvexHull::of(&part.mesh));
            pipeline
                .add(ObjectDesc {
                    model: Arc::new(model),
                    pose: part.pose,
                    group: scene.group_id(i),
                    is_static: !part.movable,
                })
                .unwrap()
        })
        .collect();
    let matrix = scene.interest_matrix(&objects);
    let key = |i: usize| InterestKey {
        object: objects[i],
        group: scene.group_id(i),
        is_static: !scene.parts[i].movable,
    };
    let mut interesting = Vec::new();
    for a in 0..scene.parts.len() {
        for b in a + 1..scene.parts.len() {
            assert_eq!(
                matrix.is_interesting(&key(a), &key(b)),
                scene.pair_of_interest(a, b),
                "parts {a} and {b}"
            );
            if scene.pair_of_interest(a, b) {
                interesting.push([a, b]);
            }
        }
    }
    // table/stand: both static; bolt/nut: by part; bolt, nut / wrench: by group.
    assert_eq!(
        interesting,
        [[0, 1], [0, 2], [0, 3], [1, 4], [2, 4], [3, 4]]
    );
}

/// With `--tree-cache`, the trees built by one start are read by the next; a damaged file is
/// refused, built again and replaced; a cache that cannot be a folder is an error.
#[test]
fn a_tree_cache_serves_the_next_start_and_refuses_a_damaged_file() {
    let binary = env!("CARGO_BIN_EXE_vas-server");
    let dir = scratch_dir("tree_cache");
    let cache = dir.join("trees");
    let _ = std::fs::remove_dir_all(&cache);
    let scene = write(
        &dir,
        "scene.toml",
        &format!(
            "name = \"s\"\n[[parts]]\nname = \"ball\"\n\
             shape = {{ kind = \"sphere\", radius = 0.1, triangles = 20000 }}\n\
             position = [0.5, 0, 0]\n{PEG}"
        ),
    );
    let check = || {
        let output = Command::new(binary)
            .args(["check-scene", "--prepare", "--tree-cache"])
            .arg(&cache)
            .arg(&scene)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "{stdout}{stderr}");
        (stdout, stderr)
    };
    let read = |count: usize| format!("trees of {count} of 2 parts read from the tree cache");
    let (stdout, _) = check();
    assert!(stdout.contains(&read(0)), "{stdout}");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .collect();
    assert_eq!(files.len(), 2, "a file a tree: {files:?}");
    let (stdout, _) = check();
    assert!(stdout.contains(&read(2)), "{stdout}");

    files.sort_by_key(|file| std::fs::metadata(file).unwrap().len());
    let ball = &files[1];
    let good = std::fs::read(ball).unwrap();
    let mut damaged = good.clone();
    let middle = damaged.len() / 2;
    damaged[middle] ^= 1;
    std::fs::write(ball, &damaged).unwrap();
    let (stdout, stderr) = check();
    assert!(stdout.contains(&read(1)), "{stdout}");
    assert!(
        stderr.contains("cached tree refused") && stderr.contains("checksum"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(ball).unwrap(), good, "replaced by a good one");
    let (stdout, _) = check();
    assert!(stdout.contains(&read(2)), "{stdout}");

    let not_a_folder = write(&dir, "file", "");
    let failed = Command::new(binary)
        .args(["check-scene", "--tree-cache"])
        .arg(&not_a_folder)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!failed.status.success());
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(
        stderr.contains("cannot use") && stderr.contains("tree cache"),
        "{stderr}"
    );
}
