//! What a client does, and so which ports it holds.

/// What a [`Client`](super::Client) does, and so which ports it holds: every service takes only so many ports
/// (see [`vas_protocol::services::clients`]), and a port a client does not use is a renderer or
/// an operator refused.
///
/// Every client holds a control client (scene info, input counters, reset, loads, metaphor):
/// [`Roles::CONTROL`] is that alone. [`Roles::RENDER`] adds a subscriber on each output service
/// (parts, hand, events, force, clearance, geometry) for [`Client::wait`](super::Client::wait) and [`Client::receive`](super::Client::receive);
/// [`Roles::INPUT`] adds a publisher and its notifier on each input stream (tracker, glove, hand
/// joints) for [`Client::send_tracker`](super::Client::send_tracker) and the other sends. Roles combine with `|`; the default
/// is [`Roles::ALL`], every port, as a client had before there were roles.
///
/// ```
/// use vas_client::Roles;
///
/// // A headset's bridge that reads the answers to its samples.
/// let device = Roles::INPUT | Roles::RENDER;
/// assert_eq!(device, Roles::ALL);
/// assert!(Roles::RENDER.contains(Roles::CONTROL));
/// assert!(!Roles::RENDER.contains(Roles::INPUT));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Roles(u8);

impl Roles {
    /// The control service only: what an operator's command (`vas-client reset`, `load-scene`,
    /// `scenes`, `set-metaphor`, `info`) takes. Every other role includes it.
    pub const CONTROL: Roles = Roles(0);
    /// Reads the server's output: a renderer, a viewer, `vas-client watch` (with control).
    pub const RENDER: Roles = Roles(1);
    /// Sends input: a device bridge, a replay, `vas-client send-*` (with control).
    pub const INPUT: Roles = Roles(2);
    /// Every role: renders and sends. The default.
    pub const ALL: Roles = Roles(Self::RENDER.0 | Self::INPUT.0);

    /// Whether these roles include every one of `other`.
    pub const fn contains(self, other: Roles) -> bool {
        self.0 & other.0 == other.0
    }
}

impl Default for Roles {
    /// [`Roles::ALL`], so that a client opened without saying keeps every port.
    fn default() -> Self {
        Roles::ALL
    }
}

impl std::ops::BitOr for Roles {
    type Output = Roles;

    fn bitor(self, other: Roles) -> Roles {
        Roles(self.0 | other.0)
    }
}

impl std::ops::BitOrAssign for Roles {
    fn bitor_assign(&mut self, other: Roles) {
        self.0 |= other.0;
    }
}

impl std::fmt::Display for Roles {
    /// `control`, `render`, `input` or `render and input`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(
            match (self.contains(Roles::RENDER), self.contains(Roles::INPUT)) {
                (false, false) => "control",
                (true, false) => "render",
                (false, true) => "input",
                (true, true) => "render and input",
            },
        )
    }
}
