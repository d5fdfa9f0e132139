//! `coherent export --format pddl` and `coherent plan --check FILE`: the tasks in PDDL,
//! and a PDDL plan checked against the rules (docs/pddl.md).

use std::io::Write;
use std::path::Path;

use crate::session::engine::{Limits, Task, shown};
use crate::session::{Error, pddl};

/// Writes the files of `--format pddl`; exit 1 when a task could not be written (the
/// domain cannot express it) or, with `--plans`, has no plan.
pub fn export(tasks: &[Task], out: &Path, plans: bool, limits: &Limits) -> Result<u8, Error> {
    let written = pddl::export_files(tasks, out, plans, limits)?;
    for refused in &written.refused {
        eprintln!("refused: {}", shown(&refused.to_string()));
    }
    for unplanned in &written.unplanned {
        eprintln!("no plan: {}", shown(unplanned));
    }
    println!(
        "wrote {} files to {} ({} tasks, {} refused)",
        written.files.len(),
        shown(&out.display().to_string()),
        tasks.len() - written.refused.len(),
        written.refused.len()
    );
    Ok(u8::from(
        !written.refused.is_empty() || !written.unplanned.is_empty(),
    ))
}

/// `coherent plan FILE --check PLAN`: the plan played through the rules of the one task
/// chosen; exit 0 when every action is allowed in turn and the goal holds at the end.
pub fn check(tasks: &[Task], plan: &Path, as_json: bool) -> Result<u8, Error> {
    let [task] = tasks else {
        return Err(Error::Invalid(format!(
            "--check plays a plan on one task, and {} were chosen: pick one with --task",
            tasks.len()
        )));
    };
    let check = pddl::check_plan_file(task, plan)?;
    let mut lines = Vec::new();
    if as_json {
        let value = serde_json::json!({
            "scene": task.meta.scene,
            "task_id": task.meta.task_id,
            "valid": check.valid(),
            "length": check.length,
            "goal_reached": check.goal_reached,
            "failure": check.failure.as_ref().map(|(line, why)| serde_json::json!({"line": line, "reason": why})),
            "actions": check.actions,
        });
        lines.push(value.to_string());
    } else {
        let head = format!("{} task {}", shown(&task.meta.scene), task.meta.task_id);
        lines.push(match &check.failure {
            Some((line, why)) => format!(
                "{head}: {} line {line}: {}",
                shown(&plan.display().to_string()),
                shown(why)
            ),
            None if check.goal_reached => format!(
                "{head}: the plan's {} actions are allowed in turn and reach the goal",
                check.length
            ),
            None => format!(
                "{head}: the plan's {} actions are allowed in turn but the goal does not hold after them",
                check.length
            ),
        });
        lines.extend(check.actions.iter().map(|a| format!("  {}", shown(a))));
    }
    // A closed pipe (e.g. `| head`) ends the listing quietly.
    let mut out = std::io::stdout().lock();
    for line in lines {
        if writeln!(out, "{line}").is_err() {
            break;
        }
    }
    Ok(u8::from(!check.valid()))
}
