//! Benchmark procedures of BENCHMARKS.md, shared by the `vas-server bench` subcommands and tests.

pub mod bounce;
pub mod grasp;
pub mod orbit;
pub mod random;
pub mod report;
pub mod slide;
pub mod tumble;
