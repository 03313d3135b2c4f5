//! The grasping module against scripted motions and the clasp against a world of balls: tests
//! that need the scripts of `vas-testkit`, run on the library's public interface.

mod clasp;
mod scenarios;
