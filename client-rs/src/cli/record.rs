//! `vas-client record`: input streams to a recording file.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use vas_client::recording::{RecordingHeader, RecordingWriter};
use vas_client::{InputTap, Roles, Wake};

/// Arguments of `vas-client record`.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
    /// The recording file to write (JSON Lines).
    file: PathBuf,
    /// Scene name for the header; by default the running server is asked.
    #[arg(long)]
    scene: Option<String>,
    /// What the recording shows, for the header.
    #[arg(long, default_value = "")]
    description: String,
    /// Stop after this many samples (default: until SIGINT or SIGTERM).
    #[arg(long)]
    count: Option<u64>,
}

/// How long one wait lasts before the loop checks again; samples wake it earlier.
const IDLE_WAIT: Duration = Duration::from_secs(1);

/// Writes every tracker, glove and hand-joints sample sent on the prefix until `count` samples or a
/// termination signal. Samples with NaN or infinite values cannot be written as JSON; they are
/// skipped and counted.
pub fn run(prefix: Option<&str>, args: &RecordArgs) -> anyhow::Result<()> {
    let scene = match &args.scene {
        Some(scene) => scene.clone(),
        None => {
            super::connect(prefix, Roles::CONTROL)?
                .scene_info(super::CONTROL_TIMEOUT)
                .context("cannot ask the server for its scene name (give it with --scene)")?
                .name
        }
    };
    let mut tap = InputTap::connect(prefix, true)?;
    let header = RecordingHeader::new(scene, args.description.clone());
    let mut writer = RecordingWriter::create(&args.file, &header)?;
    tracing::info!(file = %args.file.display(), "recording");
    let (mut written, mut skipped) = (0u64, 0u64);
    'recording: while args.count.is_none_or(|count| written < count) {
        match tap.wait(IDLE_WAIT)? {
            Wake::Terminated => break,
            Wake::Timeout => continue,
            Wake::Ready => {}
        }
        for sample in tap.receive()? {
            if args.count.is_some_and(|count| written >= count) {
                break 'recording;
            }
            if !sample.is_finite() {
                tracing::warn!(
                    seq = sample.seq(),
                    "skipping a sample with non-finite values"
                );
                skipped += 1;
                continue;
            }
            writer.write(&sample)?;
            written += 1;
        }
    }
    tracing::info!(
        file = %args.file.display(),
        written,
        skipped,
        "recording finished"
    );
    Ok(())
}
