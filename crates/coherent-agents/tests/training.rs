//! The training data's lessons (`coherent_agents::training`): in episodes with and
//! without the simulated backend's mistakes, every question's answer is read by the
//! method's own parser, and is the optimal decision from the state it was asked in: a
//! step of a shortest plan (sequential), a joint step of a plan of the fewest joint
//! steps (parallel), the subtask's action for an executor that has it, the true goal for
//! LLM+P; and the prompts the lessons keep are the calls the episode recorded.

use std::sync::Arc;

use coherent_agents::training::{self, Lesson, Taken, Teacher};
use coherent_agents::{Builtin, BuiltinBackend, Cancel, ErrorRates, Prompts, Settings};
use coherent_core::env::resolve_joint;
use coherent_core::planner::{self, Limits};
use coherent_core::{Execution, NodeId, State, Task, feasibility, joint, makespan, rules};

mod common;

/// The fewest steps from `s` (one robot's action a step).
fn steps_left(task: &Task, s: &State) -> usize {
    let search = planner::search_from(task, s, &task.robots, &task.goal, &Limits::default());
    search
        .plan
        .expect("a plan from every state of these tasks")
        .len()
}

/// The fewest joint steps from `s`, proven.
fn joint_steps_left(task: &Task, s: &State) -> usize {
    let m = makespan::search_with(task, s, &task.robots, &task.goal, None, &Limits::default());
    assert!(m.proven, "the makespan of these tasks is proven");
    m.plan.expect("a plan").len()
}

/// `actions` as one joint step from `s`: the state after it, or why the rules refuse it.
fn joint_after(task: &Task, s: &State, actions: &[(NodeId, String)]) -> Result<State, String> {
    let refs: Vec<(NodeId, &str)> = actions.iter().map(|(r, a)| (*r, a.as_str())).collect();
    let step = resolve_joint(task, s, &refs)
        .map_err(|e| e.to_string())?
        .map_err(|refused| format!("{refused:?}"))?;
    let mut after = s.clone();
    joint::apply(task, &mut after, &step);
    Ok(after)
}

