//! One fuzz target per input path of vas: each feeds what a file, a peer or a client could send
//! into the entry the server (or the client library) uses, and checks that it is either refused
//! with an error or accepted as a value that keeps the API's promises. A panic, a hang or a
//! broken promise is a failure.
//!
//! Seeds live in `tests/__fuzz__/<target>/corpus/seed-*`.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use nalgebra::{Isometry3, Vector3};
use vas_client::recording::Recording;
use vas_fuzz::{
    CollisionCase, check_hand, check_mesh, check_tree, configs_dir, is_finite, orientations,
    values_from_bytes,
};
use vas_protocol::HandSide;
use vas_protocol::{
    ControlRequest, ControlRequestKind, ControlStatus, FLEX_LIMITS_RAD, GloveSample,
    HandJointsSample, PartDescription, TrackerSample, WireText,
};
use vas_server::collision::dop_tree::{DEFAULT_LEAF_SIZE, TreeCache, reseal};
use vas_server::collision::orientation::{DEFAULT_K, SUPPORTED_K};
use vas_server::collision::{DopTree, MeshCollider, brute_force_pairs};
use vas_server::geometry::shapes;
use vas_server::geometry::{FileLimits, GltfFile, TriMesh, load_mesh, mesh_from_bytes};
use vas_server::grasping::HandModel;
use vas_server::grasping::retarget::{Capture, Retargeter};
use vas_server::runtime::control::{Reply, SceneCatalogue, Session, answer, loaded};
use vas_server::runtime::inputs::Inputs;
use vas_server::scene::{Scene, TrackingParams};

/// A mesh file's bytes, as `load_mesh` has them once read; the extension picks the parser.
fn mesh_file(name: &str, bytes: &[u8]) {
    if let Ok(mesh) = mesh_from_bytes(&configs_dir().join(name), bytes) {
        check_mesh(&mesh);
        check_tree(&mesh);
    }
}

/// The OBJ parser, seeded with the repository's meshes.
#[test]
fn obj_mesh() {
    bolero::check!().for_each(|bytes: &[u8]| mesh_file("fuzz.obj", bytes));
}

/// The STL parser, seeded with ASCII files.
#[test]
fn stl_ascii_mesh() {
    bolero::check!().for_each(|bytes: &[u8]| mesh_file("fuzz.stl", bytes));
}

/// The STL parser, seeded with binary files.
#[test]
fn stl_binary_mesh() {
    bolero::check!().for_each(|bytes: &[u8]| mesh_file("fuzz.stl", bytes));
}

/// The PLY reader, seeded with ASCII, little-endian and big-endian files.
#[test]
fn ply_mesh() {
    bolero::check!().for_each(|bytes: &[u8]| mesh_file("fuzz.ply", bytes));
}

/// The glTF reader (JSON or binary, told apart by the GLB magic), seeded with GLB files and a
/// JSON file with a `data:` buffer: as one mesh, and as an assembly's parts, whose poses must be
/// finite with unit rotations and whose baked meshes must keep `TriMesh`'s promise.
#[test]
fn gltf_mesh() {
    let path = configs_dir().join("fuzz.gltf");
    bolero::check!().for_each(|bytes: &[u8]| {
        mesh_file("fuzz.gltf", bytes);
        let Ok(file) = GltfFile::parse(&path, bytes, &FileLimits::default()) else {
            return;
        };
        for part in file.parts() {
            assert!(is_finite(&part.pose), "{}: {}", part.name, part.pose);
            assert!(
                (part.pose.rotation.norm() - 1.0).abs() < 1e-9,
                "{}",
                part.name
            );
            if let Ok(mesh) = file.mesh(part.mesh, &part.shape) {
                check_mesh(&mesh);
            }
        }
    });
}

/// The most triangles the procedural shapes of one fuzzed scene may ask for. Up to
/// `shapes::MAX_TRIANGLES` each is valid, but takes seconds and gigabytes to build: the fuzzer
/// would spend its time there, or be stopped for it.
const SCENE_TRIANGLE_BUDGET: i64 = 200_000;

