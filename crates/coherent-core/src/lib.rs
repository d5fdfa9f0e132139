//! `coherent-core`: the world of the COHERENT benchmark (Liu et al.) and its exact rules.
//!
//! A [`Task`] is read from the paper's original files ([`original`]) or from our own
//! format ([`native`]). [`rules`] gives observations, action lists and transitions,
//! [`feasibility`] says why an action cannot be done, [`reach`] what a robot can get at, [`planner`] finds shortest plans
//! and task types, [`validate`] lists semantic problems, and [`Environment`] is what
//! planners and physics plug into. [`benchmark`] is the project's own benchmark, compiled in; [`pddl`] writes tasks
//! in PDDL and reads PDDL plans back.

pub mod action;
pub mod benchmark;
mod chain;
pub mod describe;
pub mod env;
pub mod error;
pub mod events;
pub mod execution;
pub mod feasibility;
pub mod files;
pub mod footprint;
pub mod geometry;
pub mod graph;
pub mod heights;
pub mod joint;
pub mod json;
pub mod load;
pub mod makespan;
pub mod native;
pub mod original;
pub mod pddl;
pub mod planner;
pub mod reach;
pub mod relaxed;
pub mod rules;
pub mod schedule;
mod tables;
pub mod task;
pub mod text;
pub mod validate;
pub mod vocab;

pub use action::{Action, ParsedAction, Verb};
pub use env::{Environment, JointOutcome, Outcome, PartOutcome, RobotReport, SymbolicEnv};
pub use error::{Error, JsonPath, Result};
pub use execution::Execution;
pub use feasibility::{Infeasible, Reason};
pub use geometry::Layout;
pub use graph::{Edge, Idx, Node, NodeId, NodeKind, RobotKind, State};
pub use load::{load_tasks, read_tasks};
pub use planner::{Analysis, Limits, Step, Stop, TaskType};
pub use rules::Observation;
pub use schedule::Schedule;
pub use task::{
    Event, GoalPredicate, Happening, MAX_GROUND_TRUTH, RawGraph, Robot, RuleSet, Task, TaskMeta,
    Trigger,
};
pub use vocab::{PropSet, Relation, StateSet};
