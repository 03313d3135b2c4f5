//! B13's rates: what one remote renderer receives, every output at the full rate and parts and
//! hand frames thinned, while a recording plays into the server over zenoh at its own pace.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use vas_bridge::keys::{Input, Keys, Thinned};
use vas_bridge::wire;
use vas_client::recording::{InputSample, Recording};
use vas_protocol::{services, wall_clock_ns};
use zenoh::Wait;

use crate::{open_session, zenoh_error};

/// Options of `rates`.
#[derive(Debug, clap::Args)]
pub struct RatesArgs {
    /// The recording played into the server, at its own pace.
    #[arg(long)]
    recording: PathBuf,
    /// The thinned rate measured (one of the bridge's `--rate`s).
    #[arg(long, default_value_t = 90)]
    hz: u32,
    /// Write the figures as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Messages and bytes received on one key.
#[derive(Debug, Default)]
struct Counter {
    messages: AtomicU64,
    bytes: AtomicU64,
}

/// Plays the recording and prints each stream's messages and bytes a second.
pub fn run(endpoint: &str, session_name: &str, args: &RatesArgs) -> anyhow::Result<()> {
    let recording = Recording::load(&args.recording)?;
    let keys = Keys::new(session_name)?;
    let session = open_session(endpoint)?;
    let streams: Vec<(String, String)> = [
        services::PARTS,
        services::HAND,
        services::EVENTS,
        services::FORCE,
        services::CLEARANCE,
    ]
    .iter()
    .map(|service| (service.to_string(), keys.service(service)))
    .chain([
        (
            format!("parts @{}hz", args.hz),
            keys.thinned(Thinned::Parts, args.hz),
        ),
        (
            format!("hand @{}hz", args.hz),
            keys.thinned(Thinned::Hand, args.hz),
        ),
    ])
    .collect();
    let counters: Vec<Arc<Counter>> = streams.iter().map(|_| Arc::default()).collect();
    let _subscribers = (streams.iter().zip(&counters))
        .map(|((_, key), counter)| {
            let counter = Arc::clone(counter);
            session
                .declare_subscriber(key)
                .callback(move |sample| {
                    counter.messages.fetch_add(1, Ordering::Relaxed);
                    let len = sample.payload().len() as u64;
                    counter.bytes.fetch_add(len, Ordering::Relaxed);
                })
                .wait()
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(zenoh_error)?;
    let publishers = Input::ALL.map(|stream| {
        session
            .declare_publisher(keys.input(stream))
            .express(true)
            .wait()
    });
    let [tracker, glove, joints] = publishers.map(|publisher| publisher.map_err(zenoh_error));
    let (tracker, glove, joints) = (tracker?, glove?, joints?);
    // The subscriptions reach the bridge before the first sample.
    std::thread::sleep(Duration::from_millis(500));

    let start = Instant::now();
    let start_ns = wall_clock_ns();
    for recorded in &recording.samples {
        let due = start + Duration::from_secs_f64(recorded.time);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        let put = match recorded.stamped(start_ns) {
            InputSample::Tracker(sample) => tracker.put(wire::encode(&sample)),
            InputSample::Glove(sample) => glove.put(wire::encode(&sample)),
            InputSample::HandJoints(sample) => joints.put(wire::encode(&sample)),
        };
        put.wait().map_err(zenoh_error)?;
    }
    // The frames answering the last samples, and the thinned streams' last frames.
    std::thread::sleep(Duration::from_millis(200));
    let seconds = start.elapsed().as_secs_f64();

    println!("{:.1} s of {}", seconds, args.recording.display());
    println!("| stream | messages/s | bytes/s |");
    println!("|---|---|---|");
    let mut rows = serde_json::Map::new();
    let per_second = |counter: &Counter| {
        (
            counter.messages.load(Ordering::Relaxed) as f64 / seconds,
            counter.bytes.load(Ordering::Relaxed) as f64 / seconds,
        )
    };
    for ((name, _), counter) in streams.iter().zip(&counters) {
        let (messages, bytes) = per_second(counter);
        println!("| {name} | {messages:.1} | {bytes:.0} |");
        rows.insert(
            name.clone(),
            serde_json::json!({ "messages_per_s": messages, "bytes_per_s": bytes }),
        );
    }
    // A renderer draws from parts, hands, events and clearance (force is for a device).
    let total = |names: &[&str]| -> f64 {
        (streams.iter().zip(&counters))
            .filter(|((name, _), _)| names.contains(&name.as_str()))
            .map(|(_, counter)| per_second(counter).1)
            .sum()
    };
    let thinned = [
        format!("parts @{}hz", args.hz),
        format!("hand @{}hz", args.hz),
    ];
    let full = total(&[
        services::PARTS,
        services::HAND,
        services::EVENTS,
        services::CLEARANCE,
    ]);
    let at_rate = total(&[
        &thinned[0],
        &thinned[1],
        services::EVENTS,
        services::CLEARANCE,
    ]);
    println!(
        "one renderer at the full rate: {full:.0} bytes/s; at {} Hz: {at_rate:.0} bytes/s",
        args.hz
    );
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "seconds": seconds, "streams": rows,
            "renderer_full_bytes_per_s": full, "renderer_thinned_bytes_per_s": at_rate,
        });
        std::fs::write(path, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
