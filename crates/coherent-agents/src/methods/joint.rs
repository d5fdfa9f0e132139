//! The team's joint action space as text, for the methods that choose one robot's
//! action centrally or in dialogue (CMRS, DMRS, LLM-MCTS): one line per `(robot,
//! action)`, `<robot dog>(13): [grab] <mug>(7)`; the central prompt (the prompt set's
//! `central.txt`); and reading an answer back to a line.

use std::collections::VecDeque;

use coherent_core::{Action, Environment, NodeId, Robot, State, Task, rules};
use serde_json::{Value, json};

use crate::backends::llm::Message;
use crate::episode::environment::execute;
use crate::methods::answer::{field_text, json_object, normal};
use crate::methods::prompt::{self, robot_label};
use crate::methods::templates::{self, Prompts, Template};
use crate::records::transcript::{Decision, Outcome, Round};

/// One robot's action: an element of the joint action space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JointAction {
    pub robot: Robot,
    pub action: Action,
}

impl JointAction {
    /// `<robot label>: <action>`, as the prompt lists it.
    pub fn line(&self, task: &Task) -> String {
        format!(
            "{}: {}",
            task.node(self.robot.node).label(),
            self.action.render(task)
        )
    }
}

/// Every action of every robot in `s`: robots in team order, each robot's actions in
/// [`rules::actions`] order.
pub fn joint_actions(task: &Task, s: &State) -> Vec<JointAction> {
    task.robots
        .iter()
        .zip(rules::team_actions(task, s, &task.robots))
        .flat_map(|(&robot, actions)| {
            actions
                .into_iter()
                .map(move |action| JointAction { robot, action })
        })
        .collect()
}

/// Words and numbers: `[grab] <apple>(3)` gives `grab`, `apple`, `3`.
fn tokens(s: &str) -> Vec<String> {
    let mut out: Vec<String> = s
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| !t.is_empty())
        .map(str::to_ascii_lowercase)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// |a ∩ b| / |a ∪ b| of two sorted token sets.
fn overlap(a: &[String], b: &[String]) -> f64 {
    let common = a.iter().filter(|t| b.binary_search(t).is_ok()).count();
    let union = a.len() + b.len() - common;
    if union == 0 {
        0.0
    } else {
        common as f64 / union as f64
    }
}

/// The least token overlap at which an answer counts as meaning an action.
const MIN_OVERLAP: f64 = 0.5;

/// The joint action line of `lines` that `answer` means, or `None`. First an exact match
/// (ignoring case and spacing); then, when the answer names a robot by its label (the
/// first label in the text), the action of that robot whose words and ids overlap most
/// with the rest of the answer, at least half of them; when it names no robot, the best
/// such action of any robot (ties go to the earlier line).
pub fn match_line(lines: &[String], answer: &str) -> Option<usize> {
    let wanted = normal(answer);
    if wanted.is_empty() {
        return None;
    }
    if let Some(i) = lines.iter().position(|l| normal(l) == wanted) {
        return Some(i);
    }
    let split: Vec<(String, String)> = lines
        .iter()
        .map(|l| match l.split_once(": ") {
            Some((robot, action)) => (normal(robot), action.to_owned()),
            None => (String::new(), l.clone()),
        })
        .collect();
    let named = split
        .iter()
        .filter(|(robot, _)| !robot.is_empty())
        .filter_map(|(robot, _)| wanted.find(robot.as_str()).map(|at| (at, robot)))
        .min();
    let (robot, rest) = match named {
        Some((at, robot)) => {
            let rest = wanted[at + robot.len()..].trim_start_matches([':', '-', ',', ' ']);
            (Some(robot.clone()), rest.to_owned())
        }
        None => (None, wanted.clone()),
    };
    let want = tokens(&rest);
    let mut best: Option<(usize, f64)> = None;
    for (i, (r, action)) in split.iter().enumerate() {
        if robot.as_ref().is_some_and(|named| named != r) {
            continue;
        }
        let score = overlap(&want, &tokens(action));
        if score >= MIN_OVERLAP && best.is_none_or(|(_, s)| score > s) {
            best = Some((i, score));
        }
    }
    best.map(|(i, _)| i)
}

/// The action an answer names: the `action` field of its first JSON object (with its
/// `robot` field in front when the action does not name one; a `subtask` field stands in
/// for a missing `action`), else the whole text.
pub fn read_line(text: &str) -> String {
    let object = json_object(text);
    let Some(map) = object else {
        return field_text(text);
    };
    let field = |k: &str| map.get(k).and_then(Value::as_str).map(field_text);
    let action = field("action")
        .or_else(|| field("subtask"))
        .unwrap_or_default();
    match field("robot") {
        Some(robot) if !robot.is_empty() && !action.contains(&robot) => {
            format!("{robot}: {action}")
        }
        _ => action,
    }
}

