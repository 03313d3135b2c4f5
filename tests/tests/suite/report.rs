//! `vas-server report` on `peg_insert.jsonl`: the peg–block minimum clearance it reports is
//! parry's distance at the published poses, at its sample and over the whole session; the HTML
//! page opens in the headless browser with its summary rows; bad inputs fail with a clear
//! message and a non-zero exit, never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use nalgebra::Isometry3;
use parry3d::query::distance;
use vas_client::recording::{InputSample, Recording};
use vas_server::collision::parry_mesh::{ORACLE_SCALE, millimetre_pose, millimetre_trimesh};
use vas_server::replay::{Outcome, Replay};
use vas_server::scene::Scene;
use vas_testkit::browser::Browser;
use vas_testkit::{binary, fixtures_dir};

/// A report's minimum and parry's distance agree to this, metres (the bar: 1 um).
const AGREEMENT_M: f64 = 1e-6;

fn repository() -> PathBuf {
    fixtures_dir().join("../..")
}

fn peg_insert() -> (PathBuf, PathBuf) {
    (
        repository().join("configs/peg_insert.toml"),
        fixtures_dir().join("peg_insert.jsonl"),
    )
}

fn run_report(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(binary("vas-server"))
        .arg("report")
        .args(args)
        .output()
        .expect("vas-server runs")
}

/// Every part's published pose per sample of the recording, by the library's replay.
fn poses_by_sample(scene: &Scene, recording: &Recording) -> Vec<(usize, Vec<Isometry3<f64>>)> {
    let mut replay = Replay::new(scene).expect("the scene has a hand");
    let mut frames = Vec::new();
    for (index, recorded) in recording.samples.iter().enumerate() {
        let outcome = match &recorded.input {
            InputSample::Tracker(sample) => replay.tracker(sample),
            InputSample::Glove(sample) => replay.glove(sample),
            InputSample::HandJoints(sample) => replay.hand_joints(sample),
        }
        .expect("replays");
        if let Outcome::Stepped(_) = outcome {
            let interaction = replay.interaction().expect("placed");
            frames.push((index, interaction.part_poses().collect()));
        }
    }
    frames
}

#[test]
fn the_peg_block_minimum_clearance_is_parrys_distance() {
    let (scene_path, recording_path) = peg_insert();
    let scratch = tempfile::tempdir().expect("a scratch folder");
    let json = scratch.path().join("report.json");
    let html = scratch.path().join("report.html");
    let output = run_report(&[
        "--scene".as_ref(),
        scene_path.as_os_str(),
        recording_path.as_os_str(),
        "--json".as_ref(),
        json.as_os_str(),
        "--html".as_ref(),
        html.as_os_str(),
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "report failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the JSON")).expect("JSON");
    let pair = (report["pairs"].as_array().expect("pairs").iter())
        .find(|pair| pair["a"] == "block" && pair["b"] == "peg")
        .unwrap_or_else(|| panic!("no block–peg pair in {report}"));
    let reported = pair["minimum"]["clearance_m"].as_f64().expect("a minimum");
    let at_sample = pair["minimum"]["sample"].as_u64().expect("a sample") as usize;

    let scene = Scene::load(&scene_path).expect("the scene loads");
    let recording = Recording::load(&recording_path).expect("the recording loads");
    let (block, peg) = (0, 1);
    let meshes = [
        millimetre_trimesh(&scene.parts[block].mesh),
        millimetre_trimesh(&scene.parts[peg].mesh),
    ];
    let parry_distance = |poses: &[Isometry3<f64>]| {
        let (pose_block, pose_peg) = (millimetre_pose(&poses[block]), millimetre_pose(&poses[peg]));
        let mm = distance(&pose_block, &meshes[0], &pose_peg, &meshes[1]).expect("mesh pairs");
        f64::from(mm) / ORACLE_SCALE
    };
    let frames = poses_by_sample(&scene, &recording);
    let (_, at) = (frames.iter())
        .find(|(sample, _)| *sample == at_sample)
        .expect("the reported sample has a frame");
    let there = parry_distance(at);
    let lowest = (frames.iter())
        .map(|(_, poses)| parry_distance(poses))
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "block–peg: reported {reported:.9} m at sample {at_sample}; parry there {there:.9} m, \
         parry's minimum over {} frames {lowest:.9} m\n{stdout}",
        frames.len()
    );
    assert!(
        (reported - there).abs() <= AGREEMENT_M,
        "{reported} vs {there}"
    );
    assert!(
        (reported - lowest).abs() <= AGREEMENT_M,
        "{reported} vs {lowest}"
    );
    assert_eq!(pair["clash_frames"], 0, "{pair}");
    assert!(stdout.contains("block – peg"), "{stdout}");

    tokio::runtime::Runtime::new()
        .expect("a runtime")
        .block_on(summary_rows_in_the_browser(&html));
}

/// Opens the page in headless Chromium and reads the summary table's rows from the DOM.
async fn summary_rows_in_the_browser(html: &Path) {
    let browser = Browser::start(1024, 768).await;
    browser
        .client
        .goto(&format!("file://{}", html.display()))
        .await
        .expect("the page opens");
    let rows: Vec<Vec<String>> = browser
        .eval(
            "Array.from(document.querySelectorAll('#summary tbody tr.pair'))\
             .map(row => Array.from(row.cells).map(cell => cell.textContent))",
        )
        .await;
    let figures: usize = browser
        .eval("document.querySelectorAll('figure svg').length")
        .await;
    browser.close().await;
    assert!(
        rows.iter().any(|row| row[0] == "block" && row[1] == "peg"),
        "{rows:?}"
    );
    assert_eq!(figures, rows.len(), "one timeline per pair");
}

#[test]
fn bad_inputs_fail_with_a_message_and_no_panic() {
    let (scene_path, recording_path) = peg_insert();
    let other_scene = repository().join("configs/push.toml");
    let cases: [(&str, Vec<&std::ffi::OsStr>, &str); 4] = [
        (
            "missing scene",
            vec![
                "--scene".as_ref(),
                "no/such/scene.toml".as_ref(),
                recording_path.as_os_str(),
            ],
            "no/such/scene.toml",
        ),
        (
            "another scene's recording",
            vec![
                "--scene".as_ref(),
                other_scene.as_os_str(),
                recording_path.as_os_str(),
            ],
            "was recorded in scene",
        ),
        (
            "non-finite clearance",
            vec![
                "--scene".as_ref(),
                scene_path.as_os_str(),
                recording_path.as_os_str(),
                "--clearance".as_ref(),
                "nan".as_ref(),
            ],
            "a clearance must be above 0",
        ),
        (
            "unwritable output",
            vec![
                "--scene".as_ref(),
                scene_path.as_os_str(),
                recording_path.as_os_str(),
                "--html".as_ref(),
                "/no/such/folder/report.html".as_ref(),
            ],
            "cannot write",
        ),
    ];
    for (what, args, says) in cases {
        let output = run_report(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{what}: succeeded");
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
        assert!(stderr.contains(says), "{what}: {stderr}");
    }
}
