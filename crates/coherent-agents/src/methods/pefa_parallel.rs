//! PEFA in joint steps (`--execution parallel`): the robots act at the same time.
//!
//! Proposal: when some robot is idle, the [`TaskAssigner`] gives subtasks to any of the
//! idle robots in one answer (a list); a robot that has a subtask keeps it. Execution:
//! every robot with a subtask has its [`RobotExecutor`] asked at once, each seeing its
//! own observation and action list in the state before the step, and the actions they
//! pick are carried out together as one joint step (`coherent_core::joint`: refused as a
//! whole when two of them interfere). Feedback: each robot's own, as in the sequential
//! loop ([`feedback::pefa_part`]). Adjustment: the round joins the assigner's history.
//! A robot keeps its subtask across steps until its executor reports it complete, or it
//! fails (its action refused, no action, no usable answer); it is then idle, and the
//! assigner is asked again. One round is one step; a round makes one call per robot
//! with a subtask, plus the assigner's when it is asked.

use std::collections::BTreeMap;
use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, NodeId, Task};

use crate::backends::llm::Backend;
use crate::episode::ask::{Side, Unusable, ask, ask_all};
use crate::episode::cancel::Cancel;
use crate::episode::joint;
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::assigner::TaskAssigner;
use crate::methods::executor::RobotExecutor;
use crate::methods::feedback;
use crate::methods::pefa::PefaConfig;
use crate::methods::prompt::robot_label;
use crate::records::transcript::{Proposal, RobotPart, Round, RoundOutcome};

/// The subtasks robots keep from earlier rounds, with the round each was given in.
type Busy = BTreeMap<NodeId, (Proposal, u32)>;

/// Runs PEFA in joint steps on `env` until the goal holds, the budget is spent, the
/// backend fails for good, or `cancel` fires. `on_round` sees each round as it ends.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &PefaConfig,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let mut history = History::new(config.history);
    let mut busy = Busy::new();
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let past = history.entries();
        let r = round(env, task, backend, config, cancel, &past, &mut busy, step).await;
        if let Some(r) = &r {
            history.push(feedback::assigner_history(task, r));
        }
        Ok(r)
    };
    rounds(env, task, config.max_steps, cancel, on_round, play).await
}

