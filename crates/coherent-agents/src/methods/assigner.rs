//! The Task Assigner, the first of PEFA's two roles. Each round it sees the team (each
//! robot's label and type, what each type can do, the world's rules), the instruction,
//! where each robot is, the team's observations as relation facts and the last rounds,
//! and proposes one subtask for one robot: the Proposal of Proposal-Execution-Feedback-
//! Adjustment ([`crate::methods::pefa`]).
//!
//! Its prompt is the prompt set's `assigner_system.txt` and `assigner_user.txt`
//! ([`crate::prompts::templates`]), the built-in ones laid out from what never changes
//! (the rules, the team, the instruction, the scene) to what changes each round (where
//! the robots are, the states and relations, the history); its answer is one JSON object `{"reasoning", "robot", "subtask"}`, the robot constrained
//! to the team's labels, read into a [`Proposal`] wherever it sits in the text (or,
//! without one, from the first line that names a robot).

use std::sync::Arc;

use coherent_core::{Environment, NodeId, Relation, Task, rules};
use serde_json::{Value, json};

use crate::episode::environment::team_sight;
use crate::llm::{Message, Query, Role, Situation};
use crate::prompts::answer::{field_text, json_object, string_field};
use crate::prompts::fill::{fill, robot_label, team};
use crate::prompts::templates::{Prompts, Template};
use crate::records::transcript::Proposal;

/// What the assigner is told each round.
#[derive(Clone, Debug)]
pub struct AssignerView<'a> {
    /// One line per robot: label, type and where it is.
    pub robots: &'a str,
    /// The team's observations as facts, for the placeholders its template uses
    /// (`observation`, or `scene` and `state`).
    pub seen: &'a [(&'static str, String)],
    /// The last rounds, oldest first, one entry each.
    pub history: &'a [String],
}

/// The Task Assigner of one episode's task.
#[derive(Clone, Debug)]
pub struct TaskAssigner {
    task: Arc<Task>,
    prompts: Prompts,
    /// Most tokens of one answer.
    max_tokens: u32,
    /// What happened since the last round that the team did not do ([`TaskAssigner::told`]).
    news: Vec<String>,
}

impl TaskAssigner {
    /// The assigner of `task`, its prompts rendered from `prompts`.
    pub fn new(task: &Arc<Task>, prompts: &Prompts, max_tokens: u32) -> TaskAssigner {
        TaskAssigner {
            task: Arc::clone(task),
            prompts: prompts.clone(),
            max_tokens,
            news: Vec::new(),
        }
    }

    /// The assigner told `news` (what happened since the last round that the team did
    /// not do: the task's events), which its next question says first.
    pub fn told(mut self, news: &[String]) -> TaskAssigner {
        self.news = news.to_vec();
        self
    }

    /// The round's question where `env` stands, with `history`: the last rounds, oldest
    /// first.
    pub fn query(&self, env: &(dyn Environment + Send), history: &[String]) -> Query {
        let task = &self.task;
        let sight = team_sight(env, task, &self.news);
        Query {
            role: Role::Assigner,
            robot: None,
            messages: self.messages(&AssignerView {
                robots: &robot_lines(env, task),
                seen: &sight.values(self.prompts.text(Template::AssignerUser)),
                history,
            }),
            schema_name: "proposal",
            schema: self.schema(),
            max_tokens: self.max_tokens,
            situation: Situation::now(task, env, None),
        }
    }

    /// The system prompt (the team) and the user prompt (the round).
    pub fn messages(&self, view: &AssignerView<'_>) -> Vec<Message> {
        let task = &self.task;
        let history = if view.history.is_empty() {
            "(none yet)".to_owned()
        } else {
            view.history.join("\n")
        };
        let system = self.prompts.text(Template::AssignerSystem);
        let mut values = vec![
            ("instruction", task.meta.instruction.as_str()),
            ("robots", view.robots),
            ("history", &history),
        ];
        values.extend(view.seen.iter().map(|(k, v)| (*k, v.as_str())));
        vec![
            Message::system(fill(system, &[("team", &team(task))]).trim_end().to_owned()),
            Message::user(
                fill(self.prompts.text(Template::AssignerUser), &values)
                    .trim_end()
                    .to_owned(),
            ),
        ]
    }

