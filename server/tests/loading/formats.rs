//! PLY and glTF mesh files: files written by trimesh (`tests/fixtures/assembly/`, see its
//! `make_assembly.py`) load with the triangles the writer put in, hand-made files exercise the
//! formats' features, and bad files are refused with the file and the reason.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use vas_server::geometry::{EdgeAdjacency, FileLimits, TriMesh, load_mesh, load_mesh_within};

/// The trimesh fixtures.
fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures/assembly")
        .join(name)
}

/// A fresh folder for one test's files.
fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("formats")
        .join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts that two meshes have the same triangles, corner by corner, within `tolerance`.
fn assert_same_triangles(a: &TriMesh, b: &TriMesh, tolerance: f64) {
    assert_eq!(a.triangles().len(), b.triangles().len());
    for t in 0..a.triangles().len() {
        for (p, q) in a.triangle(t).iter().zip(b.triangle(t)) {
            assert!((p - q).amax() <= tolerance, "triangle {t}: {p} and {q}");
        }
    }
}

#[test]
fn ply_files_load_the_triangles_of_the_obj_of_the_same_mesh() {
    let obj = load_mesh(&fixture("part.obj")).unwrap();
    assert_eq!(obj.triangles().len(), 320);
    // trimesh writes OBJ and ASCII PLY with 8 decimals, binary PLY in single precision.
    for name in ["part_ascii.ply", "part_binary.ply", "part_big_endian.ply"] {
        let ply = load_mesh(&fixture(name)).unwrap();
        assert_eq!(ply.vertices().len(), 162, "{name}");
        assert_same_triangles(&ply, &obj, 1e-8);
        assert!(EdgeAdjacency::new(&ply).is_closed(), "{name}");
    }
}

#[test]
fn ply_polygons_are_fans_as_obj_polygons_are() {
    let dir = scratch_dir("ply_polygons");
    let corners = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n3 1 0\n2.5 2 0\n1.5 2 0\n";
    let obj_path = dir.join("polygons.obj");
    let obj = corners
        .lines()
        .map(|l| format!("v {l}\n"))
        .collect::<String>()
        + "f 1 2 3 4\nf 5 6 7 8 3\n";
    std::fs::write(&obj_path, obj).unwrap();
    let ply_path = dir.join("polygons.ply");
    let ply = format!(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\n\
         property double z\nelement face 2\nproperty list uchar uint vertex_index\nend_header\n\
         {corners}4 0 1 2 3\n5 4 5 6 7 2\n"
    );
    std::fs::write(&ply_path, ply).unwrap();
    let (obj, ply) = (load_mesh(&obj_path).unwrap(), load_mesh(&ply_path).unwrap());
    assert_eq!(ply.triangles().len(), 5);
    assert_same_triangles(&ply, &obj, 0.0);
}

/// The expected nodes of the trimesh assembly, as its script wrote them.
fn expected_nodes() -> Vec<Value> {
    let text = std::fs::read_to_string(fixture("assembly_expected.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn point(value: &Value) -> [f64; 3] {
    std::array::from_fn(|i| value[i].as_f64().unwrap())
}

#[test]
fn a_glb_loads_as_one_mesh_of_every_node_in_place() {
    let mesh = load_mesh(&fixture("assembly.glb")).unwrap();
    let nodes = expected_nodes();
    let triangles: u64 = nodes.iter().map(|n| n["triangles"].as_u64().unwrap()).sum();
    assert_eq!(mesh.triangles().len() as u64, triangles);
    let (lo, hi) = mesh.bounding_box();
    for axis in 0..3 {
        let low = (nodes.iter())
            .map(|n| point(&n["bounds"][0])[axis])
            .fold(f64::MAX, f64::min);
        let high = (nodes.iter())
            .map(|n| point(&n["bounds"][1])[axis])
            .fold(f64::MIN, f64::max);
        assert!((lo[axis] - low).abs() < 1e-6 && (hi[axis] - high).abs() < 1e-6);
    }
}

/// A small glTF document of one mesh node: `positions` (three floats each) and `indices` (u16)
/// in buffer 0, drawn in `mode`; the node placed by `node` (its JSON fields).
pub(super) fn gltf_document(
    positions: &[[f32; 3]],
    indices: &[u16],
    mode: u32,
    node: Value,
) -> (Value, Vec<u8>) {
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let index_offset = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let mut node = node;
    node["mesh"] = json!(0);
    let document = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [node],
        "meshes": [{
            "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": mode }]
        }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3" },
            { "bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": index_offset },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset }
        ],
        "buffers": [{ "byteLength": bin.len() }]
    });
    (document, bin)
}

