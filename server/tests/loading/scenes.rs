//! Scene configs: the shipped scenes load and make physical sense, every kind of bad config is
//! refused with the file, the key and the reason, and the `check-scene` and `shape` commands
//! behave.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use nalgebra::{Point2, Point3};
use vas_protocol::HandSide;
use vas_server::geometry::{TriMesh, load_mesh};
use vas_server::scene::{Scene, SceneError, default_scene_path};
use vas_server::sliding::SlidingMetaphor;

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// A fresh folder for one test's files.
fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scenes")
        .join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, contents: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, contents).unwrap();
    path
}

/// A valid part to build scenes around.
const PEG: &str = r#"
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

/// Loads `contents` as a scene and returns the error's message, checking that it names the
/// file and contains every one of `needles` (the key and the reason).
fn refused(test: &str, contents: &str, needles: &[&str]) -> SceneError {
    let dir = scratch_dir(test);
    let path = write(&dir, "scene.toml", contents);
    let error = Scene::load(&path).expect_err("the scene must be refused");
    let message = error.to_string();
    assert!(
        message.contains(&path.display().to_string()),
        "{test}: the file is not named in: {message}"
    );
    for needle in needles {
        assert!(
            message.contains(needle),
            "{test}: {needle:?} not in: {message}"
        );
    }
    error
}

#[test]
fn unknown_keys_are_refused() {
    let top = refused(
        "unknown_top",
        &format!("name = \"s\"\ncolour = 1\n{PEG}"),
        &["line 2", "colour"],
    );
    assert!(matches!(top, SceneError::Syntax { .. }));
    refused(
        "unknown_in_part",
        &format!("name = \"s\"\n{PEG}mass = 2.0\n"),
        &["mass"],
    );
    refused(
        "unknown_in_params",
        &format!("name = \"s\"\n[params.sliding]\nstiffness = 3\n{PEG}"),
        &["stiffness"],
    );
    refused(
        "unknown_in_shape",
        "name = \"s\"\n[[parts]]\nname = \"p\"\nshape = { kind = \"sphere\", radius = 1.0, triangles = 10, colour = 1 }\n",
        &["colour"],
    );
}

#[test]
fn missing_and_unloadable_meshes_are_refused() {
    let missing = refused(
        "missing_mesh",
        "name = \"s\"\n[[parts]]\nname = \"p\"\nmesh = \"nowhere/part.obj\"\n",
        &["parts[0].mesh", "nowhere/part.obj", "cannot read"],
    );
    assert!(matches!(missing, SceneError::Mesh { .. }));
    let dir = scratch_dir("bad_mesh");
    write(&dir, "broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    let path = write(
        &dir,
        "scene.toml",
        &format!("name = \"s\"\n{PEG}\n[[parts]]\nname = \"q\"\nmesh = \"broken.obj\"\n"),
    );
    let message = Scene::load(&path).unwrap_err().to_string();
    assert!(
        message.contains("parts[1].mesh")
            && message.contains("broken.obj")
            && message.contains("not a valid OBJ"),
        "{message}"
    );
}

#[test]
fn non_finite_numbers_are_refused() {
    refused(
        "nan_position",
        &format!("name = \"s\"\n{PEG}position = [0.0, nan, 0.0]\n"),
        &["parts[0].position", "finite"],
    );
    refused(
        "inf_rotation",
        &format!("name = \"s\"\n{PEG}rotation = [0.0, 0.0, 0.0, inf]\n"),
        &["parts[0].rotation", "finite"],
    );
    refused(
        "nan_shape",
        "name = \"s\"\n[[parts]]\nname = \"p\"\nshape = { kind = \"sphere\", radius = nan, triangles = 10 }\n",
        &["parts[0].shape.radius", "NaN"],
    );
    refused(
        "inf_tolerance",
        &format!("name = \"s\"\n[params.clasp]\nflex_tolerance = inf\n{PEG}"),
        &["params.clasp.flex_tolerance"],
    );
}

