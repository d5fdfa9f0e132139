//! PEFA, the paper's loop: Proposal (the Task Assigner gives one robot one subtask),
//! Execution (that robot's Executor picks one action from its list; the action is
//! checked and run through the [`Environment`]), Feedback (what ran and whether the
//! subtask is done, or why not, with the robot's actions), Adjustment (the feedback joins
//! the history the assigner sees next round). One round is one step; two model calls
//! per round.

use std::collections::VecDeque;
use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use coherent_core::{Environment, NodeId, Relation, Task, describe, rules};
use tokio::sync::Notify;

use crate::answer;
use crate::joint;
use crate::llm::{Backend, Finish, LlmError, Query, Role, Situation};
use crate::prompt::{self, AssignerView, ExecutorView};
use crate::transcript::{Call, Outcome, Round, Status, Summary};

/// Settings of one PEFA episode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PefaConfig {
    /// Rounds of history the assigner sees (the paper: 5; 0 is "w/o history").
    pub history: usize,
    /// Steps before the episode stops as a failure (2 x GT by the paper's rule).
    pub max_steps: u32,
    pub assigner_max_tokens: u32,
    pub executor_max_tokens: u32,
}

impl PefaConfig {
    pub fn new(max_steps: u32) -> PefaConfig {
        PefaConfig {
            history: 5,
            max_steps,
            assigner_max_tokens: 400,
            executor_max_tokens: 200,
        }
    }
}

/// Stops an episode from outside (Ctrl-C): between rounds, during a model call, and
/// inside a planner search through [`Cancel::flag`].
#[derive(Clone, Debug, Default)]
pub struct Cancel {
    flag: Arc<AtomicBool>,
    notify: Arc<Notify>,
}

impl Cancel {
    pub fn cancel(&self) {
        self.flag.store(true, Ordering::SeqCst);
        self.notify.notify_waiters();
    }

    pub fn is_cancelled(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }

    /// The flag itself, for `coherent_core::Limits::cancel`.
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.flag)
    }

    /// Resolves once [`Cancel::cancel`] has been called.
    pub async fn cancelled(&self) {
        let notified = self.notify.notified();
        tokio::pin!(notified);
        // Registered before the check, so a cancel in between still wakes us.
        notified.as_mut().enable();
        if self.is_cancelled() {
            return;
        }
        notified.await;
    }
}

/// An episode as it ran.
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    pub rounds: Vec<Round>,
    pub summary: Summary,
}

/// Runs PEFA on `env` until the goal holds, the budget is spent, the backend fails for
/// good, or `cancel` fires. `on_round` sees each round as it ends (the transcript writer,
/// progress lines); its error stops the episode, so that no round goes unrecorded.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &PefaConfig,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let mut history: VecDeque<String> = VecDeque::new();
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let r = round(env, task, backend, config, cancel, &history, step).await;
        if let Some(r) = &r
            && config.history > 0
        {
            history.push_back(history_entry(task, r));
            while history.len() > config.history {
                history.pop_front();
            }
        }
        Ok(r)
    };
    rounds(env, task, config.max_steps, cancel, on_round, play).await
}

/// The loop every method shares: `play` one round per step until the goal holds, the
/// budget is spent, a round ends in a backend failure, or `cancel` fires (`play` gives
/// `None` when cancelled during a round); then the summary.
pub(crate) async fn rounds(
    env: &mut (dyn Environment + Send),
    task: &Task,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
    mut play: impl AsyncFnMut(&mut (dyn Environment + Send), u32) -> io::Result<Option<Round>>,
) -> io::Result<Episode> {
    let start = Instant::now();
    let mut rounds: Vec<Round> = Vec::new();
    let mut status = if env.goal_satisfied() {
        Status::Success
    } else {
        Status::Failure
    };
    let mut error = None;
    while status == Status::Failure && rounds.len() < max_steps as usize {
        if cancel.is_cancelled() {
            status = Status::Interrupted;
            break;
        }
        let Some(round) = play(env, rounds.len() as u32 + 1).await? else {
            status = Status::Interrupted;
            break;
        };
        on_round(&round)?;
        if let Outcome::BackendError { message } = &round.outcome {
            status = Status::BackendError;
            error = Some(message.clone());
        } else if round.done {
            status = Status::Success;
        } else if let Some(why) = env.stopped() {
            status = Status::Interrupted;
            error = Some(why);
        }
        rounds.push(round);
    }
    let answers = rounds
        .iter()
        .flat_map(|r| &r.calls)
        .filter_map(|c| c.answer.as_ref());
    let (prompt_tokens, completion_tokens) = answers.fold((0, 0), |(p, c), a| {
        (p + a.usage.prompt_tokens, c + a.usage.completion_tokens)
    });
    let summary = Summary {
        status,
        success: status == Status::Success,
        steps: rounds.len() as u32,
        gt_steps: task.meta.gt_steps,
        max_steps,
        llm_calls: rounds.iter().map(|r| r.calls.len() as u32).sum(),
        prompt_tokens,
        completion_tokens,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        error,
    };
    Ok(Episode { rounds, summary })
}