/// A unit square in z = 0, as four corners.
pub(super) const SQUARE: [[f32; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];

/// `document` and `bin` as a GLB file.
pub(super) fn glb(document: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(document).unwrap();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let length = 12 + 8 + json.len() + 8 + bin.len();
    let mut file = Vec::new();
    file.extend(b"glTF");
    file.extend(2u32.to_le_bytes());
    file.extend((length as u32).to_le_bytes());
    file.extend((json.len() as u32).to_le_bytes());
    file.extend(b"JSON");
    file.extend(json);
    file.extend((bin.len() as u32).to_le_bytes());
    file.extend(b"BIN\0");
    file.extend(bin);
    file
}

#[test]
fn strips_fans_transforms_and_buffers_of_every_kind_load() {
    let dir = scratch_dir("gltf_kinds");
    // A strip and a fan over the square give its two triangles, turned the same way.
    let strip = gltf_document(&SQUARE, &[0, 1, 3, 2], 5, json!({}));
    let fan = gltf_document(&SQUARE, &[0, 1, 2, 3], 6, json!({}));
    let mut loaded = Vec::new();
    for (name, (document, bin)) in [("strip.glb", strip), ("fan.glb", fan)] {
        let path = dir.join(name);
        std::fs::write(&path, glb(&document, &bin)).unwrap();
        loaded.push(load_mesh(&path).unwrap());
    }
    for mesh in &loaded {
        assert_eq!(mesh.triangles().len(), 2);
        for t in 0..2 {
            let [a, b, c] = mesh.triangle(t);
            assert!((b - a).cross(&(c - a)).z > 0.0, "triangle {t} faces +z");
        }
    }

    // A .gltf with its buffer in a file beside it, and one with a data: URI; the node scaled
    // by -2 in x (a mirror: the triangles turn over to keep facing +z) and moved.
    let node = json!({ "translation": [5.0, 0.0, 0.0], "scale": [-2.0, 1.0, 1.0] });
    let (mut document, bin) = gltf_document(&SQUARE, &[0, 1, 2, 0, 2, 3], 4, node);
    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::write(dir.join("data/square one.bin"), &bin).unwrap();
    document["buffers"][0]["uri"] = json!("data/square%20one.bin");
    std::fs::write(
        dir.join("file.gltf"),
        serde_json::to_vec(&document).unwrap(),
    )
    .unwrap();
    use base64::Engine as _;
    let encoded = base64::engine::general_purpose::STANDARD.encode(&bin);
    document["buffers"][0]["uri"] =
        json!(format!("data:application/octet-stream;base64,{encoded}"));
    std::fs::write(
        dir.join("embedded.gltf"),
        serde_json::to_vec(&document).unwrap(),
    )
    .unwrap();
    for name in ["file.gltf", "embedded.gltf"] {
        let mesh = load_mesh(&dir.join(name)).unwrap();
        let (lo, hi) = mesh.bounding_box();
        assert_eq!((lo.x, hi.x, hi.y), (3.0, 5.0, 1.0), "{name}");
        for t in 0..2 {
            let [a, b, c] = mesh.triangle(t);
            assert!(
                (b - a).cross(&(c - a)).z > 0.0,
                "{name}: triangle {t} faces +z"
            );
        }
    }
}

/// Loads `bytes` as `name` in a fresh folder and asserts that it is refused with a message
/// naming the file and containing `reason`.
fn assert_refused(name: &str, bytes: &[u8], reason: &str) {
    let dir = scratch_dir(&format!("refused_{name}"));
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let error = load_mesh(&path).expect_err(name).to_string();
    assert!(error.contains(&path.display().to_string()), "{error}");
    assert!(error.contains(reason), "{name}: {reason:?} not in: {error}");
}

/// A document changed by `change`, with its buffer, as a GLB file.
fn changed_glb(change: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Vec<u8> {
    let (mut document, mut bin) = gltf_document(&SQUARE, &[0, 1, 2, 0, 2, 3], 4, json!({}));
    change(&mut document, &mut bin);
    glb(&document, &bin)
}

#[test]
fn bad_gltf_files_are_refused_with_the_file_and_the_reason() {
    let good = std::fs::read(fixture("assembly.glb")).unwrap();
    assert_refused(
        "truncated.glb",
        &good[..good.len() - 100],
        "header gives a length of",
    );
    let mut cut = good[..good.len() - 100].to_vec();
    let length = cut.len() as u32;
    cut[8..12].copy_from_slice(&length.to_le_bytes());
    assert_refused(
        "cut_chunk.glb",
        &cut,
        "truncated GLB file: the chunk at byte",
    );
    assert_refused("short.glb", b"glTF\x02\0", "fewer than its 12-byte header");
    let mut magic = good.clone();
    magic[..4].copy_from_slice(b"GLTF");
    assert_refused("magic.glb", &magic, "not the magic \"glTF\"");

    let out_of_range = changed_glb(|_, bin| bin[48..50].copy_from_slice(&9u16.to_le_bytes()));
    assert_refused(
        "index.glb",
        &out_of_range,
        "index 0 is 9, beyond its 4 vertices",
    );
    let nan = changed_glb(|_, bin| bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes()));
    assert_refused("nan.glb", &nan, "vertex 1 has a non-finite coordinate");
    let lying = changed_glb(|d, _| d["accessors"][0]["count"] = json!(1_000_000_000u64));
    assert_refused(
        "count.glb",
        &lying,
        "counts 1000000000 elements, more than the 48 bytes",
    );
    let sparse = changed_glb(|d, _| d["accessors"][0]["sparse"] = json!({ "count": 1 }));
    assert_refused("sparse.glb", &sparse, "accessor 0 is sparse");
    let no_position =
        changed_glb(|d, _| d["meshes"][0]["primitives"][0]["attributes"] = json!({ "NORMAL": 0 }));
    assert_refused("position.glb", &no_position, "has no POSITION attribute");
    let missing =
        changed_glb(|d, _| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7));
    assert_refused("accessor.glb", &missing, "accessor 7 does not exist");
    let cycle = changed_glb(|d, _| d["nodes"][0]["children"] = json!([0]));
    assert_refused("cycle.glb", &cycle, "node 0 is reached twice");
    let draco = changed_glb(|d, _| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]));
    assert_refused(
        "draco.glb",
        &draco,
        "requires the extension KHR_draco_mesh_compression",
    );
    let version = changed_glb(|d, _| d["asset"]["version"] = json!("1.0"));
    assert_refused("version.glb", &version, "glTF version 1.0");
    let lines = changed_glb(|d, _| d["meshes"][0]["primitives"][0]["mode"] = json!(1));
    assert_refused("lines.glb", &lines, "no (non-degenerate) triangles");
}

