//! `[[assemblies]]`: the trimesh-written assembly (`tests/fixtures/assembly/`) loads as parts
//! with the names, poses and shapes its script wrote, instances share meshes and trees, the
//! `up` turn and placement move it as documented, its parts behave as any part, and bad
//! assemblies and scenes over the triangle limit are refused with the key and the figures.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use nalgebra::{Point3, Quaternion, UnitQuaternion};
use serde_json::{Value, json};
use vas_server::collision::MeshCollider;
use vas_server::geometry::{FileLimits, TriMesh};
use vas_server::scene::{Part, Scene};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/assembly")
}

/// Loads `contents` as a scene in a fresh folder holding copies of the fixtures (so that
/// `assembly.glb` resolves); a refusal comes back as its message.
fn load_beside_the_fixtures(
    test: &str,
    contents: &str,
    limits: &FileLimits,
) -> Result<Scene, String> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("assemblies")
        .join(test);
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["assembly.glb", "part.obj", "part_binary.ply"] {
        std::fs::copy(fixtures().join(name), dir.join(name)).unwrap();
    }
    let path = dir.join(format!("test_{test}.toml"));
    std::fs::write(&path, contents).unwrap();
    Scene::load_with(&path, &(*limits).into()).map_err(|e| e.to_string())
}

fn expected_nodes() -> Vec<Value> {
    let text = std::fs::read_to_string(fixtures().join("assembly_expected.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn point(value: &Value) -> Point3<f64> {
    Point3::new(
        value[0].as_f64().unwrap(),
        value[1].as_f64().unwrap(),
        value[2].as_f64().unwrap(),
    )
}

fn part<'s>(scene: &'s Scene, name: &str) -> &'s Part {
    scene
        .parts
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no part {name}"))
}

/// The world-space bounding box of a part.
fn world_box(part: &Part) -> (Point3<f64>, Point3<f64>) {
    part.mesh
        .map_vertices(|v| part.pose.transform_point(v))
        .unwrap()
        .bounding_box()
}

/// Six times the signed volume a closed mesh encloses: positive when its triangles face out.
fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles().len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            a.coords.dot(&b.coords.cross(&c.coords))
        })
        .sum()
}

fn assembly_scene() -> Scene {
    Scene::load(&fixtures().join("assembly.toml")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_mesh_node_is_a_part_where_the_writer_put_it() {
    let scene = assembly_scene();
    let nodes = expected_nodes();
    assert_eq!(nodes.len(), 60);
    assert_eq!(
        scene.parts.len(),
        1 + nodes.len(),
        "the table and every mesh node"
    );
    assert_eq!(scene.parts[0].name, "table");
    for node in &nodes {
        let name = node["name"].as_str().unwrap();
        let part = part(&scene, name);
        let translation = point(&node["translation"]);
        assert!(
            (part.pose.translation.vector - translation.coords).amax() < 1e-12,
            "{name}"
        );
        if let Some(q) = node["rotation"].as_array() {
            let q = q.iter().map(|c| c.as_f64().unwrap()).collect::<Vec<_>>();
            let expected = UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]));
            assert!(part.pose.rotation.angle_to(&expected) < 1e-9, "{name}");
        }
        // The vertices are single precision in the file.
        let (lo, hi) = world_box(part);
        assert!(
            (lo - point(&node["bounds"][0])).amax() < 1e-7,
            "{name}: {lo}"
        );
        assert!(
            (hi - point(&node["bounds"][1])).amax() < 1e-7,
            "{name}: {hi}"
        );
        assert_eq!(
            part.mesh.triangles().len() as u64,
            node["triangles"].as_u64().unwrap()
        );
        // Closed and facing out, the mirrored node too (its triangles were turned over).
        assert!(signed_volume(&part.mesh) > 0.0, "{name}");
        assert_eq!(part.movable, name.starts_with("carriage_"), "{name}");
        assert_eq!(part.group, "assembly");
        assert!(
            part.mesh_source.contains("assembly.glb#/nodes/"),
            "{}",
            part.mesh_source
        );
        assert_eq!(part.scale, 1.0);
    }
}

