//! The tasks in PDDL (docs/pddl.md): `coherent export --format pddl` and
//! `coherent.pddl()`, our optimal plans as PDDL plans, and a PDDL plan read back and
//! checked against the rules (`coherent plan --check`, `coherent.check_pddl_plan()`).

use std::path::{Path, PathBuf};

use coherent_core::pddl::{self, Names, Pddl, PlanCheck};
use coherent_core::planner::{self, Limits};
use coherent_core::{Error, RuleSet, Task};

/// The domain and problem of `task`, or why the domain cannot express it.
pub fn export(task: &Task) -> Result<Pddl, Error> {
    pddl::export(task)
}

/// The PDDL name of `task`'s problem: its file is `<name>.pddl`.
pub fn problem_name(task: &Task) -> String {
    Names::of_task(task).problem
}

/// What `export_files` wrote and refused.
#[derive(Debug, Default)]
pub struct Written {
    pub files: Vec<PathBuf>,
    /// Tasks the domain cannot express, with the reason.
    pub refused: Vec<Error>,
    /// Tasks with `plans` whose optimal plan could not be found (no plan, or a search
    /// limit), with the planner's reason.
    pub unplanned: Vec<String>,
}

/// Writes each task's problem into `out` as `<problem>.pddl` and each rule set's domain
/// as `domain-<rules>.pddl`; with `plans`, each task's optimal plan as `<problem>.plan`
/// too, a PDDL plan file.
pub fn export_files(
    tasks: &[Task],
    out: &Path,
    plans: bool,
    limits: &Limits,
) -> Result<Written, Error> {
    std::fs::create_dir_all(out).map_err(|e| io(out, &e))?;
    let mut written = Written::default();
    let mut rule_sets = Vec::new();
    for task in tasks {
        let p = match pddl::export(task) {
            Ok(p) => p,
            Err(e) => {
                written.refused.push(e);
                continue;
            }
        };
        let name = problem_name(task);
        let file = out.join(format!("{name}.pddl"));
        write(&file, &p.problem)?;
        written.files.push(file);
        if !rule_sets.contains(&task.meta.rules) {
            rule_sets.push(task.meta.rules);
        }
        if plans {
            let analysis = planner::analyse(task, limits);
            match &analysis.plan {
                Some(plan) => {
                    let file = out.join(format!("{name}.plan"));
                    write(&file, &pddl::plan_text(task, plan))?;
                    written.files.push(file);
                }
                None => written.unplanned.push(format!(
                    "{name}: {}",
                    analysis.reason.as_deref().unwrap_or("no plan")
                )),
            }
        }
    }
    for rules in rule_sets {
        let file = out.join(format!("domain-{}.pddl", rules_key(rules)));
        write(&file, &pddl::domain(rules))?;
        written.files.push(file);
    }
    Ok(written)
}

/// A rule set's name in file names.
pub fn rules_key(rules: RuleSet) -> &'static str {
    match rules {
        RuleSet::Compatible => "compatible",
        RuleSet::Geometric => "geometric",
    }
}

/// Plays the PDDL plan in `file` through `task`'s rules.
pub fn check_plan_file(task: &Task, file: &Path) -> Result<PlanCheck, Error> {
    Ok(pddl::check_plan(task, &pddl::read_plan_file(file)?))
}

/// Plays the PDDL plan `text` through `task`'s rules.
pub fn check_plan(task: &Task, text: &str) -> PlanCheck {
    pddl::check_plan(task, text)
}

/// `task`'s optimal plan as a PDDL plan, or the planner's reason when it has none.
pub fn optimal_plan(task: &Task, limits: &Limits) -> Result<String, String> {
    let analysis = planner::analyse(task, limits);
    match &analysis.plan {
        Some(plan) => Ok(pddl::plan_text(task, plan)),
        None => Err(analysis.reason.unwrap_or_else(|| "no plan".to_owned())),
    }
}

fn write(file: &Path, text: &str) -> Result<(), Error> {
    std::fs::write(file, text).map_err(|e| io(file, &e))
}

fn io(path: &Path, e: &std::io::Error) -> Error {
    Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    }
}
