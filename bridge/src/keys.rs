//! The zenoh key expressions of a session: the iceoryx2 service names with the session's name
//! after `vas/`, so that one zenoh network carries several sessions side by side.
//!
//! ```text
//! vas/<session>/scene/geometry          geometry (published per generation; also a queryable)
//! vas/<session>/output/parts            every parts frame (queryable: the latest)
//! vas/<session>/output/parts/@<hz>hz    parts frames thinned to <hz>
//! vas/<session>/output/hand             every hand frame (queryable: each hand's latest)
//! vas/<session>/output/hand/@<hz>hz     hand frames thinned to <hz>
//! vas/<session>/output/events           every event, never thinned
//! vas/<session>/output/force            every force frame
//! vas/<session>/output/clearance        every clearance frame (queryable: the latest)
//! vas/<session>/input/tracker|glove|hand_joints   samples into the server
//! vas/<session>/control                 the control queryable
//! vas/<session>/bridge/stats            the bridge's counters, as JSON (a queryable)
//! ```
//!
//! A thinned stream's last chunk is a verbatim chunk (`@`): zenoh's wildcards never match one,
//! so a subscriber to `vas/<session>/output/**` gets every frame once, not once per rate.

use vas_protocol::services;

/// A session name that cannot be one chunk of a key expression.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid session name {0:?}: use letters, digits, '_', '-' and '.', not starting with '.'")]
pub struct SessionNameError(pub String);

/// An output stream a remote renderer may ask to have thinned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Thinned {
    /// Parts frames.
    Parts,
    /// Hand frames (a frame's hands go together).
    Hand,
}

/// An input stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// Tracker samples.
    Tracker,
    /// Glove samples.
    Glove,
    /// Hand-joints samples.
    HandJoints,
}

impl Input {
    /// Every input stream.
    pub const ALL: [Input; 3] = [Input::Tracker, Input::Glove, Input::HandJoints];

    /// The iceoryx2 service.
    pub fn service(self) -> &'static str {
        match self {
            Input::Tracker => services::TRACKER,
            Input::Glove => services::GLOVE,
            Input::HandJoints => services::HAND_JOINTS,
        }
    }

    /// The stream's name: `tracker`, `glove`, `hand_joints`.
    pub fn name(self) -> &'static str {
        let service = self.service();
        service.rsplit('/').next().unwrap_or(service)
    }
}

/// The key expressions of one session.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Keys {
    session: String,
}

impl Keys {
    /// The keys of session `session`.
    pub fn new(session: &str) -> Result<Self, SessionNameError> {
        let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
        if session.is_empty() || session.starts_with('.') || !session.chars().all(allowed) {
            return Err(SessionNameError(session.to_owned()));
        }
        Ok(Self {
            session: session.to_owned(),
        })
    }

    /// The session's name.
    pub fn session(&self) -> &str {
        &self.session
    }

    /// The key of an iceoryx2 service (one of [`vas_protocol::services`]' names).
    pub fn service(&self, service: &str) -> String {
        let rest = service.strip_prefix("vas/").unwrap_or(service);
        format!("vas/{}/{rest}", self.session)
    }

    /// The key of an output stream thinned to `hz` frames a second.
    pub fn thinned(&self, stream: Thinned, hz: u32) -> String {
        let service = match stream {
            Thinned::Parts => services::PARTS,
            Thinned::Hand => services::HAND,
        };
        format!("{}/@{hz}hz", self.service(service))
    }

    /// The key of an input stream.
    pub fn input(&self, stream: Input) -> String {
        self.service(stream.service())
    }

    /// The key expression of every input stream.
    pub fn inputs(&self) -> String {
        format!("vas/{}/input/*", self.session)
    }

    /// The control queryable's key.
    pub fn control(&self) -> String {
        self.service(services::CONTROL)
    }

    /// The bridge's counters' key.
    pub fn stats(&self) -> String {
        format!("vas/{}/bridge/stats", self.session)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_the_service_names_under_the_session() {
        let keys = Keys::new("cell-4").expect("a valid name");
        assert_eq!(keys.service(services::PARTS), "vas/cell-4/output/parts");
        assert_eq!(
            keys.service(services::GEOMETRY),
            "vas/cell-4/scene/geometry"
        );
        assert_eq!(
            keys.input(Input::HandJoints),
            "vas/cell-4/input/hand_joints"
        );
        assert_eq!(keys.control(), "vas/cell-4/control");
        assert_eq!(
            keys.thinned(Thinned::Hand, 90),
            "vas/cell-4/output/hand/@90hz"
        );
        for stream in Input::ALL {
            assert_eq!(
                keys.input(stream),
                format!("vas/cell-4/input/{}", stream.name())
            );
        }
    }

    #[test]
    fn names_that_are_no_single_chunk_are_refused() {
        for bad in [
            "", "a/b", "*", "a*", "$x", "@admin", ".hidden", "a b", "a?b", "é",
        ] {
            assert_eq!(
                Keys::new(bad),
                Err(SessionNameError(bad.to_owned())),
                "{bad:?}"
            );
        }
    }
}