/// The sum of the `triangles` counts anywhere in `value`.
fn triangles_asked(value: &toml::Value) -> i64 {
    match value {
        toml::Value::Table(table) => table
            .iter()
            .map(|(key, value)| match (key.as_str(), value) {
                ("triangles", toml::Value::Integer(n)) => (*n).max(0),
                _ => triangles_asked(value),
            })
            .fold(0, i64::saturating_add),
        toml::Value::Array(values) => values
            .iter()
            .map(triangles_asked)
            .fold(0, i64::saturating_add),
        _ => 0,
    }
}

/// A scene config's text, as `Scene::load` (check-scene, run, a load-scene request) has it once
/// read; paths are relative to `configs/`, so that seeds load the repository's meshes and hands.
#[test]
fn scene_toml() {
    let path = configs_dir().join("fuzz.toml");
    bolero::check!().for_each(|bytes: &[u8]| {
        let Ok(text) = std::str::from_utf8(bytes) else {
            return;
        };
        if let Ok(table) = text.parse::<toml::Table>()
            && triangles_asked(&toml::Value::Table(table)) > SCENE_TRIANGLE_BUDGET
        {
            return;
        }
        let Ok(scene) = Scene::from_toml(&path, text, &Default::default()) else {
            return;
        };
        assert!(!scene.name.trim().is_empty());
        for part in &scene.parts {
            check_mesh(&part.mesh);
            assert!(is_finite(&part.pose), "{}: {}", part.name, part.pose);
        }
        for pair in &scene.groups.parts_not_of_interest {
            assert!(pair[0] < pair[1] && pair[1] < scene.parts.len(), "{pair:?}");
        }
        for hand in &scene.hands {
            check_hand(&hand.model);
        }
        let _ = scene.summary();
    });
}

/// A hand model config's text, as `HandModel::load` has it once read; `mirror_of` is relative
/// to `configs/hands/`.
#[test]
fn hand_toml() {
    let path = configs_dir().join("hands/fuzz.toml");
    bolero::check!().for_each(|bytes: &[u8]| {
        if let Ok(text) = std::str::from_utf8(bytes)
            && let Ok(model) = HandModel::from_toml(&path, text, &FileLimits::default())
        {
            check_hand(&model);
        }
    });
}

/// A recording (JSON Lines), as `Recording::load` reads it.
#[test]
fn recording_jsonl() {
    let path = Path::new("fuzz.jsonl");
    bolero::check!().for_each(|bytes: &[u8]| {
        let Ok(recording) = Recording::from_reader(path, bytes) else {
            return;
        };
        let mut previous = 0.0;
        for sample in &recording.samples {
            assert!(
                sample.time.is_finite() && sample.time >= previous,
                "{sample:?}"
            );
            assert!(sample.input.is_finite(), "{sample:?}");
            previous = sample.time;
        }
    });
}

/// Tracker samples through the I/O thread's validation: an accepted one becomes a target with
/// finite poses and unit rotations.
#[test]
fn tracker_samples() {
    bolero::check!().for_each(|bytes: &[u8]| {
        let mut inputs = Inputs::default();
        for sample in values_from_bytes::<TrackerSample>(bytes) {
            if inputs.apply_tracker(&sample).is_err() {
                continue;
            }
            let input = inputs.frame().hands[0].input;
            for pose in [input.cart, input.tracker, input.cart * input.tracker] {
                assert!(is_finite(&pose), "{sample:?} gave {pose}");
                assert!((pose.rotation.norm() - 1.0).abs() < 1e-9, "{sample:?}");
            }
        }
        let stats = inputs.stats();
        assert_eq!(
            stats.tracker_accepted + stats.rejected(),
            bytes.len().div_ceil(size_of::<TrackerSample>()) as u64
        );
    });
}

/// Glove samples through the I/O thread's validation: an accepted one becomes finite flex
/// values within the joint limits.
#[test]
fn glove_samples() {
    bolero::check!().for_each(|bytes: &[u8]| {
        let mut inputs = Inputs::default();
        for sample in values_from_bytes::<GloveSample>(bytes) {
            if inputs.apply_glove(&sample).is_err() {
                continue;
            }
            let flex = inputs.frame().hands[0].input.flex;
            for (value, (low, high)) in flex.iter().zip(FLEX_LIMITS_RAD) {
                assert!((low..=high).contains(value), "{sample:?} gave {flex:?}");
            }
        }
    });
}

