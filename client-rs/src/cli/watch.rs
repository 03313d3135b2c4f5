//! `vas-client watch`: frames as JSON lines.

use std::io::Write;
use std::time::Duration;

use vas_client::Wake;

/// How long one wait lasts before the loop checks again; frames wake it earlier.
const IDLE_WAIT: Duration = Duration::from_secs(1);

/// Prints every parts and hand frame as a JSON line (`{"parts":{...}}` or `{"hand":{...}}`)
/// until `count` frames were printed or SIGINT/SIGTERM arrives.
pub fn run(prefix: Option<&str>, count: Option<u64>) -> anyhow::Result<()> {
    let mut client = super::connect(prefix)?;
    let mut out = std::io::stdout().lock();
    let mut printed = 0u64;
    while count.is_none_or(|count| printed < count) {
        match client.wait(IDLE_WAIT)? {
            Wake::Terminated => break,
            Wake::Timeout => continue,
            Wake::Ready => {}
        }
        for frame in client.receive()? {
            if count.is_some_and(|count| printed >= count) {
                break;
            }
            serde_json::to_writer(&mut out, &frame)?;
            writeln!(out)?;
            printed += 1;
        }
        out.flush()?;
    }
    Ok(())
}