/// One round; `None` when cancelled during it (nothing of it is kept).
#[allow(clippy::too_many_arguments)]
async fn round(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &PefaConfig,
    cancel: &Cancel,
    history: &[String],
    busy: &mut Busy,
    step: u32,
) -> Option<Round> {
    let start = Instant::now();
    let mut round = Round::new(step);
    let team: Vec<NodeId> = task.robots.iter().map(|r| task.id(r.node)).collect();
    let idle: Vec<NodeId> = team
        .iter()
        .copied()
        .filter(|r| !busy.contains_key(r))
        .collect();

    // Proposal, when a robot is idle.
    let mut assigner_note = None;
    let mut unusable = None;
    let mut assigned = Vec::new();
    if !idle.is_empty() {
        let assigner = TaskAssigner::new(task, &config.prompts, config.assigner_max_tokens);
        let kept: Vec<(NodeId, String, u32)> = busy
            .iter()
            .map(|(r, (p, since))| (*r, p.subtask.clone(), *since))
            .collect();
        let query = assigner.query_parallel(env, history, &kept, &idle);
        let reply = ask(backend, query, cancel, &mut round.calls).await?;
        match reply.and_then(|r| r.read(|text| assigner.parse_parallel(text, &idle))) {
            Ok(answer) => {
                if !answer.unused.is_empty() {
                    assigner_note = Some(format!(
                        "Part of your answer was not used: {}.",
                        answer.unused.join("; ")
                    ));
                }
                assigned = answer.proposals;
            }
            Err(Unusable::Failed(e)) => {
                let outcome = Unusable::Failed(e).outcome(Side::Assigner);
                return Some(closed(env, round, Vec::new(), outcome, None, start));
            }
            Err(bad) => {
                let outcome = bad.outcome(Side::Assigner);
                assigner_note = Some(note(&outcome));
                unusable = Some(outcome);
            }
        }
    }
    for p in assigned {
        busy.insert(p.robot, (p, step));
    }

    // Execution: every robot with a subtask, its executor asked beside the others'.
    let mut parts: Vec<RobotPart> = Vec::new();
    let mut executors = Vec::new();
    let mut queries = Vec::new();
    for (robot, (proposal, since)) in team.iter().filter_map(|r| Some((*r, busy.get(r)?))) {
        let mut part = RobotPart::new(robot);
        part.proposal = Some(proposal.clone());
        part.kept = *since < step;
        let max_tokens = config.executor_max_tokens;
        match RobotExecutor::of(task, robot, &config.prompts, max_tokens) {
            Ok(executor) => {
                part.actions = executor.actions(env);
                queries.push(executor.query(env, &proposal.subtask, &part.actions));
                executors.push((parts.len(), executor));
            }
            Err(e) => part.outcome = RoundOutcome::NoProposal { why: e.to_string() },
        }
        parts.push(part);
    }
    let replies = ask_all(backend, queries, cancel).await?;
    let mut failed = None;
    for ((i, executor), (calls, reply)) in executors.into_iter().zip(replies) {
        round.calls.extend(calls);
        let part = &mut parts[i];
        match reply.and_then(|r| r.read(|text| executor.parse(&part.actions, text))) {
            Ok(decision) => part.decision = Some(decision),
            Err(Unusable::Failed(e)) => {
                part.outcome = Unusable::Failed(e).outcome(Side::Executor);
                failed.get_or_insert_with(|| part.outcome.clone());
            }
            Err(bad) => part.outcome = bad.outcome(Side::Executor),
        }
    }
    if let Some(outcome) = failed {
        // The model is gone: no step is carried out, and the episode ends here.
        for part in parts.iter_mut().filter(|p| p.decision.is_some()) {
            part.outcome = RoundOutcome::Infeasible {
                reason: "step_refused".into(),
                message: "not carried out: the model could not be reached".into(),
            };
        }
        return Some(closed(env, round, parts, outcome, assigner_note, start));
    }

    // The joint step, each robot's feedback, and who keeps a subtask.
    let step_outcome = joint::carry_out(env, &mut parts);
    for part in &mut parts {
        part.feedback = feedback::pefa_part(task, env.state(), part);
        let goes_on = part.outcome == RoundOutcome::Executed
            && !part.decision.as_ref().is_some_and(|d| d.subtask_complete);
        if !goes_on {
            busy.remove(&part.robot);
        }
    }
    let outcome = unusable.unwrap_or(step_outcome);
    Some(closed(env, round, parts, outcome, assigner_note, start))
}

/// What the assigner hears of an answer that could not be used.
fn note(outcome: &RoundOutcome) -> String {
    match outcome {
        RoundOutcome::NoProposal { why } => format!(
            "Your answer could not be used ({why}). Name idle robots of the team and a subtask for each."
        ),
        other => feedback::team("", other),
    }
}

/// Closes a round: the step's outcome, its parts, what the assigner hears of it (its
/// own answer first, then each robot's subtask and what became of it), the time.
fn closed(
    env: &(dyn Environment + Send),
    mut round: Round,
    parts: Vec<RobotPart>,
    outcome: RoundOutcome,
    assigner_note: Option<String>,
    start: Instant,
) -> Round {
    let task = env.task();
    let heard: Vec<RobotPart> = parts
        .iter()
        .map(|p| RobotPart {
            feedback: match &p.proposal {
                Some(proposal) => format!(
                    "You asked {} to \"{}\": {}",
                    robot_label(task, p.robot),
                    proposal.subtask,
                    p.feedback
                ),
                None => p.feedback.clone(),
            },
            ..p.clone()
        })
        .collect();
    let step = match &outcome {
        RoundOutcome::BackendError { .. } => Some(feedback::team("", &outcome)),
        _ => assigner_note,
    };
    let paragraph = joint::paragraph(step, &heard);
    joint::close(env, &mut round, parts, outcome, paragraph);
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    round
}
