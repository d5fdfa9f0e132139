//! What a generated set says of itself: a line of `manifest.jsonl` per task
//! ([`Entry::to_json`]), and the datasheet, the folder's README: counts by split, task
//! type, team size, optimal steps and sequential steps over makespan, the share proven,
//! what the draws rejected, the command and the version ([`Tally::datasheet`]). Only
//! counts are kept, so a set of any size is summed in bounded memory.

use std::collections::BTreeMap;

use coherent_core::planner::TaskType;
use serde_json::{Value, json};

use crate::request::{KINDS, kind_name};

/// Train, validation or test: a whole scene is in one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Split {
    Train,
    Validation,
    Test,
}

impl Split {
    pub const ALL: [Split; 3] = [Split::Train, Split::Validation, Split::Test];

    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Validation => "validation",
            Split::Test => "test",
        }
    }
}

/// A kept task, as its manifest line says it.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// `<scene>/task-<id>`: its file without `.json`.
    pub id: String,
    pub scene: String,
    pub task_id: i64,
    /// The run's seed and the draw this task came from: `--seed` and that draw make it
    /// again.
    pub seed: u64,
    pub draw: u64,
    /// Robots of each kind, in `quadrotor, legged, arm` order.
    pub team: [usize; 3],
    pub task_type: Option<TaskType>,
    /// The fewest robots that reach the goal (`None`: undecided within the limits).
    pub needed: Option<usize>,
    pub predicates: usize,
    pub steps: usize,
    pub makespan: usize,
    pub makespan_lower: usize,
    pub proven: bool,
    pub split: Split,
}

impl Entry {
    pub fn team_size(&self) -> usize {
        self.team.iter().sum()
    }

    /// The manifest line.
    pub fn to_json(&self) -> Value {
        let team: serde_json::Map<String, Value> = KINDS
            .iter()
            .zip(self.team)
            .map(|(k, n)| (kind_name(*k).to_owned(), n.into()))
            .collect();
        json!({
            "id": self.id,
            "file": format!("{}.json", self.id),
            "scene": self.scene,
            "task_id": self.task_id,
            "seed": self.seed,
            "draw": self.draw,
            "team": team,
            "team_size": self.team_size(),
            "type": self.task_type.map(TaskType::name),
            "robots_needed": self.needed,
            "predicates": self.predicates,
            "optimal_steps": self.steps,
            "makespan": self.makespan,
            "bounds": {
                "optimal_steps": [self.steps, self.steps],
                "makespan": [self.makespan_lower, self.makespan],
            },
            "proven": self.proven,
            "split": self.split.name(),
        })
    }
}

/// Why a draw was not kept, in the order the checks run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Rejected {
    /// The scene had no room for the drawn team (counters, floor) or its things.
    Start,
    /// No goal of the drawn kinds and size in that start.
    Goal,
    /// The same goal from the same start as a task already kept.
    Duplicate,
    /// No plan reaches the goal.
    Unsolvable,
    /// A search limit stopped the sequential search before a plan.
    Undecided,
    /// The filters: type, robots needed, optimal steps, ratio, proven.
    Type,
    Needed,
    Steps,
    Ratio,
    Unproven,
    /// The physics could not build the scene at this start.
    Physics,
    /// The optimal plan failed in physics (`--physics`).
    PlanPhysics,
    /// The task did not read back as a native task (a fault of the generator).
    Invalid,
}

impl Rejected {
    pub fn describe(self) -> &'static str {
        match self {
            Rejected::Start => "no room for the team or the things in the scene",
            Rejected::Goal => "no goal of the kinds and size drawn",
            Rejected::Duplicate => "the same goal and start as a task kept",
            Rejected::Unsolvable => "no plan reaches the goal",
            Rejected::Undecided => "the search stopped at a limit before any plan",
            Rejected::Type => "another task type (--type)",
            Rejected::Needed => "another number of robots needed (--needed)",
            Rejected::Steps => "optimal steps out of range (--steps)",
            Rejected::Ratio => "sequential steps / makespan out of range (--ratio)",
            Rejected::Unproven => "makespan not proven (--proven)",
            Rejected::Physics => "the physics could not build the scene",
            Rejected::PlanPhysics => "the optimal plan failed in physics (--physics)",
            Rejected::Invalid => "the task file did not read back (a fault of the generator)",
        }
    }
}

/// Counts over the kept tasks and the draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    pub kept: usize,
    pub drawn: usize,
    pub rejected: BTreeMap<Rejected, usize>,
    pub by_split: BTreeMap<Split, (usize, usize)>,
    pub by_type: BTreeMap<String, usize>,
    pub by_team: BTreeMap<usize, (usize, usize)>,
    pub by_steps: BTreeMap<usize, usize>,
    /// Sequential steps over makespan, in tenths (1.0 to 1.09 is 10).
    pub by_ratio: BTreeMap<usize, usize>,
    pub by_needed: BTreeMap<String, usize>,
    pub proven: usize,
    /// What the rejected draws had: the types, steps and ratios the filters saw.
    pub seen_types: BTreeMap<String, usize>,
    pub seen_steps: Option<(usize, usize)>,
    pub seen_ratio: Option<(f64, f64)>,
    pub seen_needed: Option<(usize, usize)>,
}

impl Tally {
    pub fn keep(&mut self, e: &Entry) {
        self.kept += 1;
        self.by_split.entry(e.split).or_default().1 += 1;
        *self.by_type.entry(type_name(e.task_type)).or_default() += 1;
        let team = self.by_team.entry(e.team_size()).or_default();
        team.0 += 1;
        team.1 += usize::from(e.proven);
        *self.by_steps.entry(e.steps).or_default() += 1;
        let tenths = (e.steps * 10 / e.makespan.max(1)).max(10);
        *self.by_ratio.entry(tenths).or_default() += 1;
        let needed = e.needed.map_or("undecided".to_owned(), |n| n.to_string());
        *self.by_needed.entry(needed).or_default() += 1;
        self.proven += usize::from(e.proven);
    }