/// The right hand model, loaded once.
fn right_hand() -> &'static HandModel {
    static HAND: OnceLock<HandModel> = OnceLock::new();
    HAND.get_or_init(|| {
        HandModel::load(&configs_dir().join("hands/right.toml")).expect("the shipped hand")
    })
}

/// Hand-joints samples through the I/O thread's validation and retargeting onto a right hand
/// (seeded with the two real captures as right hands): each is counted once, accepted,
/// untracked or rejected, and an accepted one becomes a target with a finite root of unit
/// rotation and flex values within the hand's joint limits.
#[test]
fn hand_joints_samples() {
    bolero::check!().for_each(|bytes: &[u8]| {
        let mut inputs = Inputs::for_hands([(0, right_hand())], TrackingParams::default());
        let mut samples = values_from_bytes::<HandJointsSample>(bytes);
        // Half the samples name the scene's one user, half a user it does not have: arbitrary
        // bytes would almost never name user 0 and so never reach the retargeting.
        samples.iter_mut().for_each(|sample| sample.user %= 2);
        for sample in &samples {
            if inputs.apply_hand_joints(sample).is_err() {
                continue;
            }
            let input = inputs.frame().hands[0].input;
            let root = input.cart * input.tracker;
            assert!(is_finite(&root), "{sample:?} gave {root}");
            assert!((root.rotation.norm() - 1.0).abs() < 1e-9, "{sample:?}");
            for (value, limit) in input.flex.iter().zip(right_hand().limits()) {
                let (low, high) = (limit.min as f32, limit.max as f32);
                assert!((low..=high).contains(value), "{} = {value}", limit.name);
            }
        }
        // A sample stamped beyond the clock, or naming a user the scene does not have, is counted
        // with every stream's such samples; only hand-joints samples come here.
        let stats = inputs.stats();
        assert_eq!(
            stats.joints_accepted
                + stats.joints_untracked
                + stats.joints_rejected()
                + stats.rejected_ahead
                + stats.rejected_no_such_user,
            samples.len() as u64
        );
    });
}

/// The demo scene, loaded once.
fn demo_scene() -> &'static Arc<Scene> {
    static SCENE: OnceLock<Arc<Scene>> = OnceLock::new();
    SCENE.get_or_init(|| Arc::new(Scene::load(&configs_dir().join("default.toml")).expect("loads")))
}

/// Control requests answered in order on a fresh session of the demo scene, offering the scenes
/// of `configs/`.
///
/// A load is only asked for here, never carried out (the server's loader thread reads the file,
/// and what a scene file may hold is `scene_toml`'s to fuzz): a named load must resolve inside
/// the offered folder. `Reset` is skipped: it takes no argument and builds the hand anew (a
/// fifth of a second), so its answer does not depend on the bytes, and the fuzzer would spend
/// its time there.
#[test]
fn control_requests() {
    bolero::check!().for_each(|bytes: &[u8]| {
        let scene = demo_scene();
        let mut session = Session {
            scene: Arc::clone(scene),
            inputs: Inputs::default(),
            epoch: 1,
            catalogue: SceneCatalogue::of(configs_dir()),
            metaphor: scene.params.sliding.metaphor,
        };
        for request in values_from_bytes::<ControlRequest>(bytes) {
            let kind = ControlRequestKind::try_from(request.kind);
            if kind == Ok(ControlRequestKind::Reset) {
                continue;
            }
            let (response, change) = match answer(&mut session, &request, false) {
                Reply::Now(response, change) => (response, change),
                Reply::Load(path) => {
                    if kind == Ok(ControlRequestKind::LoadNamedScene) {
                        assert_eq!(path.parent(), Some(configs_dir().as_path()), "{path:?}");
                    } else {
                        assert_eq!(kind, Ok(ControlRequestKind::LoadScene));
                    }
                    continue;
                }
            };
            let status = ControlStatus::try_from(response.status).expect("a known status");
            assert_eq!(response.kind, request.kind);
            assert_eq!(response.part_count as usize, scene.parts.len());
            assert_eq!(response.stats, session.inputs.stats());
            assert!(response.scene_name.as_str().is_ok() && response.message.as_str().is_ok());
            if status != ControlStatus::Ok {
                assert!(change.is_none() && response.part == PartDescription::default());
            } else if kind == Ok(ControlRequestKind::PartInfo) {
                assert_eq!(response.part.id, request.argument);
                assert!(response.part.initial_pose.is_finite());
                assert!(response.part.name.as_str().is_ok());
            }
        }
    });
}