#[test]
fn instances_of_one_mesh_at_one_scale_share_its_mesh_and_tree() {
    let scene = assembly_scene();
    let mut groups: HashMap<String, Vec<&Part>> = HashMap::new();
    for node in expected_nodes() {
        let key = format!("{} {}", node["mesh"], node["scale"]);
        groups
            .entry(key)
            .or_default()
            .push(part(&scene, node["name"].as_str().unwrap()));
    }
    // box, cylinder and sphere at scale 1, two non-uniform scales and one mirror.
    assert_eq!(groups.len(), 6, "{:?}", groups.keys());
    let firsts: Vec<&Part> = groups.values().map(|g| g[0]).collect();
    // All but the mirrored sphere are instanced three times or more.
    assert_eq!(groups.values().filter(|g| g.len() >= 3).count(), 5);
    for group in groups.values() {
        for part in group {
            assert!(Arc::ptr_eq(&part.mesh, &group[0].mesh), "{}", part.name);
            assert!(std::ptr::eq(part.tree(), group[0].tree()), "{}", part.name);
        }
    }
    for (i, a) in firsts.iter().enumerate() {
        for b in &firsts[i + 1..] {
            assert!(!Arc::ptr_eq(&a.mesh, &b.mesh), "{} and {}", a.name, b.name);
        }
    }
}

#[test]
fn the_up_option_and_the_placement_move_the_whole_assembly() {
    let plain = assembly_scene();
    let turned = load_beside_the_fixtures(
        "up",
        "name = \"turned\"\n[[assemblies]]\nfile = \"assembly.glb\"\nup = \"y\"\n\
         position = [1.0, 0.0, 0.5]\nmovable = true\n",
        &FileLimits::default(),
    )
    .unwrap();
    assert_eq!(turned.parts.len(), plain.parts.len() - 1);
    for part in &turned.parts {
        assert!(part.movable);
        // y-up: the file's +y becomes +z and its +z becomes -y, then the assembly moves.
        let (lo, hi) = world_box(part);
        let (was_lo, was_hi) = world_box(self::part(&plain, &part.name));
        let expected_lo = Point3::new(was_lo.x + 1.0, -was_hi.z, was_lo.y + 0.5);
        let expected_hi = Point3::new(was_hi.x + 1.0, -was_lo.z, was_hi.y + 0.5);
        assert!(
            (lo - expected_lo).amax() < 1e-12,
            "{}: {lo} {expected_lo}",
            part.name
        );
        assert!(
            (hi - expected_hi).amax() < 1e-12,
            "{}: {hi} {expected_hi}",
            part.name
        );
    }
}

#[test]
fn assembly_parts_collide_and_describe_themselves_as_any_part() {
    let scene = assembly_scene();
    let (box_a, box_b) = (part(&scene, "box_0_0"), part(&scene, "carriage_0"));
    let mut stats = Default::default();
    // Where they are, apart; one moved onto the other, touching.
    let apart = box_a.pose.inverse() * box_b.pose;
    assert!(!box_a.tree().intersects(box_b.tree(), &apart, &mut stats));
    let onto = nalgebra::Isometry3::translation(0.02, 0.0, 0.0);
    assert!(box_a.tree().intersects(box_b.tree(), &onto, &mut stats));
    assert!(
        scene.pair_of_interest(
            0,
            scene
                .parts
                .iter()
                .position(|p| p.name == "carriage_0")
                .unwrap()
        )
    );
    // Grasping takes the part's shared mesh and tree.
    let grasp = box_b.grasp_geometry();
    assert!(std::ptr::eq(grasp.mesh(), &*box_b.mesh));

    // Scene info over the control service names the part and its node.
    use vas_protocol::ControlRequest;
    use vas_server::runtime::control::{Reply, SceneCatalogue, Session, answer};
    let id = scene
        .parts
        .iter()
        .position(|p| p.name == "carriage_2")
        .unwrap();
    let mut session = Session {
        metaphor: scene.params.sliding.metaphor,
        scene: Arc::new(scene),
        inputs: Default::default(),
        epoch: 1,
        catalogue: SceneCatalogue::of(fixtures()),
    };
    let Reply::Now(response, _) =
        answer(&mut session, &ControlRequest::part_info(id as u32), false)
    else {
        panic!("part info is answered at once");
    };
    assert_eq!(response.part.name.as_str().unwrap(), "carriage_2");
    assert!(
        response
            .part
            .mesh_source
            .as_str()
            .unwrap()
            .ends_with("assembly.glb#/nodes/59")
    );
    assert_ne!(response.part.flags, 0, "movable");
}

