//! The tasks in PDDL (docs/pddl.md): a domain per rule set ([`domain()`]), a problem per
//! task ([`export`]), plans written as PDDL actions ([`plan_text`]) and PDDL plans read
//! back and checked against the rules ([`check_plan`]).
//!
//! The domain is exact: every action of the rules is one PDDL action, with the same
//! preconditions and the same effects, so that an optimal PDDL plan is as long as the
//! optimal plan of [`crate::planner`]. A task the domain cannot express exactly (a thing
//! in two places at once, a robot that is also a table...) is refused with the reason.

mod domain;
mod names;
mod plan;
mod problem;

pub use domain::{domain, domain_name};
pub use names::Names;
pub use plan::{PLAN_FILE_LIMIT, PlanCheck, action_text, check_plan, plan_text, read_plan_file};

use crate::error::{Error, Result};
use crate::task::Task;

/// A task in PDDL: its rule set's domain and its problem.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pddl {
    pub domain: String,
    pub problem: String,
}

/// The domain and problem of `task`, or why the domain cannot express it exactly
/// ([`Error::Inexpressible`]).
pub fn export(task: &Task) -> Result<Pddl> {
    let classes = problem::classify(task).map_err(|reason| Error::Inexpressible {
        task: problem::task_origin(task),
        reason,
    })?;
    let names = Names::of_task(task);
    Ok(Pddl {
        domain: domain(task.meta.rules),
        problem: problem::problem(task, &classes, &names),
    })
}
