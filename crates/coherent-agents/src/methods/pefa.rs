//! PEFA, the paper's loop: Proposal (the [`TaskAssigner`] gives one robot one subtask),
//! Execution (that robot's [`RobotExecutor`] picks one action from its list; the loop
//! checks and runs it), Feedback (what ran and whether the subtask is done, or why not,
//! with the robot's actions and, for a declined subtask, the engine's reason for each
//! thing it names: [`feedback::pefa`]), Adjustment (the feedback joins the history the
//! assigner sees next round: [`feedback::assigner_history`]). One round is one step; two
//! model calls per round.
//!
//! In joint steps (`--execution parallel`) the robots act at the same time. Proposal:
//! when some robot is idle, the assigner gives subtasks to any of the idle robots in one
//! answer (a list); a robot that has a subtask keeps it. Execution: every robot with a
//! subtask has its executor asked at once, each seeing its own observation and action
//! list in the state before the step, and the loop carries the actions they pick out
//! together as one joint step (`coherent_core::joint`: refused as a whole when two of
//! them interfere). Feedback: each robot's own ([`feedback::pefa_part`]). A robot keeps
//! its subtask across steps until its executor reports it complete, or it fails (its
//! action refused, no action, no usable answer); it is then idle, and the assigner is
//! asked again. A round makes one call per robot with a subtask, plus the assigner's
//! when it is asked.

use std::collections::BTreeMap;

use coherent_core::{Execution, NodeId, State, Task};

use crate::episode::ask::{Side, Unusable, ask, ask_all};
use crate::episode::joint;
use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::methods::assigner::TaskAssigner;
use crate::methods::executor::RobotExecutor;
use crate::methods::feedback;
use crate::prompts::fill::robot_label;
use crate::prompts::templates::Prompts;
use crate::records::transcript::{Proposal, Reason, RobotPart, Round, RoundOutcome};

/// Most tokens of the assigner's answer (its reasoning, a robot and a subtask).
const ASSIGNER_MAX_TOKENS: u32 = 400;
/// Most tokens of an executor's answer.
const EXECUTOR_MAX_TOKENS: u32 = 200;

/// The subtasks robots keep from earlier rounds of a parallel episode, with the round
/// each was given in.
type Busy = BTreeMap<NodeId, (Proposal, u32)>;

/// PEFA for one episode: its prompt set, and in a parallel episode the subtasks in
/// progress and what the assigner is told of its own last answer.
#[derive(Debug)]
pub struct Pefa {
    prompts: Prompts,
    busy: Busy,
    /// What the assigner hears of its own answer this round (the part of it not used, or
    /// why none of it could be).
    assigner_note: Option<String>,
    /// The outcome of this round when the assigner's answer could not be used, while the
    /// robots with subtasks still acted.
    unusable: Option<RoundOutcome>,
}

impl Pefa {
    /// PEFA with its roles' templates from `prompts`.
    pub fn new(prompts: Prompts) -> Pefa {
        Pefa {
            prompts,
            busy: Busy::new(),
            assigner_note: None,
            unusable: None,
        }
    }

    /// A sequential round: one proposal, one executor.
    async fn propose_and_execute(&self, turn: Turn<'_>, round: &mut Round) -> Option<Decided> {
        let Turn { task, env, .. } = turn;
        // Proposal.
        let assigner = TaskAssigner::new(task, &self.prompts, ASSIGNER_MAX_TOKENS).told(turn.news);
        let query = assigner.query(env, turn.history);
        let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
        let proposal = match reply.and_then(|r| r.read(|text| assigner.parse(text))) {
            Ok(p) => p,
            Err(e) => return Some(Decided::Ends(e.outcome(Side::Assigner))),
        };
        round.proposal = Some(proposal.clone());

        // Execution: the executor's decision, which the loop checks and runs.
        let executor =
            match RobotExecutor::of(task, proposal.robot, &self.prompts, EXECUTOR_MAX_TOKENS)
                .map(|e| e.told(turn.news))
            {
                Ok(executor) => executor,
                Err(e) => {
                    let why = e.to_string();
                    return Some(Decided::Ends(RoundOutcome::NoProposal { why }));
                }
            };
        round.actions = executor.actions(env);
        let query = executor.query(env, &proposal.subtask, &round.actions);
        let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
        match reply.and_then(|r| r.read(|text| executor.parse(&round.actions, text))) {
            Ok(decision) => {
                round.decision = Some(decision);
                Some(Decided::CarryOut)
            }
            Err(e) => Some(Decided::Ends(e.outcome(Side::Executor))),
        }
    }

