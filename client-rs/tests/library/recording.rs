//! The recording format: what the writer writes, the loader reads back, and what it refuses.

use std::io::Write;

use vas_client::recording::{
    FORMAT, InputSample, RecordedSample, Recording, RecordingError, RecordingHeader,
    RecordingWriter, VERSION,
};
use vas_protocol::{
    FLEX_COUNT, GloveSample, HandJointsSample, HandSide, JOINT_ORIENTATION_VALID,
    JOINT_POSITION_VALID, JointLocation, TrackerSample, WirePose,
};

fn tracker(seq: u64, timestamp_ns: u64) -> InputSample {
    InputSample::Tracker(TrackerSample {
        seq,
        timestamp_ns,
        hand: WirePose {
            position: [0.1 * seq as f64, -0.2, 0.3],
            rotation: [0.0, 0.6, 0.0, 0.8],
        },
        cart: WirePose::IDENTITY,
        sensor_id: 1,
        user: 0,
        side: 0,
        reserved: 0,
    })
}

fn glove(seq: u64, timestamp_ns: u64) -> InputSample {
    let mut flex = [0.0; FLEX_COUNT];
    flex[5] = 0.5 + seq as f32 * 0.01;
    InputSample::Glove(GloveSample {
        seq,
        timestamp_ns,
        flex,
        user: 0,
        side: 0,
    })
}

fn hand_joints(seq: u64, timestamp_ns: u64) -> InputSample {
    let joint = |i: usize| JointLocation {
        position: [0.01 * i as f64, 0.0, -0.02 * seq as f64],
        rotation: [0.0, 0.0, 0.6, 0.8],
        radius: 0.008,
        flags: JOINT_POSITION_VALID | JOINT_ORIENTATION_VALID,
    };
    InputSample::HandJoints(HandJointsSample {
        seq,
        timestamp_ns,
        joints: std::array::from_fn(joint),
        side: HandSide::Left as u32,
        user: 0,
    })
}

#[test]
fn written_recordings_load_back_with_times_from_the_timestamps() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("take.jsonl");
    let header = RecordingHeader::new("demo", "reach and grasp");
    let inputs = [
        tracker(1, 5_000_000_000),
        glove(1, 5_010_000_000),
        tracker(2, 5_020_000_000),
        // The sender's clock steps back: the time holds instead of going back.
        glove(2, 5_015_000_000),
        hand_joints(1, 5_030_000_000),
    ];
    let mut writer = RecordingWriter::create(&path, &header).expect("create");
    for input in &inputs {
        writer.write(input).expect("write");
    }
    drop(writer);

    let recording = Recording::load(&path).expect("load");
    assert_eq!(recording.header, header);
    assert_eq!(recording.header.format, FORMAT);
    assert_eq!(recording.header.version, VERSION);
    let loaded: Vec<_> = recording.samples.iter().map(|s| s.input).collect();
    assert_eq!(loaded, inputs);
    let times: Vec<_> = recording.samples.iter().map(|s| s.time).collect();
    let expected = [0.0, 0.01, 0.02, 0.02, 0.03];
    for (time, expected) in times.iter().zip(expected) {
        assert!((time - expected).abs() < 1e-9, "{times:?}");
    }
}

#[test]
fn every_number_reads_back_exactly_as_written() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("exact.jsonl");
    let InputSample::HandJoints(mut sample) = hand_joints(1, 0) else {
        unreachable!("built as a hand-joints sample")
    };
    // Values whose shortest decimal form the default float parser reads an ulp off.
    sample.joints[0].rotation = [
        0.028114062452158094,
        -0.13945532529925805,
        0.9263732154469696,
        0.18353810463444512,
    ];
    let written = [InputSample::HandJoints(sample)];
    let mut writer =
        RecordingWriter::create(&path, &RecordingHeader::new("s", "")).expect("create");
    writer.write(&written[0]).expect("write");
    drop(writer);
    let read: Vec<_> = (Recording::load(&path).expect("load").samples.iter())
        .map(|s| s.input)
        .collect();
    assert_eq!(read, written);
}

#[test]
fn a_replay_stamps_samples_at_their_recorded_times() {
    let sample = RecordedSample {
        time: 0.25,
        input: glove(3, 77),
    };
    let sent = sample.stamped(1_000);
    assert_eq!(sent.timestamp_ns(), 250_001_000);
    assert_eq!(sent.seq(), 3);
    let recording = Recording {
        header: RecordingHeader::new("s", ""),
        samples: vec![sample],
    };
    assert_eq!(recording.duration_ns(), 250_000_000);
}

