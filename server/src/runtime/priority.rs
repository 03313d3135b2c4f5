//! Realtime scheduling of the server's own threads (`vas-server run --realtime PRIORITY`).
//!
//! Beside a renderer that keeps the cores busy, a woken loop at the normal policy waits behind
//! it for the rest of its time slice, milliseconds; under `SCHED_FIFO` it runs at once. Only the
//! I/O thread and the three loops are raised, each by itself, and with `SCHED_RESET_ON_FORK`:
//! the threads they start (a scene loader, rayon's tree builders) run at the normal policy, so
//! seconds of building a loaded scene's trees never hold a core against the renderer.
//!
//! A realtime thread that waits awake for an announced frame (`rendezvous`) yields only
//! to realtime threads, so for at most `ANNOUNCED_WAIT` it keeps its core
//! from the renderer; the kernel's realtime throttling (by default 5 % of every second left to
//! other threads) bounds any longer run.

/// A `SCHED_FIFO` priority, 1 (lowest) to 99.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RealtimePriority(u8);

/// Why a thread could not be raised to realtime priority.
#[derive(Debug, thiserror::Error)]
pub enum PriorityError {
    /// Not one of `SCHED_FIFO`'s priorities.
    #[error("a realtime priority is 1 to 99, not {0}")]
    OutOfRange(u64),
    /// The kernel refused (most often: not permitted).
    #[error(
        "cannot run at realtime priority {priority}: {source}; it needs CAP_SYS_NICE or a \
         realtime priority limit of at least {priority} (`ulimit -r {priority}`, or `rtprio` in \
         /etc/security/limits.conf)"
    )]
    Refused {
        /// The priority asked for.
        priority: u8,
        /// What the kernel said.
        source: std::io::Error,
    },
}

impl RealtimePriority {
    /// The priority, if `priority` is one of `SCHED_FIFO`'s.
    pub fn new(priority: u64) -> Result<Self, PriorityError> {
        u8::try_from(priority)
            .ok()
            .filter(|priority| (1..=99).contains(priority))
            .map(RealtimePriority)
            .ok_or(PriorityError::OutOfRange(priority))
    }

    /// The priority's number.
    pub fn get(self) -> u8 {
        self.0
    }

    /// Puts the calling thread under `SCHED_FIFO` at this priority; threads it starts from now
    /// on run at the normal policy.
    pub fn raise_this_thread(self) -> Result<(), PriorityError> {
        let refused = |source| PriorityError::Refused {
            priority: self.0,
            source,
        };
        #[cfg(target_os = "linux")]
        {
            let param = libc::sched_param {
                sched_priority: i32::from(self.0),
            };
            // SAFETY: `param` is a valid sched_param for the call's duration; pid 0 is the
            // calling thread.
            let result = unsafe {
                libc::sched_setscheduler(0, libc::SCHED_FIFO | libc::SCHED_RESET_ON_FORK, &param)
            };
            if result == 0 {
                Ok(())
            } else {
                Err(refused(std::io::Error::last_os_error()))
            }
        }
        #[cfg(not(target_os = "linux"))]
        {
            Err(refused(std::io::Error::new(
                std::io::ErrorKind::Unsupported,
                "realtime threads are supported on Linux only",
            )))
        }
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// The calling thread's policy, without the reset-on-fork flag, and priority.
    fn policy_of_this_thread() -> (i32, i32) {
        let mut param = libc::sched_param { sched_priority: 0 };
        // SAFETY: pid 0 is the calling thread; `param` outlives the call.
        let (policy, result) = unsafe {
            (
                libc::sched_getscheduler(0),
                libc::sched_getparam(0, &mut param),
            )
        };
        assert!(
            policy >= 0 && result == 0,
            "the thread's policy is readable"
        );
        (policy & !libc::SCHED_RESET_ON_FORK, param.sched_priority)
    }

    #[test]
    fn priorities_are_those_of_sched_fifo() {
        assert_eq!(
            RealtimePriority::new(1).map(RealtimePriority::get).ok(),
            Some(1)
        );
        assert_eq!(
            RealtimePriority::new(99).map(RealtimePriority::get).ok(),
            Some(99)
        );
        for wrong in [0, 100, 255, 256, u64::MAX] {
            let error = RealtimePriority::new(wrong).expect_err("out of range");
            assert_eq!(
                error.to_string(),
                format!("a realtime priority is 1 to 99, not {wrong}")
            );
        }
    }

    /// Raised where the process may (as root, or with an rtprio limit), refused with the way to
    /// permit it otherwise; either way the threads a raised thread starts stay at the normal
    /// policy.
    #[test]
    fn a_raised_thread_is_fifo_and_its_children_are_not() {
        let priority = RealtimePriority::new(3).expect("in range");
        let outcome = std::thread::spawn(move || {
            let raised = priority.raise_this_thread();
            let own = policy_of_this_thread();
            let child = std::thread::spawn(policy_of_this_thread)
                .join()
                .expect("the child thread ends");
            (raised, own, child)
        })
        .join()
        .expect("the thread ends");
        let (raised, own, child) = outcome;
        assert_eq!(
            child,
            (libc::SCHED_OTHER, 0),
            "the child runs at the normal policy"
        );
        match raised {
            Ok(()) => assert_eq!(own, (libc::SCHED_FIFO, 3)),
            Err(error) => {
                assert_eq!(own, (libc::SCHED_OTHER, 0), "a refused thread is unchanged");
                let message = error.to_string();
                assert!(
                    message.starts_with("cannot run at realtime priority 3: ")
                        && message.contains("CAP_SYS_NICE")
                        && message.contains("ulimit -r 3"),
                    "{message}"
                );
            }
        }
    }
}
