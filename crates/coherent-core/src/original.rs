//! The paper's released task format: a JSON list of tasks per scene file, each with
//! `task_id`, `task_name`, `env_id`, `init_graph`, `task_goal`,
//! `ground_truth_step_num` and `goal_instruction`. Import and export are lossless for
//! every field the format defines.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Result, Site, clip, ensure, quoted};
use crate::task::{RawGraph, RawPredicate, RuleSet, Source, Task, TaskMeta};
use crate::vocab::Relation;

/// The format name written into [`Source::format`].
pub const FORMAT: &str = "coherent-original";

#[derive(Debug, Deserialize, Serialize)]
struct OriginalTask {
    task_id: i64,
    #[serde(default)]
    task_name: String,
    #[serde(default)]
    env_id: Value,
    init_graph: RawGraph,
    task_goal: serde_json::Map<String, Value>,
    #[serde(default)]
    ground_truth_step_num: Vec<u32>,
    #[serde(default)]
    goal_instruction: Vec<String>,
}

/// Reads every task of an original-format file. The outer list must parse; each task
/// is then read on its own, so one malformed task does not hide the others.
pub fn read(file: &str, scene: &str, value: &Value) -> Result<Vec<Result<Task>>> {
    let root = Site::new(file, crate::JsonPath::root());
    let Value::Array(items) = value else {
        return Err(root.error(format!(
            "expected a list of tasks (the original format), found {}",
            crate::json::describe(value)
        )));
    };
    Ok(items
        .iter()
        .enumerate()
        .map(|(i, item)| read_task(file, scene, i, item, &root.index(i)))
        .collect())
}

fn read_task(file: &str, scene: &str, index: usize, item: &Value, at: &Site<'_>) -> Result<Task> {
    let raw: OriginalTask = crate::json::from_value(item, at)?;
    let mut goal = Vec::with_capacity(raw.task_goal.len());
    let goal_site = at.key("task_goal");
    for (key, value) in &raw.task_goal {
        let site = goal_site.key(key);
        let (relation, subject, target) = parse_goal_key(key).map_err(|why| site.error(why))?;
        let count = goal_count(value, &site)?;
        goal.push(RawPredicate {
            relation,
            subject: (subject, site.clone()),
            target: (target, site),
            count,
        });
    }
    let gt_site = at.key("ground_truth_step_num");
    ensure!(
        raw.ground_truth_step_num.len() <= 1,
        gt_site,
        "expected one step count, found {}",
        clip(&format!("{:?}", raw.ground_truth_step_num))
    );
    ensure!(
        raw.goal_instruction.len() <= 1,
        at.key("goal_instruction"),
        "expected one instruction, found {}",
        raw.goal_instruction.len()
    );
    let file_name = std::path::Path::new(file)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let meta = TaskMeta {
        scene: scene.to_owned(),
        task_id: raw.task_id,
        name: raw.task_name,
        instruction: raw.goal_instruction.into_iter().next().unwrap_or_default(),
        gt_steps: raw.ground_truth_step_num.first().copied(),
        rules: RuleSet::Compatible,
        geometry: None,
        source: Some(Source {
            format: FORMAT.to_owned(),
            file: file_name,
            index,
            env_id: raw.env_id,
        }),
    };
    Task::build(meta, &raw.init_graph, &goal, &at.key("init_graph"))
}

/// `[1, []]`: the count, then a list the released files always leave empty.
fn goal_count(value: &Value, site: &Site<'_>) -> Result<u32> {
    let count = match value.as_array().map(Vec::as_slice) {
        Some([n, Value::Array(rest)]) if rest.is_empty() => n.as_u64(),
        _ => None,
    };
    count.and_then(|n| u32::try_from(n).ok()).ok_or_else(|| {
        site.error(format!(
            "expected [count, []] with a count >= 0, found {}",
            crate::json::describe(value)
        ))
    })
}

/// Parses `on_<name>(id)_<name>(id)` or `inside_<name>(id)_<name>(id)`.
pub fn parse_goal_key(key: &str) -> std::result::Result<(Relation, i64, i64), String> {
    let bad = || {
        format!(
            "goal {} is not of the form on_<name>(id)_<name>(id) or inside_<name>(id)_<name>(id)",
            quoted(key)
        )
    };
    let (relation, rest) = if let Some(rest) = key.strip_prefix("on_") {
        (Relation::On, rest)
    } else if let Some(rest) = key.strip_prefix("inside_") {
        (Relation::Inside, rest)
    } else {
        return Err(bad());
    };
    let (subject, rest) = labelled_id(rest).ok_or_else(bad)?;
    let rest = rest.strip_prefix('_').ok_or_else(bad)?;
    let (target, rest) = labelled_id(rest).ok_or_else(bad)?;
    if !rest.is_empty() {
        return Err(bad());
    }
    Ok((relation, subject, target))
}

/// `<name>(id)` at the start of `s`; returns the id and the rest.
fn labelled_id(s: &str) -> Option<(i64, &str)> {
    let s = s.strip_prefix('<')?;
    let close = s.find(">(")?;
    let after = &s[close + 2..];
    let end = after.find(')')?;
    let id = after[..end].parse().ok()?;
    Some((id, &after[end + 1..]))
}

/// The task in the original format (one element of a scene file's list).
pub fn to_value(task: &Task) -> Value {
    let goal = task
        .goal
        .iter()
        .map(|p| (task.predicate_label(p), serde_json::json!([p.count, []])))
        .collect();
    let out = OriginalTask {
        task_id: task.meta.task_id,
        task_name: task.meta.name.clone(),
        env_id: task
            .meta
            .source
            .as_ref()
            .map(|s| s.env_id.clone())
            .unwrap_or(Value::Null),
        init_graph: task.initial_raw_graph(),
        task_goal: goal,
        ground_truth_step_num: task.meta.gt_steps.into_iter().collect(),
        goal_instruction: vec![task.meta.instruction.clone()],
    };
    serde_json::to_value(out).expect("plain data always serializes")
}
