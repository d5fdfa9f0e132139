//! DMRS, the paper's decentralised dialogue baselines after CoELA (docs/methods.md,
//! `dmrs-1d` and `dmrs-2d`): each step the robots speak in a random order (seeded); each speaker sees
//! the task, its own observation, the action lists of itself and of the robots who spoke
//! before it, the last executed actions and the step's dialogue so far, and proposes
//! one `<robot>: <action>` line. The last speaker's proposal is checked and run.
//! DMRS-1D has one dialogue round per step, DMRS-2D two (in the second every robot's
//! list is known). One model call per robot per dialogue round.
//!
//! In a parallel episode each speaker proposes its own action (or none), hearing what the
//! others said they will do; the dialogue ends in one action per robot, each robot's
//! last proposal, carried out together as the step's joint step.

use coherent_core::{Environment, Execution, NodeId, Task};
use serde_json::{Value, json};

use crate::episode::ask::{Side, Unusable, ask};
use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::llm::{Message, Query, Role, Situation};
use crate::methods::{central, decision};
use crate::prompts::answer::{field_text, json_object, normal, read_line};
use crate::prompts::fill::{self, Sight, robot_label};
use crate::prompts::team_actions::{self, TeamAction};
use crate::prompts::templates::{self, Prompts, Template};
use crate::records::transcript::Round;
use crate::rng::{Rng, seed_of};

/// Most tokens of one turn (a sentence and a line).
const MAX_TOKENS: u32 = 200;

/// DMRS for one episode.
#[derive(Debug)]
pub struct Dmrs {
    /// Dialogue rounds per step: 1 (DMRS-1D) or 2 (DMRS-2D).
    dialogue_rounds: u32,
    /// Seeds the speaking order of every step.
    seed: u64,
    /// The speakers' template (`dmrs_speaker.txt`; `dmrs_speaker_parallel.txt` in joint
    /// steps) comes from here.
    prompts: Prompts,
}

impl Dmrs {
    /// DMRS with `dialogue_rounds` rounds of dialogue a step (1 or 2), its speaking
    /// orders drawn from `seed`.
    pub fn new(dialogue_rounds: u32, seed: u64, prompts: Prompts) -> Dmrs {
        Dmrs {
            dialogue_rounds,
            seed,
            prompts,
        }
    }

    /// This step's speaking order: the team shuffled, seeded by the episode's seed and
    /// the step.
    fn order(&self, task: &Task, step: u32) -> Vec<NodeId> {
        let mut order: Vec<NodeId> = task.robots.iter().map(|r| task.id(r.node)).collect();
        Rng::new(seed_of(self.seed, u64::from(step))).shuffle(&mut order);
        order
    }
}

impl Method for Dmrs {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            Ok(match turn.execution {
                Execution::Sequential => self.dialogue(turn, round).await,
                Execution::Parallel => self.joint_dialogue(turn, round).await,
            })
        })
    }

    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        decision::team_feedback(closing.task, round, None);
    }

    fn recall(&self, task: &Task, round: &Round) -> Option<String> {
        decision::executed_line(task, round)
    }
}

/// The team actions of the robots heard so far in a round's dialogue, as listed to the
/// next speaker.
fn heard_lines(task: &Task, all: &[TeamAction], heard: &[NodeId]) -> Vec<String> {
    all.iter()
        .filter(|a| heard.contains(&task.id(a.robot.node)))
        .map(|a| a.line(task))
        .collect()
}

/// The `message` of a speaker's answer, as text, or nothing.
fn message_in(text: &str) -> String {
    json_object(text)
        .and_then(|m| m.get("message").and_then(Value::as_str).map(field_text))
        .unwrap_or_default()
}

/// One speaker's turn, as the next speakers hear it.
fn said(task: &Task, speaker: NodeId, text: &str, proposal: Option<&(NodeId, String)>) -> String {
    let message = message_in(text);
    let proposal = proposal.map_or("nothing usable".to_owned(), |(robot, action)| {
        format!("{}: {action}", robot_label(task, *robot))
    });
    format!(
        "{} said: {} It proposed {proposal}.",
        robot_label(task, speaker),
        message.trim()
    )
}

