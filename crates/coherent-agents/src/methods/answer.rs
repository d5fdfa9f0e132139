//! Reading the roles' answers: the JSON object the prompt asks for, wherever it sits in
//! the text (code fences, chatter around it), and when there is none, the free text
//! itself. Anything unreadable is an error with the reason, never a panic.

use coherent_core::{NodeId, Task};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The assigner's proposal.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Proposal {
    pub robot: NodeId,
    pub subtask: String,
    pub reasoning: String,
}

/// The executor's decision.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Decision {
    pub can_do: bool,
    /// The action to run, as answered (matched to the list's spelling when it is one of
    /// them); `None` when the executor declines.
    pub action: Option<String>,
    /// The executor's own judgement that this action finishes the subtask.
    pub subtask_complete: bool,
    pub note: String,
}

/// The first JSON object in `text`.
pub(crate) fn json_object(text: &str) -> Option<Map<String, Value>> {
    text.match_indices('{').take(16).find_map(|(i, _)| {
        let mut values = serde_json::Deserializer::from_str(&text[i..]).into_iter::<Value>();
        match values.next() {
            Some(Ok(Value::Object(map))) => Some(map),
            _ => None,
        }
    })
}

fn string_field(map: &Map<String, Value>, key: &str) -> Option<String> {
    match map.get(key)? {
        Value::String(s) => Some(s.trim().to_owned()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    }
}

fn bool_field(map: &Map<String, Value>, key: &str) -> Option<bool> {
    match map.get(key)? {
        Value::Bool(b) => Some(*b),
        Value::String(s) => match s.trim().to_ascii_lowercase().as_str() {
            "true" | "yes" => Some(true),
            "false" | "no" => Some(false),
            _ => None,
        },
        _ => None,
    }
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

pub fn parse_proposal(task: &Task, text: &str) -> Result<Proposal, String> {
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
                subtask: if rest.is_empty() { line } else { rest }.to_owned(),
                reasoning: text.trim().to_owned(),
            });
        }
    }
    Err(format!(
        "no JSON object and no line naming a robot of the team ({})",
        team_list(task)
    ))
}

/// Lower case with single spaces, for matching an action however it was spaced.
pub(crate) fn normal(s: &str) -> String {
    s.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_lowercase()
}

/// `answer` spelled as in `actions` when it is one of them, else as answered.
fn match_action(actions: &[String], answer: &str) -> String {
    let n = normal(answer);
    actions
        .iter()
        .find(|a| normal(a) == n)
        .cloned()
        .unwrap_or_else(|| answer.trim().to_owned())
}

pub fn parse_decision(actions: &[String], text: &str) -> Result<Decision, String> {
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
                can_do: false,
                action: None,
                subtask_complete: false,
                note: text.trim().to_owned(),
            })
        }
        None => Err("no JSON object and no action of the list in the answer".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
