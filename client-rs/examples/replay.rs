//! How to play a recording into the server in lockstep and follow what happens.
//!
//! Reads a JSON Lines recording (as `vas-client record` writes it, or one of
//! `tests/fixtures/`), then sends its samples one at a time, each once the hand frame answering
//! the previous one arrived, regardless of the recorded times. Prints every event the server
//! publishes meanwhile (grasp, release, contact begin and end) and, at the end, how many of
//! each kind. With a server started with `--lockstep`, the output is the same every time.
//!
//! ```text
//! cargo run --release -p vas-server -- run --prefix demo --lockstep --scene configs/peg_insert.toml
//! cargo run --release -p vas-client --example replay -- --prefix demo tests/fixtures/peg_insert.jsonl
//! ```

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

use clap::Parser;
use vas_client::recording::Recording;
use vas_client::{Client, Frame, HAND_PART_ID, Roles, wall_clock_ns};

/// How long to wait for the answer to a sample.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(10);

/// Plays a recording in lockstep and prints the events.
#[derive(Parser)]
struct Args {
    /// The server's iceoryx2 prefix (its `--prefix`).
    #[arg(long)]
    prefix: Option<String>,
    /// The recording (JSON Lines).
    recording: PathBuf,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let recording = Recording::load(&args.recording)?;
    // A lockstep replay reads the answer to each sample and the events it caused.
    let mut client = Client::builder()
        .prefix(args.prefix.as_deref())
        .roles(Roles::INPUT | Roles::RENDER)
        .connect()?;
    // Waits for the server (it may still be loading its scene): samples sent before it listens
    // would be lost.
    let scene = client.scene_info(Duration::from_secs(30))?;
    if scene.name != recording.header.scene {
        eprintln!(
            "warning: recorded against scene {:?}, the server has {:?}",
            recording.header.scene, scene.name
        );
    }
    let name = |id: u32| match scene.parts.get(id as usize) {
        Some(part) => part.name.clone(),
        None if id == HAND_PART_ID => "hand".to_owned(),
        None => format!("#{id}"),
    };

    let mut counts = BTreeMap::new();
    for recorded in &recording.samples {
        // Stamped now, so that the answer's timestamps measure this replay.
        let input = recorded.input.with_timestamp(wall_clock_ns());
        client.send_input(&input)?;
        // The server publishes a frame's events before its hand frame: when the answer comes,
        // the events the sample caused have come too.
        let mut events = Vec::new();
        let answer = client.wait_for_hand_frame(
            ANSWER_TIMEOUT,
            |hand| input.is_answered_by(hand),
            |frame| {
                if let Frame::Event(event) = frame {
                    events.push(event);
                }
            },
        )?;
        for event in events {
            let kind = event.kind().ok_or("an event of an unknown kind")?;
            *counts.entry(format!("{kind:?}")).or_insert(0) += 1;
            let grasp = event.grasp().ok_or("an event with an unknown grasp")?;
            println!(
                "event frame={} kind={kind:?} part={:?} other={:?} grasp={grasp:?}",
                event.frame,
                name(event.part),
                name(event.other)
            );
        }
        if answer.is_none() {
            return Err(format!("no answer to sample {input:?} in time").into());
        }
    }
    let counts: Vec<String> = counts
        .iter()
        .map(|(kind, n)| format!("{kind}={n}"))
        .collect();
    println!(
        "replayed samples={} events: {}",
        recording.samples.len(),
        counts.join(" ")
    );
    Ok(())
}