#[test]
fn gltf_buffers_must_be_files_inside_the_folder_and_within_the_limit() {
    let dir = scratch_dir("gltf_buffers");
    let (mut document, bin) = gltf_document(&SQUARE, &[0, 1, 2, 0, 2, 3], 4, json!({}));
    std::fs::create_dir_all(dir.join("inner")).unwrap();
    std::fs::write(dir.join("outside.bin"), &bin).unwrap();
    std::fs::create_dir_all(dir.join("inner/folder.bin")).unwrap();
    let write = |uri: &str, document: &mut Value| {
        document["buffers"][0]["uri"] = json!(uri);
        let path = dir.join("inner/scene.gltf");
        std::fs::write(&path, serde_json::to_vec(document).unwrap()).unwrap();
        path
    };
    let outside = dir.join("outside.bin").display().to_string();
    for (uri, reason) in [
        (
            "../outside.bin",
            "not a relative path inside the glTF file's folder",
        ),
        ("%2E%2E/outside.bin", "not a relative path inside"),
        (outside.as_str(), "not a relative path inside"),
        ("file:///etc/passwd", "not a relative path inside"),
        ("folder.bin", "not a regular file"),
        ("missing.bin", "No such file"),
    ] {
        let path = write(uri, &mut document);
        let error = load_mesh(&path).expect_err(uri).to_string();
        assert!(
            error.contains("scene.gltf") && error.contains(reason),
            "{uri}: {error}"
        );
    }
    std::fs::write(dir.join("inner/square.bin"), &bin).unwrap();
    let path = write("square.bin", &mut document);
    assert_eq!(load_mesh(&path).unwrap().triangles().len(), 2);
    // The .gltf and its buffer together exceed a limit that either alone would meet.
    let gltf_bytes = std::fs::metadata(&path).unwrap().len();
    let limits = FileLimits {
        mesh_bytes: gltf_bytes + bin.len() as u64 - 1,
        ..FileLimits::default()
    };
    let error = load_mesh_within(&path, &limits).unwrap_err().to_string();
    assert!(
        error.contains("square.bin") && error.contains("in all"),
        "{error}"
    );
}