    /// The answer: a robot of the team and a subtask, reasoning first so that a model
    /// thinks before it commits.
    pub fn schema(&self) -> Value {
        let task = &self.task;
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

    /// The proposal in an answer: its JSON object's robot (by label, id, or a type the
    /// team has one robot of) and subtask; without an object, the first line that names
    /// a robot by its label, the subtask being what follows the label.
    pub(crate) fn parse(&self, text: &str) -> Result<Proposal, String> {
        let task = &self.task;
        if let Some(map) = json_object(text) {
            let robot_text = string_field(&map, "robot").ok_or("the answer has no \"robot\"")?;
            let robot = resolve_robot(task, &robot_text).ok_or_else(|| {
                format!(
                    "{robot_text:?} is not a robot of the team ({})",
                    team_list(task)
                )
            })?;
            let subtask = string_field(&map, "subtask").unwrap_or_default();
            if subtask.is_empty() {
                return Err("the answer has no subtask".into());
            }
            return Ok(Proposal {
                robot,
                subtask,
                reasoning: string_field(&map, "reasoning").unwrap_or_default(),
            });
        }
        // Free text: the first line that names a robot by its label; the subtask is what
        // follows the label (or the whole line).
        for line in text.lines().map(str::trim) {
            let mention = task
                .robots
                .iter()
                .filter_map(|r| {
                    let label = task.node(r.node).label();
                    line.find(&label)
                        .map(|at| (at, at + label.len(), task.id(r.node)))
                })
                .min();
            if let Some((_, end, robot)) = mention {
                let rest = line[end..].trim_start_matches([':', '-', ',', ' ']).trim();
                return Ok(Proposal {
                    robot,
                    subtask: field_text(if rest.is_empty() { line } else { rest }),
                    reasoning: field_text(text),
                });
            }
        }
        Err(format!(
            "no JSON object and no line naming a robot of the team ({})",
            team_list(task)
        ))
    }
}

/// What a parallel assigner's answer gives: a subtask for each idle robot it names, and
/// what of the answer could not be used (a robot that is not idle, named twice, or given
/// no subtask), in words.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Assignments {
    pub proposals: Vec<Proposal>,
    pub unused: Vec<String>,
}

impl TaskAssigner {
    /// The round's question in a parallel episode where `env` stands, with `history`:
    /// `busy` are the robots still working on a subtask (with it, and the round it was
    /// given in), `idle` those it may give one now.
    pub fn query_parallel(
        &self,
        env: &(dyn Environment + Send),
        history: &[String],
        busy: &[(NodeId, String, u32)],
        idle: &[NodeId],
    ) -> Query {
        let task = &self.task;
        let lines = |lines: Vec<String>| {
            if lines.is_empty() {
                "(none)".to_owned()
            } else {
                lines.join("\n")
            }
        };
        let busy = lines(
            busy.iter()
                .map(|(r, subtask, since)| {
                    format!(
                        "- {}: {subtask:?} (given in round {since})",
                        robot_label(task, *r)
                    )
                })
                .collect(),
        );
        let free = lines(
            idle.iter()
                .map(|r| format!("- {}", robot_label(task, *r)))
                .collect(),
        );
        let sight = team_sight(env, task, &self.news);
        let view = AssignerView {
            robots: &robot_lines(env, task),
            seen: &sight.values(self.prompts.text(Template::AssignerParallelUser)),
            history,
        };
        Query {
            role: Role::Assigner,
            robot: None,
            messages: self.messages_parallel(&view, &busy, &free),
            schema_name: "proposals",
            schema: self.schema_parallel(idle),
            max_tokens: self.max_tokens,
            situation: Situation {
                robots: idle.to_vec(),
                ..Situation::now(task, env, None)
            },
        }
    }

