//! A Robot Executor, the second of PEFA's two roles: one per robot. Given the subtask
//! the task assigner proposed, it sees its type's description, its own observation and
//! its action list from the rules, and picks one action, or none when no action is a
//! step of the subtask now: the Execution of Proposal-Execution-Feedback-Adjustment
//! ([`crate::methods::pefa`]).
//!
//! Its prompt is one system prompt per robot type (`executor_quadrotor.txt`,
//! `executor_robot_dog.txt`, `executor_robot_arm.txt`) and `executor_user.txt`, from the
//! prompt set ([`crate::prompts::templates`]); its answer is one JSON object `{"action", "subtask_complete", "note"}`, the action
//! constrained to its list or `none`, read into a [`Decision`] (or, without an object,
//! from the first action of the list the text names). What the assigner hears of the
//! round is [`crate::methods::feedback::pefa`]'s.

use std::sync::Arc;

use coherent_core::{Environment, NodeId, RobotKind, Task};
use serde_json::{Value, json};

use crate::error::Error;
use crate::llm::{Message, Query, Role, Situation};
use crate::prompts::answer::{bool_field, field_text, json_object, normal, string_field};
use crate::prompts::fill::{Sight, fill};
use crate::prompts::templates::{Prompts, Template};
use crate::records::transcript::Decision;

/// What one executor is told.
#[derive(Clone, Debug)]
pub struct ExecutorView<'a> {
    pub subtask: &'a str,
    /// Its own observation as facts, for the placeholders its template uses
    /// (`observation`, or `scene` and `state`).
    pub seen: &'a [(&'static str, String)],
    pub actions: &'a [String],
}

/// The Robot Executor of one robot of the team.
#[derive(Clone, Debug)]
pub struct RobotExecutor {
    task: Arc<Task>,
    robot: NodeId,
    /// `<label>(id)`.
    label: String,
    kind: RobotKind,
    prompts: Prompts,
    /// Most tokens of one answer.
    max_tokens: u32,
    /// What happened since the last round that the team did not do ([`RobotExecutor::told`]).
    news: Vec<String>,
}

impl RobotExecutor {
    /// The executor of `robot`, its prompts rendered from `prompts`, or why there is none.
    pub fn of(
        task: &Arc<Task>,
        robot: NodeId,
        prompts: &Prompts,
        max_tokens: u32,
    ) -> Result<RobotExecutor, Error> {
        let Ok(r) = task.robot_by_id(robot) else {
            return Err(Error::Invalid(format!("robot {robot} is not in the team")));
        };
        Ok(RobotExecutor {
            task: Arc::clone(task),
            robot,
            label: task.node(r.node).label(),
            kind: r.kind,
            prompts: prompts.clone(),
            max_tokens,
            news: Vec::new(),
        })
    }

    /// The executor told `news` (what happened since the last round that the team did
    /// not do: the task's events), which its next question says first.
    pub fn told(mut self, news: &[String]) -> RobotExecutor {
        self.news = news.to_vec();
        self
    }

    /// Its action list where `env` stands (empty when it has none).
    pub fn actions(&self, env: &(dyn Environment + Send)) -> Vec<String> {
        env.actions(self.robot).unwrap_or_default()
    }

    /// The question where `env` stands: `subtask`, with its own observation and its
    /// `actions`.
    pub fn query(
        &self,
        env: &(dyn Environment + Send),
        subtask: &str,
        actions: &[String],
    ) -> Query {
        let task = &self.task;
        let sight = Sight {
            task,
            state: env.state(),
            observations: env.observe(self.robot).into_iter().collect(),
            news: &self.news,
        };
        Query {
            role: Role::Executor,
            robot: Some(self.robot),
            messages: self.messages(&ExecutorView {
                subtask,
                seen: &sight.values(self.prompts.text(Template::ExecutorUser)),
                actions,
            }),
            schema_name: "decision",
            schema: self.schema(actions),
            max_tokens: self.max_tokens,
            situation: Situation::now(task, env, Some(subtask.to_owned())),
        }
    }

    /// The system prompt (its type's) and the user prompt (the subtask and its list).
    pub fn messages(&self, view: &ExecutorView<'_>) -> Vec<Message> {
        let system = self.prompts.text(match self.kind {
            RobotKind::Quadrotor => Template::ExecutorQuadrotor,
            RobotKind::RobotDog => Template::ExecutorRobotDog,
            RobotKind::RobotArm => Template::ExecutorRobotArm,
        });
        let actions = if view.actions.is_empty() {
            "(none)".to_owned()
        } else {
            view.actions
                .iter()
                .map(|a| format!("- {a}"))
                .collect::<Vec<_>>()
                .join("\n")
        };
        let mut values = vec![("subtask", view.subtask), ("actions", &actions)];
        values.extend(view.seen.iter().map(|(k, v)| (*k, v.as_str())));
        vec![
            Message::system(
                fill(system, &[("robot", &self.label)])
                    .trim_end()
                    .to_owned(),
            ),
            Message::user(
                fill(self.prompts.text(Template::ExecutorUser), &values)
                    .trim_end()
                    .to_owned(),
            ),
        ]
    }