#[test]
fn bad_quaternions_are_refused_not_normalised() {
    refused(
        "long_quaternion",
        &format!("name = \"s\"\n{PEG}rotation = [0.0, 0.0, 0.0, 2.0]\n"),
        &["parts[0].rotation", "norm 2", "unit quaternion"],
    );
    refused(
        "zero_quaternion",
        &format!("name = \"s\"\n{PEG}rotation = [0.0, 0.0, 0.0, 0.0]\n"),
        &["parts[0].rotation", "norm 0"],
    );
    refused(
        "short_quaternion",
        &format!("name = \"s\"\n{PEG}rotation = [0.0, 0.0, 1.0]\n"),
        &["line"],
    );
}

#[test]
fn duplicate_part_names_are_refused() {
    refused(
        "duplicate_names",
        &format!("name = \"s\"\n{PEG}{PEG}"),
        &["parts[1].name", "\"peg\"", "parts[0]"],
    );
}

#[test]
fn unknown_groups_in_the_interest_matrix_are_refused() {
    refused(
        "unknown_group",
        &format!("name = \"s\"\n[groups]\nnot_of_interest = [[\"parts\", \"tools\"]]\n{PEG}"),
        &["groups.not_of_interest[0]", "\"tools\""],
    );
}

#[test]
fn bad_dop_orientation_counts_are_refused() {
    refused(
        "bad_k",
        &format!("name = \"s\"\n[params]\ndop_orientations = 12\n{PEG}"),
        &["params.dop_orientations", "12", "[6, 14, 18, 24, 26]"],
    );
}

#[test]
fn negative_and_zero_rates_are_refused() {
    refused(
        "negative_rate",
        &format!("name = \"s\"\n[rates]\nsliding_hz = -5.0\n{PEG}"),
        &["rates.sliding_hz", "-5"],
    );
    refused(
        "zero_rate",
        &format!("name = \"s\"\n[rates]\npublish_hz = 0\n{PEG}"),
        &["rates.publish_hz"],
    );
}

#[test]
fn inconsistent_parts_are_refused() {
    refused(
        "no_geometry",
        "name = \"s\"\n[[parts]]\nname = \"p\"\n",
        &["parts[0]", "mesh", "shape"],
    );
    refused(
        "mesh_and_shape",
        &format!("name = \"s\"\n{PEG}mesh = \"x.obj\"\n"),
        &["parts[0].shape", "not both"],
    );
    refused(
        "scaled_shape",
        &format!("name = \"s\"\n{PEG}scale = 2.0\n"),
        &["parts[0].scale"],
    );
    refused(
        "hole_too_big",
        "name = \"s\"\n[[parts]]\nname = \"p\"\nshape = { kind = \"sheet-with-hole\", width = 0.1, hole_radius = 0.05, triangles = 100 }\n",
        &["parts[0].shape.hole_radius"],
    );
    refused("empty_name", "name = \"\"\n", &["name", "empty"]);
    refused(
        "missing_hand",
        &format!("name = \"s\"\nhand = \"hands/left.toml\"\n{PEG}"),
        &["hand", "hands/left.toml", "No such file"],
    );
    refused("not_toml", "name = \n", &["line 1"]);
}

