//! The Unity sample of `client-c/examples/unity/`: its C# compiles with Mono's `mcs` as Unity's
//! scripts outside Unity (warnings as errors), and a console program P/Invokes the built C
//! library under Mono: every struct as C# lays it out has the library's size and last field's
//! offset, and the library's answers come through.

use std::mem::{offset_of, size_of};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use vas_client_c::{
    VasGeometry, VasHandGeometry, VasHandInfo, VasMesh, VasPartInfo, VasReceived, VasSceneInfo,
};
use vas_protocol::{
    ForceFrame, GloveSample, HandFrame, HandJointsSample, InputStamp, InputStats, JointLocation,
    PartState, PartsFrameHeader, SimEvent, TrackerSample, WirePose,
};

use vas_testkit::binary;

/// The sample's folder.
fn unity_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../client-c/examples/unity")
}

/// The folder of the C library this test run built: the suite's first use of [`binary`] builds
/// every member of the workspace, and `vas-client-c`'s shared library, built as a dependency of
/// its tests, lies in the `deps` folder beside the binaries.
fn library_dir() -> PathBuf {
    let server = binary("vas-server");
    let dir = server.parent().expect("the binaries' folder").join("deps");
    assert!(
        dir.join("libvas_client.so").is_file(),
        "{} holds no libvas_client.so",
        dir.display()
    );
    dir
}

/// Runs `command`; its output once it succeeded.
fn run(command: &mut Command) -> Output {
    let output =
        (command.output()).unwrap_or_else(|error| panic!("{command:?} does not run: {error}"));
    assert!(
        output.status.success(),
        "{command:?} failed with {}:\n{}{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// A struct's line of the layout check: its C# name, size and last field's offset.
macro_rules! layout {
    ($type:ty, $name:literal, $field:ident, $last:literal) => {
        format!(
            "{} size={} {}={}",
            $name,
            size_of::<$type>(),
            $last,
            offset_of!($type, $field)
        )
    };
}

#[test]
fn the_unity_sample_compiles_and_lays_out_the_library_s_structs() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let unity = unity_dir();
    let file = |name: &str| unity.join(name).into_os_string();
    // Unity's scripts, outside Unity: the renderer compiles to nothing without UNITY_5_3_OR_NEWER.
    let library = dir.path().join("Vas.dll");
    run(Command::new("mcs")
        .args(["-target:library", "-warnaserror"])
        .arg(format!("-out:{}", library.display()))
        .args([
            file("VasNative.cs"),
            file("VasClient.cs"),
            file("VasRenderer.cs"),
        ]));
    assert!(library.is_file(), "mcs wrote no library");

    let check = dir.path().join("check.exe");
    run(Command::new("mcs")
        .arg("-warnaserror")
        .arg(format!("-out:{}", check.display()))
        .args([
            file("VasNative.cs"),
            file("VasClient.cs"),
            file("check/LayoutCheck.cs"),
        ]));
    let output = run(Command::new("mono")
        .arg(&check)
        .env("LD_LIBRARY_PATH", library_dir()));
    let printed = String::from_utf8(output.stdout).expect("UTF-8");
    let lines: Vec<&str> = printed.lines().collect();

    let expected = [
        layout!(VasReceived, "Received", geometry, "Geometry"),
        layout!(WirePose, "WirePose", rotation, "Rotation"),
        layout!(InputStamp, "InputStamp", timestamp_ns, "TimestampNs"),
        layout!(
            PartsFrameHeader,
            "PartsFrameHeader",
            part_count,
            "PartCount"
        ),
        layout!(PartState, "PartState", rotation, "Rotation"),
        layout!(HandFrame, "HandFrame", segments, "Segments"),
        layout!(SimEvent, "SimEvent", distance, "Distance"),
        layout!(ForceFrame, "ForceFrame", user, "User"),
        layout!(TrackerSample, "TrackerSample", reserved, "Reserved"),
        layout!(GloveSample, "GloveSample", side, "Side"),
        layout!(JointLocation, "JointLocation", flags, "Flags"),
        layout!(HandJointsSample, "HandJointsSample", user, "User"),
        layout!(VasMesh, "NativeMesh", triangle_count, "TriangleCount"),
        layout!(
            VasHandGeometry,
            "NativeHandGeometry",
            segment_count,
            "SegmentCount"
        ),
        layout!(VasGeometry, "NativeGeometry", hand_count, "HandCount"),
        layout!(
            InputStats,
            "InputStats",
            rejected_no_such_hand,
            "RejectedNoSuchHand"
        ),
        layout!(VasPartInfo, "NativePartInfo", scale, "Scale"),
        layout!(VasHandInfo, "NativeHandInfo", model, "Model"),
        layout!(VasSceneInfo, "NativeSceneInfo", user_count, "UserCount"),
    ];
    assert!(lines.len() > expected.len(), "{printed}");
    for (line, expected) in lines.iter().zip(&expected) {
        assert_eq!(line, expected, "C# lays a struct out unlike the library");
    }

    // vas's point (1, 2, 3) turned 90 degrees about z. Unity's (x, y, z) is vas's (x, z, y):
    // the point is (1, 3, 2); the turn's axis z becomes Unity's y, and the mirror between a
    // right- and a left-handed frame reverses its sense: a -90 degree turn about y, the
    // quaternion (0, -sqrt(1/2), 0, sqrt(1/2)).
    let unity = lines[expected.len()];
    let values: Vec<f64> = (unity
        .strip_prefix("unity position=")
        .expect("the converted pose"))
    .replace("rotation=", "")
    .split(' ')
    .map(|value| value.parse().expect("a number"))
    .collect();
    let half = 0.5f64.sqrt();
    let by_hand = [1.0, 3.0, 2.0, 0.0, -half, 0.0, half];
    assert_eq!(values.len(), by_hand.len(), "{unity}");
    for (value, by_hand) in values.iter().zip(by_hand) {
        assert!((value - by_hand).abs() < 1e-15, "{unity}");
    }
    assert_eq!(lines[expected.len() + 1], "segment 6 name=index_distal");
    assert_eq!(
        lines[expected.len() + 2],
        "null client status=NullArgument message=client is null"
    );
}
