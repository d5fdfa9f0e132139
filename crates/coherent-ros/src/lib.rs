//! `coherent-ros`: the robot executors of a COHERENT episode over ROS 2 actions, in pure
//! Rust (ros2-client over RustDDS; no ROS installation needed), on ROS 2 Jazzy's wire
//! format.
//!
//! Each robot of a task is one action server, `/<namespace>/<robot>/execute`, of type
//! `coherent_msgs/action/Execute` (the package is `ros/coherent_msgs` in the repository;
//! [`wire`] has its types). [`Ros2Env`] is the planner's side, an `Environment` of
//! `coherent-core`: the rules check each action before it is sent, the robot carries it
//! out and reports, and the symbolic state follows the robot's success. [`serve`] runs
//! the reference robot servers, which act in the project's own engine (the rules, or
//! Rapier), carry a dynamic task's events out in it when the bridge asks their world's
//! service, `/<namespace>/befall` (`coherent_msgs/srv/Befall`), and inject faults on
//! demand ([`Faults`]). The bridge's DDS side runs in a child process with a memory limit
//! ([`link_process`]), so that what a DDS participant sends can end that process, never
//! the run.

mod befall;
pub mod bridge;
mod error;
pub mod faults;
mod link;
pub mod link_process;
pub mod relations;
pub mod server;
pub mod wire;
mod world;

pub use bridge::{BridgeOptions, Ros2Env};
pub use error::Error;
pub use faults::Faults;
pub use link_process::{LINK_MEMORY_LIMIT, LinkCommand};
pub use server::{SERVE_MEMORY_LIMIT, ServeOptions, serve};
pub use world::World;
