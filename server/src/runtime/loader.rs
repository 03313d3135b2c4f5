//! Scenes requested over `vas/control` load on a thread of their own: reading meshes and building
//! their trees can take seconds, and meanwhile the I/O thread keeps serving the current scene
//! (input, frames, other control requests). The loaded scene is swapped in between frames, and the
//! request is answered then.

use std::path::PathBuf;

use crossbeam_channel::{Receiver, TryRecvError};
use iceoryx2::active_request::ActiveRequest;
use iceoryx2::prelude::*;
use vas_protocol::{ControlRequest, ControlResponse};

use super::wakeup::Waker;
use crate::scene::{LoadOptions, Scene};

/// A control request being answered, held until its answer is ready.
pub(super) type PendingRequest =
    ActiveRequest<ipc::Service, ControlRequest, (), ControlResponse, ()>;

/// At most one scene load at a time, on its own thread.
pub(super) struct SceneLoader {
    /// Wakes the I/O thread when a load finishes.
    waker: Waker,
    /// How scenes are loaded.
    options: LoadOptions,
    loading: Option<Loading>,
}

/// The load under way: the request it answers and where its outcome arrives.
struct Loading {
    request: PendingRequest,
    outcome: Receiver<Result<Scene, String>>,
}

/// A finished load: the request to answer and the scene, or why there is none.
pub(super) struct Loaded {
    pub(super) request: PendingRequest,
    pub(super) outcome: Result<Scene, String>,
}

impl SceneLoader {
    /// A loader whose threads load scenes with `options` and wake the I/O thread with `waker`
    /// when they finish.
    pub(super) fn new(waker: Waker, options: LoadOptions) -> Self {
        Self {
            waker,
            options,
            loading: None,
        }
    }

    /// Whether a load is under way.
    pub(super) fn is_loading(&self) -> bool {
        self.loading.is_some()
    }

    /// Starts loading `path` for `request`. A thread that cannot be started gives the request
    /// back as loaded with the reason.
    pub(super) fn start(&mut self, path: PathBuf, request: PendingRequest) -> Option<Loaded> {
        let (sender, outcome) = crossbeam_channel::bounded(1);
        let waker = self.waker.clone();
        let options = self.options.clone();
        let spawned = std::thread::Builder::new()
            .name("scene-loader".into())
            .spawn(move || {
                let loaded = Scene::load_with(&path, &options).map_err(|error| error.to_string());
                if let Ok(scene) = &loaded {
                    scene.prepare();
                }
                // The receiver is gone only when the server is shutting down.
                let _ = sender.send(loaded);
                waker.wake();
            });
        match spawned {
            Ok(_detached) => {
                self.loading = Some(Loading { request, outcome });
                None
            }
            Err(error) => Some(Loaded {
                request,
                outcome: Err(format!("cannot start the scene loader thread: {error}")),
            }),
        }
    }

    /// The finished load, if one finished since the last call. A loader thread that died (a
    /// panic while loading) finishes its load with that as the reason: the server goes on.
    pub(super) fn finished(&mut self) -> Option<Loaded> {
        let outcome = match self.loading.as_ref()?.outcome.try_recv() {
            Ok(outcome) => outcome,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => {
                Err("the scene loader failed; the log says where".to_owned())
            }
        };
        let Loading { request, .. } = self.loading.take()?;
        Some(Loaded { request, outcome })
    }
}
