//! `vas-client replay --lockstep --pace`: a recording played at its own timing, each sample
//! still answered before the next is sent.

use std::io::{BufRead, BufReader};
use std::process::Stdio;

use vas_client::recording::Recording;
use vas_protocol::wall_clock_ns;
use vas_testkit::{PATIENCE, Server, configs_dir, fixtures_dir};

#[test]
fn a_paced_lockstep_replay_sends_no_sample_before_its_recorded_time() {
    let fixture = fixtures_dir().join("peg_insert.jsonl");
    let recording = Recording::load(&fixture).expect("the fixture parses");
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with(
        "paced_replay",
        &["--lockstep", "--scene", scene.to_str().expect("utf-8")],
    );
    server.connect();
    let before_ns = wall_clock_ns();
    let mut replay = server.client_tool(
        &[
            "replay",
            "--lockstep",
            "--pace",
            fixture.to_str().expect("utf-8"),
        ],
        Stdio::piped(),
    );
    let stdout = replay.take_stdout().expect("piped");
    // Each answer: when the server published it, and the newest sample stamp it answers.
    let answers: Vec<(u64, u64)> = BufReader::new(stdout)
        .lines()
        .map_while(Result::ok)
        .filter_map(|line| {
            let frame: serde_json::Value = serde_json::from_str(&line).expect("a JSON line");
            let hand = frame.get("hand")?;
            let stamp = ["tracker", "glove"]
                .iter()
                .filter_map(|stream| hand[stream]["timestamp_ns"].as_u64())
                .max()?;
            Some((hand["timestamp_ns"].as_u64()?, stamp))
        })
        .collect();
    let status = replay.wait_exit(PATIENCE * 4).expect("the replay ends");
    assert!(status.success(), "{}", replay.log());
    assert_eq!(answers.len(), recording.samples.len(), "{}", replay.log());

    // Stamped as sent live: from the replay's start on, at the recorded spacing.
    let first_stamp = answers[0].1;
    assert!(
        first_stamp >= before_ns,
        "stamped before the replay started"
    );
    for ((published, stamp), recorded) in answers.iter().zip(&recording.samples) {
        assert_eq!(
            stamp - first_stamp,
            (recorded.time * 1e9).round() as u64,
            "the recorded spacing"
        );
        // Sent no earlier than its stamp, so answered after it.
        assert!(
            published >= stamp,
            "sample at {} s answered early",
            recorded.time
        );
    }
    let (last_published, _) = answers.last().expect("answers");
    assert!(
        last_published - before_ns >= recording.duration_ns(),
        "the replay took the recording's time"
    );
}
