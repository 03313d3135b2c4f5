//! The scene's geometry on the wire: every part's and hand segment's mesh, sent again under a new
//! generation after each reset and load, whole however large a part is, part by part for an
//! assembly.

use std::time::Instant;

use vas_client::{Client, ClientError, Frame};
use vas_protocol::ControlStatus;
use vas_server::scene::Scene;
use vas_testkit::{PATIENCE, Server, configs_dir, fixtures_dir};

/// Receives frames until a geometry frame of a generation after `after` arrives.
fn next_geometry(client: &mut Client, after: u64) -> std::sync::Arc<vas_protocol::SceneGeometry> {
    let deadline = Instant::now() + PATIENCE;
    loop {
        assert!(
            Instant::now() < deadline,
            "no geometry after generation {after}"
        );
        client.wait(PATIENCE).expect("wait");
        for frame in client.receive().expect("receive") {
            if let Frame::Geometry(geometry) = frame
                && geometry.generation > after
            {
                return geometry;
            }
        }
    }
}

/// The geometry on the wire is the scene's: a mesh per part with the server's own vertices
/// (scale applied) and triangles, the hand's segments; a reset sends it again under a new
/// generation, and a scene loaded by name sends its own.
#[test]
fn the_geometry_follows_every_reset_and_load() {
    let mut server = Server::start("geometry");
    let mut client = server.connect();
    let own = Scene::load(&configs_dir().join("default.toml")).expect("loads");
    let first = next_geometry(&mut client, 0);
    assert_eq!(first.parts.len(), own.parts.len());
    for (mesh, part) in first.parts.iter().zip(&own.parts) {
        assert_eq!(mesh.name, part.name);
        assert_eq!(mesh.triangles, part.mesh.triangles());
        let vertices = part.mesh.vertices();
        assert_eq!(mesh.positions.len(), vertices.len());
        for (wire, own) in mesh.positions.iter().zip(vertices) {
            assert!(
                (0..3).all(|i| (f64::from(wire[i]) - own[i]).abs() < 1e-6),
                "{}",
                part.name
            );
        }
    }
    let model = &own.hands.first().expect("the demo has a hand").model;
    assert_eq!(first.hands.len(), 1);
    assert_eq!(first.hands[0].model, model.name());
    assert_eq!(first.hands[0].segments.len(), model.segments().len());
    assert!(
        first.hands[0]
            .segments
            .iter()
            .all(|s| !s.triangles.is_empty())
    );

    client.reset(PATIENCE).expect("reset");
    let reset = next_geometry(&mut client, first.generation);
    assert_eq!((&reset.parts, &reset.hands), (&first.parts, &first.hands));

    let names = client.scene_names(PATIENCE).expect("the scenes offered");
    assert!(names.iter().any(|name| name == "peg_insert"), "{names:?}");
    for outside in ["../configs/peg_insert", "/etc/passwd", "peg_insert.toml"] {
        match client.load_named_scene(outside, PATIENCE) {
            Err(ClientError::Refused { status, .. }) => {
                assert_eq!(status, ControlStatus::SceneLoadFailed, "{outside}")
            }
            other => panic!("{outside} is no offered name, got {other:?}"),
        }
    }
    client
        .load_named_scene("peg_insert", PATIENCE)
        .expect("loads");
    let loaded = next_geometry(&mut client, reset.generation);
    let peg = Scene::load(&configs_dir().join("peg_insert.toml")).expect("loads");
    let names: Vec<&str> = loaded.parts.iter().map(|mesh| mesh.name.as_str()).collect();
    let expected: Vec<&str> = peg.parts.iter().map(|part| part.name.as_str()).collect();
    assert_eq!(names, expected);
}

/// A part of two million triangles goes through the geometry service whole: every vertex and
/// triangle the server's shape generator makes for it.
#[test]
fn a_two_million_triangle_part_reaches_a_client_whole() {
    let (mut server, _folder) = Server::start_on_scene(
        "big_geometry",
        "name = \"panel\"\n\n[[parts]]\nname = \"panel\"\n\
         shape = { kind = \"box\", size = [1.0, 0.6, 0.01], triangles = 2000000 }\n",
    );
    let mut client = server.connect();
    let geometry = next_geometry(&mut client, 0);

    let own =
        vas_server::geometry::shapes::cuboid(nalgebra::Vector3::new(1.0, 0.6, 0.01), 2_000_000);
    assert!(
        own.triangles().len() >= 2_000_000,
        "{}",
        own.triangles().len()
    );
    let [panel] = geometry.parts.as_slice() else {
        panic!("one part, not {}", geometry.parts.len());
    };
    assert_eq!(panel.triangles.len(), own.triangles().len());
    assert!(
        panel.triangles.as_slice() == own.triangles(),
        "the triangles differ"
    );
    assert_eq!(panel.positions.len(), own.vertices().len());
    let worst = panel
        .positions
        .iter()
        .zip(own.vertices())
        .map(|(wire, own)| {
            (0..3)
                .map(|i| (f64::from(wire[i]) - own[i]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "a vertex is {worst} m off");
}

/// A scene of a glTF assembly is served as any other: scene info gives every mesh node's part
/// with its node as the mesh source, and the geometry carries each part's baked mesh.
#[test]
fn an_assembly_is_served_part_by_part() {
    let path = fixtures_dir().join("assembly/assembly.toml");
    let scene = Scene::load(&path).expect("the assembly scene loads");
    assert!(scene.parts.len() > 50);
    let mut server = Server::start_with(
        "assembly",
        &["--scene", path.to_str().expect("a UTF-8 path")],
    );
    let mut client = server.connect();
    let info = client.scene_info(PATIENCE).expect("scene info");
    assert_eq!(info.parts.len(), scene.parts.len());
    for (described, part) in info.parts.iter().zip(&scene.parts) {
        assert_eq!(described.name, part.name);
        assert_eq!(described.mesh_source, part.mesh_source);
        assert_eq!(described.movable, part.movable);
    }
    let geometry = next_geometry(&mut client, 0);
    assert_eq!(geometry.parts.len(), scene.parts.len());
    for (mesh, part) in geometry.parts.iter().zip(&scene.parts) {
        assert_eq!(mesh.name, part.name);
        assert_eq!(mesh.triangles, part.mesh.triangles());
        for (wire, own) in mesh.positions.iter().zip(part.mesh.vertices()) {
            assert!(
                (0..3).all(|i| (f64::from(wire[i]) - own[i]).abs() < 1e-6),
                "{}",
                part.name
            );
        }
    }
}
