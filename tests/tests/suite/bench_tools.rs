//! The benchmarks of `vas-bench` against real servers: a short `e2e`, a short `soak`, the tree
//! build and a small `assembly` produce complete reports. Figures are not checked (speed is for benchmarks, not
//! tests), only that every sample was measured and the reports hang together.

use std::process::Stdio;

use vas_testkit::{PATIENCE, Server};

fn report(path: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).expect("the report is written");
    serde_json::from_str(&text).expect("the report is JSON")
}

/// The SVG figure exists and names every series in its legend.
fn assert_plot(path: &std::path::Path, series: &[&str]) {
    let svg = std::fs::read_to_string(path).expect("the figure is written");
    assert!(svg.starts_with("<svg"), "{}", path.display());
    for name in series {
        assert!(svg.contains(name), "{} lacks {name}", path.display());
    }
}

fn run_tool(server: &Server, args: &[&str]) {
    let mut tool = server.bench_tool(args, Stdio::null());
    let status = tool.wait_exit(PATIENCE).expect("the tool ends");
    assert!(status.success(), "{}", tool.log());
}

/// Runs `vas-bench e2e` with 40 measured samples (and `extra` arguments) against `server`,
/// writing into `dir`; checks that every path (`raw`, `c` with `--c-library`, `vas`) answered
/// every sample with ordered percentiles and returns the report.
fn short_e2e(server: &Server, dir: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let e2e_out = dir.join("b7.json");
    let e2e_svg = dir.join("b7.svg");
    let mut args = vec![
        "e2e",
        "--samples",
        "40",
        "--warmup",
        "5",
        "--json",
        e2e_out.to_str().expect("utf-8"),
        "--svg",
        e2e_svg.to_str().expect("utf-8"),
    ];
    args.extend_from_slice(extra);
    run_tool(server, &args);
    let e2e = report(&e2e_out);
    let expected_paths: &[&str] = match extra.contains(&"--c-library") {
        true => &["raw", "c", "vas"],
        false => &["raw", "vas"],
    };
    assert_plot(&e2e_svg, expected_paths);
    let rows = e2e["rows"].as_array().expect("rows");
    let paths: Vec<&str> = rows
        .iter()
        .map(|row| row["path"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(paths, expected_paths);
    for row in rows {
        assert_eq!(row["samples"], 40, "{row}");
        assert_eq!(row["unanswered"], 0, "{row}");
        let [p50, p99, max] = ["p50_us", "p99_us", "max_us"].map(|key| {
            row[key]
                .as_f64()
                .unwrap_or_else(|| panic!("{key} in {row}"))
        });
        assert!(0.0 < p50 && p50 <= p99 && p99 <= max, "{row}");
    }
    assert!(
        e2e["vas_samples_per_s"]
            .as_f64()
            .is_some_and(|rate| rate > 0.0),
        "{e2e}"
    );
    e2e
}

#[test]
fn bench_e2e_and_a_short_soak_report_every_sample() {
    let mut server = Server::start("benchtools");
    server.connect();
    let dir = tempfile::tempdir().expect("temporary directory");

    let e2e = short_e2e(&server, dir.path(), &[]);
    assert_eq!(e2e["input"], "synthetic tracker");

    let soak_out = dir.path().join("soak.json");
    let soak_svg = dir.path().join("soak.svg");
    let pid = server.process.id().to_string();
    run_tool(
        &server,
        &[
            "soak",
            "--rate",
            "100",
            "--seconds",
            "2",
            "--server-pid",
            &pid,
            "--json",
            soak_out.to_str().expect("utf-8"),
            "--svg",
            soak_svg.to_str().expect("utf-8"),
        ],
    );
    let soak = report(&soak_out);
    assert_plot(&soak_svg, &["resident memory"]);
    for stream in ["tracker", "glove"] {
        let count = &soak[stream];
        assert_eq!(count["sent"], 200, "{soak}");
        let parts = ["answered", "superseded", "dropped"].map(|key| count[key].as_u64());
        assert_eq!(
            parts.iter().copied().sum::<Option<u64>>(),
            Some(200),
            "{soak}"
        );
    }
    // The server answers every sample, or merges it into the frame of a newer one of its stream
    // when that one arrives first (superseded: the latest wins); a sample counts as dropped only
    // when the frames that answered it were lost in the soak's own full buffer, which its frame
    // numbering reveals.
    let dropped = soak["dropped"].as_u64().expect("dropped");
    let missed = soak["frames_missed_by_client"]
        .as_u64()
        .expect("missed frames");
    assert!(dropped <= missed, "{soak}");
    let memory = &soak["memory"];
    let samples = memory["samples"].as_array().expect("memory samples");
    // Start, one per second, end.
    assert!(samples.len() >= 3, "{memory}");
    assert!(
        memory["start_kib"].as_u64().is_some_and(|kib| kib > 0),
        "{memory}"
    );
    assert!(memory["growth_kib_per_min"].is_f64(), "{memory}");
}

/// B7 with two hands' joints: every sample of both hands answered on both paths, each accepted
/// by the server as a hand of the scene.
#[test]
fn bench_e2e_takes_two_hands_joints() {
    let scene = vas_testkit::configs_dir().join("two_hand_handover.toml");
    let mut server =
        Server::start_with("benchjoints", &["--scene", scene.to_str().expect("utf-8")]);
    let client = server.connect();
    let dir = tempfile::tempdir().expect("temporary directory");
    let e2e = short_e2e(&server, dir.path(), &["--hand-joints"]);
    assert_eq!(e2e["input"], "synthetic hand joints, two hands");
    let stats = client.input_stats(PATIENCE).expect("input counters");
    assert_eq!(
        (
            stats.joints_accepted,
            stats.rejected(),
            stats.joints_untracked
        ),
        (45, 0, 0)
    );
}

/// B7 with the C library's path: the `raw` path's samples through the C library's calls, every
/// one answered, and the p99 it adds reported as the `c` row's less the `raw` row's.
#[test]
fn bench_e2e_measures_the_c_library() {
    let mut server = Server::start("benchclib");
    server.connect();
    let dir = tempfile::tempdir().expect("temporary directory");
    let e2e = short_e2e(&server, dir.path(), &["--c-library"]);
    let p99 = |row: usize| e2e["rows"][row]["p99_us"].as_f64().expect("a p99");
    let added = e2e["c_library_p99_added_us"].as_f64();
    assert_eq!(added, Some(p99(1) - p99(0)), "{e2e}");
}

/// `tree-build` reports each mesh's DOP-tree build and, when FCL was found as vas-bench was
/// built, FCL's; the ratio is against FCL's median exactly when FCL was measured.
#[test]
fn bench_tree_build_reports_each_mesh() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let (json, svg) = (dir.path().join("build.json"), dir.path().join("build.svg"));
    let bunny = vas_testkit::configs_dir().join("meshes/low_poly_bunny.obj");
    let meshes = format!("shape:sphere:2000,{}", bunny.display());
    let output = std::process::Command::new(vas_testkit::binary("vas-bench"))
        .args(["tree-build", "--runs", "1", "--meshes", &meshes, "--json"])
        .arg(&json)
        .arg("--svg")
        .arg(&svg)
        .output()
        .expect("vas-bench runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_plot(&svg, &["DOP-tree, 1 thread", "FCL OBB-tree"]);
    let rows = report(&json);
    let triangles: Vec<u64> = (rows.as_array().expect("rows").iter())
        .map(|row| row["triangles"].as_u64().expect("triangles"))
        .collect();
    assert_eq!(triangles, [2000, 696]);
    for row in rows.as_array().expect("rows") {
        let number = |key: &str| {
            row[key]
                .as_f64()
                .unwrap_or_else(|| panic!("{key} in {row}"))
        };
        assert!(number("dop_1_thread_s") > 0.0 && number("dop_all_threads_s") > 0.0);
        // Nodes, boxes and offsets of about two nodes a triangle, and the triangle itself.
        assert!(number("dop_bytes_per_triangle") > 100.0, "{row}");
        let fcl = row["fcl_obb_s"].as_f64();
        assert_eq!(
            row["ratio_measured"].as_bool(),
            Some(fcl.is_some()),
            "{row}"
        );
        let against = fcl.unwrap_or(2.5);
        assert!(
            (number("ratio") - number("dop_all_threads_s") / against).abs() < 1e-9,
            "{row}"
        );
        assert!(
            (number("ratio_1_thread") - number("dop_1_thread_s") / against).abs() < 1e-9,
            "{row}"
        );
        if fcl.is_some() {
            assert!(number("fcl_bytes_per_triangle") > 0.0, "{row}");
        }
    }
}

/// `assembly` at a small scale: 30 parts and 200,000 triangles generated, the server started on
/// them cold and with the tree cache it filled, and the bar grasped and slid along the right side
/// panel for a second at 1 kHz; parry finds none of its published poses penetrating.
#[test]
fn bench_assembly_grasps_and_slides_the_bar_without_penetration() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let (json, svg) = (dir.path().join("b8.json"), dir.path().join("b8.svg"));
    let output = std::process::Command::new(vas_testkit::binary("vas-bench"))
        .args([
            "assembly",
            "--parts",
            "30",
            "--triangles",
            "200000",
            "--seconds",
            "1",
        ])
        .args(["--timeout-s", "60", "--hand"])
        .arg(vas_testkit::configs_dir().join("hands/right.toml"))
        .arg("--json")
        .arg(&json)
        .arg("--svg")
        .arg(&svg)
        .output()
        .expect("vas-bench runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_plot(
        &svg,
        &[
            "median of 50 ms",
            "longest of 50 ms",
            "grasped",
            "slide starts",
        ],
    );
    let report = report(&json);
    let number = |key: &str| {
        report[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} in {report}"))
    };
    for key in [
        "ready_s_cold",
        "ready_s_cached",
        "peak_rss_mb",
        "bytes_per_triangle",
        "grasping_hz",
        "grasping_p99_us",
        "sliding_hz",
        "sliding_p99_us",
        "collision_hz",
        "collision_p99_us",
        "e2e_p99_us",
    ] {
        assert!(number(key) > 0.0, "{key} in {report}");
    }
    assert_eq!(
        (report["parts"].as_u64(), report["triangles"].as_u64()),
        (Some(30), Some(200_000)),
        "{report}"
    );
    // A tree a part: every generated mesh differs.
    assert_eq!(report["tree_cache_files"].as_u64(), Some(30), "{report}");
    assert_eq!(report["grasped"].as_bool(), Some(true), "{report}");
    assert_eq!(report["unanswered"].as_u64(), Some(0), "{report}");
    assert!(number("checked_poses") > 100.0, "{report}");
    assert_eq!(report["penetrations"].as_u64(), Some(0), "{report}");
    // The slide takes the bar 40 cm forward and 10 cm up and down along the panel.
    assert!(number("sliding_frames") > 100.0, "{report}");
    assert!(number("slid_m") > 0.3, "{report}");
}
