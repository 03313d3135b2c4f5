//! The client library over real iceoryx2 services, without a server: what a client sends reaches
//! an input tap, waits end on data or timeout, and control requests without a server time out
//! without spinning.

use std::time::Duration;

use vas_client::recording::InputSample;
use vas_client::{Client, ClientError, InputTap, Wake};
use vas_protocol::{FLEX_COUNT, GloveSample, HandSide, TrackerSample, WirePose};

/// A prefix no other test (or process) uses.
fn prefix(test: &str) -> String {
    format!("vas_c{}_{test}_", std::process::id())
}

/// Removes what the test's prefix left in shared memory.
///
/// # Safety
/// Every port and node of the test on `prefix` must have been dropped.
unsafe fn forget(prefix: &str) {
    // SAFETY: as the caller guarantees; a failure leaves one small file behind.
    let _ = unsafe { vas_protocol::services::remove_prefix_segment(prefix) };
}

const PATIENCE: Duration = Duration::from_secs(5);

#[test]
fn samples_sent_by_a_client_reach_an_input_tap() {
    let prefix = prefix("tap");
    let mut tap = InputTap::connect(Some(&prefix), false).expect("tap");
    let client = Client::connect(Some(&prefix)).expect("client");
    let tracker = TrackerSample {
        seq: 1,
        timestamp_ns: 10,
        hand: WirePose {
            position: [1.0, 2.0, 3.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        },
        cart: WirePose::IDENTITY,
        sensor_id: 4,
        user: 0,
        side: 0,
        reserved: 0,
    };
    let glove = GloveSample {
        seq: 1,
        timestamp_ns: 20,
        flex: [0.25; FLEX_COUNT],
        user: 0,
        side: 0,
    };
    client.send_tracker(&tracker).expect("send tracker");
    client.send_glove(&glove).expect("send glove");

    let mut received = Vec::new();
    while received.len() < 2 {
        assert_eq!(
            tap.wait(PATIENCE).expect("wait"),
            Wake::Ready,
            "samples arrive"
        );
        received.extend(tap.receive().expect("receive"));
    }
    assert_eq!(
        received,
        [InputSample::Tracker(tracker), InputSample::Glove(glove)]
    );
    drop((tap, client));
    // SAFETY: the tap and the client were the prefix's only nodes.
    unsafe { forget(&prefix) };
}

#[test]
fn waiting_without_frames_times_out() {
    let prefix = prefix("idle");
    let mut client = Client::connect(Some(&prefix)).expect("client");
    assert_eq!(
        client.wait(Duration::from_millis(50)).expect("wait"),
        Wake::Timeout
    );
    assert_eq!(client.poll().expect("poll"), Default::default());
    assert!(client.latest_parts().is_none());
    assert!(client.latest_hands().is_empty());
    assert!(client.latest_hand_of(0, HandSide::Right).is_none());
    drop(client);
    // SAFETY: the client was the prefix's only node.
    unsafe { forget(&prefix) };
}

/// Without a server a control request times out, sent again now and then meanwhile without
/// spinning: a client waiting for a starting server leaves the processor to it.
#[test]
fn control_requests_without_a_server_time_out() {
    let prefix = prefix("noserver");
    let client = Client::connect(Some(&prefix)).expect("client");
    let cpu_before = thread_cpu_ticks();
    let error = client
        .scene_info(Duration::from_millis(500))
        .expect_err("no server answers");
    assert!(matches!(error, ClientError::Timeout { .. }), "{error}");
    let cpu = thread_cpu_ticks() - cpu_before;
    // Clock ticks are 10 ms: the wait spun if it took a fifth of its half second.
    assert!(
        cpu < 10,
        "{cpu} clock ticks of processor time in half a second"
    );
    drop(client);
    // SAFETY: the client was the prefix's only node.
    unsafe { forget(&prefix) };
}

/// The processor time this thread has used (user and system), in clock ticks: fields 14 and 15
/// of `/proc/thread-self/stat`, counted after the command name (in parentheses, and free to
/// hold spaces), whose closing parenthesis ends field 2.
fn thread_cpu_ticks() -> u64 {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").expect("the thread's stat");
    let after_name = &stat[stat.rfind(')').expect("a command name") + 1..];
    let fields: Vec<&str> = after_name.split_whitespace().collect();
    let ticks = |field: usize| -> u64 { fields[field - 3].parse().expect("a tick count") };
    ticks(14) + ticks(15)
}

#[test]
fn invalid_prefixes_are_refused() {
    let error = Client::connect(Some("no/slashes/")).err().expect("refused");
    assert!(matches!(error, ClientError::Prefix(_)), "{error}");
}