impl Dmrs {
    /// A sequential round: the speakers in order, each proposing a team action; the
    /// last speaker's is the round's decision. `None` when cancelled.
    async fn dialogue(&self, turn: Turn<'_>, round: &mut Round) -> Option<Decided> {
        let Turn { task, env, .. } = turn;
        let order = self.order(task, round.step);
        let all = team_actions::offered(task, env.state());
        let mut dialogue: Vec<String> = Vec::new();
        let mut heard: Vec<NodeId> = Vec::new();
        let mut proposal: Option<(NodeId, String)> = None;
        for _ in 0..self.dialogue_rounds.max(1) {
            for &speaker in &order {
                if !heard.contains(&speaker) {
                    heard.push(speaker);
                }
                let lines = heard_lines(task, &all, &heard);
                let query = Query {
                    role: Role::Executor,
                    robot: Some(speaker),
                    messages: speaker_messages(
                        self.prompts.text(Template::DmrsSpeaker),
                        &speaker_sight(env, task, speaker, turn.news),
                        speaker,
                        turn.history,
                        &dialogue,
                        &lines,
                    ),
                    schema_name: "team_action",
                    schema: speaker_schema(&lines),
                    max_tokens: MAX_TOKENS,
                    situation: Situation::now(task, env, None),
                };
                let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
                let text = reply.as_ref().map_or(String::new(), |r| r.text.clone());
                match reply.and_then(|r| r.read(|text| central::choose(task, &lines, text))) {
                    Ok(p) => proposal = Some(p),
                    Err(Unusable::Failed(e)) => {
                        return Some(Decided::Ends(Unusable::Failed(e).outcome(Side::Executor)));
                    }
                    Err(Unusable::Bad(_)) => proposal = None,
                }
                dialogue.push(said(task, speaker, &text, proposal.as_ref()));
            }
        }
        round.actions = all.iter().map(|a| a.line(task)).collect();
        let Some((robot, action)) = proposal else {
            let why = "the last speaker proposed nothing usable".to_owned();
            return Some(Decided::Ends(Unusable::Bad(why).outcome(Side::Executor)));
        };
        decision::choose(round, robot, &action, dialogue.join("\n"));
        Some(Decided::CarryOut)
    }

    /// A parallel round: each speaker proposes its own action, hearing what the others
    /// said; each robot's last proposal is carried out, all together. `None` when
    /// cancelled.
    async fn joint_dialogue(&self, turn: Turn<'_>, round: &mut Round) -> Option<Decided> {
        let Turn { task, env, .. } = turn;
        let order = self.order(task, round.step);
        let all = team_actions::offered(task, env.state());
        let mut dialogue: Vec<String> = Vec::new();
        let mut heard: Vec<NodeId> = Vec::new();
        // Each speaker's last word: its own action (or none) and its message; `None` while
        // its last answer gave nothing usable.
        let mut last: Vec<(NodeId, Option<Word>)> = Vec::new();
        for _ in 0..self.dialogue_rounds.max(1) {
            for &speaker in &order {
                if !heard.contains(&speaker) {
                    heard.push(speaker);
                }
                let lines = heard_lines(task, &all, &heard);
                let own = env.actions(speaker).unwrap_or_default();
                let query = Query {
                    role: Role::Executor,
                    robot: Some(speaker),
                    messages: speaker_messages(
                        self.prompts.text(Template::DmrsSpeakerParallel),
                        &speaker_sight(env, task, speaker, turn.news),
                        speaker,
                        turn.history,
                        &dialogue,
                        &lines,
                    ),
                    schema_name: "own_action",
                    schema: own_schema(&own),
                    max_tokens: MAX_TOKENS,
                    situation: Situation::now(task, env, None),
                };
                let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
                let word = match reply
                    .and_then(|r| r.read(|text| own_action(task, speaker, &own, text)))
                {
                    Ok(word) => Some(word),
                    Err(Unusable::Failed(e)) => {
                        return Some(Decided::Ends(Unusable::Failed(e).outcome(Side::Executor)));
                    }
                    Err(Unusable::Bad(_)) => None,
                };
                let proposed = match &word {
                    Some((Some(action), _)) => format!("It will do {action}."),
                    Some((None, _)) => "It will do nothing this step.".to_owned(),
                    None => "It proposed nothing usable.".to_owned(),
                };
                let message = word.as_ref().map_or("", |(_, m)| m.as_str());
                dialogue.push(format!(
                    "{} said: {} {proposed}",
                    robot_label(task, speaker),
                    message.trim()
                ));
                last.retain(|(r, _)| *r != speaker);
                last.push((speaker, word));
            }
        }
        round.actions = all.iter().map(|a| a.line(task)).collect();
        if last.iter().all(|(_, word)| word.is_none()) {
            let why = "no speaker proposed anything usable".to_owned();
            return Some(Decided::Ends(Unusable::Bad(why).outcome(Side::Executor)));
        }
        round.parts = last
            .into_iter()
            .filter_map(|(robot, word)| {
                let (action, message) = word?;
                Some(decision::part(env, robot, action.as_deref()?, message))
            })
            .collect();
        Some(Decided::CarryOut)
    }
}

