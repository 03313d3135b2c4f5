//! How a renderer connects: the loop of a renderer that draws nothing.
//!
//! It connects to a vas server, asks for the scene (part names and geometry), then waits for
//! frames. Each time it wakes it "draws" the newest state, as a renderer does (frames that
//! arrived meanwhile are skipped): one line per part of the newest parts frame, and one line for
//! a new hand frame.
//!
//! ```text
//! cargo run --release -p vas-server -- run --prefix demo
//! cargo run --release -p vas-client --example renderer -- --prefix demo --frames 20
//! ```

use std::time::Duration;

use clap::Parser;
use vas_client::{Client, GraspType, HandSegment, Wake};

/// Prints the scene's parts and hand as the server moves them.
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

    // Once per scene: what each part id is (a real renderer loads `mesh_source` here). The
    // answer also tells that the server is up (it may still be loading its scene).
    let scene = client.scene_info(Duration::from_secs(30))?;
    println!("scene {:?} parts={}", scene.name, scene.parts.len());

    let mut drawn = 0;
    while args.frames.is_none_or(|limit| drawn < limit) {
        match client.wait(Duration::from_secs(1))? {
            Wake::Ready => {}
            Wake::Timeout => continue,
            Wake::Terminated => break,
        }
        let received = client.poll()?;
        if let Some(frame) = client.latest_parts().filter(|_| received.parts > 0) {
            println!("parts frame={}", frame.header.frame);
            for part in &frame.parts {
                let name = scene.parts.get(part.id as usize).map_or("?", |p| &p.name);
                let (position, rotation) = (part.position, part.rotation);
                println!(
                    "part id={} name={name:?} position={position:?} rotation={rotation:?}",
                    part.id
                );
            }
        }
        if let Some(hand) = client.latest_hand().filter(|_| received.hand > 0) {
            let grasp =
                GraspType::try_from(hand.grasp_type).map_or("?".into(), |g| format!("{g:?}"));
            let touching: Vec<String> = HandSegment::ALL
                .iter()
                .filter(|segment| hand.touching & segment.bit() != 0)
                .map(|segment| format!("{segment:?}"))
                .collect();
            let (position, rotation) = (hand.root.position, hand.root.rotation);
            println!(
                "hand frame={} position={position:?} rotation={rotation:?} grasp={grasp} touching={}",
                hand.frame,
                if touching.is_empty() {
                    "none".to_owned()
                } else {
                    touching.join(",")
                }
            );
        }
        // A wake-up for events or force frames alone draws nothing.
        drawn += u64::from(received.parts > 0 || received.hand > 0);
    }
    Ok(())
}
