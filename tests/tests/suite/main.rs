//! The end-to-end tests, in one test binary so that the workspace links it once: the real
//! `vas-server`, `vas-client` and `vas-bench` binaries and the examples, each test on its own
//! iceoryx2 prefix.

mod bench_tools;
mod bridge;
mod bridge_users;
mod c_library;
mod clearance;
mod client_roles;
mod end_to_end;
mod examples;
mod faults;
mod filtered_handover;
mod fixtures;
mod geometry_delivery;
mod hand_joints;
mod hostile_input;
mod paced_replay;
mod replays;
mod report;
mod retarget;
mod server_process;
mod unity_sample;
