//! How a renderer connects: the loop of a renderer that draws nothing.
//!
//! The scene's geometry (each part's mesh with its scale applied, each hand segment's mesh)
//! arrives on connecting and after every load or reset. Each wake-up "draws" the newest state,
//! as a renderer does (frames that arrived meanwhile are skipped): a line per part of a new
//! parts frame, and a line per hand segment of a new hand frame.
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
    // What was drawn last: a renderer redraws when the newest state differs, whichever poll
    // brought it (the meshes may come after the first frames, or before).
    let (mut drawn, mut generation, mut parts_frame, mut hand_frame) = (0, None, None, None);
    while args.frames.is_none_or(|limit| drawn < limit) {
        match client.wait(Duration::from_secs(1))? {
            Wake::Ready => client.poll()?,
            Wake::Timeout => continue,
            Wake::Terminated => break,
        };
        let Some(geometry) = client.geometry() else {
            continue; // Nothing to draw before the meshes.
        };
        if generation.replace(geometry.generation) != Some(geometry.generation) {
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
        let parts = (client.latest_parts()).filter(|f| parts_frame != Some(f.header.frame));
        let hand = (client.latest_hand()).filter(|hand| hand_frame != Some(hand.frame));
        if parts.is_none() && hand.is_none() {
            continue; // Events or force frames alone draw nothing.
        }
        drawn += 1;
        if let Some(frame) = parts {
            parts_frame = Some(frame.header.frame);
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
        if let Some(hand) = hand {
            hand_frame = Some(hand.frame);
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
    }
    Ok(())
}