/// A speaker's word in a parallel dialogue: its own action (or none), and its message.
pub(crate) type Word = (Option<String>, String);

/// A speaker's own action in its answer (matched to the spelling of its list `own` when
/// it is one of them, else as written for the feasibility check to judge; `none` for
/// none, its own label in front allowed), and its message; an error when the answer
/// names no action.
pub(crate) fn own_action(
    task: &Task,
    speaker: NodeId,
    own: &[String],
    text: &str,
) -> Result<Word, String> {
    let message = message_in(text);
    let said = read_line(text);
    let label = robot_label(task, speaker);
    let said = said
        .strip_prefix(&label)
        .map_or(said.as_str(), |rest| rest.trim_start_matches([':', ' ']))
        .trim();
    if said.is_empty() {
        return Err("the answer names no action".into());
    }
    if matches!(normal(said).as_str(), "none" | "null" | "nothing") {
        return Ok((None, message));
    }
    let action = own
        .iter()
        .find(|a| normal(a) == normal(said))
        .cloned()
        .unwrap_or_else(|| field_text(said));
    Ok((Some(action), message))
}

/// A parallel speaker's answer: a message, and one of its own actions or `none`.
fn own_schema(own: &[String]) -> Value {
    let mut choices: Vec<&str> = own.iter().map(String::as_str).collect();
    choices.push("none");
    json!({
        "type": "object",
        "properties": {
            "message": {"type": "string"},
            "action": {"type": "string", "enum": choices},
        },
        "required": ["message", "action"],
        "additionalProperties": false,
    })
}

/// What `speaker` is shown: its own observation, after `news` (what happened since the
/// last round that the team did not do).
fn speaker_sight<'a>(
    env: &'a dyn Environment,
    task: &'a Task,
    speaker: NodeId,
    news: &'a [String],
) -> Sight<'a> {
    Sight {
        task,
        state: env.state(),
        observations: env.observe(speaker).into_iter().collect(),
        news,
    }
}

fn speaker_messages(
    template: &str,
    sight: &Sight<'_>,
    speaker: NodeId,
    history: &[String],
    dialogue: &[String],
    lines: &[String],
) -> Vec<Message> {
    let task = sight.task;
    let kind = task
        .robot_by_id(speaker)
        .map_or(String::new(), |r| r.kind.to_string());
    let or_none = |items: &[String]| {
        if items.is_empty() {
            "(none yet)".to_owned()
        } else {
            items.join("\n")
        }
    };
    let mut values = vec![
        ("robot", robot_label(task, speaker)),
        ("kind", kind),
        ("team", fill::team(task)),
        ("instruction", task.meta.instruction.clone()),
        ("history", or_none(history)),
        ("dialogue", or_none(dialogue)),
        ("actions", or_none(lines)),
    ];
    values.extend(sight.values(template));
    let values: Vec<(&str, &str)> = values.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let (system, user) = templates::split(template);
    vec![
        Message::system(fill::fill(system, &values).trim().to_owned()),
        Message::user(fill::fill(user, &values).trim().to_owned()),
    ]
}

fn speaker_schema(lines: &[String]) -> Value {
    json!({
        "type": "object",
        "properties": {
            "message": {"type": "string"},
            "action": {"type": "string", "enum": lines},
        },
        "required": ["message", "action"],
        "additionalProperties": false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prompts::fill::demo_task;

    #[test]
    fn every_placeholder_of_the_template_is_filled() {
        let (system, user) = Template::DmrsSpeaker
            .builtin()
            .split_once(templates::USER_MARK)
            .expect("a user part");
        for key in ["robot", "kind", "team"] {
            assert!(system.contains(&format!("{{{{{key}}}}}")), "{key}");
        }
        for key in [
            "instruction",
            "scene",
            "state",
            "history",
            "dialogue",
            "actions",
        ] {
            assert!(user.contains(&format!("{{{{{key}}}}}")), "{key}");
        }
    }

    #[test]
    fn every_placeholder_a_template_may_use_is_filled() {
        let task = demo_task();
        let env = coherent_core::SymbolicEnv::new(std::sync::Arc::clone(&task));
        let prompts = crate::prompts::fill::every_placeholder(Template::DmrsSpeaker);
        let speaker = task.id(task.robots[0].node);
        let lines = ["a: b".to_owned()];
        let template = prompts.text(Template::DmrsSpeaker);
        for m in &speaker_messages(
            template,
            &speaker_sight(&env, &task, speaker, &[]),
            speaker,
            &[],
            &[],
            &lines,
        ) {
            assert!(!m.content.contains("{{"), "{}", m.content);
        }
    }
}
