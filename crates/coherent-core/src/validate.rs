//! Semantic checks of a well-formed task: problems that make it unsolvable, trivial or
//! inconsistent. (Malformed input is rejected earlier, by the loaders.)

use crate::error::{clip, quoted};
use crate::graph::{Idx, NodeKind, RobotKind};
use crate::planner::Analysis;
use crate::rules::room_of;
use crate::task::{MAX_GROUND_TRUTH, Task, predicate_holds};
use crate::text::has_unsafe;
use crate::vocab::{PropSet, Relation, StateSet};

/// Everything semantically wrong with `task`, in words; empty when it is clean.
pub fn findings(task: &Task, analysis: &Analysis) -> Vec<String> {
    let mut out = Vec::new();
    if task.goal.is_empty() {
        out.push("the goal is empty".to_owned());
    } else if task.goal.iter().all(|p| predicate_holds(&task.init, p)) {
        let labels: Vec<String> = task
            .goal
            .iter()
            .map(|p| clip(&task.predicate_label(p)))
            .collect();
        out.push(format!(
            "the goal already holds at the start: {}",
            labels.join(", ")
        ));
    }
    match (&analysis.reason, analysis.stop) {
        (Some(reason), Some(_)) => out.push(format!(
            "the goal could not be decided within the search limits: {reason}"
        )),
        (Some(reason), None) => out.push(format!("the goal cannot be reached: {reason}")),
        (None, _) => {}
    }
    if let Some(gt) = task.meta.gt_steps.filter(|&gt| gt > MAX_GROUND_TRUTH) {
        out.push(format!(
            "ground truth says {gt} steps, more than any task needs (at most {MAX_GROUND_TRUTH}; \
             an episode's budget is 2 x GT steps)"
        ));
    }
    // With events, the ground truth is the reference of docs/dynamic.md (the planner
    // replanning at each event), which the task without them does not bound.
    if let (Some(gt), Some(plan)) = (task.meta.gt_steps, &analysis.plan)
        && task.events.is_empty()
        && (gt as usize) < plan.len()
    {
        out.push(format!(
            "ground truth says {gt} steps, but the shortest plan takes {}",
            plan.len()
        ));
    }
    for n in task.indices() {
        out.extend(
            role_contradictions(task, n)
                .into_iter()
                .map(|m| format!("{}: {m}", task.node(n).short_label())),
        );
    }
    // Names reach terminals, progress lines, table headers and file names.
    let names = [("scene", &task.meta.scene), ("name", &task.meta.name)]
        .into_iter()
        .map(|(what, text)| (what.to_owned(), text.clone()))
        .chain(task.indices().map(|n| {
            (
                format!("node {}", task.node(n).id.0),
                task.node(n).class_name.clone(),
            )
        }));
    for (what, text) in names {
        if has_unsafe(&text) {
            out.push(format!(
                "{what}: the name {} holds control or direction characters, which a terminal \
                 acts on",
                quoted(&text)
            ));
        }
    }
    let listed = task.init_edges.len();
    let distinct = task.init.edges().len();
    if listed != distinct {
        out.push(format!(
            "{} edges are listed more than once",
            listed - distinct
        ));
    }
    out
}

/// Properties and placements that contradict what a node is.
fn role_contradictions(task: &Task, n: Idx) -> Vec<String> {
    let node = task.node(n);
    let s = &task.init;
    let props = node.properties;
    let mut out = Vec::new();
    let locations = s.out(n).iter().filter(|e| e.rel().is_location()).count();
    if props.contains(PropSet::HIGH_HEIGHT) && props.contains(PropSet::LOW_HEIGHT) {
        out.push("both HIGH_HEIGHT and LOW_HEIGHT".to_owned());
    }
    match node.kind {
        NodeKind::Room | NodeKind::Door if props.contains(PropSet::GRABABLE) => {
            out.push("a room or door that is GRABABLE".to_owned());
        }
        NodeKind::Room if task.floor_of(n).is_none() => {
            out.push(
                "a room with no floor: robots moving there have nothing to stand on".to_owned(),
            );
        }
        NodeKind::Door => {
            let rooms = task.doors().iter().filter(|(d, _)| *d == n).count();
            if rooms != 2 {
                out.push(format!(
                    "a door must lead to 2 rooms, this one leads to {rooms}"
                ));
            }
        }
        NodeKind::Floor if !props.contains(PropSet::SURFACES) => {
            out.push("a floor that is not a surface (no SURFACES)".to_owned());
        }
        NodeKind::Robot(kind) => {
            if props.contains(PropSet::GRABABLE) {
                out.push("a robot that is GRABABLE".to_owned());
            }
            let rooms = s
                .targets(n, Relation::Inside)
                .filter(|&t| task.node(t).kind == NodeKind::Room)
                .count();
            if rooms != 1 || room_of(task, s, n).is_none() {
                out.push(format!(
                    "a robot must be INSIDE exactly one room, this one is in {rooms}"
                ));
            }
            match kind {
                RobotKind::Quadrotor => {
                    if task.basket_of(n).is_none() {
                        out.push("a quadrotor without a basket (no WITH edge)".to_owned());
                    }
                    let st = s.states(n);
                    if !st.intersects(StateSet::LAND | StateSet::FLYING) {
                        out.push(
                            "a quadrotor that is neither LAND nor FLYING can never act".to_owned(),
                        );
                    }
                    if st.contains(StateSet::LAND) && s.target(n, Relation::On).is_none() {
                        out.push(
                            "a quadrotor in state LAND that is ON nothing can never take off"
                                .to_owned(),
                        );
                    }
                }
                RobotKind::RobotArm if s.target(n, Relation::On).is_none() => {
                    out.push("a robot arm that stands ON no surface reaches nothing".to_owned());
                }
                _ => {}
            }
        }
        NodeKind::Tool if !props.contains(PropSet::CONTAINERS) || !s.states(n).is_open() => {
            out.push("a basket must be an open container (CONTAINERS, OPEN_FOREVER)".to_owned());
        }
        NodeKind::Object if locations > 1 => {
            out.push(format!(
                "an object in {locations} places at once (grabbing it removes only the first ON/INSIDE edge)"
            ));
        }
        _ => {}
    }
    if props.contains(PropSet::CAN_OPEN)
        && !s
            .states(n)
            .intersects(StateSet::OPEN | StateSet::CLOSED | StateSet::OPEN_FOREVER)
    {
        out.push("CAN_OPEN, but neither OPEN, CLOSED nor OPEN_FOREVER".to_owned());
    }
    out
}
