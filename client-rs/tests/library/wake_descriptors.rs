//! The render role's wake-up descriptors, waited on with poll(2) as an engine's own loop does: a
//! stand-in server publishes a hand frame on a private prefix, and a poll quiets them again.

use std::os::fd::RawFd;
use std::time::Duration;

use iceoryx2::prelude::*;
use vas_client::{Client, ClientError, Roles};
use vas_protocol::services::{self, config_with_prefix};
use vas_protocol::{HandFrame, HandSide};

/// How long poll(2) may wait for a notification that was sent.
const PATIENCE: Duration = Duration::from_secs(5);

/// How many of `descriptors` poll(2) reports readable within `timeout`.
fn readable(descriptors: &[RawFd], timeout: Duration) -> usize {
    let mut polled: Vec<libc::pollfd> = (descriptors.iter())
        .map(|&fd| libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        })
        .collect();
    let millis = libc::c_int::try_from(timeout.as_millis()).expect("a short time-out");
    // SAFETY: `polled` holds `polled.len()` initialised entries for the call's duration.
    let ready = unsafe { libc::poll(polled.as_mut_ptr(), polled.len() as libc::nfds_t, millis) };
    assert!(ready >= 0, "poll: {}", std::io::Error::last_os_error());
    assert!(
        polled
            .iter()
            .all(|entry| entry.revents & !libc::POLLIN == 0),
        "an error on a descriptor: {polled:?}"
    );
    ready as usize
}

#[test]
fn descriptors_are_readable_from_a_publish_until_a_poll() {
    let prefix = format!("vas_c{}_wakefd_", std::process::id());
    let node = NodeBuilder::new()
        .config(&config_with_prefix(Some(&prefix)).expect("a prefix"))
        .create::<ipc::Service>()
        .expect("the stand-in server's node");
    let hand = services::open_hand(&node).expect("the hand service");
    let publisher = (hand.publisher_builder().create()).expect("a hand publisher");
    let notifier = (services::open_wakeup(&node, services::HAND).expect("the hand wake-up"))
        .notifier_builder()
        .create()
        .expect("a hand notifier");

    let mut client = (Client::builder().prefix(Some(&prefix)))
        .roles(Roles::RENDER)
        .connect()
        .expect("client");
    let descriptors = client.wake_descriptors().expect("descriptors");
    assert_eq!(descriptors.len(), 6, "one per output service");
    assert_eq!(
        readable(&descriptors, Duration::ZERO),
        0,
        "nothing published"
    );

    let frame = HandFrame {
        frame: 7,
        hand: HandSide::Right as u32,
        ..HandFrame::default()
    };
    publisher.send_copy(frame).expect("publish");
    notifier.notify().expect("notify");
    assert_eq!(readable(&descriptors, PATIENCE), 1, "the hand's descriptor");
    assert_eq!(client.poll().expect("poll").hand, 1);
    assert_eq!(client.latest_hand_of(0, HandSide::Right), Some(&frame));
    assert_eq!(
        readable(&descriptors, Duration::ZERO),
        0,
        "quiet after a poll"
    );

    // Each publish wakes them again; receive quiets them as poll does.
    publisher.send_copy(frame).expect("publish");
    notifier.notify().expect("notify");
    assert_eq!(readable(&descriptors, PATIENCE), 1, "woken again");
    assert_eq!(client.receive().expect("receive").len(), 1);
    assert_eq!(
        readable(&descriptors, Duration::ZERO),
        0,
        "quiet after a receive"
    );

    drop((client, notifier, publisher, hand, node));
    // SAFETY: the client and the stand-in server were the prefix's only nodes.
    let _ = unsafe { services::remove_prefix_segment(&prefix) };
}

#[test]
fn descriptors_need_the_render_role() {
    let prefix = format!("vas_c{}_wakefd_control_", std::process::id());
    let client = (Client::builder().prefix(Some(&prefix)))
        .roles(Roles::CONTROL)
        .connect()
        .expect("client");
    let error = client.wake_descriptors().expect_err("no render role");
    assert!(matches!(error, ClientError::MissingRole { .. }), "{error}");
    drop(client);
    // SAFETY: the client was the prefix's only node.
    let _ = unsafe { services::remove_prefix_segment(&prefix) };
}
