//! Bad scene configs: every kind is refused with the file, the key and the reason, and the
//! message stays short and quotes nothing of a file that is no config.

use std::process::Command;

use vas_protocol::HandSide;
use vas_server::scene::{Scene, SceneError};

use crate::scenes::{PEG, configs, scratch_dir, write};

/// Loads `contents` as a scene and returns the error's message, checking that it names the
/// file and contains every one of `needles` (the key and the reason).
pub(crate) fn refused(test: &str, contents: &str, needles: &[&str]) -> SceneError {
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
        &["parts[1].name", "is the name of parts[0] too"],
    );
}

#[test]
fn unknown_groups_in_the_interest_matrix_are_refused() {
    refused(
        "unknown_group",
        &format!("name = \"s\"\n[groups]\nnot_of_interest = [[\"parts\", \"tools\"]]\n{PEG}"),
        &[
            "groups.not_of_interest[0]",
            "its second group is the group of no part",
        ],
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
fn unknown_parts_in_the_interest_matrix_are_refused() {
    refused(
        "unknown_interest_part",
        &format!("name = \"s\"\n[groups]\nparts_not_of_interest = [[\"peg\", \"nail\"]]\n{PEG}"),
        &[
            "groups.parts_not_of_interest[0]",
            "its second name is the name of no part",
        ],
    );
    refused(
        "same_interest_part",
        &format!("name = \"s\"\n[groups]\nparts_not_of_interest = [[\"peg\", \"peg\"]]\n{PEG}"),
        &["groups.parts_not_of_interest[0]", "twice"],
    );
}

/// A refusal names the key, never the value: a config's names, groups and paths, even on lines
/// of their own or in multi-line strings, are not quoted, so that asking the server to load a
/// file shows nothing of the file.
#[test]
fn refusals_quote_no_value_of_the_config() {
    let long = "a_value_long_enough_to_be_noticed_if_quoted";
    let sphere = "shape = { kind = \"sphere\", radius = 0.1, triangles = 20 }";
    for (test, contents, key) in [
        (
            "unknown_interest_group",
            format!(
                "name = \"s\"\n[groups]\nnot_of_interest = [[\n\"default\",\n\"{long}\"\n]]\n{PEG}"
            ),
            "groups.not_of_interest[0]",
        ),
        (
            "unknown_interest_part",
            format!(
                "name = \"s\"\n[groups]\nparts_not_of_interest = [[\n\"peg\",\n\"{long}\"\n]]\n{PEG}"
            ),
            "groups.parts_not_of_interest[0]",
        ),
        (
            "multi_line_name",
            format!("name = \"\"\"\n{long}\n\"\"\"\n{PEG}"),
            "name",
        ),
        (
            "multi_line_part_name",
            format!("name = \"s\"\n[[parts]]\nname = '''\n{long}\n'''\n{sphere}\n"),
            "parts[0].name",
        ),
        (
            "multi_line_group",
            format!("name = \"s\"\n[[parts]]\nname = \"p\"\ngroup = '''\n{long}\n'''\n{sphere}\n"),
            "parts[0].group",
        ),
        (
            "multi_line_mesh",
            format!("name = \"s\"\n[[parts]]\nname = \"p\"\nmesh = \"\"\"\n{long}\n\"\"\"\n"),
            "parts[0].mesh",
        ),
        (
            "multi_line_hand",
            format!("name = \"s\"\nhands = [\"\"\"\n{long}\n\"\"\"]\n{PEG}"),
            "hands[0]",
        ),
    ] {
        let message = refused(test, &contents, &[key]).to_string();
        assert!(
            !message.contains(long),
            "{test}: the value is quoted in {message}"
        );
    }
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
