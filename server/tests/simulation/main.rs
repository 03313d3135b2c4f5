//! The simulation step offline, driven by the scripts of `vas-testkit`.

mod interaction;
