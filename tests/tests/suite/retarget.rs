//! `vas-server retarget` on the real hand captures: each calibrated on the other, as captured
//! (left hands) and mirrored (right hands), its JSON report within the retargeting's bar.

use std::process::Command;

use vas_testkit::{binary, fixtures_dir};

/// Runs `vas-server retarget` with `args` and a JSON report, and returns the report.
fn retarget(args: &[&str]) -> serde_json::Value {
    let out = tempfile::NamedTempFile::new().expect("a scratch file");
    let output = Command::new(binary("vas-server"))
        .arg("retarget")
        .args(args)
        .arg("--json")
        .arg(out.path())
        .output()
        .expect("vas-server runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "retarget {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains("fingertip error (mm):"), "{stdout}");
    serde_json::from_str(&std::fs::read_to_string(out.path()).expect("the report")).expect("JSON")
}

#[test]
fn retarget_reports_fingertips_within_the_bar_on_real_captures() {
    let hands = fixtures_dir().join("hands");
    let path = |name: &str| hands.join(name).to_string_lossy().into_owned();
    let (pinch, relaxed) = (path("webxr_pinch.json"), path("webxr_relaxed.json"));
    for (capture, calibration) in [(&pinch, &relaxed), (&relaxed, &pinch)] {
        for mirror in [false, true] {
            let mut args = vec![capture.as_str(), "--calibrate", calibration.as_str()];
            if mirror {
                args.push("--mirror");
            }
            let report = retarget(&args);
            let side = if mirror { "right" } else { "left" };
            assert_eq!(report["side"], side, "{report}");
            assert!(
                report["hand"]
                    .as_str()
                    .unwrap()
                    .ends_with(&format!("{side}.toml")),
                "the model of the capture's side: {report}"
            );
            let rms = report["fingertip_rms_mm"].as_f64().unwrap();
            let max = report["fingertip_max_mm"].as_f64().unwrap();
            assert!(rms <= 5.0 && max <= 10.0, "{args:?}: {report}");
            let angles = report["angles_deg"].as_object().unwrap();
            assert_eq!(angles.len(), 22);
            assert!(angles["index inner (MCP)"].as_f64().unwrap().is_finite());
            let fingertips = report["fingertip_mm"].as_object().unwrap();
            assert_eq!(fingertips.len(), 5);
            let largest = fingertips
                .values()
                .map(|v| v.as_f64().unwrap())
                .fold(0.0, f64::max);
            assert_eq!(largest, max);
        }
    }
    // The pinch closes the index finger more than the relaxed hand.
    let index = |capture: &str| {
        retarget(&[capture])["angles_deg"]["index inner (MCP)"]
            .as_f64()
            .unwrap()
    };
    assert!(index(&pinch) > index(&relaxed) + 20.0);
}

#[test]
fn retarget_refuses_a_malformed_capture_with_the_reason() {
    let dir = tempfile::tempdir().expect("a scratch folder");
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, r#"{"joints": []}"#).unwrap();
    let output = Command::new(binary("vas-server"))
        .arg("retarget")
        .arg(&bad)
        .output()
        .expect("vas-server runs");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("bad.json: joints: expected 25 joints"),
        "{stderr}"
    );
}
