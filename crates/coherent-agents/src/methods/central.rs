//! The central prompt (the prompt set's `central.txt`), which CMRS answers once per step
//! and LLM-MCTS samples for its prior: the team, the rules, the instruction, the team's
//! observation, every joint action line ([`crate::methods::joint`]) and the last
//! executed actions; and the line an answer chooses.

use coherent_core::{NodeId, Task};
use serde_json::{Value, json};

use crate::backends::llm::Message;
use crate::methods::answer::{normal, read_line};
use crate::methods::prompt::{self, Sight};
use crate::methods::templates::{self, Prompts, Template};

/// The central prompt: the team, the rules, the instruction, what `sight` shows the
/// team, the last executed actions and every joint action line (CMRS, LLM-MCTS
/// samples), rendered from `prompts`.
pub(crate) fn messages(
    prompts: &Prompts,
    sight: &Sight<'_>,
    lines: &[String],
    history: &[String],
) -> Vec<Message> {
    let task = sight.task;
    let team = prompt::team(task);
    let history = if history.is_empty() {
        "(none yet)".to_owned()
    } else {
        history.join("\n")
    };
    let actions = lines.join("\n");
    let text = prompts.text(Template::Central);
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
            prompt::fill(system, &values).trim().to_owned(),
        ));
    }
    messages.push(Message::user(prompt::fill(user, &values).trim().to_owned()));
    messages
}

/// The answer: one of the joint action lines.
pub fn schema(lines: &[String]) -> Value {
    json!({
        "type": "object",
        "properties": {"action": {"type": "string", "enum": lines}},
        "required": ["action"],
        "additionalProperties": false,
    })
}

/// The robot and action an answer chooses: one of `lines` (matched ignoring case and
/// spacing), or else `<robot label>: <action>` for a robot of the team, the action then
/// taken as written for the feasibility check to judge. No nearest-match guessing: that
/// is LLM-MCTS's own mechanism ([`crate::methods::answer::match_line`]), not these methods'.
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
        let task = crate::methods::prompt::demo_task();
        let prompts = crate::methods::prompt::every_placeholder(Template::Central);
        let sight = Sight {
            task: &task,
            state: &task.init,
            observations: Vec::new(),
        };
        let messages = messages(&prompts, &sight, &["a: b".into()], &[]);
        for m in &messages {
            assert!(!m.content.contains("{{"), "{}", m.content);
        }
    }
}