    /// The parallel system prompt (the team) and user prompt (the round, the robots
    /// still busy and the idle ones, one line each).
    pub fn messages_parallel(
        &self,
        view: &AssignerView<'_>,
        busy: &str,
        idle: &str,
    ) -> Vec<Message> {
        let task = &self.task;
        let history = if view.history.is_empty() {
            "(none yet)".to_owned()
        } else {
            view.history.join("\n")
        };
        let system = self.prompts.text(Template::AssignerParallelSystem);
        let mut values = vec![
            ("instruction", task.meta.instruction.as_str()),
            ("robots", view.robots),
            ("history", &history),
            ("busy", busy),
            ("idle", idle),
        ];
        values.extend(view.seen.iter().map(|(k, v)| (*k, v.as_str())));
        vec![
            Message::system(fill(system, &[("team", &team(task))]).trim_end().to_owned()),
            Message::user(
                fill(self.prompts.text(Template::AssignerParallelUser), &values)
                    .trim_end()
                    .to_owned(),
            ),
        ]
    }

    /// The parallel answer: reasoning first, then a list of subtasks, each for one of
    /// the `idle` robots.
    pub fn schema_parallel(&self, idle: &[NodeId]) -> Value {
        let task = &self.task;
        let robots: Vec<String> = idle.iter().map(|r| robot_label(task, *r)).collect();
        json!({
            "type": "object",
            "properties": {
                "reasoning": {"type": "string"},
                "assignments": {
                    "type": "array",
                    "items": {
                        "type": "object",
                        "properties": {
                            "robot": {"type": "string", "enum": robots},
                            "subtask": {"type": "string"},
                        },
                        "required": ["robot", "subtask"],
                        "additionalProperties": false,
                    },
                },
            },
            "required": ["reasoning", "assignments"],
            "additionalProperties": false,
        })
    }

