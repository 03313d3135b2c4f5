//! The two-user hand-over across two zenoh peers: anna's samples (tracker and glove) come from
//! one zenoh session and ben's (hand joints) from another, each connected to a `vas-bridge` on
//! loopback that takes input for those two users alone. Replayed twice in lockstep (each sample
//! after the answer to the previous one, whichever peer sent it) and judged as the local replay
//! is ([`check_through`]): the grasps, the hand-over and the release in order with their users,
//! no penetration by parry in any published frame, the same on the second replay. Each peer
//! receives every event over zenoh as well, in the server's order; a sample of a user the bridge
//! does not take is refused and counted, and never reaches the server.

use std::time::{Duration, Instant};

use vas_bridge::keys::{Input, Keys};
use vas_bridge::stats::StatsSnapshot;
use vas_bridge::wire::{self, Message};
use vas_client::Client;
use vas_client::recording::{InputSample, Recording};
use vas_protocol::{SimEvent, services};
use vas_testkit::{PATIENCE, Server, Spawned};
use zenoh::Wait;
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::Sample;

use super::bridge::{endpoint, start_bridge};
use super::replays::{Inputs, Replay, check_through, identity, scenario};

/// The zenoh session name of the test.
const SESSION: &str = "two-users";

/// Room for every event of both replays in a peer's queue, so that zenoh never waits for the
/// test to read them.
const EVENT_QUEUE: usize = 4096;

/// One user's machine: a zenoh peer of its own, publishing that user's samples and hearing the
/// session's events.
struct Peer {
    /// Publishers of the tracker, glove and hand-joints streams, in [`Input::ALL`]'s order.
    publishers: Vec<Publisher<'static>>,
    events: Subscriber<FifoChannelHandler<Sample>>,
    session: zenoh::Session,
}

