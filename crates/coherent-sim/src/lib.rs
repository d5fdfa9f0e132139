//! `coherent-sim`: Rapier grounding of the COHERENT world (quadrotors, legged robots,
//! fixed arms). It depends on `coherent-core` only and implements its `Environment`
//! physically: [`layout`] places everything (a task's geometry, or generated from the
//! graph), [`world`] builds the bodies and robot models, executes an action and reads
//! the relations back, and [`PhysicalEnv`] checks each step against the rules.

pub mod env;
pub mod layout;
mod path;
pub mod render;
pub mod world;

pub use env::{
    JointReport, PhysicalEnv, PlanReport, StepReport, disagreements, execute_joint_plan,
    execute_plan,
};
pub use layout::{Layout, LayoutError, RobotSpecs};
pub use world::{FailureKind, PhysicsError, Placement, Tolerances, World};