#[test]
fn bad_assemblies_are_refused_with_the_key_and_the_reason() {
    let limits = FileLimits::default();
    for (test, contents, needles) in [
        (
            "unknown_movable",
            "movable = [\"box_0_0\", \"wheel\"]",
            &["assemblies[0].movable[1]", "names no part of"][..],
        ),
        ("bad_up", "up = \"x\"", &["unknown variant"][..]),
        (
            "bad_movable",
            "movable = 3",
            &["true, false, or a list of part names"][..],
        ),
        (
            "unknown_key",
            "scale = 2.0",
            &["unknown field", "scale"][..],
        ),
        (
            "far",
            "position = [1e9, 0.0, 0.0]",
            &["assemblies[0].position", "within"][..],
        ),
        (
            "empty_group",
            "group = \" \"",
            &["assemblies[0].group", "empty"][..],
        ),
    ] {
        let contents =
            format!("name = \"s\"\n[[assemblies]]\nfile = \"assembly.glb\"\n{contents}\n");
        let message = load_beside_the_fixtures(test, &contents, &limits).expect_err(test);
        assert!(message.contains(&format!("test_{test}.toml")), "{message}");
        for needle in needles {
            assert!(
                message.contains(needle),
                "{test}: {needle:?} not in: {message}"
            );
        }
    }
    let not_gltf = load_beside_the_fixtures(
        "not_gltf",
        "name = \"s\"\n[[assemblies]]\nfile = \"part.obj\"\n",
        &limits,
    )
    .unwrap_err();
    assert!(
        not_gltf.contains("assemblies[0].file") && not_gltf.contains("not a .gltf or .glb"),
        "{not_gltf}"
    );
    let missing = load_beside_the_fixtures(
        "missing_file",
        "name = \"s\"\n[[assemblies]]\nfile = \"nowhere.glb\"\n",
        &limits,
    )
    .unwrap_err();
    assert!(
        missing.contains("assemblies[0].file") && missing.contains("nowhere.glb"),
        "{missing}"
    );
    let clash = load_beside_the_fixtures(
        "clash",
        "name = \"s\"\n[[parts]]\nname = \"sphere_0_2\"\n\
         shape = { kind = \"sphere\", radius = 0.1, triangles = 100 }\n\
         position = [5.0, 0.0, 0.0]\n[[assemblies]]\nfile = \"assembly.glb\"\n",
        &limits,
    )
    .unwrap_err();
    assert!(
        clash.contains("assemblies[0]") && clash.contains("#/nodes/2 has the name of part 0"),
        "{clash}"
    );
}