    /// A parallel round: the assigner when a robot is idle, then every robot with a
    /// subtask, its executor asked beside the others'.
    async fn assign_and_execute(&mut self, turn: Turn<'_>, round: &mut Round) -> Option<Decided> {
        let Turn { task, env, .. } = turn;
        let team: Vec<NodeId> = task.robots.iter().map(|r| task.id(r.node)).collect();
        // A robot out of the team (an event took it down) keeps no subtask.
        self.busy.retain(|r, _| team.contains(r));
        let idle: Vec<NodeId> = team
            .iter()
            .copied()
            .filter(|r| !self.busy.contains_key(r))
            .collect();
        self.assigner_note = None;
        self.unusable = None;

        // Proposal, when a robot is idle.
        if !idle.is_empty() {
            let assigner =
                TaskAssigner::new(task, &self.prompts, ASSIGNER_MAX_TOKENS).told(turn.news);
            let kept: Vec<(NodeId, String, u32)> = self
                .busy
                .iter()
                .map(|(r, (p, since))| (*r, p.subtask.clone(), *since))
                .collect();
            let query = assigner.query_parallel(env, turn.history, &kept, &idle);
            let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
            match reply.and_then(|r| r.read(|text| assigner.parse_parallel(text, &idle))) {
                Ok(answer) => {
                    if !answer.unused.is_empty() {
                        self.assigner_note = Some(format!(
                            "Part of your answer was not used: {}.",
                            answer.unused.join("; ")
                        ));
                    }
                    for p in answer.proposals {
                        self.busy.insert(p.robot, (p, round.step));
                    }
                }
                Err(Unusable::Failed(e)) => {
                    let outcome = Unusable::Failed(e).outcome(Side::Assigner);
                    return Some(Decided::Ends(outcome));
                }
                Err(bad) => {
                    let outcome = bad.outcome(Side::Assigner);
                    self.assigner_note = Some(unusable_note(&outcome));
                    self.unusable = Some(outcome);
                }
            }
        }

        // Execution: every robot with a subtask.
        let mut executors = Vec::new();
        let mut queries = Vec::new();
        for (robot, (proposal, since)) in team.iter().filter_map(|r| Some((*r, self.busy.get(r)?)))
        {
            let mut part = RobotPart::new(robot);
            part.proposal = Some(proposal.clone());
            part.kept = *since < round.step;
            match RobotExecutor::of(task, robot, &self.prompts, EXECUTOR_MAX_TOKENS)
                .map(|e| e.told(turn.news))
            {
                Ok(executor) => {
                    part.actions = executor.actions(env);
                    queries.push(executor.query(env, &proposal.subtask, &part.actions));
                    executors.push((round.parts.len(), executor));
                }
                Err(e) => part.outcome = RoundOutcome::NoProposal { why: e.to_string() },
            }
            round.parts.push(part);
        }
        let replies = ask_all(turn.backend, queries, turn.cancel).await?;
        let mut failed = None;
        for ((i, executor), (calls, reply)) in executors.into_iter().zip(replies) {
            round.calls.extend(calls);
            let part = &mut round.parts[i];
            match reply.and_then(|r| r.read(|text| executor.parse(&part.actions, text))) {
                Ok(decision) => part.decision = Some(decision),
                Err(Unusable::Failed(e)) => {
                    part.outcome = Unusable::Failed(e).outcome(Side::Executor);
                    failed.get_or_insert_with(|| part.outcome.clone());
                }
                Err(bad) => part.outcome = bad.outcome(Side::Executor),
            }
        }
        let Some(outcome) = failed else {
            return Some(Decided::CarryOut);
        };
        // The model is gone: no step is carried out, and the episode ends here.
        for part in round.parts.iter_mut().filter(|p| p.decision.is_some()) {
            part.outcome = RoundOutcome::Infeasible {
                reason: Reason::Engine(coherent_core::Reason::StepRefused),
                message: "not carried out: the model could not be reached".into(),
            };
        }
        Some(Decided::Ends(outcome))
    }

    /// A parallel round's feedback: each robot's own, and who keeps a subtask (unless the
    /// model could not be reached, which ends the episode); what the assigner hears is
    /// its own answer first, then each robot's subtask and what became of it.
    fn conclude_joint(&mut self, task: &Task, state: &State, round: &mut Round) {
        let model_gone = matches!(round.outcome, RoundOutcome::BackendError { .. });
        if !model_gone {
            for part in &mut round.parts {
                part.feedback = feedback::pefa_part(task, state, part);
                let goes_on = part.outcome == RoundOutcome::Executed
                    && !part.decision.as_ref().is_some_and(|d| d.subtask_complete);
                if !goes_on {
                    self.busy.remove(&part.robot);
                }
            }
            if let Some(outcome) = self.unusable.take() {
                round.outcome = outcome;
            }
        }
        let heard: Vec<RobotPart> = round
            .parts
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
        let step = if model_gone {
            Some(feedback::team("", &round.outcome))
        } else {
            self.assigner_note.take()
        };
        round.feedback = joint::paragraph(step, &heard);
    }
}

impl Method for Pefa {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            Ok(match turn.execution {
                Execution::Sequential => self.propose_and_execute(turn, round).await,
                Execution::Parallel => self.assign_and_execute(turn, round).await,
            })
        })
    }

    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        let Closing {
            task,
            state,
            execution,
        } = closing;
        match execution {
            Execution::Sequential => {
                let outcome = round.outcome.clone();
                round.feedback = feedback::pefa(task, state, round, &outcome);
            }
            Execution::Parallel => self.conclude_joint(task, state, round),
        }
    }

    fn recall(&self, task: &Task, round: &Round) -> Option<String> {
        Some(feedback::assigner_history(task, round))
    }
}

/// What the assigner hears of an answer that could not be used.
fn unusable_note(outcome: &RoundOutcome) -> String {
    match outcome {
        RoundOutcome::NoProposal { why } => format!(
            "Your answer could not be used ({why}). Name idle robots of the team and a subtask for each."
        ),
        other => feedback::team("", other),
    }
}
