//! The prompts: template files under `prompts/`, one per role and robot type, filled with
//! the situation. Observations are written as relation facts (`coherent_core::describe`).

use coherent_core::{RobotKind, Task};
use serde_json::{Value, json};

use crate::llm::Message;

const ASSIGNER_SYSTEM: &str = include_str!("../../prompts/assigner_system.txt");
const ASSIGNER_USER: &str = include_str!("../../prompts/assigner_user.txt");
const EXECUTOR_USER: &str = include_str!("../../prompts/executor_user.txt");
const EXECUTOR_QUADROTOR: &str = include_str!("../../prompts/executor_quadrotor.txt");
const EXECUTOR_ROBOT_DOG: &str = include_str!("../../prompts/executor_robot_dog.txt");
const EXECUTOR_ROBOT_ARM: &str = include_str!("../../prompts/executor_robot_arm.txt");

/// `template` with every `{{key}}` replaced by its value, in one pass: a value that
/// itself contains `{{...}}` (an instruction, say) is left as written.
pub fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(open) = rest.find("{{") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 2..];
        let value = after.find("}}").and_then(|close| {
            let key = &after[..close];
            values
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| (*v, close))
        });
        match value {
            Some((v, close)) => {
                out.push_str(v);
                rest = &after[close + 2..];
            }
            None => {
                out.push_str("{{");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// What the assigner is told each round.
#[derive(Clone, Debug)]
pub struct AssignerView<'a> {
    /// One line per robot: label, type and where it is.
    pub robots: &'a str,
    /// The team's observations as facts.
    pub observation: &'a str,
    /// The last rounds, oldest first, one entry each.
    pub history: &'a [String],
}

/// The team list of a system prompt: each robot's label and type, one per line.
pub(crate) fn team(task: &Task) -> String {
    task.robots
        .iter()
        .map(|r| format!("- {}: {}", task.node(r.node).label(), r.kind))
        .collect::<Vec<_>>()
        .join("\n")
}

pub fn assigner_messages(task: &Task, view: &AssignerView<'_>) -> Vec<Message> {
    let history = if view.history.is_empty() {
        "(none yet)".to_owned()
    } else {
        view.history.join("\n")
    };
    vec![
        Message::system(
            fill(ASSIGNER_SYSTEM, &[("team", &team(task))])
                .trim_end()
                .to_owned(),
        ),
        Message::user(
            fill(
                ASSIGNER_USER,
                &[
                    ("instruction", &task.meta.instruction),
                    ("robots", view.robots),
                    ("observation", view.observation),
                    ("history", &history),
                ],
            )
            .trim_end()
            .to_owned(),
        ),
    ]
}

/// The assigner's answer: a robot of the team and a subtask, reasoning first so that a
/// model thinks before it commits.
pub fn assigner_schema(task: &Task) -> Value {
    let robots: Vec<String> = task
        .robots
        .iter()
        .map(|r| task.node(r.node).label())
        .collect();
    json!({
        "type": "object",
        "properties": {
            "reasoning": {"type": "string"},
            "robot": {"type": "string", "enum": robots},
            "subtask": {"type": "string"},
        },
        "required": ["reasoning", "robot", "subtask"],
        "additionalProperties": false,
    })
}

/// What one executor is told.
#[derive(Clone, Debug)]
pub struct ExecutorView<'a> {
    pub robot: &'a str,
    pub kind: RobotKind,
    pub subtask: &'a str,
    pub observation: &'a str,
    pub actions: &'a [String],
}

pub fn executor_messages(view: &ExecutorView<'_>) -> Vec<Message> {
    let system = match view.kind {
        RobotKind::Quadrotor => EXECUTOR_QUADROTOR,
        RobotKind::RobotDog => EXECUTOR_ROBOT_DOG,
        RobotKind::RobotArm => EXECUTOR_ROBOT_ARM,
    };
    let actions = if view.actions.is_empty() {
        "(none)".to_owned()
    } else {
        view.actions
            .iter()
            .map(|a| format!("- {a}"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    vec![
        Message::system(fill(system, &[("robot", view.robot)]).trim_end().to_owned()),
        Message::user(
            fill(
                EXECUTOR_USER,
                &[
                    ("subtask", view.subtask),
                    ("observation", view.observation),
                    ("actions", &actions),
                ],
            )
            .trim_end()
            .to_owned(),
        ),
    ]
}

/// The executor's answer: one action of its list, or `none` when no action is a step of
/// the subtask (that is its "cannot do it now"; a separate yes/no field would let a
/// model say yes and name nothing).
pub fn executor_schema(actions: &[String]) -> Value {
    let mut choices: Vec<&str> = actions.iter().map(String::as_str).collect();
    choices.push("none");
    json!({
        "type": "object",
        "properties": {
            "action": {"type": "string", "enum": choices},
            "subtask_complete": {"type": "boolean"},
            "note": {"type": "string"},
        },
        "required": ["action", "subtask_complete", "note"],
        "additionalProperties": false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_replaces_every_known_key_once() {
        assert_eq!(
            fill(
                "{{a}} and {{a}}, {{b}} {{c}}",
                &[("a", "x"), ("b", "{{a}}")]
            ),
            "x and x, {{a}} {{c}}"
        );
    }

    #[test]
    fn every_template_placeholder_is_filled() {
        let cases: [(&str, &[&str]); 6] = [
            (ASSIGNER_SYSTEM, &["team"]),
            (
                ASSIGNER_USER,
                &["instruction", "robots", "observation", "history"],
            ),
            (EXECUTOR_USER, &["subtask", "observation", "actions"]),
            (EXECUTOR_QUADROTOR, &["robot"]),
            (EXECUTOR_ROBOT_DOG, &["robot"]),
            (EXECUTOR_ROBOT_ARM, &["robot"]),
        ];
        for (template, keys) in cases {
            let values: Vec<(&str, &str)> = keys.iter().map(|&k| (k, "value")).collect();
            let filled = fill(template, &values);
            assert!(!filled.contains("{{"), "unfilled placeholder in:\n{filled}");
            for k in keys {
                assert!(template.contains(&format!("{{{{{k}}}}}")), "{k} unused");
            }
        }
    }
}