#[test]
fn a_scene_over_the_triangle_limit_names_the_part_and_the_figures() {
    let at = |scene_triangles: u64, contents: &str| {
        load_beside_the_fixtures(
            "limit",
            contents,
            &FileLimits {
                scene_triangles,
                ..FileLimits::default()
            },
        )
    };
    // The assembly's 3,052 triangles after the table's: the node that passes 1,000 is refused.
    let fixture = std::fs::read_to_string(fixtures().join("assembly.toml")).unwrap();
    let hand = format!(
        "hand = \"{}/",
        fixtures().join("../../../configs").display()
    );
    let fixture = fixture.replace("hand = \"../../../configs/", &hand);
    let total = at(u64::MAX, &fixture)
        .unwrap()
        .parts
        .iter()
        .map(|p| p.mesh.triangles().len() as u64)
        .sum::<u64>();
    let table = total - 3_052;
    let message = at(1_000, &fixture).unwrap_err();
    assert!(
        message.contains("assemblies[0].file") && message.contains("limit of 1000 triangles"),
        "{message}"
    );
    assert!(
        message.contains("assemblies[0].file node ") && message.contains("needs at least"),
        "{message}"
    );
    assert!(at(table + 3_052, &fixture).is_ok());
    assert!(at(table + 3_051, &fixture).is_err());

    // A shape is refused by the count it asks for, before it is built.
    let shape = "name = \"s\"\n[[parts]]\nname = \"ball\"\n\
                 shape = { kind = \"sphere\", radius = 0.1, triangles = 20000000 }\n";
    let started = std::time::Instant::now();
    let message = at(1_000_000, shape).unwrap_err();
    assert!(started.elapsed().as_secs() < 5, "the sphere was not built");
    assert!(
        message.contains("parts[0].shape")
            && message.contains("the part needs at least 20000000 triangles")
            && message
                .contains("limit of 1000000 triangles (--max-scene-triangles) leaves 1000000"),
        "{message}"
    );
    // A mesh file, by the count its header gives.
    let ply = "name = \"s\"\n[[parts]]\nname = \"a\"\nmesh = \"part_binary.ply\"\n\
               [[parts]]\nname = \"b\"\nmesh = \"part_binary.ply\"\nscale = 2.0\n";
    let message = at(500, ply).unwrap_err();
    assert!(
        message.contains("parts[1].mesh")
            && message.contains("the part needs at least 320")
            && message.contains("leaves 180"),
        "{message}"
    );

    // Mesh files are read ahead in parallel, each within its share of the limit or read again
    // in its turn; the parts are counted in order, as if each file were read in its turn.
    let two = "name = \"s\"\n[[parts]]\nname = \"a\"\nmesh = \"part.obj\"\n\
               [[parts]]\nname = \"b\"\nmesh = \"part_binary.ply\"\n";
    let message = at(639, two).unwrap_err();
    assert!(
        message.contains("parts[1].mesh")
            && message.contains("the part needs at least 320")
            && message.contains("leaves 319"),
        "{message}"
    );
    for limit in [640, 700, 1_000_000] {
        let scene = at(limit, two).unwrap();
        assert_eq!(scene.triangle_count(), 640, "limit {limit}");
    }

    // check-scene takes the limit as a flag.
    let path = fixtures().join("assembly.toml");
    let check = |limit: &str| {
        Command::new(env!("CARGO_BIN_EXE_vas-server"))
            .args(["check-scene", "--max-scene-triangles", limit])
            .arg(&path)
            .output()
            .unwrap()
    };
    let refused = check("1000");
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("limit of 1000 triangles"), "{stderr}");
    let accepted = check(&total.to_string());
    assert!(
        accepted.status.success(),
        "{}",
        String::from_utf8_lossy(&accepted.stderr)
    );
    let summary = format!("parts: 61 (4 movable), {total} triangles");
    assert!(String::from_utf8_lossy(&accepted.stdout).contains(&summary));
}

/// An assembly of 100,000 nodes that share one small mesh loads as 100,000 parts: its names are
/// checked against a map, not pairwise (which took seconds for 32,000 nodes and did not finish
/// for 100,000).
#[test]
fn an_assembly_of_a_hundred_thousand_nodes_loads() {
    const NODES: usize = 100_000;
    let (mut document, bin) =
        super::formats::gltf_document(&super::formats::SQUARE, &[0, 1, 2, 0, 2, 3], 4, json!({}));
    let nodes: Vec<Value> = (0..NODES)
        .map(|i| json!({ "mesh": 0, "translation": [2.0 * i as f64, 0.0, 0.0] }))
        .collect();
    document["nodes"] = json!(nodes);
    document["scenes"] = json!([{ "nodes": (0..NODES).collect::<Vec<_>>() }]);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("assemblies")
        .join("many_nodes");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("many.glb"), super::formats::glb(&document, &bin)).unwrap();
    let path = dir.join("many.toml");
    std::fs::write(
        &path,
        "name = \"many\"\n[[assemblies]]\nfile = \"many.glb\"\n",
    )
    .unwrap();
    let scene = Scene::load(&path).expect("the assembly loads");
    assert_eq!(scene.parts.len(), NODES);
    let names: std::collections::HashSet<&str> =
        scene.parts.iter().map(|part| part.name.as_str()).collect();
    assert_eq!(names.len(), NODES, "every part has a name of its own");
}
