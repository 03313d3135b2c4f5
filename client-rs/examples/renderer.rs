//! How a renderer connects: the loop of a renderer that draws nothing.
//!
//! The scene's geometry (each part's mesh with its scale applied, each hand segment's mesh)
//! arrives on connecting and after every load or reset. Each wake-up "draws" the newest state,
//! as a renderer does (frames that arrived meanwhile are skipped): a line per part of a new
//! parts frame, and for each hand (right, then left) with a new frame, a line for the hand and
//! one per segment, naming the hand's user (the scene info names the users).
//!
//! ```text
//! cargo run --release -p vas-server -- run --prefix demo
//! cargo run --release -p vas-client --example renderer -- --prefix demo --frames 20
//! ```

use std::time::Duration;

use clap::Parser;
use vas_client::protocol::ControlRequest;
use vas_client::{
    Client, ClientError, GraspType, HandFrame, HandSegment, HandSide, PartsFrame, Roles,
    SceneGeometry, Wake,
};

/// Prints the scene's meshes, then its parts and hands as the server moves them.
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
    // With the signals handled, Ctrl-C ends the loop below and the client leaves cleanly. A
    // renderer only reads: it takes the render role, and no input ports.
    let mut client = Client::builder()
        .handle_termination_signals(true)
        .prefix(args.prefix.as_deref())
        .roles(Roles::RENDER)
        .connect()?;
    // The scene's users' names, asked for with each new scene's meshes.
    let mut users = Vec::new();
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
            upload_meshes(geometry); // Once per scene,
            users = user_names(&client)?; // with the names of its users.
        }
        let parts = (client.latest_parts()).filter(|f| parts_frame != Some(f.header.frame));
        // Every hand, right then left, published each frame under one number: a frame's hands
        // are drawn together (a poll may end between two of them).
        let hands = client.latest_hands();
        let new_hands = (hands.first().map(|hand| hand.frame)).filter(|&frame| {
            hand_frame != Some(frame) && hands.iter().all(|hand| hand.frame == frame)
        });
        if parts.is_none() && new_hands.is_none() {
            continue; // Events or force frames alone draw nothing.
        }
        drawn += 1;
        if let Some(frame) = parts {
            parts_frame = Some(frame.header.frame);
            draw_parts(geometry, frame);
        }
        if new_hands.is_some() {
            hand_frame = new_hands;
            hands.iter().for_each(|hand| draw_hand(&users, hand));
        }
    }
    Ok(())
}

/// The scene's users' names, by the index that hand frames name their user with.
fn user_names(client: &Client) -> Result<Vec<String>, ClientError> {
    let scene = client.control(ControlRequest::scene_info(), Duration::from_secs(5))?;
    Ok(scene.user_names().map(str::to_owned).collect())
}

/// Where a real renderer uploads the scene's meshes: a line per part's mesh.
fn upload_meshes(geometry: &SceneGeometry) {
    for (id, mesh) in geometry.parts.iter().enumerate() {
        let (min, max) = mesh.bounds().unwrap_or_default();
        let triangles = mesh.triangles.len();
        println!(
            "mesh part={id} name={:?} triangles={triangles} min={min:?} max={max:?}",
            mesh.name
        );
    }
}

/// Each part's mesh goes to its pose: a line per part.
fn draw_parts(geometry: &SceneGeometry, frame: &PartsFrame) {
    for part in &frame.parts {
        let name = (geometry.parts.get(part.id as usize)).map_or("?", |mesh| &mesh.name);
        let (frame, position, rotation) = (frame.header.frame, part.position, part.rotation);
        println!(
            "part frame={frame} id={} name={name:?} position={position:?} rotation={rotation:?}",
            part.id
        );
    }
}

/// Each segment's mesh of the hand goes where the server verified the segment, no kinematics
/// here: a line for the hand, then one per segment, each naming the hand's user and side.
fn draw_hand(users: &[String], hand: &HandFrame) {
    let (frame, side) = (hand.frame, hand.side().map_or("unknown", HandSide::name));
    let user = users.get(hand.user as usize).map_or("?", String::as_str);
    let grasp = hand.grasp().map_or("unknown", GraspType::name);
    let position = hand.root.position;
    println!("hand frame={frame} user={user:?} side={side} grasp={grasp} position={position:?}");
    for (segment, pose) in HandSegment::ALL.iter().zip(hand.segment_poses()) {
        let (name, position, rotation) = (segment.name(), pose.position, pose.rotation);
        println!(
            "segment frame={frame} user={user:?} side={side} name={name} position={position:?} \
             rotation={rotation:?}"
        );
    }
}
