//! Keeping the rayon pool's threads awake while a frame needs them: a thread asleep takes long to
//! wake, and a frame's parallel parts are short.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Keeps the other threads of the current rayon pool awake from a frame's first queued move until
/// the frame's back end starts.
///
/// A thread asleep between frames is slow to take up the back end, and one woken by the first
/// move but left idle often falls asleep again while the moves are queued. So it is handed a task
/// that spins until the back end starts, or [`WARM_SPIN_LIMIT`] passes (a frame queued but not
/// run soon). Only from inside a pool of several threads: elsewhere there is none to wake.
#[derive(Default)]
pub(super) struct PoolWarmer {
    /// Counts the back ends started: a spinning task stops when it changes.
    back_ends: Arc<AtomicU64>,
}

/// The cores of this machine: a [`PoolWarmer`] keeps no more threads spinning than there are
/// cores besides the caller's, so that they never take the core the caller queues moves on.
fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, usize::from))
}

/// Longest a [`PoolWarmer`] task spins.
const WARM_SPIN_LIMIT: Duration = Duration::from_micros(300);

impl PoolWarmer {
    /// Wakes the other threads of the current pool and keeps them awake until [`Self::release`].
    pub(super) fn wake(&self) {
        if rayon::current_thread_index().is_none() {
            return;
        }
        let started = self.back_ends.load(Ordering::Relaxed);
        for _ in 1..rayon::current_num_threads().min(cores()) {
            let back_ends = Arc::clone(&self.back_ends);
            rayon::spawn(move || {
                let deadline = Instant::now() + WARM_SPIN_LIMIT;
                while back_ends.load(Ordering::Relaxed) == started && Instant::now() < deadline {
                    std::hint::spin_loop();
                }
            });
        }
    }

    /// Lets the spinning tasks end: the back end's work is about to be handed out.
    pub(super) fn release(&self) {
        self.back_ends.fetch_add(1, Ordering::Relaxed);
    }
}

/// Waits for `done` awake: runs the current pool's pending tasks meanwhile, or spins.
///
/// Rayon's own waits (at the end of a `join` or a `scope`) put a thread to sleep after a few
/// microseconds without work, and waking it takes longer than a frame's tail of work. Only for
/// waits that end within a frame: a thread kept spinning from frame to frame is taken off its
/// core by the host more often.
pub(super) fn help_until(done: impl Fn() -> bool) {
    while !done() {
        help_once();
    }
}

/// Runs one pending task of the current pool, or spins once if there is none.
pub(super) fn help_once() {
    if rayon::yield_now() != Some(rayon::Yield::Executed) {
        std::hint::spin_loop();
    }
}
