//! Loading real and hand-made mesh files: triangle counts of the shared test meshes, OBJ and STL
//! features, clear errors for bad files, and no panic whatever the bytes.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use proptest::prelude::*;
use vas_server::geometry::shapes::{self, ShapeKind};
use vas_server::geometry::{
    EdgeAdjacency, FileLimits, GeometryError, TriMesh, load_mesh, load_mesh_within,
    parse_mesh_spec, weld, write_obj,
};

/// The repository root (the server crate's parent).
fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn shipped_mesh(name: &str) -> PathBuf {
    repository_root().join("configs/meshes").join(name)
}

/// A fresh scratch file path for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mesh_files");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write_scratch(name: &str, contents: &[u8]) -> PathBuf {
    let path = scratch(name);
    std::fs::write(&path, contents).unwrap();
    path
}

#[derive(Debug, PartialEq)]
enum Surface {
    Closed,
    Open,
    /// Every triangle has its own three vertices.
    Soup,
}

#[test]
fn shipped_meshes_have_the_documented_triangle_counts() {
    // Face counts from the shared data's README, and how many of them are degenerate: one face of
    // model 1's object 2 has three collinear corners (one is the midpoint of the others) and is
    // dropped. The bunny, listed there as open, is closed (350 vertices, 1,044 edges, 696 faces).
    let expected = [
        ("fcl_env.obj", 2_180, 0, Surface::Soup),
        ("fcl_rob.obj", 216, 0, Surface::Soup),
        ("low_poly_bunny.obj", 696, 0, Surface::Closed),
        ("ur5e_base.obj", 4_838, 0, Surface::Open),
        ("ur5e_wrist3.obj", 911, 0, Surface::Open),
        ("fcl_manyframes_model1_obj1.obj", 3_322, 0, Surface::Closed),
        ("fcl_manyframes_model1_obj2.obj", 3_564, 1, Surface::Open),
    ];
    for (name, faces, degenerate, surface) in expected {
        let path = shipped_mesh(name);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), faces);
        let mesh = load_mesh(&path).unwrap();
        let triangles = faces - degenerate;
        assert_eq!(mesh.triangles().len(), triangles, "{name}");
        let adjacency = EdgeAdjacency::new(&mesh);
        let open = adjacency.open_edges().count();
        match surface {
            Surface::Closed => assert!(adjacency.is_closed(), "{name}"),
            Surface::Open => assert!(open > 0 && open < adjacency.edge_count(), "{name}"),
            Surface::Soup => {
                assert_eq!(mesh.vertices().len(), 3 * triangles, "{name}");
                assert_eq!(open, 3 * triangles, "{name}");
            }
        }
    }
}

#[test]
fn welding_a_real_soup_connects_its_triangles() {
    let soup = load_mesh(&shipped_mesh("fcl_rob.obj")).unwrap();
    // Coordinates are about ±500 with one decimal: a hundredth merges only true duplicates.
    let welded = weld(&soup, 0.01);
    assert_eq!(welded.triangles().len(), soup.triangles().len());
    assert!(welded.vertices().len() < soup.vertices().len() / 4);
    // The soup has only open edges; welded, most triangles have neighbours (the rest of the rims
    // are T-junctions of the model, which welding does not change).
    let adjacency = EdgeAdjacency::new(&welded);
    assert!(adjacency.open_edges().count() < 3 * soup.triangles().len() / 6);
}

#[test]
fn a_real_cad_part_of_forty_thousand_triangles_loads() {
    let mesh = load_mesh(&shipped_mesh("ur5e_upperarm.obj")).unwrap();
    assert_eq!(mesh.triangles().len(), 40_124);
    assert!(!EdgeAdjacency::new(&mesh).is_closed());
}

#[test]
fn obj_polygons_groups_and_relative_indices_become_one_mesh() {
    let text = "\
# a unit square (quad) in one group and a pentagon fan in another, sharing vertex 2
mtllib missing.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
g first
usemtl steel
f 1/1/1 2/1/1 3/1/1 4/1/1
g second
v 2 0 0
v 3 1 0
v 2.5 2 0
v 1.5 2 0
f -4//1 -3//1 -2//1 -1//1 3//1
l 1 2
";
    let mesh = load_mesh(&write_scratch("polygons.obj", text.as_bytes())).unwrap();
    // A quad gives 2 triangles, a pentagon 3.
    assert_eq!(mesh.triangles().len(), 5);
    // Vertex 3 of the file is used by both groups and stays one vertex.
    assert_eq!(mesh.vertices().len(), 8);
    let adjacency = EdgeAdjacency::new(&mesh);
    let shared = mesh
        .vertices()
        .iter()
        .position(|v| v.x == 1.0 && v.y == 1.0)
        .unwrap();
    assert_eq!(adjacency.vertex_triangles(shared).len(), 3);
}

