//! PEFA, the paper's loop: Proposal (the [`TaskAssigner`] gives one robot one subtask),
//! Execution (that robot's [`RobotExecutor`] picks one action from its list; the action
//! is checked and run through the [`Environment`]), Feedback (what ran and whether the
//! subtask is done, or why not, with the robot's actions and, for a declined subtask,
//! the engine's reason for each thing it names: [`feedback::pefa`]),
//! Adjustment (the feedback joins the [`History`] the assigner sees next round). One
//! round is one step; two model calls per round.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, Task};

use crate::backends::llm::Backend;
use crate::episode::ask::{Side, ask};
use crate::episode::environment::execute;
use crate::episode::rounds::{HISTORY_WINDOW, History, rounds};
use crate::methods::assigner::TaskAssigner;
use crate::methods::executor::RobotExecutor;
use crate::methods::feedback;
use crate::methods::templates::Prompts;
use crate::records::transcript::{Round, RoundOutcome};

/// The shared loop's types, where PEFA's callers have always found them.
pub use crate::episode::cancel::Cancel;
pub use crate::episode::rounds::Episode;

/// Settings of one PEFA episode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PefaConfig {
    /// Rounds of history the assigner sees ([`HISTORY_WINDOW`]; 0 is "w/o history").
    pub history: usize,
    /// Steps before the episode stops as a failure (2 x GT by the paper's rule).
    pub max_steps: u32,
    pub assigner_max_tokens: u32,
    pub executor_max_tokens: u32,
    /// The roles' templates come from here.
    pub prompts: Prompts,
}

impl PefaConfig {
    pub fn new(max_steps: u32) -> PefaConfig {
        PefaConfig {
            history: HISTORY_WINDOW,
            max_steps,
            assigner_max_tokens: 400,
            executor_max_tokens: 200,
            prompts: Prompts::builtin(),
        }
    }
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
    let mut history = History::new(config.history);
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let r = round(env, task, backend, config, cancel, &history.entries(), step).await;
        // Adjustment: the round joins the history the assigner sees next.
        if let Some(r) = &r {
            history.push(feedback::assigner_history(task, r));
        }
        Ok(r)
    };
    rounds(env, task, config.max_steps, cancel, on_round, play).await
}

/// One round; `None` when cancelled during it (nothing of it is kept).
async fn round(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &PefaConfig,
    cancel: &Cancel,
    history: &[String],
    step: u32,
) -> Option<Round> {
    let start = Instant::now();
    let mut round = Round::new(step);

    // Proposal.
    let assigner = TaskAssigner::new(task, &config.prompts, config.assigner_max_tokens);
    let query = assigner.query(env, history);
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    let proposal = match reply.and_then(|r| r.read(|text| assigner.parse(text))) {
        Ok(p) => p,
        Err(e) => return Some(finish(env, round, e.outcome(Side::Assigner), start)),
    };
    round.proposal = Some(proposal.clone());

    // Execution.
    let robot = proposal.robot;
    let executor = match RobotExecutor::of(task, robot, &config.prompts, config.executor_max_tokens)
    {
        Ok(executor) => executor,
        Err(e) => {
            let why = e.to_string();
            return Some(finish(env, round, RoundOutcome::NoProposal { why }, start));
        }
    };
    round.actions = executor.actions(env);
    let query = executor.query(env, &proposal.subtask, &round.actions);
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    let decision = match reply.and_then(|r| r.read(|text| executor.parse(&round.actions, text))) {
        Ok(d) => d,
        Err(e) => return Some(finish(env, round, e.outcome(Side::Executor), start)),
    };
    round.decision = Some(decision.clone());
    let outcome = match &decision.action {
        Some(action) if decision.can_do => execute(env, &mut round, robot, action),
        _ => RoundOutcome::Declined,
    };
    Some(finish(env, round, outcome, start))
}

/// Closes a round: the outcome, the Feedback for the assigner, whether the goal holds.
fn finish(
    env: &(dyn Environment + Send),
    mut round: Round,
    outcome: RoundOutcome,
    start: Instant,
) -> Round {
    round.feedback = feedback::pefa(env.task(), env.state(), &round, &outcome);
    round.outcome = outcome;
    round.done = env.goal_satisfied();
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    round
}
