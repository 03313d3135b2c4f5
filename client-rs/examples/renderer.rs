//! How a renderer connects: the loop of a renderer that draws nothing.
//!
//! The scene's geometry arrives first (each part's mesh with its scale applied, each hand
//! segment's mesh), and again after every load or reset. Then each wake-up "draws" the newest
//! state, as a renderer does (frames that arrived meanwhile are skipped): a line per part of a
//! new parts frame, and a line per hand segment of a new hand frame.
//!
//! ```text
//! cargo run --release -p vas-server -- run --prefix demo
//! cargo run --release -p vas-client --example renderer -- --prefix demo --frames 20
//! ```

use std::time::Duration;

use clap::Parser;
use vas_client::words::{grasp_name, hand_name};
use vas_client::{Client, HandSegment, Wake};

/// Prints the scene's meshes, then its parts and hand as the server moves them.
#[derive(Parser)]
struct Args {
    /// The server's iceoryx2 prefix (its `--prefix`).
    #[arg(long)]
    prefix: Option<String>,
    /// Stop after drawing this many frames (default: run until Ctrl-C).
    #[arg(long)]
    frames: Option<u64>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    // With the signals handled, Ctrl-C ends the loop below and the client leaves cleanly.
    let mut client = Client::builder()
        .handle_termination_signals(true)
        .prefix(args.prefix.as_deref())
        .connect()?;
    let mut drawn = 0;
    while args.frames.is_none_or(|limit| drawn < limit) {
        match client.wait(Duration::from_secs(1))? {
            Wake::Ready => {}
            Wake::Timeout => continue,
            Wake::Terminated => break,
        }
        let received = client.poll()?;
        let Some(geometry) = client.geometry() else {
            continue; // Nothing to draw before the meshes.
        };
        if received.geometry > 0 {
            // Once per scene: a real renderer uploads the meshes here.
            for (id, mesh) in geometry.parts.iter().enumerate() {
                let (min, max) = mesh.bounds().unwrap_or_default();
                let triangles = mesh.triangles.len();
                println!(
                    "mesh part={id} name={:?} triangles={triangles} min={min:?} max={max:?}",
                    mesh.name
                );
            }
        }
        if let Some(frame) = client.latest_parts().filter(|_| received.parts > 0) {
            for part in &frame.parts {
                let name = geometry
                    .parts
                    .get(part.id as usize)
                    .map_or("?", |m| &m.name);
                let (frame, position, rotation) =
                    (frame.header.frame, part.position, part.rotation);
                println!(
                    "part frame={frame} id={} name={name:?} position={position:?} rotation={rotation:?}",
                    part.id
                );
            }
        }
        if let Some(hand) = client.latest_hand().filter(|_| received.hand > 0) {
            let (frame, side, grasp) = (
                hand.frame,
                hand_name(hand.hand),
                grasp_name(hand.grasp_type),
            );
            println!(
                "hand frame={frame} side={side} grasp={grasp} position={:?}",
                hand.root.position
            );
            // Each segment's mesh goes where the server verified the segment: no kinematics here.
            for (segment, pose) in HandSegment::ALL.iter().zip(hand.segment_poses()) {
                let (position, rotation) = (pose.position, pose.rotation);
                println!(
                    "segment frame={frame} name={} position={position:?} rotation={rotation:?}",
                    segment.name()
                );
            }
        }
        // A wake-up for events or force frames alone draws nothing.
        drawn += u64::from(received.parts > 0 || received.hand > 0);
    }
    Ok(())
}
