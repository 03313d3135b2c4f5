//! What a page may send: commands, and acknowledgements of the frames it was sent.
//!
//! A page sends small JSON objects with a `type`, and in a WebXR session binary hand-joints
//! messages ([`crate::hand_joints`]). Anything else (other binary, not JSON, an unknown type,
//! unexpected or missing fields, more than [`MAX_COMMAND_BYTES`], a malformed hand) is refused:
//! the page that sent it is broken or hostile, so its connection is closed and the refusal
//! counted.

use serde::{Deserialize, Serialize};
use vas_client::SlidingMetaphor;

use crate::hand_joints::HandJointsError;

/// The largest command a page may send, in bytes.
pub const MAX_COMMAND_BYTES: usize = 4096;

/// A command from a page, carried out by the link thread on the vas server.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// Put the scene back to its initial state. (A struct variant: serde lets a unit variant
    /// of a tagged enum through with any other fields.)
    Reset {},
    /// Load one of the scenes the server offers, by name (never a path).
    LoadScene {
        /// The scene's name, as the server lists it.
        name: String,
    },
    /// Slide grasped parts with another metaphor.
    SetMetaphor {
        /// Which one.
        metaphor: SlidingMetaphor,
    },
}

impl Command {
    /// The command's `type`, for replies and logs.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Reset {} => "reset",
            Self::LoadScene { .. } => "load_scene",
            Self::SetMetaphor { .. } => "set_metaphor",
        }
    }
}

/// Why a page's message was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// Not a well-formed command.
    Malformed,
    /// Longer than [`MAX_COMMAND_BYTES`].
    Oversized,
    /// A `type` this viewer does not know.
    Unknown,
    /// A hand-joints message that is not one hand's 25 finite joints.
    HandJoints(HandJointsError),
}

impl Refusal {
    /// The refusal in words, for the close frame and the log.
    pub fn reason(self) -> &'static str {
        match self {
            Self::Malformed => "malformed command",
            Self::Oversized => "command too long",
            Self::Unknown => "unknown command",
            Self::HandJoints(error) => error.reason(),
        }
    }
}

/// A page's text message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PageMessage {
    /// `{"type":"ack"}`: the page has taken a frame and may be sent another (see
    /// [`crate::page::FRAMES_IN_FLIGHT`]).
    Ack,
    /// A command for the server.
    Command(Command),
}

/// The command or acknowledgement in a page's text message.
pub fn parse(text: &str) -> Result<PageMessage, Refusal> {
    if text.len() > MAX_COMMAND_BYTES {
        return Err(Refusal::Oversized);
    }
    let value: serde_json::Value = serde_json::from_str(text).map_err(|_| Refusal::Malformed)?;
    let kind = value
        .get("type")
        .and_then(serde_json::Value::as_str)
        .ok_or(Refusal::Malformed)?;
    match kind {
        "ack" if value.as_object().is_some_and(|fields| fields.len() == 1) => Ok(PageMessage::Ack),
        "ack" => Err(Refusal::Malformed),
        "reset" | "load_scene" | "set_metaphor" => serde_json::from_value(value)
            .map(PageMessage::Command)
            .map_err(|_| Refusal::Malformed),
        _ => Err(Refusal::Unknown),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_commands_and_the_ack_parse() {
        let command = |text| match parse(text) {
            Ok(PageMessage::Command(command)) => command,
            other => panic!("{text} gave {other:?}"),
        };
        assert_eq!(command(r#"{"type":"reset"}"#), Command::Reset {});
        assert_eq!(
            command(r#"{"type":"load_scene","name":"peg insert"}"#),
            Command::LoadScene {
                name: "peg insert".into()
            }
        );
        assert_eq!(
            command(r#"{"type":"set_metaphor","metaphor":"spiral-spring"}"#),
            Command::SetMetaphor {
                metaphor: SlidingMetaphor::SpiralSpring
            }
        );
        assert_eq!(parse(r#"{"type":"ack"}"#), Ok(PageMessage::Ack));
    }

    #[test]
    fn anything_else_is_refused_with_its_reason() {
        for malformed in [
            "",
            "reset",
            "[]",
            r#"{"kind":"reset"}"#,
            r#"{"type":7}"#,
            r#"{"type":"reset","extra":1}"#,
            r#"{"type":"load_scene"}"#,
            r#"{"type":"set_metaphor","metaphor":"glue"}"#,
            r#"{"type":"ack","frame":3}"#,
        ] {
            assert_eq!(parse(malformed), Err(Refusal::Malformed), "{malformed}");
        }
        assert_eq!(parse(r#"{"type":"shutdown"}"#), Err(Refusal::Unknown));
        let long = format!(r#"{{"type":"load_scene","name":"{}"}}"#, "x".repeat(5000));
        assert_eq!(parse(&long), Err(Refusal::Oversized));
    }
}
