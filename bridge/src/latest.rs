//! The latest state a renderer that joins late asks for: the geometry, the latest parts frame,
//! each hand's latest frame and the latest clearance frame, answered by queryables on the keys
//! they are published on (zenoh subscribers get no history, as iceoryx2's late readers do).

use std::sync::{Arc, Mutex};

use vas_protocol::services;
use zenoh::Wait;
use zenoh::bytes::ZBytes;
use zenoh::query::Queryable;

use crate::keys::Keys;
use crate::server::Shared;

/// The latest encoded messages of the services that keep history.
#[derive(Debug, Default)]
pub struct Latest {
    /// The current generation's geometry.
    pub geometry: Option<ZBytes>,
    /// The latest parts frame.
    pub parts: Option<ZBytes>,
    /// Each hand's latest frame.
    pub hands: Vec<ZBytes>,
    /// The latest clearance frame.
    pub clearance: Option<ZBytes>,
}

impl Latest {
    /// The messages a query on `service` is answered with.
    fn of(&self, service: &str) -> Vec<ZBytes> {
        match service {
            services::GEOMETRY => self.geometry.iter().cloned().collect(),
            services::PARTS => self.parts.iter().cloned().collect(),
            services::HAND => self.hands.clone(),
            services::CLEARANCE => self.clearance.iter().cloned().collect(),
            _ => Vec::new(),
        }
    }
}

/// Declares the queryables of the latest state; they answer until dropped.
pub fn declare(
    session: &zenoh::Session,
    keys: &Keys,
    shared: &Arc<Shared>,
) -> zenoh::Result<Vec<Queryable<()>>> {
    [
        services::GEOMETRY,
        services::PARTS,
        services::HAND,
        services::CLEARANCE,
    ]
    .into_iter()
    .map(|service| {
        let key = keys.service(service);
        let shared = Arc::clone(shared);
        let reply_key = key.clone();
        session
            .declare_queryable(key)
            .callback(move |query| {
                let messages = lock(&shared.latest).of(service);
                for message in messages {
                    if let Err(error) = query.reply(&reply_key, message).wait() {
                        tracing::debug!(%error, key = reply_key, "cannot answer a query");
                    }
                }
            })
            .wait()
    })
    .collect()
}

/// Locks the latest state; a thread that panicked while holding it left whole messages only.
pub fn lock(latest: &Mutex<Latest>) -> std::sync::MutexGuard<'_, Latest> {
    latest
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