    /// The subtasks a parallel answer gives the `idle` robots: its JSON object's
    /// `assignments` (or, without them, its one `robot` and `subtask`, as a sequential
    /// answer has them); without an object, each line that names an idle robot by its
    /// label, the subtask being what follows it. An entry for a robot that is not idle,
    /// for one already given a subtask in the answer, or with no subtask is left out and
    /// said so; an answer with no entry at all is an error.
    pub(crate) fn parse_parallel(
        &self,
        text: &str,
        idle: &[NodeId],
    ) -> Result<Assignments, String> {
        let task = &self.task;
        let entries: Vec<(String, String)> = match json_object(text) {
            Some(map) => match map.get("assignments").and_then(Value::as_array) {
                Some(items) => items
                    .iter()
                    .map(|item| {
                        let field = |name| {
                            item.as_object()
                                .and_then(|o| string_field(o, name))
                                .unwrap_or_default()
                        };
                        (field("robot"), field("subtask"))
                    })
                    .collect(),
                None => match string_field(&map, "robot") {
                    Some(robot) => vec![(robot, string_field(&map, "subtask").unwrap_or_default())],
                    None => return Err("the answer has no \"assignments\"".into()),
                },
            },
            None => match named_lines(task, text, idle) {
                found if found.is_empty() => {
                    return Err(format!(
                        "no JSON object and no line naming an idle robot ({})",
                        idle.iter()
                            .map(|r| robot_label(task, *r))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                }
                found => found,
            },
        };
        let reasoning = json_object(text)
            .and_then(|m| string_field(&m, "reasoning"))
            .unwrap_or_default();
        let mut out = Assignments::default();
        for (robot_text, subtask) in entries {
            let Some(robot) = resolve_robot(task, &robot_text) else {
                out.unused.push(format!(
                    "{robot_text:?} is not a robot of the team ({})",
                    team_list(task)
                ));
                continue;
            };
            let label = robot_label(task, robot);
            if !idle.contains(&robot) {
                out.unused
                    .push(format!("{label} is not idle: it keeps its subtask"));
            } else if out.proposals.iter().any(|p| p.robot == robot) {
                out.unused
                    .push(format!("{label} was given two subtasks: the first counts"));
            } else if subtask.trim().is_empty() {
                out.unused.push(format!("{label} was given no subtask"));
            } else {
                out.proposals.push(Proposal {
                    robot,
                    subtask,
                    reasoning: reasoning.clone(),
                });
            }
        }
        if out.proposals.is_empty() && !out.unused.is_empty() {
            return Err(out.unused.join("; "));
        }
        Ok(out)
    }
}

/// Without a JSON object: each line that names one of `idle` by its label, as
/// `(label, what follows it)`.
fn named_lines(task: &Task, text: &str, idle: &[NodeId]) -> Vec<(String, String)> {
    text.lines()
        .map(str::trim)
        .filter_map(|line| {
            let (at, robot) = idle
                .iter()
                .filter_map(|&r| line.find(&robot_label(task, r)).map(|at| (at, r)))
                .min()?;
            let label = robot_label(task, robot);
            let rest = line[at + label.len()..]
                .trim_start_matches([':', '-', ',', ' '])
                .trim();
            Some((label, field_text(rest)))
        })
        .collect()
}

/// One line per robot: type, room, and what it stands on, hovers above or holds.
fn robot_lines(env: &(dyn Environment + Send), task: &Task) -> String {
    let s = env.state();
    task.robots
        .iter()
        .map(|r| {
            let mut line = format!("- {}: {}", task.node(r.node).label(), r.kind);
            if let Some(room) = rules::room_of(task, s, r.node) {
                line.push_str(&format!(", in {}", task.node(room).label()));
            }
            for e in s.out(r.node) {
                let word = match e.rel() {
                    Relation::On => "on",
                    Relation::Above => "above",
                    Relation::Hold => "holding",
                    _ => continue,
                };
                line.push_str(&format!(", {word} {}", task.node(e.to()).label()));
            }
            let states = task.vocab.state_names(s.states(r.node));
            if !states.is_empty() {
                line.push_str(&format!(" ({})", states.join(", ")));
            }
            line
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The robot `text` names: its label `<quadrotor>(22)`, its id, or its type when the
/// team has only one robot of that type.
fn resolve_robot(task: &Task, text: &str) -> Option<NodeId> {
    let text = text.trim();
    let labelled = task.robots.iter().find(|r| {
        let label = task.node(r.node).label();
        text == label || text.contains(&label)
    });
    if let Some(r) = labelled {
        return Some(task.id(r.node));
    }
    let digits: String = text.chars().filter(char::is_ascii_digit).collect();
    if let Ok(id) = digits.parse::<i64>()
        && let Some(r) = task.robots.iter().find(|r| task.id(r.node).0 == id)
    {
        return Some(task.id(r.node));
    }
    let lower = text.to_ascii_lowercase();
    let mut of_type = task.robots.iter().filter(|r| {
        lower.contains(r.kind.class_name()) || lower.contains(&task.node(r.node).class_name)
    });
    match (of_type.next(), of_type.next()) {
        (Some(r), None) => Some(task.id(r.node)),
        _ => None,
    }
}

fn team_list(task: &Task) -> String {
    task.robots
        .iter()
        .map(|r| task.node(r.node).label())
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prompts::fill::{check_placeholders, demo_task, every_placeholder};
    use coherent_core::SymbolicEnv;

    #[test]
    fn every_template_placeholder_is_filled() {
        check_placeholders(Template::AssignerSystem.builtin(), &["team"]);
        check_placeholders(
            Template::AssignerUser.builtin(),
            &["instruction", "robots", "scene", "state", "history"],
        );
        check_placeholders(
            Template::AssignerUser.paper_layout(),
            &["instruction", "robots", "observation", "history"],
        );
    }

    #[test]
    fn every_placeholder_a_template_may_use_is_filled() {
        let task = demo_task();
        let env = SymbolicEnv::new(Arc::clone(&task));
        for template in [Template::AssignerSystem, Template::AssignerUser] {
            let assigner = TaskAssigner::new(&task, &every_placeholder(template), 100);
            let messages = assigner.query(&env, &["Round 1: ...".to_owned()]).messages;
            for m in &messages {
                assert!(!m.content.contains("{{"), "{}", m.content);
            }
        }
    }
}
