//! `check-scene --prepare`, and a server's warning, name the pairs of parts that collide where
//! the scene places them.

use std::path::Path;
use std::process::Command;

use vas_testkit::{PATIENCE, Server};

/// A scene of a peg, a second peg through it and a third standing clear of both.
const OVERLAPPING: &str = r#"
name = "overlapping"

[[parts]]
name = "peg"
shape = { kind = "cylinder", radius = 0.01, height = 0.05, triangles = 200 }
movable = true

[[parts]]
name = "crossing"
shape = { kind = "cylinder", radius = 0.01, height = 0.05, triangles = 200 }
position = [0.0, 0.0, 0.01]
rotation = [0.7071067811865476, 0.0, 0.0, 0.7071067811865476]
movable = true

[[parts]]
name = "apart"
shape = { kind = "cylinder", radius = 0.01, height = 0.05, triangles = 200 }
position = [0.2, 0.0, 0.0]
movable = true
"#;

fn check_scene_prepared(scene: &Path) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_vas-server"))
        .args(["check-scene", "--prepare"])
        .arg(scene)
        .output()
        .expect("run check-scene");
    assert!(output.status.success(), "{output:?}");
    String::from_utf8(output.stdout).expect("UTF-8")
}

#[test]
fn check_scene_names_the_pairs_that_collide_as_placed() {
    let dir = tempfile::tempdir().expect("a scratch folder");
    let scene = dir.path().join("overlapping.toml");
    std::fs::write(&scene, OVERLAPPING).expect("write the scene");
    let stdout = check_scene_prepared(&scene);
    assert!(
        stdout.contains(
            "parts collide as the scene places them (not checked until they part): \
             peg – crossing\n"
        ),
        "{stdout}"
    );

    let clear = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/peg_in_hole.toml");
    let stdout = check_scene_prepared(&clear);
    assert!(
        stdout.contains("no parts collide as the scene places them"),
        "{stdout}"
    );
}

#[test]
fn a_server_on_overlapping_parts_warns_naming_the_pairs() {
    let (mut server, _folder) = Server::start_on_scene("overlap_warning", OVERLAPPING);
    drop(server.connect());
    assert!(
        server
            .process
            .wait_for_log("parts collide as the scene places them", PATIENCE),
        "{}",
        server.process.log()
    );
    let log = server.process.log();
    let warning = (log.lines())
        .find(|line| line.contains("parts collide as the scene places them"))
        .expect("found above");
    assert!(warning.contains("peg – crossing"), "{warning}");
    assert!(!warning.contains("apart"), "{warning}");
}