/// One round; `None` when cancelled during it (nothing of it is kept).
async fn round(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &PefaConfig,
    cancel: &Cancel,
    history: &VecDeque<String>,
    step: u32,
) -> Option<Round> {
    let start = Instant::now();
    let mut round = Round::new(step);

    // Proposal.
    let history: Vec<String> = history.iter().cloned().collect();
    let query = Query {
        role: Role::Assigner,
        robot: None,
        messages: prompt::assigner_messages(
            task,
            &AssignerView {
                robots: &robot_lines(env, task),
                observation: &team_observation(env, task),
                history: &history,
            },
        ),
        schema_name: "proposal",
        schema: prompt::assigner_schema(task),
        max_tokens: config.assigner_max_tokens,
        situation: Situation::now(task, env, None),
    };
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    let proposal = match reply.and_then(|r| r.read(|text| answer::parse_proposal(task, text))) {
        Ok(p) => p,
        Err(e) => return Some(finish(env, round, e.outcome(Side::Assigner), start)),
    };
    round.proposal = Some(proposal.clone());

    // Execution.
    let robot = proposal.robot;
    let Ok(r) = task.robot_by_id(robot) else {
        return Some(finish(
            env,
            round,
            Outcome::NoProposal {
                why: format!("robot {robot} is not in the team"),
            },
            start,
        ));
    };
    round.actions = env.actions(robot).unwrap_or_default();
    let observation = env
        .observe(robot)
        .map(|o| describe::facts(task, env.state(), &[&o]))
        .unwrap_or_default();
    let label = task.node(r.node).label();
    let query = Query {
        role: Role::Executor,
        robot: Some(robot),
        messages: prompt::executor_messages(&ExecutorView {
            robot: &label,
            kind: r.kind,
            subtask: &proposal.subtask,
            observation: &observation,
            actions: &round.actions,
        }),
        schema_name: "decision",
        schema: prompt::executor_schema(&round.actions),
        max_tokens: config.executor_max_tokens,
        situation: Situation::now(task, env, Some(proposal.subtask.clone())),
    };
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    let decision =
        match reply.and_then(|r| r.read(|text| answer::parse_decision(&round.actions, text))) {
            Ok(d) => d,
            Err(e) => return Some(finish(env, round, e.outcome(Side::Executor), start)),
        };
    round.decision = Some(decision.clone());
    let outcome = match &decision.action {
        Some(action) if decision.can_do => execute(env, &mut round, robot, action),
        _ => Outcome::Declined,
    };
    Some(finish(env, round, outcome, start))
}

/// Checks and runs `action` for `robot`: executed, or why not; what a robot outside this
/// process said about it goes into `round`.
pub(crate) fn execute(
    env: &mut (dyn Environment + Send),
    round: &mut Round,
    robot: NodeId,
    action: &str,
) -> Outcome {
    match env.step(robot, action) {
        Ok(o) => {
            round.robot = o.report;
            match o.infeasible {
                None => Outcome::Executed,
                Some(why) => Outcome::Infeasible {
                    reason: why.reason.name().to_owned(),
                    message: why.message,
                },
            }
        }
        Err(e) => Outcome::Infeasible {
            reason: "error".into(),
            message: e.to_string(),
        },
    }
}

/// Why a role's answer gave nothing to act on.
pub(crate) enum Unusable {
    /// The backend failed for good.
    Failed(LlmError),
    /// An answer came, but not one that can be used.
    Bad(String),
}

#[derive(Clone, Copy)]
pub(crate) enum Side {
    Assigner,
    Executor,
}

impl Unusable {
    pub(crate) fn outcome(self, side: Side) -> Outcome {
        match (self, side) {
            (Unusable::Failed(e), _) => Outcome::BackendError {
                message: e.to_string(),
            },
            (Unusable::Bad(why), Side::Assigner) => Outcome::NoProposal { why },
            (Unusable::Bad(why), Side::Executor) => Outcome::NoDecision { why },
        }
    }
}

/// An answer's text, and whether generation was cut at the token limit.
pub(crate) struct Reply {
    pub(crate) text: String,
    truncated: bool,
}

impl Reply {
    /// Parses the text; a truncated answer counts when what matters came before the cut
    /// (a small model may pad a complete action with whitespace up to the limit).
    pub(crate) fn read<T>(
        self,
        parse: impl FnOnce(&str) -> Result<T, String>,
    ) -> Result<T, Unusable> {
        parse(&self.text).map_err(|why| {
            Unusable::Bad(if self.truncated {
                format!(
                    "the answer was cut off at the token limit ({why}): {:?}",
                    excerpt(&self.text)
                )
            } else {
                why
            })
        })
    }
}