#[test]
fn bad_ply_files_are_refused_with_the_file_and_the_reason() {
    let good = std::fs::read(fixture("part_binary.ply")).unwrap();
    let text = String::from_utf8_lossy(&good);
    let with_count = |count: &str| {
        let header_end = text.find("end_header").unwrap();
        let header = text[..header_end].replace("element vertex 162", count);
        [header.as_bytes(), &good[header_end..]].concat()
    };
    assert_refused(
        "overcounted.ply",
        &with_count("element vertex 1000000000"),
        "the header counts 1000000000 vertex elements, more than the",
    );
    let ascii = std::fs::read_to_string(fixture("part_ascii.ply")).unwrap();
    assert_refused(
        "undercounted.ply",
        ascii
            .replace("element face 320", "element face 319")
            .as_bytes(),
        "follow the last element the header counts",
    );
    assert_refused(
        "truncated.ply",
        &good[..good.len() - 7],
        "more than the file holds",
    );
    let vertices = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\n";
    let no_faces = format!("{vertices}end_header\n0 0 0\n1 0 0\n0 1 0\n");
    assert_refused("no_faces.ply", no_faces.as_bytes(), "no face element");
    assert_refused(
        "magic.ply",
        b"PLY\n",
        "does not begin with the line \"ply\"",
    );
    assert_refused(
        "nan.ply",
        format!(
            "{vertices}element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n"
        )
        .as_bytes(),
        "vertex 1 has a non-finite coordinate",
    );
}

#[test]
fn files_with_more_triangles_than_the_limit_are_refused_before_they_are_read() {
    let limits = FileLimits {
        scene_triangles: 100,
        ..FileLimits::default()
    };
    for (name, count) in [
        ("part_binary.ply", 320),
        ("assembly.glb", 3052),
        ("part.obj", 320),
    ] {
        let error = load_mesh_within(&fixture(name), &limits)
            .unwrap_err()
            .to_string();
        let figures = format!("at least {count} triangles, more than the 100 allowed");
        assert!(error.contains(name) && error.contains(&figures), "{error}");
    }
}

#[test]
fn every_prefix_of_the_fixtures_loads_or_fails_cleanly() {
    let dir = scratch_dir("prefixes");
    for name in [
        "assembly.glb",
        "part_binary.ply",
        "part_ascii.ply",
        "part_big_endian.ply",
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        let path = dir.join(name);
        for end in (0..bytes.len()).step_by(7) {
            std::fs::write(&path, &bytes[..end]).unwrap();
            // Any outcome but a panic is fine; only the whole file holds every triangle.
            let _ = load_mesh(&path);
        }
    }
}

/// `bytes` with each `(position, value)` applied: a digit is replaced by another digit (so that
/// JSON stays JSON and its indices, counts and offsets change), any other byte by `value`.
fn mutated(bytes: &[u8], edits: &[(usize, u8)]) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
    for &(position, value) in edits {
        let at = position % bytes.len();
        bytes[at] = if bytes[at].is_ascii_digit() {
            b'0' + value % 10
        } else {
            value
        };
    }
    bytes
}

/// Loads the fixtures edited by `edits` as one mesh and as an assembly's parts: any outcome but
/// a panic is fine, and what loads has finite vertices, finite poses and unit rotations.
fn load_edited(edits: &[(usize, u8)]) {
    use base64::Engine as _;
    use vas_server::geometry::{GltfFile, mesh_from_bytes};
    let node = json!({ "scale": [1.0, 2.0, 3.0] });
    let (mut document, bin) = gltf_document(&SQUARE, &[0, 1, 2, 0, 2, 3], 4, node);
    let encoded = base64::engine::general_purpose::STANDARD.encode(&bin);
    document["buffers"][0]["uri"] = json!(format!("data:;base64,{encoded}"));
    let sources = [
        ("edited.gltf", serde_json::to_vec(&document).unwrap()),
        (
            "edited.glb",
            std::fs::read(fixture("assembly.glb")).unwrap(),
        ),
        (
            "edited.ply",
            std::fs::read(fixture("part_binary.ply")).unwrap(),
        ),
        (
            "edited.ply",
            std::fs::read(fixture("part_ascii.ply")).unwrap(),
        ),
    ];
    for (name, bytes) in sources {
        let path = fixture(name);
        let bytes = mutated(&bytes, edits);
        if let Ok(mesh) = mesh_from_bytes(&path, &bytes) {
            assert!(
                mesh.vertices()
                    .iter()
                    .all(|v| v.iter().all(|c| c.is_finite()))
            );
        }
        if name.ends_with(".ply") {
            continue;
        }
        if let Ok(file) = GltfFile::parse(&path, &bytes, &FileLimits::default()) {
            for part in file.parts() {
                let pose = part.pose;
                assert!(pose.translation.vector.iter().all(|c| c.is_finite()));
                assert!((pose.rotation.norm() - 1.0).abs() < 1e-9, "{pose}");
                let _ = file.mesh(part.mesh, &part.shape);
            }
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]

    #[test]
    fn edited_files_never_panic(
        edits in proptest::collection::vec((0usize..1 << 20, proptest::prelude::any::<u8>()), 1..6),
    ) {
        load_edited(&edits);
    }
}