/// The fixed mesh of the collision target: the low-poly bunny in [-1, 1]^3.
fn bunny() -> &'static TriMesh {
    static BUNNY: OnceLock<TriMesh> = OnceLock::new();
    BUNNY.get_or_init(|| {
        load_mesh(&configs_dir().join("meshes/low_poly_bunny.obj"))
            .expect("loads")
            .normalized_to_unit_box()
    })
}

/// The bunny's tree for each orientation set, built once.
fn bunny_tree(k: usize) -> &'static DopTree {
    static TREES: OnceLock<Vec<DopTree>> = OnceLock::new();
    let trees = TREES.get_or_init(|| {
        SUPPORTED_K
            .iter()
            .map(|&k| DopTree::with_orientations(bunny(), orientations(k)))
            .collect()
    });
    &trees[SUPPORTED_K
        .iter()
        .position(|&s| s == k)
        .expect("a supported k")]
}

/// A small fuzzed mesh, validated and built into a DOP-tree, against the bunny at fuzzed poses:
/// the first-hit answer and the intersecting triangle pairs equal brute force over all pairs
/// with the same exact triangle test, in both roles (the bunny as A, then as B).
#[test]
fn dop_tree_against_brute_force() {
    bolero::check!()
        .with_type::<CollisionCase>()
        .for_each(|case: &CollisionCase| {
            let Ok(mesh) = case.mesh.validate() else {
                return;
            };
            check_mesh(&mesh);
            let k = SUPPORTED_K[usize::from(case.orientations) % SUPPORTED_K.len()];
            let leaf_size = 1 + usize::from(case.leaf_size % 4);
            let tree = DopTree::with_options(&mesh, orientations(k), leaf_size);
            let (bunny, bunny_tree) = (bunny(), bunny_tree(k));
            let mut stats = Default::default();
            for pose in case.poses.iter().filter_map(|p| p.isometry()) {
                for (a, tree_a, b, tree_b, b_to_a) in [
                    (bunny, bunny_tree, &mesh, &tree, pose),
                    (&mesh, &tree, bunny, bunny_tree, pose.inverse()),
                ] {
                    let expected = brute_force_pairs(a, b, &b_to_a);
                    let hit = tree_a.intersects(tree_b, &b_to_a, &mut stats);
                    assert_eq!(hit, !expected.is_empty(), "first hit at {b_to_a}");
                    let mut pairs = Vec::new();
                    tree_a.intersecting_pairs(tree_b, &b_to_a, &mut pairs, &mut stats);
                    pairs.sort_unstable();
                    assert_eq!(pairs, expected, "pairs at {b_to_a}");
                }
            }
        });
}

/// A tree cache over a small sphere, its file, and the brute force's answers against a cube
/// at a few poses: what every tree the cache serves for the sphere must answer.
struct CachedSphere {
    mesh: TriMesh,
    cache: TreeCache,
    file: PathBuf,
    other_tree: DopTree,
    poses: Vec<Isometry3<f64>>,
    expected: Vec<Vec<[u32; 2]>>,
}

impl CachedSphere {
    /// The case of fuzz target `target`, in a scratch folder of its own (the targets run at once
    /// under `cargo test`).
    fn new(target: &str) -> CachedSphere {
        let mesh = shapes::sphere(0.05, 200);
        let other = shapes::cuboid(Vector3::new(0.04, 0.04, 0.04), 12);
        let set = orientations(DEFAULT_K);
        let folder = std::env::temp_dir().join(format!("vas-fuzz-{target}-{}", std::process::id()));
        let cache = TreeCache::open(&folder).expect("a scratch folder");
        let file = cache.file_of(&mesh, set, DEFAULT_LEAF_SIZE);
        let poses: Vec<_> = [0.0, 0.03, 0.06, 0.1]
            .map(|x| Isometry3::new(Vector3::new(x, 0.01, 0.0), Vector3::new(0.3, 0.2, 0.1)))
            .into();
        let expected = (poses.iter())
            .map(|pose| brute_force_pairs(&mesh, &other, pose))
            .collect();
        CachedSphere {
            other_tree: DopTree::with_options(&other, set, DEFAULT_LEAF_SIZE),
            mesh,
            cache,
            file,
            poses,
            expected,
        }
    }