    /// A solved draw the filters saw, kept or not.
    pub fn saw(
        &mut self,
        task_type: Option<TaskType>,
        steps: usize,
        ratio: f64,
        needed: Option<usize>,
    ) {
        *self.seen_types.entry(type_name(task_type)).or_default() += 1;
        let widen = |r: Option<(usize, usize)>, x: usize| {
            Some(r.map_or((x, x), |(a, b)| (a.min(x), b.max(x))))
        };
        self.seen_steps = widen(self.seen_steps, steps);
        if let Some(n) = needed {
            self.seen_needed = widen(self.seen_needed, n);
        }
        self.seen_ratio = Some(
            self.seen_ratio
                .map_or((ratio, ratio), |(a, b)| (a.min(ratio), b.max(ratio))),
        );
    }

    pub fn reject(&mut self, why: Rejected) {
        *self.rejected.entry(why).or_default() += 1;
    }

    /// The datasheet, in Markdown.
    pub fn datasheet(&self, about: &About<'_>) -> String {
        let mut out = String::new();
        out.push_str("# A generated task set\n\n");
        out.push_str(&format!(
            "Made by coherent {} with\n\n```sh\n{}\n```\n\n",
            about.version, about.command
        ));
        out.push_str(&format!(
            "{} tasks in {} scenes (seed {}){}. Every task is a native task file \
             (`docs/task-format.md`, the `geometric` rules) with its geometry in metres; \
             `manifest.jsonl` has a line per task (its file, scene, team, type, robots \
             needed, optimal steps, makespan and their bounds, whether proven, split).\n\n",
            self.kept,
            about.scenes,
            about.seed,
            if about.interrupted {
                ", stopped by Ctrl-C before the set was complete"
            } else {
                ""
            }
        ));
        let pct = |n: usize| {
            if self.kept == 0 {
                0.0
            } else {
                100.0 * n as f64 / self.kept as f64
            }
        };
        out.push_str(&format!(
            "**Ground truth.** Each file's `ground_truth.steps` is its optimal number of \
             sequential steps, proven by the planner's A* search. The makespan (fewest \
             joint steps, robots acting at once) is proven for {} of {} tasks ({:.1}%); for \
             the others the search stopped at a limit, and the manifest gives the best \
             plan found as `makespan` and `bounds.makespan` = [lower, upper] with \
             `proven: false`.\n\n",
            self.proven,
            self.kept,
            pct(self.proven)
        ));
        table(
            &mut out,
            "Split",
            &["split", "scenes", "tasks"],
            self.by_split.iter().map(|(s, (scenes, n))| {
                vec![s.name().to_owned(), scenes.to_string(), n.to_string()]
            }),
        );
        table(
            &mut out,
            "Task type (the fewest robot types that reach the goal)",
            &["type", "tasks", "share"],
            self.by_type
                .iter()
                .map(|(t, n)| vec![t.clone(), n.to_string(), format!("{:.1}%", pct(*n))]),
        );
        table(
            &mut out,
            "Team size",
            &["robots", "tasks", "makespan proven"],
            self.by_team.iter().map(|(k, (n, p))| {
                vec![
                    k.to_string(),
                    n.to_string(),
                    format!("{p} ({:.1}%)", 100.0 * *p as f64 / (*n).max(1) as f64),
                ]
            }),
        );
        table(
            &mut out,
            "Robots needed (the fewest robots that reach the goal)",
            &["robots", "tasks"],
            self.by_needed
                .iter()
                .map(|(k, n)| vec![k.clone(), n.to_string()]),
        );
        table(
            &mut out,
            "Optimal steps",
            &["steps", "tasks"],
            self.by_steps
                .iter()
                .map(|(k, n)| vec![k.to_string(), n.to_string()]),
        );
        table(
            &mut out,
            "Sequential steps / makespan",
            &["ratio", "tasks"],
            self.by_ratio.iter().map(|(k, n)| {
                vec![
                    format!("{:.1} to {:.2}", *k as f64 / 10.0, *k as f64 / 10.0 + 0.09),
                    n.to_string(),
                ]
            }),
        );
        out.push_str(&format!(
            "## Draws\n\n{} candidate tasks drawn, {} kept",
            self.drawn, self.kept
        ));
        if self.rejected.is_empty() {
            out.push_str(".\n");
        } else {
            out.push_str("; the others:\n\n| reason | draws |\n|---|---|\n");
            for (why, n) in &self.rejected {
                out.push_str(&format!("| {} | {n} |\n", why.describe()));
            }
        }
        out
    }
}

/// What the datasheet says of how the set was made.
#[derive(Clone, Debug)]
pub struct About<'a> {
    pub command: &'a str,
    pub version: &'a str,
    pub seed: u64,
    pub scenes: usize,
    pub interrupted: bool,
}

fn type_name(t: Option<TaskType>) -> String {
    t.map_or("undecided", TaskType::name).to_owned()
}

/// A Markdown table under a heading.
fn table(out: &mut String, title: &str, heads: &[&str], rows: impl Iterator<Item = Vec<String>>) {
    out.push_str(&format!(
        "## {title}\n\n| {} |\n|{}\n",
        heads.join(" | "),
        "---|".repeat(heads.len())
    ));
    for row in rows {
        out.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    out.push('\n');
}
