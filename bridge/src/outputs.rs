//! The output thread: the server's frames out on zenoh, as they come and thinned.
//!
//! It owns the render role's client (iceoryx2 ports live on one thread), waits on its WaitSet,
//! and puts every frame it receives on the key of its service at once, then offers parts and
//! hand frames to each thinned stream. It also keeps the latest state for the queryables and
//! watches the server: a second of silence makes it ask for the counters, and no answer
//! ends the server's lifetime (see [`crate::server`]).

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use vas_client::{ClientError, Frame, Roles, Wake};
use vas_protocol::services;
use zenoh::Wait;
use zenoh::bytes::ZBytes;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;

use crate::keys::{Keys, Thinned};
use crate::latest::lock;
use crate::server::{CONTROL_TIMEOUT, RETRY, Shared, connect, wait_for_server};
use crate::thinning::Thinner;
use crate::wire;

/// Longest wait for frames: bounds how late a stop is noticed.
const WAIT: Duration = Duration::from_millis(100);
/// Silence after which the thread checks that the server is still there (in lockstep a server
/// publishes only when it gets input, so silence alone says nothing); not while a load or reset
/// is under way, which may keep it busy for longer than an answer is waited for.
const QUIET: Duration = Duration::from_secs(1);

/// A thinned stream: its publisher and its thinner.
struct ThinnedStream {
    stream: Thinned,
    publisher: Publisher<'static>,
    thinner: Thinner<ZBytes>,
}

/// The output thread's publishers.
pub struct Outputs<'a> {
    shared: &'a Shared,
    geometry: Publisher<'static>,
    parts: Publisher<'static>,
    hand: Publisher<'static>,
    events: Publisher<'static>,
    force: Publisher<'static>,
    clearance: Publisher<'static>,
    thinned: Vec<ThinnedStream>,
}

/// Declares a publisher on `key`: express (no batching, for latency), and blocking where no
/// message may be lost (events, geometry) rather than dropping under congestion.
fn publisher(
    session: &zenoh::Session,
    key: String,
    lossless: bool,
) -> zenoh::Result<Publisher<'static>> {
    let congestion = if lossless {
        CongestionControl::Block
    } else {
        CongestionControl::Drop
    };
    session
        .declare_publisher(key)
        .express(true)
        .congestion_control(congestion)
        .wait()
}

impl<'a> Outputs<'a> {
    /// Declares every output publisher of the session, thinned ones for each of `rates`.
    pub fn declare(
        session: &zenoh::Session,
        keys: &Keys,
        rates: &[u32],
        shared: &'a Shared,
    ) -> zenoh::Result<Self> {
        let mut thinned = Vec::new();
        for &hz in rates {
            for stream in [Thinned::Parts, Thinned::Hand] {
                thinned.push(ThinnedStream {
                    stream,
                    publisher: publisher(session, keys.thinned(stream, hz), false)?,
                    thinner: Thinner::new(hz),
                });
            }
        }
        Ok(Self {
            shared,
            geometry: publisher(session, keys.service(services::GEOMETRY), true)?,
            parts: publisher(session, keys.service(services::PARTS), false)?,
            hand: publisher(session, keys.service(services::HAND), false)?,
            events: publisher(session, keys.service(services::EVENTS), true)?,
            force: publisher(session, keys.service(services::FORCE), false)?,
            clearance: publisher(session, keys.service(services::CLEARANCE), false)?,
            thinned,
        })
    }

    /// Serves servers on `prefix` one after the other until the bridge stops.
    pub fn run(&mut self, prefix: Option<&str>) {
        while !self.shared.stopping() {
            let served = wait_for_server(prefix, self.shared).and_then(|found| match found {
                true => self.serve(prefix),
                false => Ok(()),
            });
            if let Err(error) = served {
                tracing::warn!(%error, "lost the vas server; waiting for one");
                std::thread::sleep(RETRY);
            }
            *lock(&self.shared.latest) = Default::default();
        }
    }