#[test]
fn binary_and_ascii_stl_load() {
    let cube = shapes::build(ShapeKind::Box, 12);
    let facets: Vec<stl_io::Triangle> = (0..cube.triangles().len())
        .map(|t| {
            let corners = cube.triangle(t).map(|p| p.coords.map(|c| c as f32));
            stl_io::Triangle {
                normal: stl_io::Normal::new([0.0; 3]),
                vertices: corners.map(|c| stl_io::Vertex::new([c.x, c.y, c.z])),
            }
        })
        .collect();
    let binary = scratch("cube.stl");
    stl_io::write_stl(&mut std::fs::File::create(&binary).unwrap(), facets.iter()).unwrap();

    let mut ascii = String::from("solid cube\n");
    for facet in &facets {
        ascii.push_str("facet normal 0 0 0\nouter loop\n");
        for v in facet.vertices {
            ascii.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        ascii.push_str("endloop\nendfacet\n");
    }
    ascii.push_str("endsolid cube\n");
    let ascii = write_scratch("cube_ascii.STL", ascii.as_bytes());

    let limit = |scene_triangles| FileLimits {
        scene_triangles,
        ..FileLimits::default()
    };
    for path in [binary, ascii] {
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(mesh.triangles().len(), 12, "{}", path.display());
        // Identical corners are shared, so the cube is closed.
        assert_eq!(mesh.vertices().len(), 8, "{}", path.display());
        assert!(EdgeAdjacency::new(&mesh).is_closed());
        assert_eq!(load_mesh_within(&path, &limit(12)).unwrap(), mesh);
        // Binary files are refused by their count, ASCII ones at the first triangle too many.
        match load_mesh_within(&path, &limit(11)) {
            Err(GeometryError::TooManyTriangles { count, allowed, .. }) => {
                assert_eq!((count, allowed), (12, 11), "{}", path.display());
            }
            other => panic!("{}: {other:?}", path.display()),
        }
    }
}

#[test]
fn written_obj_files_load_back_exactly() {
    for kind in [ShapeKind::Torus, ShapeKind::SheetWithHole] {
        let mesh = shapes::build(kind, 2_000);
        let path = scratch(&format!("{kind}.obj"));
        write_obj(&mesh, &path).unwrap();
        let loaded = load_mesh(&path).unwrap();
        // Vertices may be renumbered (by first use); the triangles and corners are the same.
        assert_eq!(loaded.vertices().len(), mesh.vertices().len());
        assert_eq!(loaded.triangles().len(), mesh.triangles().len());
        let same = (0..mesh.triangles().len()).all(|t| loaded.triangle(t) == mesh.triangle(t));
        assert!(same, "{kind} changed in the round trip");
    }
}

#[test]
fn mesh_specs_name_shapes_or_files() {
    let torus = parse_mesh_spec("shape:torus:50000").unwrap();
    assert_eq!(torus.triangles().len(), 50_000);
    let bunny = shipped_mesh("low_poly_bunny.obj");
    let loaded = parse_mesh_spec(bunny.to_str().unwrap()).unwrap();
    assert_eq!(loaded.triangles().len(), 696);
    for bad in [
        "shape:torus",
        "shape:donut:100",
        "shape:torus:many",
        "shape:torus:0",
    ] {
        let error = parse_mesh_spec(bad).unwrap_err();
        assert!(matches!(error, GeometryError::BadSpec { .. }), "{bad}");
        assert!(error.to_string().contains(bad), "{error}");
    }
}

/// Asserts that loading `contents` as `name` fails with a message naming the file and containing
/// `reason`.
fn assert_refused(name: &str, contents: &[u8], reason: &str) {
    let path = write_scratch(name, contents);
    let error = load_mesh(&path).unwrap_err().to_string();
    assert!(error.contains(&path.display().to_string()), "{error}");
    assert!(error.contains(reason), "{name}: {error}");
}

#[test]
fn bad_files_are_refused_with_the_file_and_the_reason() {
    assert_refused("empty.obj", b"", "no (non-degenerate) triangles");
    assert_refused(
        "comments_only.obj",
        b"# nothing\n",
        "no (non-degenerate) triangles",
    );
    assert_refused("empty.stl", b"", "not a valid STL file");
    assert_refused(
        "nan.obj",
        b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
        "non-finite",
    );
    assert_refused(
        "infinite.obj",
        b"v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n",
        "non-finite",
    );
    assert_refused(
        "out_of_range.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
        "not a valid OBJ file",
    );
    assert_refused("not_a_number.obj", b"v 0 zero 0\n", "not a valid OBJ file");
    assert_refused(
        "mesh.3ds",
        b"MM",
        "unsupported format (expected a .obj, .stl, .ply, .gltf or .glb file)",
    );
    let mut truncated = Vec::from([0u8; 80]);
    truncated.extend(5u32.to_le_bytes());
    truncated.extend([0u8; 70]);
    assert_refused("truncated.stl", &truncated, "not a valid STL file");
    // A count smaller than the data: the reader stopped at the count and dropped the rest.
    let mut undercounted = Vec::from([0u8; 80]);
    undercounted.extend(1u32.to_le_bytes());
    undercounted.extend([0u8; 100]);
    assert_refused(
        "undercounted.stl",
        &undercounted,
        "does not match its 184 bytes (an 84-byte header and 50 bytes a triangle: room for 2)",
    );

    let missing = scratch("does_not_exist.obj");
    let error = load_mesh(&missing).unwrap_err();
    assert!(matches!(error, GeometryError::Read { .. }));
    assert!(error.to_string().contains("does_not_exist.obj"));
}

/// Collects what the `tracing` macros print, for checking warnings.
#[derive(Clone, Default)]
struct Captured(Arc<Mutex<Vec<u8>>>);

impl Write for Captured {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(bytes);
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning_naming_the_file() {
    let path = write_scratch(
        "degenerate.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n",
    );
    let captured = Captured::default();
    let writer = captured.clone();
    let subscriber = tracing_subscriber::fmt()
        .with_writer(move || writer.clone())
        .with_ansi(false)
        .finish();
    let mesh: TriMesh = tracing::subscriber::with_default(subscriber, || load_mesh(&path)).unwrap();
    assert_eq!(mesh.triangles().len(), 1);
    let log = String::from_utf8(captured.0.lock().unwrap().clone()).unwrap();
    assert!(log.contains("WARN"), "{log}");
    assert!(
        log.contains("degenerate.obj") && log.contains("removed=2"),
        "{log}"
    );
}

#[test]
fn every_prefix_of_valid_files_loads_or_fails_cleanly() {
    let cube = shapes::build(ShapeKind::Box, 12);
    let obj = scratch("prefix_source.obj");
    write_obj(&cube, &obj).unwrap();
    let obj_bytes = std::fs::read(&obj).unwrap();
    let mut stl_bytes = Vec::new();
    let facets: Vec<stl_io::Triangle> = (0..cube.triangles().len())
        .map(|t| stl_io::Triangle {
            normal: stl_io::Normal::new([0.0; 3]),
            vertices: cube
                .triangle(t)
                .map(|p| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32])),
        })
        .collect();
    stl_io::write_stl(&mut stl_bytes, facets.iter()).unwrap();
    for (name, bytes) in [("prefix.obj", &obj_bytes), ("prefix.stl", &stl_bytes)] {
        for end in 0..bytes.len() {
            let path = write_scratch(name, &bytes[..end]);
            // Any outcome but a panic is fine; a full file must load.
            let _ = load_mesh(&path);
        }
        let path = write_scratch(name, bytes);
        assert_eq!(load_mesh(&path).unwrap().triangles().len(), 12);
    }
}

