//! The central prompt (the prompt set's `central.txt`), which CMRS answers once per step
//! and LLM-MCTS samples for its prior: the team, the rules, the instruction, the team's
//! observation, the last executed actions and every team action line
//! ([`crate::prompts::team_actions`]); and the line an answer chooses.

use coherent_core::{NodeId, Task};
use serde_json::{Value, json};

use crate::llm::Message;
use crate::prompts::answer::{field_text, json_object, normal, read_line};
use crate::prompts::fill::{self, Sight};
use crate::prompts::templates::{self, Prompts, Template};

/// The central prompt: the team, the rules, the instruction, what `sight` shows the
/// team, the last executed actions and every team action line (CMRS, LLM-MCTS
/// samples), rendered from `prompts`.
pub(crate) fn messages(
    prompts: &Prompts,
    sight: &Sight<'_>,
    lines: &[String],
    history: &[String],
) -> Vec<Message> {
    render(prompts.text(Template::Central), sight, lines, history)
}

/// `text` (a system part, the user mark, a user part) filled.
fn render(text: &str, sight: &Sight<'_>, lines: &[String], history: &[String]) -> Vec<Message> {
    let task = sight.task;
    let team = fill::team(task);
    let history = if history.is_empty() {
        "(none yet)".to_owned()
    } else {
        history.join("\n")
    };
    let actions = lines.join("\n");
    let seen = sight.values(text);
    let mut values = vec![
        ("team", team.as_str()),
        ("instruction", task.meta.instruction.as_str()),
        ("history", history.as_str()),
        ("actions", actions.as_str()),
    ];
    values.extend(seen.iter().map(|(k, v)| (*k, v.as_str())));
    let (system, user) = templates::split(text);
    let mut messages = Vec::new();
    if !system.trim().is_empty() {
        messages.push(Message::system(
            fill::fill(system, &values).trim().to_owned(),
        ));
    }
    messages.push(Message::user(fill::fill(user, &values).trim().to_owned()));
    messages
}

/// The answer: one of the team action lines.
pub fn schema(lines: &[String]) -> Value {
    json!({
        "type": "object",
        "properties": {"action": {"type": "string", "enum": lines}},
        "required": ["action"],
        "additionalProperties": false,
    })
}

/// The central prompt of a parallel episode (CMRS in joint steps): as [`messages`], the
/// model choosing at most one line per robot for the step.
pub(crate) fn messages_parallel(
    prompts: &Prompts,
    sight: &Sight<'_>,
    lines: &[String],
    history: &[String],
) -> Vec<Message> {
    render(
        prompts.text(Template::CentralParallel),
        sight,
        lines,
        history,
    )
}

/// The answer of a parallel episode: a list of the team action lines.
pub fn schema_parallel(lines: &[String]) -> Value {
    json!({
        "type": "object",
        "properties": {
            "actions": {"type": "array", "items": {"type": "string", "enum": lines}},
        },
        "required": ["actions"],
        "additionalProperties": false,
    })
}

/// What a parallel answer chose, `(robot, action)` in its order, and the reasons for
/// the lines that were left out.
pub(crate) type Choices = (Vec<(NodeId, String)>, Vec<String>);

/// The robots and actions a parallel answer chooses, at most one per robot (a robot's
/// later lines are left out and said so), each read as [`choose`] reads one line: the
/// `actions` list of its JSON object, else (an answer in the sequential form) the one
/// line it names. Returns the choices in the answer's order and what was left out; an
/// error when no line is usable.
pub(crate) fn choose_several(task: &Task, lines: &[String], text: &str) -> Result<Choices, String> {
    let said: Vec<String> = match json_object(text)
        .as_ref()
        .and_then(|m| m.get("actions"))
        .and_then(Value::as_array)
    {
        Some(items) => items
            .iter()
            .map(|v| v.as_str().map(field_text).unwrap_or_default())
            .collect(),
        None => vec![read_line(text)],
    };
    let mut chosen: Vec<(NodeId, String)> = Vec::new();
    let mut unused = Vec::new();
    for line in said {
        match choose(task, lines, &line) {
            Ok((robot, _)) if chosen.iter().any(|(r, _)| *r == robot) => unused.push(format!(
                "{} was given two actions: the first counts",
                fill::robot_label(task, robot)
            )),
            Ok(pick) => chosen.push(pick),
            Err(why) => unused.push(why),
        }
    }
    if chosen.is_empty() && !unused.is_empty() {
        return Err(unused.join("; "));
    }
    Ok((chosen, unused))
}

/// The robot and action an answer chooses: one of `lines` (matched ignoring case and
/// spacing), or else `<robot label>: <action>` for a robot of the team, the action then
/// taken as written for the feasibility check to judge. No nearest-match guessing: that
/// is LLM-MCTS's own mechanism ([`crate::prompts::answer::match_line`]), not these methods'.
pub(crate) fn choose(
    task: &Task,
    lines: &[String],
    text: &str,
) -> Result<(NodeId, String), String> {
    let said = read_line(text);
    let line = lines
        .iter()
        .find(|l| normal(l) == normal(&said))
        .cloned()
        .unwrap_or(said);
    for r in &task.robots {
        let label = task.node(r.node).label();
        if let Some(action) = line.strip_prefix(&label) {
            let action = action.trim_start_matches([':', ' ']).trim();
            if !action.is_empty() {
                return Ok((task.id(r.node), action.to_owned()));
            }
        }
    }
    Err(format!(
        "{:?} is not \"<robot>: <action>\" for a robot of the team",
        excerpt(&line)
    ))
}

fn excerpt(text: &str) -> String {
    text.chars().take(120).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_template_is_filled_and_split() {
        let (system, user) = Template::Central
            .builtin()
            .split_once(templates::USER_MARK)
            .expect("a user part");
        assert!(system.contains("{{team}}"));
        for key in ["instruction", "scene", "state", "history", "actions"] {
            assert!(user.contains(&format!("{{{{{key}}}}}")), "{key}");
        }
    }

    #[test]
    fn every_placeholder_a_template_may_use_is_filled() {
        let task = crate::prompts::fill::demo_task();
        let prompts = crate::prompts::fill::every_placeholder(Template::Central);
        let sight = Sight {
            task: &task,
            state: &task.init,
            observations: Vec::new(),
            news: &[],
        };
        let messages = messages(&prompts, &sight, &["a: b".into()], &[]);
        for m in &messages {
            assert!(!m.content.contains("{{"), "{}", m.content);
        }
    }
}