    /// One server's lifetime: its frames out until it goes away (an error) or the bridge stops.
    fn serve(&mut self, prefix: Option<&str>) -> Result<(), ClientError> {
        let mut client = connect(prefix, Roles::RENDER)?;
        let scene = client.scene_info(CONTROL_TIMEOUT)?;
        self.shared.epoch.fetch_add(1, Ordering::AcqRel);
        self.shared.stats.server_connected();
        tracing::info!(
            scene = scene.name,
            parts = scene.parts.len(),
            "serving a vas server"
        );
        let mut last_heard = Instant::now();
        while !self.shared.stopping() {
            let wait = (self.thinned.iter())
                .filter_map(|stream| stream.thinner.deadline())
                .min()
                .map_or(WAIT, |due| {
                    due.saturating_duration_since(Instant::now()).min(WAIT)
                });
            match client.wait(wait)? {
                Wake::Ready => {
                    last_heard = Instant::now();
                    let frames = client.receive()?;
                    self.publish(&frames);
                    let mut latest = lock(&self.shared.latest);
                    latest.hands = client
                        .latest_hands()
                        .iter()
                        .map(|h| wire::encode(h).into())
                        .collect();
                }
                Wake::Timeout
                    if last_heard.elapsed() >= QUIET
                        && !self.shared.loading.load(Ordering::Relaxed) =>
                {
                    client.input_stats(CONTROL_TIMEOUT)?;
                    last_heard = Instant::now();
                }
                Wake::Timeout => {}
                Wake::Terminated => self.shared.stop.store(true, Ordering::Relaxed),
            }
            self.flush_thinned(Instant::now());
        }
        Ok(())
    }

    /// Puts every frame on its key, offers parts and hands to the thinned streams, and keeps
    /// the latest state.
    fn publish(&mut self, frames: &[Frame]) {
        let now = Instant::now();
        for frame in frames {
            let (publisher, bytes, group) = match frame {
                Frame::Geometry(geometry) => {
                    let bytes = ZBytes::from(wire::encode_geometry(geometry));
                    self.shared
                        .generation
                        .store(geometry.generation, Ordering::Release);
                    lock(&self.shared.latest).geometry = Some(bytes.clone());
                    (&self.geometry, bytes, None)
                }
                Frame::Parts(parts) => {
                    let bytes = ZBytes::from(wire::encode_parts(&parts.header, &parts.parts));
                    lock(&self.shared.latest).parts = Some(bytes.clone());
                    let group = (Thinned::Parts, parts.header.frame);
                    (&self.parts, bytes, Some(group))
                }
                Frame::Hand(hand) => {
                    let group = (Thinned::Hand, hand.frame);
                    (&self.hand, wire::encode(hand).into(), Some(group))
                }
                Frame::Event(event) => (&self.events, wire::encode(event).into(), None),
                Frame::Force(force) => (&self.force, wire::encode(force).into(), None),
                Frame::Clearance(clearance) => {
                    let bytes = ZBytes::from(wire::encode(clearance.as_ref()));
                    lock(&self.shared.latest).clearance = Some(bytes.clone());
                    (&self.clearance, bytes, None)
                }
            };
            put(publisher, bytes.clone(), self.shared);
            let Some((kind, group)) = group else { continue };
            for stream in self
                .thinned
                .iter_mut()
                .filter(|stream| stream.stream == kind)
            {
                for bytes in stream.thinner.offer(now, group, bytes.clone()) {
                    put(&stream.publisher, bytes, self.shared);
                }
            }
        }
    }

    /// Sends the held frames of every thinned stream that is due.
    fn flush_thinned(&mut self, now: Instant) {
        for stream in &mut self.thinned {
            for bytes in stream.thinner.flush(now) {
                put(&stream.publisher, bytes, self.shared);
            }
        }
    }
}

/// Puts `bytes` on `publisher`, counting it; a failure is logged, never fatal.
fn put(publisher: &Publisher<'static>, bytes: ZBytes, shared: &Shared) {
    match publisher.put(bytes).wait() {
        Ok(()) => shared.stats.published(1),
        Err(error) => tracing::warn!(%error, key = %publisher.key_expr(), "cannot publish"),
    }
}