    /// The bytes of a valid file of the sphere's tree.
    fn valid_file(&self) -> Vec<u8> {
        (self.cache).tree(&self.mesh, orientations(DEFAULT_K), DEFAULT_LEAF_SIZE);
        std::fs::read(&self.file).expect("the cache stored the tree")
    }

    /// With `bytes` as the sphere's file, the cache serves a tree (the file's if it is valid,
    /// else a fresh build) whose answers are the brute force's.
    fn serves_from(&self, bytes: &[u8]) {
        std::fs::write(&self.file, bytes).expect("write the file");
        let set = orientations(DEFAULT_K);
        let (tree, _) = self.cache.tree(&self.mesh, set, DEFAULT_LEAF_SIZE);
        let mut stats = Default::default();
        for (pose, expected) in self.poses.iter().zip(&self.expected) {
            let mut pairs = Vec::new();
            tree.intersecting_pairs(&self.other_tree, pose, &mut pairs, &mut stats);
            pairs.sort_unstable();
            assert_eq!(&pairs, expected, "pairs at {pose}");
        }
    }
}

/// A file of the tree cache (`--tree-cache`), seeded with a valid one: whatever the file holds,
/// the cache serves a tree of the mesh whose answers are the brute force's.
#[test]
fn tree_cache_file() {
    let case = CachedSphere::new("tree_cache_file");
    bolero::check!().for_each(|bytes: &[u8]| case.serves_from(bytes));
}

/// The tree cache's reader past its checksum: a valid file with fuzzed bytes written over it
/// (at offsets taken modulo its length) and its checksum made to match, so that the damage
/// reaches the checks of the node counts, the structure, the triangle ids and the bounds, which
/// raw bytes (`tree_cache_file`) almost never get past the checksum to. Whatever the damage, the
/// cache serves a tree whose answers are the brute force's.
#[test]
fn tree_cache_reader() {
    let case = CachedSphere::new("tree_cache_reader");
    let valid = case.valid_file();
    bolero::check!()
        .with_type::<Vec<(u32, u8)>>()
        .for_each(|edits: &Vec<(u32, u8)>| {
            let mut bytes = valid.clone();
            for &(at, value) in edits {
                let length = bytes.len();
                bytes[at as usize % length] = value;
            }
            reseal(&mut bytes);
            case.serves_from(&bytes);
        });
}

