//! Checking and planning tasks: the findings `coherent validate` and
//! `coherent.validate()` report, the optimal plan with its physical execution, and the
//! import into native files.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::makespan::{self, Makespan};
use coherent_core::planner::{self, Analysis, Limits, Stop};
use coherent_core::text::{file_name_part, shown};
use coherent_core::{Error, Task, native, original, validate};
use coherent_sim::PlanReport;

/// Every problem of `task`, empty when it is clean: the rules' findings (unknown ids,
/// unreachable goals, wrong ground truths, ...) from the optimal planner's analysis, and
/// the geometry's (stairs follow rules of their own that only physics needs; a scene
/// author hears of a broken flight here).
pub fn findings(task: &Task, limits: &Limits) -> Vec<String> {
    let analysis = planner::analyse(task, limits);
    let mut found = validate::findings(task, &analysis);
    if let Some(Err(e)) = task
        .meta
        .geometry
        .as_ref()
        .map(coherent_sim::layout::flights)
    {
        found.push(format!("geometry: {e}"));
    }
    found
}

/// What `coherent plan` does besides the shortest plan.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanOptions {
    /// Carry the plan out in Rapier, checking it against the rules after every step;
    /// with `parallel`, the makespan plan too, each joint step's robots moving at once.
    pub physics: bool,
    /// Also find the fewest joint steps (`--parallel`, docs/planner.md, "Parallel plans").
    pub parallel: bool,
}

/// A task's optimal plan, and, when asked, its fewest joint steps and those plans
/// carried out in Rapier.
#[derive(Debug)]
pub struct Planned {
    pub analysis: Analysis,
    pub makespan: Option<Makespan>,
    /// The sequential plan in Rapier.
    pub physics: Option<PlanReport>,
    /// The makespan plan in Rapier (`steps_done` counts joint steps).
    pub makespan_physics: Option<PlanReport>,
}

impl Planned {
    /// One line of `coherent plan --json`, `coherent.plan()`'s dict.
    pub fn to_json(&self, task: &Task) -> serde_json::Value {
        let mut value = self.analysis.to_json(task);
        if let Some(m) = &self.makespan {
            let plan: Option<Vec<serde_json::Value>> = m.plan.as_ref().map(|plan| {
                plan.iter()
                    .map(|step| {
                        step.iter()
                            .map(|s| serde_json::json!({"robot": task.id(s.robot).0, "action": s.action.render(task)}))
                            .collect()
                    })
                    .collect()
            });
            value["makespan"] = m.makespan().into();
            value["makespan_proven"] = m.proven.into();
            value["makespan_lower"] = m.lower.into();
            value["makespan_stop"] = m.stop.map(stop_name).into();
            value["parallel_plan"] = plan.into();
            value["makespan_states_expanded"] = m.states_expanded.into();
            value["makespan_ms"] = ((m.elapsed.as_secs_f64() * 1e6).round() / 1e3).into();
        }
        if let Some(r) = &self.physics {
            physics_json(&mut value, "", r);
        }
        if let Some(r) = &self.makespan_physics {
            physics_json(&mut value, "makespan_", r);
        }
        value
    }

    /// Whether a plan carried out in Rapier failed there.
    pub fn physics_failed(&self) -> bool {
        [&self.physics, &self.makespan_physics]
            .iter()
            .any(|r| r.as_ref().is_some_and(|r| !r.physics_ok))
    }

    /// The plans' runs in Rapier for `coherent plan`'s text, a line each:
    /// `  physics: ok, 59.3 s simulated in 210 ms`, `  parallel physics: ...`, or the
    /// failure (it names the step, or joint step, and the numbers); empty without physics.
    pub fn physics_text(&self) -> String {
        let runs = [
            ("physics", &self.physics),
            ("parallel physics", &self.makespan_physics),
        ];
        let mut text = String::new();
        for (label, run) in runs {
            let Some(r) = run else { continue };
            text.push_str(&match &r.physics_error {
                None => format!(
                    "\n  {label}: ok, {:.1} s simulated in {:.0} ms",
                    r.sim_seconds, r.wall_ms
                ),
                Some(e) => format!("\n  {label}: failed: {}", shown(e)),
            });
        }
        text
    }
}

/// A plan's run in Rapier as the keys `physics_ok`, `physics_error`, `sim_seconds` and
/// `physics_wall_ms`, each after `prefix`.
fn physics_json(value: &mut serde_json::Value, prefix: &str, r: &PlanReport) {
    value[format!("{prefix}physics_ok")] = r.physics_ok.into();
    value[format!("{prefix}physics_error")] = r.physics_error.clone().into();
    value[format!("{prefix}sim_seconds")] = r.sim_seconds.into();
    value[format!("{prefix}physics_wall_ms")] = ((r.wall_ms * 1e3).round() / 1e3).into();
}

