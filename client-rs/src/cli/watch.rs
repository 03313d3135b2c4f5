//! `vas-client watch`: frames as JSON lines, with their codes in words.

use std::io::Write;
use std::time::Duration;

use vas_client::{Client, Frame, Roles, SceneWords, Wake};

/// How long one wait lasts before the loop checks again; frames wake it earlier.
const IDLE_WAIT: Duration = Duration::from_secs(1);

/// How long a control request may take while checking whether a server answers.
const PROBE_TIMEOUT: Duration = Duration::from_secs(2);

/// Prints every frame as a JSON line (`{"parts":{...}}`, `{"hand":{...}}`, `{"event":{...}}`...)
/// until `count` frames were printed or SIGINT/SIGTERM arrives. Says on stderr when no server
/// answers, and when one does again.
pub fn run(prefix: Option<&str>, count: Option<u64>) -> anyhow::Result<()> {
    let mut client = super::connect(prefix, Roles::RENDER)?;
    let mut served = Served::default();
    served.refresh(&client);
    let mut out = std::io::stdout().lock();
    let mut printed = 0u64;
    while count.is_none_or(|count| printed < count) {
        match client.wait(IDLE_WAIT)? {
            Wake::Terminated => break,
            Wake::Timeout => {
                if served.words.is_none() {
                    served.refresh(&client);
                }
                continue;
            }
            Wake::Ready => {}
        }
        for frame in client.receive()? {
            if count.is_some_and(|count| printed >= count) {
                break;
            }
            if let Frame::Geometry(_) = frame {
                // A new scene generation: its parts may have other names.
                served.refresh(&client);
            }
            let words = served.words.clone().unwrap_or_default();
            serde_json::to_writer(&mut out, &super::named::named(&frame, &words)?)?;
            writeln!(out)?;
            printed += 1;
        }
        out.flush()?;
    }
    Ok(())
}

/// What the tool knows of the server: its scene's part names, once it answered.
#[derive(Default)]
struct Served {
    words: Option<SceneWords>,
    /// Whether "no server answers" was said since the last answer.
    said_absent: bool,
}

impl Served {
    /// Asks for the scene again; says on stderr when no server answers, once, and when one
    /// answers after that.
    fn refresh(&mut self, client: &Client) {
        match client.scene_info(PROBE_TIMEOUT) {
            Ok(scene) => {
                if self.words.is_none() {
                    tracing::info!(
                        scene = scene.name,
                        parts = scene.parts.len(),
                        "a server answers"
                    );
                }
                self.words = Some(SceneWords::new(&scene));
                self.said_absent = false;
            }
            Err(error) if !self.said_absent => {
                tracing::warn!("no vas server answers on this prefix ({error}); waiting for one");
                self.said_absent = true;
            }
            Err(_) => {}
        }
    }
}
