//! The project's own task format, version 1 (documented in `docs/task-format.md`, JSON
//! Schema in `schema/task.schema.json`): one task per file, the scene graph in the
//! original format's field names, robots, goal, instruction, optional ground truth and
//! optional geometry.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Result, Site, ensure, quoted};
use crate::geometry::{self, Layout};
use crate::graph::NodeKind;
use crate::heights;
use crate::task::{RawGraph, RawPredicate, RuleSet, Source, Task, TaskMeta};
use crate::vocab::Relation;

/// The value of the `format` field.
pub const FORMAT: &str = "coherent-task";
/// The version this build reads and writes.
pub const VERSION: u32 = 1;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct NativeTask {
    format: String,
    version: u32,
    scene: String,
    task_id: i64,
    #[serde(default)]
    name: String,
    #[serde(default)]
    rules: RuleSet,
    instruction: String,
    goal: Vec<NativePredicate>,
    #[serde(default)]
    ground_truth: Option<GroundTruth>,
    robots: Vec<NativeRobot>,
    graph: RawGraph,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    geometry: Option<Layout>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<Source>,
    /// Read once the graph is built (its ids are checked against it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    events: Option<Value>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct NativePredicate {
    relation: String,
    subject: i64,
    target: i64,
    #[serde(default = "one")]
    count: u32,
}

fn one() -> u32 {
    1
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct GroundTruth {
    steps: u32,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct NativeRobot {
    id: i64,
    #[serde(rename = "type")]
    kind: String,
}

/// Reads one native task (a JSON object with `"format": "coherent-task"`).
pub fn read(file: &str, value: &Value) -> Result<Task> {
    let root = Site::new(file, crate::JsonPath::root());
    if let Some(v) = value.get("version") {
        ensure!(
            v.as_u64() == Some(u64::from(VERSION)),
            root.key("version"),
            "unsupported version {} (this build reads version {VERSION})",
            crate::json::describe(v)
        );
    }
    let raw: NativeTask = crate::json::from_value(value, &root)?;
    ensure!(
        raw.format == FORMAT,
        root.key("format"),
        "expected {FORMAT:?}, found {}",
        quoted(&raw.format)
    );
    let goal_site = root.key("goal");
    let mut goal = Vec::with_capacity(raw.goal.len());
    for (i, p) in raw.goal.iter().enumerate() {
        let site = goal_site.index(i);
        let relation = match p.relation.as_str() {
            "ON" => Relation::On,
            "INSIDE" => Relation::Inside,
            other => {
                return Err(site.key("relation").error(format!(
                    "goal relation {}: expected \"ON\" or \"INSIDE\"",
                    quoted(other)
                )));
            }
        };
        goal.push(RawPredicate {
            relation,
            subject: (p.subject, site.key("subject")),
            target: (p.target, site.key("target")),
            count: p.count,
        });
    }
    let meta = TaskMeta {
        scene: raw.scene,
        task_id: raw.task_id,
        name: raw.name,
        instruction: raw.instruction,
        gt_steps: raw.ground_truth.map(|g| g.steps),
        rules: raw.rules,
        geometry: raw.geometry,
        source: raw.source,
    };
    let mut task = Task::build(meta, &raw.graph, &goal, &root.key("graph"))?;
    check_robots(&task, &raw.robots, &root.key("robots"))?;
    if let Some(events) = &raw.events {
        task.events = crate::events::read(&task, events, file, root.key("events").path)?;
    }
    if let Some(layout) = task.meta.geometry.clone() {
        if let Some(missing) = layout.missing_entry(&task) {
            return Err(root.key("geometry").error(missing));
        }
        if task.meta.rules == RuleSet::Geometric {
            heights::derive_heights(&mut task, &layout, &root)?;
        }
    } else {
        ensure!(
            task.meta.rules != RuleSet::Geometric,
            root.key("rules"),
            "the geometric rule set derives heights from the geometry, and the task has none"
        );
    }
    Ok(task)
}

/// The robot list must name exactly the graph's `Agents` nodes, with their types.
fn check_robots(task: &Task, robots: &[NativeRobot], site: &Site<'_>) -> Result<()> {
    for (i, r) in robots.iter().enumerate() {
        let at = site.index(i);
        if let Some(first) = robots[..i].iter().position(|o| o.id == r.id) {
            return Err(at.key("id").error(format!(
                "robot {} is listed twice (also robots[{first}])",
                r.id
            )));
        }
        let node = task.idx(crate::NodeId(r.id)).map(|n| task.node(n));
        let Some(node) = node else {
            return Err(at.key("id").error(format!("unknown node id {}", r.id)));
        };
        let NodeKind::Robot(kind) = node.kind else {
            return Err(at.key("id").error(format!(
                "node {} ({}) is not a robot (category {})",
                r.id,
                quoted(&node.class_name),
                quoted(&node.category)
            )));
        };
        ensure!(
            kind.class_name() == r.kind,
            at.key("type"),
            "robot {} is a {:?} in the graph, not {}",
            r.id,
            kind.class_name(),
            quoted(&r.kind)
        );
    }
    for robot in &task.robots {
        let id = task.id(robot.node);
        ensure!(
            robots.iter().any(|r| r.id == id.0),
            site,
            "robot {id} ({}) of the graph is missing from the list",
            robot.kind
        );
    }
    Ok(())
}

/// The task as a native task file.
pub fn to_value(task: &Task) -> Value {
    let out = NativeTask {
        format: FORMAT.to_owned(),
        version: VERSION,
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        name: task.meta.name.clone(),
        rules: task.meta.rules,
        instruction: task.meta.instruction.clone(),
        goal: task
            .goal
            .iter()
            .map(|p| NativePredicate {
                relation: p.relation.name().to_owned(),
                subject: task.id(p.subject).0,
                target: task.id(p.target).0,
                count: p.count,
            })
            .collect(),
        ground_truth: task.meta.gt_steps.map(|steps| GroundTruth { steps }),
        robots: task
            .robots
            .iter()
            .map(|r| NativeRobot {
                id: task.id(r.node).0,
                kind: r.kind.class_name().to_owned(),
            })
            .collect(),
        graph: written_graph(task),
        geometry: task.meta.geometry.clone(),
        source: task.meta.source.clone(),
        events: (!task.events.is_empty()).then(|| crate::events::to_value(task)),
    };
    let mut value = serde_json::to_value(out).expect("plain data always serializes");
    if let Some(g) = value.get_mut("geometry") {
        shortest_f32(g);
    }
    value
}

/// Every fractional number of `v` written as the shortest decimal that reads back to
/// the same `f32`: the geometry is kept in `f32`, and widened to `f64` for JSON, 6.9
/// would be written 6.900000095367432. Both read back to the same value.
fn shortest_f32(v: &mut Value) {
    match v {
        Value::Number(n) if n.is_f64() => {
            if let Some(x) = n.as_f64() {
                let short: Option<f64> = (x as f32).to_string().parse().ok();
                if let Some(m) = short.and_then(serde_json::Number::from_f64) {
                    *n = m;
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(shortest_f32),
        Value::Object(map) => map.values_mut().for_each(shortest_f32),
        _ => {}
    }
}

/// The initial graph, without the labels the geometric rules derive (a file under them
/// may not set those by hand).
fn written_graph(task: &Task) -> RawGraph {
    let mut graph = task.initial_raw_graph();
    if task.meta.rules == RuleSet::Geometric {
        let derived = task.vocab.property_names(geometry::DERIVED);
        for node in &mut graph.nodes {
            node.properties.retain(|p| !derived.contains(p));
        }
    }
    graph
}
