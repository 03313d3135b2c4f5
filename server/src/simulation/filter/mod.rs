//! Smoothing of tracked hand input with the One Euro filter (Casiez, Roussel and Vogel, "1€
//! Filter: A Simple Speed-based Low-pass Filter for Noisy Input in Interactive Systems", CHI
//! 2012): a first-order low-pass whose cut-off frequency rises with the signal's speed, so
//! that a still hand is held still (a low cut-off removes the tracker's jitter) and a fast one
//! follows closely (a high cut-off, little lag).
//!
//! [`Gain`] is the filter's adaptive part, shared by every kind of value: from the step of a
//! sample away from the estimate it tracks the speed and answers how far to move the estimate.
//! [`StreamFilter`] applies it to one input stream: a root pose (position and rotation, see
//! [`rotation`] for how rotations are smoothed) and a fixed number of scalar values (a hand's
//! flex values), timed by the samples' own timestamps ([`SampleClock`]) so that a lockstep
//! replay gives the same output every time.
//!
//! It lives in the simulation layer, beside the frames it feeds, rather than in the runtime
//! that applies it to the samples it takes in: it is plain state with no threads or ports, it
//! reads its tuning from the scene's `[params.tracking]`, and the benchmarks measure it alone.

mod clock;
mod gain;
pub mod rotation;
mod stream;

pub use clock::{SampleClock, TimeFault};
pub use gain::{Gain, Tuning, smoothing};
pub use stream::{Filtered, NonFiniteSample, Passage, Sample, StreamFilter};

#[cfg(test)]
mod tests;