/// Checks one lesson's answer: read by the method's parser and optimal from its state.
/// Returns what it decided.
fn check(method: Builtin, execution: Execution, lesson: &Lesson, name: &str) -> Taken {
    let task = &lesson.situation.task;
    let s = &lesson.situation.state;
    let answer = lesson
        .answer
        .as_ref()
        .expect("every state of these tasks has a plan");
    let taken = training::read_back(method, &Prompts::builtin(), lesson, answer)
        .unwrap_or_else(|why| panic!("{name}: the method's parser refuses {answer:?}: {why}"));
    match (&taken, lesson.schema) {
        (Taken::Goal(goal), _) => assert_eq!(*goal, task.goal, "{name}: the true goal"),
        (Taken::Actions(actions), "decision") => {
            let subtask = lesson.situation.subtask.clone().unwrap_or_default();
            assert_eq!(
                actions,
                &vec![(lesson.robot.expect("a robot"), subtask)],
                "{name}"
            );
        }
        (Taken::Nothing, "decision") => {
            let robot = task
                .robot_by_id(lesson.robot.expect("a robot"))
                .expect("in the team");
            let offered: Vec<String> = rules::actions(task, s, robot)
                .iter()
                .map(|a| a.render(task))
                .collect();
            let subtask = lesson.situation.subtask.clone().unwrap_or_default();
            assert!(
                !offered.contains(&subtask),
                "{name}: declines a subtask it has: {subtask}"
            );
        }
        (Taken::Actions(actions), _) if execution == Execution::Sequential => {
            let [(robot, action)] = &actions[..] else {
                panic!("{name}: one action a step, not {actions:?}");
            };
            let r = task.robot_by_id(*robot).expect("in the team");
            let a = feasibility::check(task, s, r, action)
                .unwrap_or_else(|why| panic!("{name}: {action} is not feasible: {why:?}"));
            let mut after = s.clone();
            rules::apply(task, &mut after, r, a);
            assert_eq!(
                steps_left(task, &after) + 1,
                steps_left(task, s),
                "{name}: {action}"
            );
        }
        (Taken::Actions(actions), _) => {
            let after = joint_after(task, s, actions)
                .unwrap_or_else(|why| panic!("{name}: {actions:?} refused: {why}"));
            // A speaker names its own part; an assigner gives the idle robots theirs: the
            // whole step is the optimal one only when everyone is in it.
            let whole = match lesson.schema {
                "proposals" => lesson.situation.robots.len() == task.robots.len(),
                "own_action" => false,
                _ => true,
            };
            if whole {
                assert_eq!(
                    joint_steps_left(task, &after) + 1,
                    joint_steps_left(task, s),
                    "{name}: {actions:?}"
                );
            }
        }
        (Taken::Nothing, _) => {
            assert!(
                lesson.schema == "own_action",
                "{name}: only a speaker may do nothing"
            );
        }
    }
    taken
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_lesson_is_read_by_the_methods_parser_and_is_the_optimal_decision() {
    // Short tasks of all three types, of every released scene but the one with the
    // longest makespan searches.
    let tasks: Vec<Arc<Task>> = [
        ("env0", 2),
        ("env1", 3),
        ("env2", 5),
        ("env0", 9),
        ("env1", 1),
    ]
    .into_iter()
    .map(|(scene, id)| common::task(scene, id))
    .collect();
    let limits = Limits::default();
    let mut checked = 0;
    let mut off_plan = 0;
    for method in [
        Builtin::Pefa,
        Builtin::Cmrs,
        Builtin::Dmrs1d,
        Builtin::LlmPddl,
    ] {
        for execution in training::executions(method) {
            for task in &tasks {
                for seed in [None, Some(1)] {
                    let planner = Arc::new(BuiltinBackend::new(limits.clone()));
                    let acting = seed.map(|s| planner.with_errors(ErrorRates::all(0.25), s));
                    let teacher = Teacher::new(Arc::clone(&planner), acting);
                    let settings = Settings {
                        execution,
                        seed,
                        ..Settings::new(method)
                    };
                    let (episode, lessons) =
                        training::episode(task, &settings, &teacher, &limits, &Cancel::default())
                            .await
                            .expect("the episode plays");
                    let calls: Vec<_> = episode.rounds.iter().flat_map(|r| &r.calls).collect();
                    assert_eq!(calls.len(), lessons.len(), "a lesson per call");
                    for (call, lesson) in calls.iter().zip(&lessons) {
                        assert_eq!(call.messages, lesson.messages, "the prompt the method sent");
                        let name = format!(
                            "{} {execution} {} task {} seed {seed:?} {}",
                            method.name(),
                            task.meta.scene,
                            task.meta.task_id,
                            lesson.schema
                        );
                        check(method, execution, lesson, &name);
                        checked += 1;
                        if call.answer.as_ref().map(|a| &a.text) != lesson.answer.as_ref().ok() {
                            off_plan += 1;
                        }
                    }
                    if seed.is_none() {
                        assert_eq!(
                            episode.summary.status,
                            coherent_agents::Status::Success,
                            "{} {execution}: the planner's episode ends at the goal",
                            method.name()
                        );
                    }
                }
            }
        }
    }
    assert!(checked > 400, "{checked} lessons checked");
    assert!(
        off_plan > 20,
        "{off_plan} lessons where the episode's answer was a mistake"
    );
}

#[test]
fn the_roles_of_each_method_and_none_for_those_that_ask_no_model() {
    assert_eq!(training::roles(Builtin::Pefa), ["assigner", "executor"]);
    assert_eq!(training::role(Builtin::Pefa, "proposals"), "assigner");
    assert_eq!(training::role(Builtin::Pefa, "decision"), "executor");
    assert_eq!(training::role(Builtin::Cmrs, "joint_step"), "central");
    assert_eq!(training::role(Builtin::Dmrs2d, "own_action"), "speaker");
    assert_eq!(training::role(Builtin::LlmMcts, "team_action"), "prior");
    for m in [Builtin::Optimal, Builtin::Mcts, Builtin::Random] {
        assert!(training::roles(m).is_empty(), "{}", m.name());
    }
}