/// The central prompt: the team, the rules, the instruction, the team's observation,
/// the last executed actions and every joint action line (CMRS, LLM-MCTS samples),
/// rendered from `prompts`.
pub fn central_messages(
    prompts: &Prompts,
    task: &Task,
    observation: &str,
    lines: &[String],
    history: &[String],
) -> Vec<Message> {
    let team = prompt::team(task);
    let history = if history.is_empty() {
        "(none yet)".to_owned()
    } else {
        history.join("\n")
    };
    let actions = lines.join("\n");
    let values = [
        ("team", team.as_str()),
        ("instruction", task.meta.instruction.as_str()),
        ("observation", observation),
        ("history", history.as_str()),
        ("actions", actions.as_str()),
    ];
    let (system, user) = templates::split(prompts.text(Template::Central));
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
pub fn central_schema(lines: &[String]) -> Value {
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
/// is LLM-MCTS's own mechanism ([`match_line`]), not these methods'.
pub fn choose(task: &Task, lines: &[String], text: &str) -> Result<(NodeId, String), String> {
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

/// Runs `robot`'s `action` as the round's decision: records the line, checks and
/// executes it, and says what came of it.
pub(crate) fn act(
    env: &mut (dyn Environment + Send),
    task: &Task,
    round: &mut Round,
    robot: NodeId,
    action: &str,
    note: String,
) {
    let outcome = execute(env, round, robot, action);
    decided(task, round, robot, action, outcome, note);
}

/// Records `robot`'s `action` as the round's decision, with what came of it (`outcome`)
/// and the sentence that says so.
pub(crate) fn decided(
    task: &Task,
    round: &mut Round,
    robot: NodeId,
    action: &str,
    outcome: Outcome,
    note: String,
) {
    let line = format!("{}: {action}", robot_label(task, robot));
    round.outcome = outcome;
    round.feedback = feedback(&line, &round.outcome);
    round.decision = Some(Decision {
        can_do: true,
        action: Some(line),
        subtask_complete: true,
        note,
    });
}

/// What a round of a central or dialogue method did, in a sentence for the transcript.
pub(crate) fn feedback(line: &str, outcome: &Outcome) -> String {
    match outcome {
        Outcome::Executed => format!("{line} ran."),
        Outcome::Infeasible { message, .. } => format!("{line} could not run: {message}"),
        Outcome::NoProposal { why } | Outcome::NoDecision { why } => {
            format!("No usable answer: {why}")
        }
        Outcome::BackendError { message } => format!("The model could not be reached: {message}"),
        Outcome::MethodError { message } => format!("The method failed: {message}"),
        Outcome::Declined => "No action was chosen.".to_owned(),
    }
}

fn excerpt(text: &str) -> String {
    text.chars().take(120).collect()
}

/// The last executed joint actions, oldest first: the action history the baselines
/// see (the paper's baselines: the last 5; docs/methods.md).
#[derive(Clone, Debug, Default)]
pub(crate) struct Executed {
    lines: VecDeque<String>,
    keep: usize,
}

impl Executed {
    pub(crate) fn new(keep: usize) -> Executed {
        Executed {
            lines: VecDeque::new(),
            keep,
        }
    }

    /// Adds the round's action when it ran.
    pub(crate) fn record(&mut self, round: &Round) {
        if round.outcome == Outcome::Executed
            && let Some(line) = round.decision.as_ref().and_then(|d| d.action.clone())
            && self.keep > 0
        {
            self.lines.push_back(line);
            while self.lines.len() > self.keep {
                self.lines.pop_front();
            }
        }
    }

    pub(crate) fn lines(&self) -> Vec<String> {
        self.lines.iter().cloned().collect()
    }
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
        for key in ["instruction", "observation", "history", "actions"] {
            assert!(user.contains(&format!("{{{{{key}}}}}")), "{key}");
        }
    }

    #[test]
    fn every_placeholder_a_template_may_use_is_filled() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/tasks/demo.json");
        let task = coherent_core::load_tasks(&path)
            .expect("the demo")
            .remove(0);
        let prompts = crate::methods::prompt::every_placeholder(Template::Central);
        let messages = central_messages(&prompts, &task, "facts", &["a: b".into()], &[]);
        for m in &messages {
            assert!(!m.content.contains("{{"), "{}", m.content);
        }
    }
}