#[test]
fn sample_lines_name_their_stream() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("one.jsonl");
    let mut writer =
        RecordingWriter::create(&path, &RecordingHeader::new("s", "")).expect("create");
    writer.write(&glove(4, 1)).expect("write");
    drop(writer);
    let text = std::fs::read_to_string(&path).expect("read");
    let lines: Vec<_> = text.lines().collect();
    assert_eq!(lines.len(), 2);
    assert!(
        lines[0].starts_with(r#"{"format":"vas-recording","version":2"#),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with(r#"{"time":0.0,"glove":{"seq":4"#),
        "{}",
        lines[1]
    );
}

#[test]
fn non_finite_samples_are_refused_by_the_writer() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("nan.jsonl");
    let mut writer =
        RecordingWriter::create(&path, &RecordingHeader::new("s", "")).expect("create");
    let InputSample::Tracker(mut sample) = tracker(9, 1) else {
        unreachable!("built as a tracker sample")
    };
    sample.hand.position[1] = f64::NAN;
    let error = writer
        .write(&InputSample::Tracker(sample))
        .expect_err("NaN refused");
    assert!(
        matches!(error, RecordingError::NonFinite { seq: 9, .. }),
        "{error}"
    );
}

fn write_file(lines: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("input.jsonl");
    let mut file = std::fs::File::create(&path).expect("create");
    for line in lines {
        writeln!(file, "{line}").expect("write");
    }
    (dir, path)
}

fn load_error(lines: &[&str]) -> String {
    let (_dir, path) = write_file(lines);
    let error = Recording::load(&path).expect_err("invalid recording");
    assert!(
        error.to_string().contains("input.jsonl"),
        "names the file: {error}"
    );
    error.to_string()
}

#[test]
fn invalid_recordings_are_refused_naming_file_and_line() {
    let header = r#"{"format":"vas-recording","version":1,"scene":"s","description":""}"#;
    let glove_line = |time: &str| {
        format!(
            r#"{{"time":{time},"glove":{{"seq":1,"timestamp_ns":0,"flex":[{}]}}}}"#,
            ["0.0"; FLEX_COUNT].join(",")
        )
    };
    assert!(load_error(&[]).contains("empty"));
    assert!(
        load_error(&[r#"{"format":"other","version":1,"scene":"s","description":""}"#])
            .contains(":1:")
    );
    assert!(
        load_error(&[r#"{"format":"vas-recording","version":3,"scene":"s","description":""}"#])
            .contains("version 3")
    );
    // Hand-joints samples came with version 2.
    let InputSample::HandJoints(sample) = hand_joints(1, 0) else {
        unreachable!("built as a hand-joints sample")
    };
    let joints_line = format!(
        r#"{{"time":0.0,"hand_joints":{}}}"#,
        serde_json::to_string(&sample).expect("serialises")
    );
    assert!(load_error(&[header, &joints_line]).contains(":2: a hand-joints sample"));
    let version_2 = r#"{"format":"vas-recording","version":2,"scene":"s","description":""}"#;
    let (_dir, path) = write_file(&[version_2, &joints_line, &glove_line("0.0")]);
    assert_eq!(Recording::load(&path).expect("valid").samples.len(), 2);
    assert!(load_error(&[header, r#"{"time":0.0,"mouse":{}}"#]).contains(":2:"));
    let (late, early) = (glove_line("0.5"), glove_line("0.25"));
    assert!(load_error(&[header, &late, &early]).contains(":3:"));
    // A well-formed file with a blank line loads.
    let (_dir, path) = write_file(&[header, "", &glove_line("0.0")]);
    assert_eq!(Recording::load(&path).expect("valid").samples.len(), 1);
}

#[test]
fn values_beyond_the_range_of_their_type_are_refused() {
    // A glove value beyond f32's range was read as infinity, and the recording loaded.
    let header = r#"{"format":"vas-recording","version":1,"scene":"s","description":""}"#;
    let mut flex = ["0.0"; FLEX_COUNT];
    flex[3] = "1e39";
    let line = format!(
        r#"{{"time":0.0,"glove":{{"seq":1,"timestamp_ns":0,"flex":[{}]}}}}"#,
        flex.join(",")
    );
    let error = load_error(&[header, &line]);
    assert!(error.contains(":2: a value is beyond the range"), "{error}");
}
