//! The viewer's counters, served as JSON on `GET /stats` for operators and tests.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use serde_json::{Value, json};

/// Counters shared by the link thread and every page.
#[derive(Debug, Default)]
pub struct Stats {
    /// Pages connected now.
    pub pages_open: AtomicU64,
    /// Pages connected since start.
    pub pages_served: AtomicU64,
    /// Page messages refused for not being a well-formed command (not JSON, wrong fields,
    /// binary, or a broken WebSocket frame).
    pub refused_malformed: AtomicU64,
    /// Page messages refused for their size.
    pub refused_oversized: AtomicU64,
    /// Page messages refused for an unknown command type.
    pub refused_unknown: AtomicU64,
    /// Events a slow page missed because its queue was full (the oldest go first).
    pub events_dropped: AtomicU64,
    /// Commands carried out or refused by the server.
    pub commands: AtomicU64,
    /// Frames the link thread received and passed on (each page may skip some).
    pub frames: AtomicU64,
    /// Scenes passed on (a first scene, a new generation, a server that came back).
    pub scenes: AtomicU64,
    /// Hand-joints messages taken from pages (well-formed, whatever becomes of them).
    pub hand_joints_accepted: AtomicU64,
    /// Hand-joints messages refused as malformed (each closes its page's connection).
    pub hand_joints_rejected: AtomicU64,
    /// Hand-joints messages taken but not published: the link thread was too far behind, or
    /// there was no server to publish them to.
    pub hand_joints_dropped: AtomicU64,
    /// Hand-joints samples published on the server's hand-joints service.
    pub hand_joints_published: AtomicU64,
    /// Requests refused because their `Host` names another site (DNS rebinding): 421.
    pub refused_host: AtomicU64,
    /// Requests refused for want of the access token (or a session it opened): 401.
    pub refused_token: AtomicU64,
    /// Pages refused because as many as the cap were open: 503.
    pub refused_pages: AtomicU64,
    /// Connections closed on accepting them because as many as the cap were open.
    pub refused_connections: AtomicU64,
    /// Pages closed for sending nothing, not even an answer to a ping, for the idle time-out.
    pub timed_out_pages: AtomicU64,
    /// Connections closed for not sending a whole request head (or TLS handshake) within the
    /// header time-out: half-sent requests, and keep-alive connections left idle.
    pub timed_out_requests: AtomicU64,
    /// Whether a vas server answers now.
    pub server: AtomicBool,
}

impl Stats {
    /// Adds one to `counter`.
    pub fn count(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    /// The counters as a JSON object.
    pub fn snapshot(&self) -> Value {
        let get = |counter: &AtomicU64| counter.load(Ordering::Relaxed);
        let refused = json!({
            "malformed": get(&self.refused_malformed),
            "oversized": get(&self.refused_oversized),
            "unknown": get(&self.refused_unknown),
        });
        let hand_joints = json!({
            "accepted": get(&self.hand_joints_accepted),
            "rejected": get(&self.hand_joints_rejected),
            "dropped": get(&self.hand_joints_dropped),
            "published": get(&self.hand_joints_published),
        });
        let refused_requests = json!({
            "host": get(&self.refused_host),
            "token": get(&self.refused_token),
            "pages": get(&self.refused_pages),
            "connections": get(&self.refused_connections),
        });
        let timed_out = json!({
            "pages": get(&self.timed_out_pages),
            "requests": get(&self.timed_out_requests),
        });
        json!({
            "server": self.server.load(Ordering::Relaxed),
            "pages_open": get(&self.pages_open),
            "pages_served": get(&self.pages_served),
            "refused": refused,
            "events_dropped": get(&self.events_dropped),
            "commands": get(&self.commands),
            "frames": get(&self.frames),
            "scenes": get(&self.scenes),
            "hand_joints": hand_joints,
            "refused_requests": refused_requests,
            "timed_out": timed_out,
        })
    }
}
