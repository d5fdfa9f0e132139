//! The tasks in PDDL (docs/pddl.md): every released and native task is written, its
//! optimal plan written as PDDL actions plays back through the rules to the goal, a
//! plan the rules refuse is named by its line, and a task the domain cannot express is
//! refused with the reason. The PDDL planners' side is python/tests/test_pddl.py.

mod common;

use std::path::Path;

use coherent_core::pddl::{check_plan, domain_name, export, plan_text};
use coherent_core::planner::{self, Limits};
use coherent_core::{Error, Task, load_tasks, original};

fn native_tasks() -> Vec<Task> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../benchmark/tasks");
    load_tasks(&folder).expect("the native tasks load")
}

#[test]
fn every_task_is_written_and_its_optimal_plan_plays_back_to_the_goal() {
    let mut tasks = common::released_tasks();
    tasks.extend(native_tasks());
    let mut solvable = 0;
    for task in &tasks {
        let name = common::name(task);
        let pddl = export(task).unwrap_or_else(|e| panic!("{name}: {e}"));
        let domain = domain_name(task.meta.rules);
        assert!(
            pddl.domain.contains(&format!("(domain {domain})")),
            "{name}"
        );
        assert!(
            pddl.problem.contains(&format!("(:domain {domain})")),
            "{name}"
        );
        let Some(plan) = planner::analyse(task, &Limits::default()).plan else {
            continue;
        };
        let text = plan_text(task, &plan);
        let check = check_plan(task, &text);
        assert!(check.valid(), "{name}: {:?}\n{text}", check.failure);
        assert_eq!(check.length, plan.len(), "{name}");
        solvable += 1;
    }
    assert_eq!(
        (tasks.len(), solvable),
        (181, 180),
        "81 released tasks (80 solvable) and 100 native ones"
    );
}

#[test]
fn a_plan_the_rules_refuse_is_named_by_its_line() {
    let task = &common::released_tasks()[0];
    // The quadrotor of env0 task 0 starts landed: it cannot fly to another room.
    let check = check_plan(
        task,
        "; a comment\n(quadrotor-movetowards-room quadrotor_22 livingroom_4)\n",
    );
    assert!(!check.valid() && !check.goal_reached);
    let (line, why) = check.failure.expect("refused");
    assert_eq!(line, 2);
    assert!(why.contains("landed"), "{why}");
    let unknown = check_plan(task, "(arm-grab robot-arm_24 nothing_99)\n");
    let (_, why) = unknown.failure.expect("refused");
    assert!(why.contains("nothing_99"), "{why}");
}

#[test]
fn a_thing_in_two_places_is_refused_with_the_reason() {
    let mut list = common::original_list(0);
    let edges = list[0]["init_graph"]["edges"]
        .as_array_mut()
        .expect("an edge list");
    // The sunglasses stand on the dining table (13); now on the sofa (11) as well.
    edges.push(serde_json::json!({"from_id": 55, "to_id": 11, "relation_type": "ON"}));
    let value = serde_json::Value::Array(vec![list.swap_remove(0)]);
    let task = original::read("env0.json", "env0", &value)
        .expect("the list reads")
        .remove(0)
        .expect("the task reads");
    match export(&task) {
        Err(Error::Inexpressible { task, reason }) => {
            assert!(task.contains("env0"), "{task}");
            assert!(
                reason.contains("<sunglasses>(55) stands in 2 places"),
                "{reason}"
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}