/// OBJ-like lines built from the tokens that reach the parser's corner cases.
fn obj_line() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        Just("v".to_owned()),
        Just("f".to_owned()),
        Just("vt".to_owned()),
        Just("vn".to_owned()),
        Just("g".to_owned()),
        Just("nan".to_owned()),
        Just("1e999".to_owned()),
        Just("-0".to_owned()),
        Just("/".to_owned()),
        Just("//".to_owned()),
        any::<i64>().prop_map(|i| i.to_string()),
        (-3i32..6).prop_map(|i| i.to_string()),
        (-3i32..6, -3i32..6).prop_map(|(a, b)| format!("{a}/{b}/{a}")),
        any::<f64>().prop_map(|x| x.to_string()),
        "[ -~]{0,6}",
    ];
    proptest::collection::vec(token, 0..6).prop_map(|tokens| tokens.join(" "))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        for name in ["garbage.obj", "garbage.stl"] {
            let _ = load_mesh(&write_scratch(name, &bytes));
        }
    }

    #[test]
    fn arbitrary_obj_lines_never_panic(lines in proptest::collection::vec(obj_line(), 0..30)) {
        let path = write_scratch("lines.obj", lines.join("\n").as_bytes());
        if let Ok(mesh) = load_mesh(&path) {
            prop_assert!(mesh.vertices().iter().all(|v| v.iter().all(|c| c.is_finite())));
        }
    }
}

/// Runs `load` on another thread and returns its error message; fails the test if it takes
/// longer than a patient timeout (a FIFO once blocked its reader forever) or succeeds.
fn refusal_within_a_timeout<T: Send + 'static, E: std::fmt::Display + Send + 'static>(
    load: impl FnOnce() -> Result<T, E> + Send + 'static,
) -> String {
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = sender.send(load().err().map(|error| error.to_string()));
    });
    receiver
        .recv_timeout(std::time::Duration::from_secs(30))
        .expect("the load ended")
        .expect("the load was refused")
}

#[test]
fn only_regular_files_are_read() {
    let dir = scratch("not_regular");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let fifo = dir.join("pipe.obj");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let zero = dir.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    for path in [fifo.clone(), zero, dir.join("folder.obj")] {
        let message = refusal_within_a_timeout(move || load_mesh(&path));
        assert!(message.contains("not a regular file"), "{message}");
    }
    let scene_fifo = dir.join("scene.toml");
    let made = std::process::Command::new("mkfifo")
        .arg(&scene_fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let message = refusal_within_a_timeout(move || vas_server::scene::Scene::load(&scene_fifo));
    assert!(message.contains("not a regular file"), "{message}");
}