    /// The answer: one action of its list, or `none` when no action is a step of the
    /// subtask (that is its "cannot do it now"; a separate yes/no field would let a
    /// model say yes and name nothing).
    pub fn schema(&self, actions: &[String]) -> Value {
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

    /// The decision in an answer, given the list it chose from, or why there is none.
    pub(crate) fn parse(&self, actions: &[String], text: &str) -> Result<Decision, String> {
        let decision = parse_decision(actions, text)?;
        Ok(Decision {
            robot: Some(self.robot),
            ..decision
        })
    }
}

fn parse_decision(actions: &[String], text: &str) -> Result<Decision, String> {
    if let Some(map) = json_object(text) {
        let action = string_field(&map, "action").filter(|a| {
            let a = normal(a);
            !a.is_empty() && a != "none" && a != "null"
        });
        // `can_do` is optional (the schema leaves it out: `none` says it); a model that
        // says it can but names nothing has not chosen.
        let can_do = bool_field(&map, "can_do").unwrap_or(true) && action.is_some();
        let note = string_field(&map, "note").unwrap_or_default();
        return Ok(Decision {
            robot: None,
            can_do,
            action: if can_do {
                action.map(|a| match_action(actions, &a))
            } else {
                None
            },
            subtask_complete: bool_field(&map, "subtask_complete").unwrap_or(false),
            note,
        });
    }
    // Free text: the action of the list that appears first.
    let lower = normal(text);
    let found = actions
        .iter()
        .filter_map(|a| {
            lower
                .find(&normal(a))
                .map(|at| (at, std::cmp::Reverse(a.len()), a))
        })
        .min();
    match found {
        Some((_, _, action)) => Ok(Decision {
            robot: None,
            can_do: true,
            action: Some(action.clone()),
            subtask_complete: false,
            note: String::new(),
        }),
        None if ["cannot", "can't", "can not", "unable"]
            .iter()
            .any(|w| lower.contains(w)) =>
        {
            Ok(Decision {
                robot: None,
                can_do: false,
                action: None,
                subtask_complete: false,
                note: field_text(text),
            })
        }
        None => Err("no JSON object and no action of the list in the answer".into()),
    }
}

/// `answer` spelled as in `actions` when it is one of them, else as answered.
fn match_action(actions: &[String], answer: &str) -> String {
    let n = normal(answer);
    actions
        .iter()
        .find(|a| normal(a) == n)
        .cloned()
        .unwrap_or_else(|| field_text(answer))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prompts::fill::{check_placeholders, demo_task, every_placeholder};
    use coherent_core::SymbolicEnv;

    #[test]
    fn every_template_placeholder_is_filled() {
        check_placeholders(
            Template::ExecutorUser.builtin(),
            &["subtask", "scene", "state", "actions"],
        );
        check_placeholders(
            Template::ExecutorUser.paper_layout(),
            &["subtask", "observation", "actions"],
        );
        for system in [
            Template::ExecutorQuadrotor,
            Template::ExecutorRobotDog,
            Template::ExecutorRobotArm,
        ] {
            check_placeholders(system.builtin(), &["robot"]);
        }
    }

    #[test]
    fn every_placeholder_a_template_may_use_is_filled() {
        let task = demo_task();
        let env = SymbolicEnv::new(Arc::clone(&task));
        let templates = [
            Template::ExecutorQuadrotor,
            Template::ExecutorRobotDog,
            Template::ExecutorRobotArm,
            Template::ExecutorUser,
        ];
        for template in templates {
            let prompts = every_placeholder(template);
            for r in &task.robots {
                let executor =
                    RobotExecutor::of(&task, task.id(r.node), &prompts, 100).expect("a robot");
                let query = executor.query(&env, "go", &executor.actions(&env));
                for m in &query.messages {
                    assert!(!m.content.contains("{{"), "{}", m.content);
                }
            }
        }
    }

    fn actions() -> Vec<String> {
        vec![
            "[grab] <mug>(7)".to_owned(),
            "[movetowards] <kitchen>(2)".to_owned(),
        ]
    }

    #[test]
    fn decisions_are_found_in_fences_and_chatter() {
        let text = "Sure!\n```json\n{\"can_do\": true, \"action\": \"[grab]  <MUG>(7)\", \"subtask_complete\": true, \"note\": \"\"}\n```";
        let d = parse_decision(&actions(), text).expect("a decision");
        assert_eq!(d.action.as_deref(), Some("[grab] <mug>(7)"));
        assert!(d.can_do && d.subtask_complete);
    }

    #[test]
    fn an_action_outside_the_list_is_kept_for_the_feasibility_check() {
        let d = parse_decision(
            &actions(),
            r#"{"can_do": "yes", "action": "[grab] <cup>(9)"}"#,
        )
        .expect("a decision");
        assert_eq!(d.action.as_deref(), Some("[grab] <cup>(9)"));
    }

    #[test]
    fn free_text_decisions() {
        let d = parse_decision(&actions(), "I will do [movetowards] <kitchen>(2) now.")
            .expect("found in text");
        assert_eq!(d.action.as_deref(), Some("[movetowards] <kitchen>(2)"));
        let d = parse_decision(&actions(), "I cannot reach it.").expect("a refusal");
        assert!(!d.can_do);
        assert!(parse_decision(&actions(), "").is_err());
        let d = parse_decision(&actions(), r#"{"action": "none", "note": "too far"}"#)
            .expect("a refusal");
        assert!(!d.can_do && d.action.is_none() && d.note == "too far");
        assert!(parse_decision(&actions(), "{\"can_do\": tr").is_err());
    }
}