/// Asks `backend`, records the call, and gives the answer's text unless it is empty,
/// refused or filtered; `None` when cancelled.
pub(crate) async fn ask(
    backend: &dyn Backend,
    query: Query,
    cancel: &Cancel,
    calls: &mut Vec<Call>,
) -> Option<Result<Reply, Unusable>> {
    let mut call = Call {
        role: query.role,
        robot: query.robot.map(|r| r.0),
        messages: query.messages.clone(),
        answer: None,
        error: None,
    };
    let result = tokio::select! {
        biased;
        () = cancel.cancelled() => return None,
        r = backend.ask(query) => r,
    };
    let reply = match result {
        Ok(answer) => {
            let reply = match &answer.finish {
                Finish::Refusal(words) => Err(format!("the model refused: {words}")),
                Finish::ContentFilter => Err("the answer was withheld by a content filter".into()),
                _ if answer.text.trim().is_empty() => Err(if answer.finish == Finish::Length {
                    "the answer was cut off at the token limit before any text".into()
                } else {
                    "the answer was empty".into()
                }),
                finish => Ok(Reply {
                    text: answer.text.clone(),
                    truncated: *finish == Finish::Length,
                }),
            };
            call.answer = Some(answer);
            reply.map_err(Unusable::Bad)
        }
        Err(e) => {
            call.error = Some(e.clone());
            if e.ends_episode() {
                Err(Unusable::Failed(e))
            } else {
                Err(Unusable::Bad(e.to_string()))
            }
        }
    };
    calls.push(call);
    Some(reply)
}

fn excerpt(text: &str) -> String {
    let mut s: String = text.chars().take(120).collect();
    if s.len() < text.len() {
        s.push('…');
    }
    s
}

/// Closes a round: the outcome, the feedback for the assigner, whether the goal holds.
fn finish(
    env: &(dyn Environment + Send),
    mut round: Round,
    outcome: Outcome,
    start: Instant,
) -> Round {
    round.feedback = feedback(env, &round, &outcome);
    round.outcome = outcome;
    round.done = env.goal_satisfied();
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    round
}

/// What the assigner hears about a round: self-reflection built from the executor's
/// answer and the checked outcome.
fn feedback(env: &(dyn Environment + Send), round: &Round, outcome: &Outcome) -> String {
    let task = env.task();
    let robot = round
        .proposal
        .as_ref()
        .map(|p| joint::label(task, p.robot))
        .unwrap_or_default();
    let action = round
        .decision
        .as_ref()
        .and_then(|d| d.action.clone())
        .unwrap_or_default();
    let can_do_now = || {
        if round.actions.is_empty() {
            format!("{robot} can do nothing now.")
        } else {
            format!("{robot} can do now: {}.", round.actions.join("; "))
        }
    };
    match outcome {
        Outcome::Executed => {
            let done = round.decision.as_ref().is_some_and(|d| d.subtask_complete);
            let note = round
                .decision
                .as_ref()
                .map(|d| d.note.trim().to_owned())
                .unwrap_or_default();
            if done {
                format!("{robot} did {action}. The subtask is complete.")
            } else if note.is_empty() {
                format!("{robot} did {action}. The subtask is not complete yet.")
            } else {
                format!("{robot} did {action}. The subtask is not complete yet: {note}")
            }
        }
        Outcome::Infeasible { message, .. } => {
            format!(
                "{robot} tried {action}, which cannot be done: {message}. {}",
                can_do_now()
            )
        }
        Outcome::Declined => {
            let note = round
                .decision
                .as_ref()
                .map(|d| d.note.trim().to_owned())
                .filter(|n| !n.is_empty())
                .unwrap_or_else(|| "no reason given".into());
            format!(
                "{robot} cannot do this subtask now ({note}). {}",
                can_do_now()
            )
        }
        Outcome::NoProposal { why } => format!(
            "Your answer could not be used ({why}). Name one robot of the team and one subtask."
        ),
        Outcome::NoDecision { why } => {
            format!("{robot} gave no usable answer ({why}). {}", can_do_now())
        }
        Outcome::BackendError { message } => format!("The model could not be reached: {message}"),
    }
}

/// The history line of a round, oldest first in the prompt.
fn history_entry(task: &Task, round: &Round) -> String {
    match &round.proposal {
        Some(p) => format!(
            "Round {}: you asked {} to \"{}\". {}",
            round.step,
            joint::label(task, p.robot),
            p.subtask,
            round.feedback
        ),
        None => format!("Round {}: {}", round.step, round.feedback),
    }
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

/// Every robot's observation, merged, as facts.
pub(crate) fn team_observation(env: &(dyn Environment + Send), task: &Task) -> String {
    let observations: Vec<_> = task
        .robots
        .iter()
        .filter_map(|r| env.observe(task.id(r.node)).ok())
        .collect();
    let refs: Vec<_> = observations.iter().collect();
    describe::facts(task, env.state(), &refs)
}