/// Plans `task` optimally; with `parallel`, also finds its fewest joint steps from the
/// shortest plan; with `physics`, also carries the plan out in Rapier and checks it
/// against the rules after every step, and with both the makespan plan as well, after
/// every joint step.
pub fn plan(task: &Task, limits: &Limits, options: PlanOptions) -> Planned {
    let analysis = planner::analyse(task, limits);
    let makespan = options.parallel.then(|| {
        makespan::search_with(
            task,
            &task.init,
            &task.robots,
            &task.goal,
            analysis.plan.as_deref(),
            limits,
        )
    });
    let shared = options.physics.then(|| Arc::new(task.clone()));
    let physics = match (&analysis.plan, &shared) {
        (Some(plan), Some(task)) => Some(coherent_sim::execute_plan(task, plan)),
        _ => None,
    };
    let joint = makespan.as_ref().and_then(|m| m.plan.as_ref());
    let makespan_physics = match (joint, &shared) {
        (Some(plan), Some(task)) => Some(coherent_sim::execute_joint_plan(task, plan)),
        _ => None,
    };
    Planned {
        analysis,
        makespan,
        physics,
        makespan_physics,
    }
}

/// The limit a search stopped at, as `makespan_stop` names it.
fn stop_name(stop: Stop) -> &'static str {
    match stop {
        Stop::States => "states",
        Stop::Memory => "memory",
        Stop::Cancelled => "cancelled",
        Stop::Depth => "depth",
    }
}

/// Writes each task as a native task file, `<out>/<scene>/task-<id>.json`, the scene's
/// folder named in safe characters only (no `..`, no `/`, no control character; a hash
/// when its name had to change, `coherent_core::text::file_name_part`); returns the
/// files written.
pub fn import(tasks: &[Task], out: &Path) -> Result<Vec<PathBuf>, Error> {
    let mut written = HashSet::new();
    let mut files = Vec::new();
    for t in tasks {
        let dir = out.join(file_name_part(&t.meta.scene, 64).as_ref());
        let path = dir.join(format!("task-{:03}.json", t.meta.task_id));
        if !written.insert(path.clone()) {
            return Err(Error::Io {
                file: path.display().to_string(),
                message: format!(
                    "two tasks map to this file (scene {:?}, task_id {}); import them into different folders",
                    t.meta.scene, t.meta.task_id
                ),
            });
        }
        let io = |e: std::io::Error| Error::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        };
        std::fs::create_dir_all(&dir).map_err(io)?;
        let text = serde_json::to_string_pretty(&native::to_value(t))
            .expect("JSON values always serialize");
        std::fs::write(&path, text + "\n").map_err(io)?;
        files.push(path);
    }
    Ok(files)
}

/// Writes tasks in the paper's own format: one env file per scene, `<out>/<scene>.json`
/// (the scene's name in safe characters, as [`import`] names folders), a list of its
/// tasks in the order given, each as [`original::to_value`] writes it: the graph at the
/// start with every height a label (under the `geometric` rules the labels the geometry
/// gives), the goal as keys, the ground truth and the instruction in lists. The
/// authors' code reads such files; `coherent import` reads them back to the same tasks.
/// Returns the files written.
pub fn export_original(tasks: &[Task], out: &Path) -> Result<Vec<PathBuf>, Error> {
    let mut scenes: Vec<(&str, Vec<serde_json::Value>)> = Vec::new();
    for t in tasks {
        let value = original::to_value(t);
        match scenes.iter_mut().find(|(s, _)| *s == t.meta.scene) {
            Some((_, list)) => list.push(value),
            None => scenes.push((&t.meta.scene, vec![value])),
        }
    }
    let mut files: Vec<PathBuf> = Vec::new();
    for (scene, list) in scenes {
        let path = out.join(format!("{}.json", file_name_part(scene, 64)));
        if files.contains(&path) {
            return Err(Error::Io {
                file: path.display().to_string(),
                message: format!(
                    "two scenes map to this file ({scene:?} and another whose name differs only in characters a file name cannot hold)"
                ),
            });
        }
        let io = |e: std::io::Error| Error::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        };
        std::fs::create_dir_all(out).map_err(io)?;
        let text = serde_json::to_string_pretty(&serde_json::Value::Array(list))
            .expect("JSON values always serialize");
        std::fs::write(&path, text + "\n").map_err(io)?;
        files.push(path);
    }
    Ok(files)
}