impl Peer {
    /// A peer connected to the bridge at `endpoint` alone, once each of its publishers is
    /// matched by the bridge's input subscriber (a sample published before would be lost).
    fn connect(endpoint: &str, keys: &Keys) -> Self {
        let mut config = zenoh::Config::default();
        for (key, value) in [
            ("mode", "\"peer\"".to_owned()),
            ("connect/endpoints", format!("[\"{endpoint}\"]")),
            ("scouting/multicast/enabled", "false".to_owned()),
        ] {
            config.insert_json5(key, &value).expect("a zenoh setting");
        }
        let session = zenoh::open(config).wait().expect("a zenoh session");
        let publishers: Vec<Publisher<'static>> = (Input::ALL.iter())
            .map(|&stream| {
                (session.declare_publisher(keys.input(stream)))
                    .congestion_control(CongestionControl::Block)
                    .express(true)
                    .wait()
                    .expect("a publisher")
            })
            .collect();
        let events = (session.declare_subscriber(keys.service(services::EVENTS)))
            .with(zenoh::handlers::FifoChannel::new(EVENT_QUEUE))
            .wait()
            .expect("an events subscriber");
        let deadline = Instant::now() + PATIENCE;
        for publisher in &publishers {
            while !publisher
                .matching_status()
                .wait()
                .expect("status")
                .matching()
            {
                assert!(Instant::now() < deadline, "the bridge never subscribed");
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        Self {
            publishers,
            events,
            session,
        }
    }

    /// Publishes `sample` on `stream`'s key, in the bridge's wire encoding.
    fn put<T: Message>(&self, stream: Input, sample: &T) {
        (self.publishers[stream as usize].put(wire::encode(sample)))
            .wait()
            .expect("publish a sample");
    }

    /// Every event heard, once there are `count`; fails after [`PATIENCE`] with fewer.
    fn events(&self, count: usize) -> Vec<[u32; 6]> {
        let deadline = Instant::now() + PATIENCE;
        let mut events = Vec::new();
        while events.len() < count {
            let left = deadline.saturating_duration_since(Instant::now());
            let Ok(Some(sample)) = self.events.recv_timeout(left) else {
                panic!("{} of {count} events came over zenoh", events.len());
            };
            let event: SimEvent =
                wire::decode(&sample.payload().to_bytes()).expect("an event as specified");
            events.push(identity(&event));
        }
        events
    }

    /// The bridge's counters, asked over zenoh.
    fn bridge_stats(&self, keys: &Keys) -> StatsSnapshot {
        let replies = (self.session.get(keys.stats()))
            .timeout(PATIENCE)
            .wait()
            .expect("a stats query");
        let reply = replies.recv().expect("the bridge answers its stats");
        let payload = reply.result().expect("stats").payload().to_bytes();
        serde_json::from_slice(&payload).expect("the counters as JSON")
    }
}

/// The bridge and one peer per user (by the scene's user index).
struct Remote {
    keys: Keys,
    peers: Vec<Peer>,
    /// Declared last, dropped last: the peers leave before the bridge.
    bridge: Spawned,
}

impl Inputs for Remote {
    fn send(&mut self, _client: &Client, input: &InputSample) {
        let user = match input {
            InputSample::Tracker(sample) => sample.user,
            InputSample::Glove(sample) => sample.user,
            InputSample::HandJoints(sample) => sample.user,
        };
        let peer = &self.peers[user as usize];
        match input {
            InputSample::Tracker(sample) => peer.put(Input::Tracker, sample),
            InputSample::Glove(sample) => peer.put(Input::Glove, sample),
            InputSample::HandJoints(sample) => peer.put(Input::HandJoints, sample),
        }
    }
}

/// The bridge of `server`, taking input for `users` alone, and a peer for each of them.
fn connect_remote(server: &mut Server, users: &[&str]) -> Remote {
    let endpoint = endpoint();
    let mut args = vec!["--listen", &endpoint];
    for user in users {
        args.extend(["--user", user]);
    }
    let bridge = start_bridge(server.prefix(), SESSION, &args);
    let keys = Keys::new(SESSION).expect("a session name");
    let peers = (users.iter())
        .map(|_| Peer::connect(&endpoint, &keys))
        .collect();
    Remote {
        keys,
        peers,
        bridge,
    }
}

/// Waits until the bridge counts a refused user, asking over `user`'s peer.
fn wait_for_refusal(remote: &Remote, user: usize, before: &StatsSnapshot) -> StatsSnapshot {
    let deadline = Instant::now() + PATIENCE;
    loop {
        let stats = remote.peers[user].bridge_stats(&remote.keys);
        if stats.refused_user > before.refused_user {
            return stats;
        }
        assert!(
            Instant::now() < deadline,
            "no refusal counted: {stats:?}\n{}",
            remote.bridge.log()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn two_users_on_two_zenoh_peers_hand_a_part_over() {
    let scenario = scenario("two_user_handover");
    let recording = Recording::load(&scenario.fixture_path()).expect("the fixture loads");
    let (first, mut server, remote): (Replay, Server, Remote) =
        check_through(scenario, |server| connect_remote(server, &["anna", "ben"]));
    assert_eq!(
        first.grasping_users(),
        [0, 1, 0, 1],
        "grasp, grasp, hand-over, release: anna, ben, anna, ben"
    );
    // Both replays' events, on either user's machine, as the server published them.
    let both_replays = [first.events.as_slice(), &first.events].concat();
    for (user, peer) in remote.peers.iter().enumerate() {
        assert_eq!(
            peer.events(both_replays.len()),
            both_replays,
            "the events user {user} heard over zenoh"
        );
    }

    // Every sample of both replays came through the bridge; a stray publisher's sample for a
    // user the bridge does not take (a third one) is refused and counted.
    let ben = &remote.peers[1];
    let before = ben.bridge_stats(&remote.keys);
    let forwarded = |stats: &StatsSnapshot| {
        stats.tracker_forwarded + stats.glove_forwarded + stats.hand_joints_forwarded
    };
    assert_eq!(forwarded(&before), 2 * recording.samples.len() as u64);
    assert_eq!(before.refused_user, 0, "{before:?}");
    let stray = (recording.samples.iter())
        .find_map(|recorded| match recorded.input {
            InputSample::HandJoints(sample) => Some(sample),
            _ => None,
        })
        .expect("ben's hand joints");
    ben.put(
        Input::HandJoints,
        &vas_protocol::HandJointsSample { user: 2, ..stray },
    );
    let after = wait_for_refusal(&remote, 1, &before);
    assert_eq!(after.refused_user, 1, "{after:?}");
    assert_eq!(forwarded(&after), forwarded(&before), "{after:?}");
    let client = server.connect();
    let stats = client.input_stats(PATIENCE).expect("the server's counters");
    assert_eq!(stats.rejected_no_such_user, 0, "the server never saw it");
    drop(remote);
}
