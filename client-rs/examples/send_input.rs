//! How an input device talks to the server: a scripted hand that moves and closes its fingers.
//!
//! Alternately sends a tracker sample (the hand a step further along x, above the demo scene's
//! table) and a glove sample (the fingers bent a step further), and after each waits for the
//! hand frame that answers it: the one carrying the sample's sequence number and timestamp for
//! its stream. Prints one line per answer.
//!
//! ```text
//! cargo run --release -p vas-server -- run --prefix demo
//! cargo run --release -p vas-client --example send_input -- --prefix demo --samples 10
//! ```

use std::time::Duration;

use clap::Parser;
use vas_client::recording::InputSample;
use vas_client::{
    Client, FLEX_COUNT, GloveSample, GraspType, Roles, TrackerSample, WirePose, wall_clock_ns,
};

/// How long to wait for the answer to a sample.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(10);

/// The flex values that bend a finger or the thumb (not roll, abduction, palm arch or wrist).
const BENDING_JOINTS: [usize; 14] = [1, 2, 4, 5, 6, 7, 8, 9, 11, 12, 13, 15, 16, 17];

/// Sends a scripted hand motion and prints the server's answers.
#[derive(Parser)]
struct Args {
    /// The server's iceoryx2 prefix (its `--prefix`).
    #[arg(long)]
    prefix: Option<String>,
    /// How many samples to send, tracker and glove alternately.
    #[arg(long, default_value_t = 10)]
    samples: u64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    // A device that reads the answers to its samples: it sends input and renders.
    let mut client = Client::builder()
        .prefix(args.prefix.as_deref())
        .roles(Roles::INPUT | Roles::RENDER)
        .connect()?;
    // Inputs have no history: a sample sent before the server listens is lost. Once the server
    // answers a control request (it may still be loading its scene), it listens.
    let scene = client.scene_info(Duration::from_secs(30))?;
    println!("scene {:?}", scene.name);
    for step in 0..args.samples {
        // From 0 to 1 over the script.
        let progress = (step + 1) as f64 / args.samples as f64;
        // Each stream numbers its samples from 1.
        let seq = step / 2 + 1;
        let input = if step % 2 == 0 {
            InputSample::Tracker(TrackerSample {
                seq,
                timestamp_ns: wall_clock_ns(),
                hand: WirePose {
                    position: [-0.2 + 0.4 * progress, 0.0, 1.0],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                },
                cart: WirePose::IDENTITY,
                sensor_id: 0,
                user: 0,
                side: 0,
                reserved: 0,
            })
        } else {
            let mut flex = [0.0f32; FLEX_COUNT];
            for joint in BENDING_JOINTS {
                flex[joint] = 1.2 * progress as f32;
            }
            InputSample::Glove(GloveSample {
                seq,
                timestamp_ns: wall_clock_ns(),
                flex,
                user: 0,
                side: 0,
            })
        };
        client.send_input(&input)?;
        let answer = client
            .wait_for_hand_frame(ANSWER_TIMEOUT, |hand| input.is_answered_by(hand), drop)?
            .ok_or_else(|| format!("no answer to {input:?} within {ANSWER_TIMEOUT:?}"))?;
        let stream = match input {
            InputSample::Tracker(_) => "tracker",
            InputSample::Glove(_) => "glove",
            InputSample::HandJoints(_) => "hand_joints",
        };
        let bend = BENDING_JOINTS.iter().map(|&j| answer.flex[j]).sum::<f32>()
            / BENDING_JOINTS.len() as f32;
        let grasp = answer.grasp().map_or("unknown", GraspType::name);
        println!(
            "answer input={stream} seq={seq} frame={} position={:?} bend={bend:.3} grasp={grasp} touching={:#x}",
            answer.frame, answer.root.position, answer.touching
        );
    }
    Ok(())
}