#[test]
fn a_scene_has_at_most_one_hand_of_each_side() {
    let [right, left] = ["right", "left"].map(|side| configs().join(format!("hands/{side}.toml")));
    let dir = scratch_dir("two_hands");
    let path = write(
        &dir,
        "scene.toml",
        &format!("name = \"s\"\nhands = [{right:?}, {left:?}]\n{PEG}"),
    );
    let scene = Scene::load(&path).unwrap();
    let sides: Vec<HandSide> = scene.hands.iter().map(|hand| hand.model.side()).collect();
    assert_eq!(sides, [HandSide::Right, HandSide::Left]);
    refused(
        "hand_and_hands",
        &format!("name = \"s\"\nhand = {right:?}\nhands = [{left:?}]\n{PEG}"),
        &["hands", "not both"],
    );
    refused(
        "two_right_hands",
        &format!("name = \"s\"\nhands = [{right:?}, {right:?}]\n{PEG}"),
        &["hands[1]", "at most one of each side"],
    );
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

#[test]
fn unknown_parts_in_the_interest_matrix_are_refused() {
    refused(
        "unknown_interest_part",
        &format!("name = \"s\"\n[groups]\nparts_not_of_interest = [[\"peg\", \"nail\"]]\n{PEG}"),
        &["groups.parts_not_of_interest[0]", "\"nail\""],
    );
    refused(
        "same_interest_part",
        &format!("name = \"s\"\n[groups]\nparts_not_of_interest = [[\"peg\", \"peg\"]]\n{PEG}"),
        &["groups.parts_not_of_interest[0]", "twice"],
    );
}

/// Scenes whose derived values would overflow: a scale that makes the mesh's coordinates huge
/// (once accepted, then a NaN bound killed the server), a vertex at 1e308, a part placed out of
/// any workspace, a rate whose period no timer holds, and an empty hand model file: each is
/// refused at load with its key, so that check-scene, run and load-scene refuse it alike.
#[test]
fn scenes_whose_derived_values_would_overflow_are_refused() {
    let dir = scratch_dir("overflow");
    write(&dir, "far.obj", "v 0 0 0\nv 1 0 0\nv 1e308 1 0\nf 1 2 3\n");
    write(&dir, "unit.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write(&dir, "empty_hand.toml", "");
    let part =
        |extra: &str| format!("name = \"s\"\n[[parts]]\nname = \"p\"\nmovable = true\n{extra}\n");
    for (test, contents, needles) in [
        (
            "huge_scale",
            part("mesh = \"unit.obj\"\nscale = 1e300"),
            &["parts[0].mesh", "beyond"][..],
        ),
        (
            "scale_1e120",
            part("mesh = \"unit.obj\"\nscale = 1e120"),
            &["parts[0].mesh", "beyond"],
        ),
        (
            "far_vertex",
            part("mesh = \"far.obj\""),
            &["parts[0].mesh", "beyond"],
        ),
        (
            "far_part",
            part("mesh = \"unit.obj\"\nposition = [1e300, 0, 0]"),
            &["parts[0].position", "within"],
        ),
        (
            "slow_publish",
            format!(
                "{}[rates]\npublish_hz = 1e-300\n",
                part("mesh = \"unit.obj\"")
            ),
            &["rates.publish_hz"],
        ),
        (
            "empty_hand",
            format!(
                "hand = \"empty_hand.toml\"\n{}",
                part("mesh = \"unit.obj\"")
            ),
            &["hand"],
        ),
    ] {
        let path = write(&dir, &format!("{test}.toml"), &contents);
        let message = Scene::load(&path)
            .expect_err("the scene must be refused")
            .to_string();
        for needle in needles {
            assert!(
                message.contains(needle),
                "{test}: {needle:?} not in: {message}"
            );
        }
    }
}

/// A file that is no config (a password file, a key file) is refused naming the file, where and
/// what is wrong, and quoting nothing of it: a scene load once answered with its first line.
#[test]
fn errors_name_the_file_and_quote_none_of_it() {
    let dir = scratch_dir("foreign_files");
    for (name, contents) in [
        (
            "shadow",
            "root:$6$hunter2salt$hunter2hash:19000:0:99999:7:::\n",
        ),
        ("key", "hunter2-private-key\n"),
        ("values", "name = \"hunter2\"\nhand = 42\n"),
    ] {
        let file = write(&dir, name, contents);
        let scene_error = Scene::load(&file).expect_err("refused").to_string();
        let hand_error = vas_server::grasping::HandModel::load(&file)
            .expect_err("refused")
            .to_string();
        for message in [scene_error, hand_error] {
            assert!(message.contains(&file.display().to_string()), "{message}");
            assert!(message.contains("line "), "{message}");
            assert!(!message.contains("hunter2"), "{message}");
        }
    }
}

/// A config of one endless line is refused with a message of bounded length (a 50 MB line once
/// came back whole in the error).
#[test]
fn errors_of_a_huge_line_are_short() {
    let dir = scratch_dir("huge_line");
    let line = format!("name = {}\n", "x".repeat(1_000_000));
    let scene = write(&dir, "scene.toml", &line);
    let hand = write(&dir, "hand.toml", &line);
    let scene_error = Scene::load(&scene).expect_err("refused").to_string();
    let hand_error = vas_server::grasping::HandModel::load(&hand)
        .expect_err("refused")
        .to_string();
    for message in [scene_error, hand_error] {
        assert!(message.contains("line 1"), "{message}");
        assert!(message.len() < 1_000, "{} bytes", message.len());
    }
}

/// Files larger than the configured limits are refused with the file and the limit, whichever
/// the file is (scene, mesh, hand model), and `check-scene` takes the limits as flags.
#[test]
fn files_beyond_the_configured_limits_are_refused() {
    use vas_server::geometry::FileLimits;
    let scene = configs().join("default.toml");
    let loose = FileLimits::default();
    Scene::load_with(&scene, &loose.into()).expect("the default limits take the demo scene");

    let refusal = |limits: FileLimits| {
        Scene::load_with(&scene, &limits.into())
            .expect_err("a limit below the file's size refuses it")
            .to_string()
    };
    let config = refusal(FileLimits {
        config_bytes: 64,
        ..loose
    });
    assert!(
        config.contains("default.toml") && config.contains("64 bytes"),
        "{config}"
    );
    let mesh = refusal(FileLimits {
        mesh_bytes: 1024,
        ..loose
    });
    assert!(
        mesh.contains("bunny") && mesh.contains("1024 bytes"),
        "{mesh}"
    );
    // The scene file itself fits in 4 KiB, the hand model it names does not.
    let hand = refusal(FileLimits {
        config_bytes: 4096,
        ..loose
    });
    assert!(
        hand.contains("right.toml") && hand.contains("4096 bytes"),
        "{hand}"
    );

    let binary = env!("CARGO_BIN_EXE_vas-server");
    let check = |size: &str| {
        Command::new(binary)
            .args(["check-scene", "--max-mesh-file", size])
            .arg(&scene)
            .output()
            .unwrap()
    };
    let refused = check("1KiB");
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("1024 bytes"), "{stderr}");
    assert!(check("64MiB").status.success());
    let nonsense = check("lots");
    assert!(!nonsense.status.success());
    let stderr = String::from_utf8_lossy(&nonsense.stderr);
    assert!(stderr.contains("--max-mesh-file"), "{stderr}");
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

/// A huge or tiny number a config gives is quoted in scientific notation, not as hundreds of
/// digits.
#[test]
fn errors_quote_huge_numbers_in_scientific_notation() {
    let dir = scratch_dir("huge_numbers");
    for (name, part, quoted) in [
        ("position", "position = [1e300, 0.0, 0.0]", "not 1e300"),
        (
            "rotation",
            "rotation = [1e300, 0.0, 0.0, 1.0]",
            "[1e300, 0, 0, 1]",
        ),
    ] {
        let text = format!(
            "name = \"huge\"\n[[parts]]\nname = \"box\"\n\
             shape = {{ kind = \"box\", size = [0.1, 0.1, 0.1], triangles = 12 }}\n{part}\n"
        );
        let file = write(&dir, &format!("{name}.toml"), &text);
        let error = Scene::load(&file).expect_err("refused").to_string();
        assert!(error.contains(quoted), "{error}");
        assert!(error.len() < 400, "{error}");
    }
}