/// A `LoadScene` request naming a file of fuzzed bytes, carried out as the server does (the
/// answer asks for a load, the loader reads the scene, the answer reports it): a scene is
/// served, or the load is refused with a message that names the file and quotes none of its
/// lines (issue 50: a load once answered with a file's first line).
#[test]
fn control_load_requests() {
    let folder = std::env::temp_dir().join(format!("vas-fuzz-load-{}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("a scratch folder");
    let file = folder.join("fuzz.toml");
    let path = WireText::new(&file.display().to_string()).expect("a short path");
    let mut session = Session {
        scene: Arc::clone(demo_scene()),
        inputs: Inputs::default(),
        epoch: 1,
        catalogue: SceneCatalogue::of(folder.clone()),
        metaphor: demo_scene().params.sliding.metaphor,
    };
    bolero::check!().for_each(|bytes: &[u8]| {
        if let Ok(table) = std::str::from_utf8(bytes)
            .unwrap_or("")
            .parse::<toml::Table>()
            && triangles_asked(&toml::Value::Table(table)) > SCENE_TRIANGLE_BUDGET
        {
            return;
        }
        std::fs::write(&file, bytes).expect("write the file");
        let Reply::Load(asked) = answer(&mut session, &ControlRequest::load_scene(path), false)
        else {
            panic!("a load-scene request asks for a load");
        };
        assert_eq!(asked, file);
        let outcome = Scene::load(&asked).map_err(|error| error.to_string());
        let refused = outcome.is_err();
        let (response, change) = loaded(&mut session, outcome);
        let status = ControlStatus::try_from(response.status).expect("a known status");
        assert_eq!(status == ControlStatus::Ok, change.is_some());
        if !refused {
            return;
        }
        let message = response.message.as_str().expect("UTF-8");
        assert!(message.contains("fuzz.toml"), "{message}");
        // Lines long enough that no message of the server's own words holds one by chance.
        let text = String::from_utf8_lossy(bytes);
        for line in text.lines().map(str::trim).filter(|line| line.len() >= 32) {
            assert!(!message.contains(line), "{line:?} quoted in {message:?}");
        }
    });
}

/// A captured hand pose (`vas-server retarget`), seeded with the real captures: refused with the
/// reason, or retargeted onto the model of its side to a finite root and flex values within the
/// joint limits, calibrated on itself or not.
#[test]
fn hand_capture_json() {
    let path = Path::new("fuzz.json");
    let retargeter = |side: HandSide| {
        let file = match side {
            HandSide::Left => "hands/left.toml",
            HandSide::Right => "hands/right.toml",
        };
        let model = HandModel::load(&configs_dir().join(file)).expect("the shipped hand");
        Retargeter::new(model).expect("the shipped hand retargets")
    };
    let (left, right) = (retargeter(HandSide::Left), retargeter(HandSide::Right));
    bolero::check!().for_each(|bytes: &[u8]| {
        let Ok(text) = std::str::from_utf8(bytes) else {
            return;
        };
        let Ok(capture) = Capture::from_json(path, text) else {
            return;
        };
        let joints = &capture.joints;
        let retargeter = if joints.side == HandSide::Left {
            &left
        } else {
            &right
        };
        let calibrated = retargeter.calibrated(joints).ok();
        for retargeter in std::iter::once(retargeter).chain(calibrated.as_ref()) {
            let Ok(fit) = retargeter.fit(joints) else {
                continue;
            };
            assert!(is_finite(&fit.root), "root {}", fit.root);
            for (value, limit) in fit.flex.iter().zip(retargeter.model().limits()) {
                assert!(
                    (limit.min..=limit.max).contains(value),
                    "{} = {value} beyond its limits",
                    limit.name
                );
            }
        }
    });
}

/// A message from a viewer page, as the viewer judges it: the first byte picks a text message
/// (even) or a binary one (odd), the rest is its payload. A command or an acknowledgement comes
/// only from a text message of at most `MAX_COMMAND_BYTES`, and a command reads back the same
/// when written out again; a hand's joints only from a binary message of their exact length,
/// and they become a sample the server can take (finite, each joint known or unknown).
#[test]
fn websocket_messages() {
    use axum::extract::ws::Message;
    use vas_viewer::commands::{MAX_COMMAND_BYTES, PageMessage, parse};
    use vas_viewer::hand_joints::{HandJoints, MESSAGE_BYTES, encode};
    use vas_viewer::page::{Judged, judge};
    bolero::check!().for_each(|bytes: &[u8]| {
        let Some((&kind, payload)) = bytes.split_first() else {
            return;
        };
        let text = String::from_utf8_lossy(payload);
        let message = if kind % 2 == 0 {
            Message::Text(text.as_ref().into())
        } else {
            Message::Binary(payload.to_vec().into())
        };
        let judged = judge(&message);
        if matches!(judged, Judged::Command(_) | Judged::Ack) {
            assert!(
                kind % 2 == 0 && text.len() <= MAX_COMMAND_BYTES,
                "{judged:?}"
            );
        }
        if let Judged::Command(command) = &judged {
            let written = serde_json::to_string(command).expect("a command writes as JSON");
            assert_eq!(parse(&written), Ok(PageMessage::Command(command.clone())));
        }
        // A hand taken is one binary message of exactly one hand's joints, and becomes a
        // sample of finite values with the palm unknown and each joint known or not at all.
        if let Judged::HandJoints(joints) = &judged {
            assert!(kind % 2 == 1 && payload.len() == MESSAGE_BYTES);
            let written = encode(joints.user, joints.side as u32, &joints.joints);
            assert_eq!(HandJoints::parse(&written).as_ref(), Ok(joints.as_ref()));
            let sample = joints.sample(1, 1);
            assert!(sample.is_finite());
            assert_eq!(sample.joints[0].flags, 0);
            assert!(
                sample
                    .joints
                    .iter()
                    .all(|joint| [0, 0b1111].contains(&joint.flags))
            );
        }
    });
}
