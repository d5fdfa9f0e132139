//! CMRS, the paper's centralised baseline (docs/methods.md, `cmrs`): each step one model
//! sees every robot's observation, the union of all robots' action lists and the last
//! executed actions, and answers one `<robot>: <action>` line, which is checked and run.
//! In a parallel episode it answers a list of lines, at most one per robot, carried out
//! together as the step's joint step. One model call per step.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, Task};

use crate::backends::llm::{Backend, Query, Role, Situation};
use crate::episode::ask::{Side, ask};
use crate::episode::cancel::Cancel;
use crate::episode::environment::team_sight;
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::team_actions;
use crate::methods::templates::Prompts;
use crate::methods::{central, decision, feedback};
use crate::records::transcript::{Execution, Round};

/// Most tokens of one answer (a line and a little reasoning).
const MAX_TOKENS: u32 = 200;

/// Settings of a CMRS episode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CmrsConfig {
    /// Executed actions shown (the paper: 5); in a parallel episode, executed steps.
    pub history: usize,
    /// The central template (`central.txt`; `central_parallel.txt` in joint steps) comes
    /// from here.
    pub prompts: Prompts,
    /// One robot's action a step, or joint steps.
    pub execution: Execution,
}

/// Runs CMRS on `env` until the goal holds, `max_steps` are spent, the backend fails for
/// good, or `cancel` fires.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    config: &CmrsConfig,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let mut history = History::new(config.history);
    let prompts = &config.prompts;
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let past = history.entries();
        let r = round(
            env,
            task,
            backend,
            prompts,
            config.execution,
            cancel,
            &past,
            step,
        )
        .await;
        if let Some(line) = r.as_ref().and_then(|r| decision::executed_line(task, r)) {
            history.push(line);
        }
        Ok(r)
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}

#[allow(clippy::too_many_arguments)]
async fn round(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    prompts: &Prompts,
    execution: Execution,
    cancel: &Cancel,
    history: &[String],
    step: u32,
) -> Option<Round> {
    let start = Instant::now();
    let lines: Vec<String> = team_actions::offered(task, env.state())
        .iter()
        .map(|a| a.line(task))
        .collect();
    let mut round = Round::new(step);
    round.actions = lines.clone();
    if execution == Execution::Parallel {
        return parallel(env, task, backend, prompts, cancel, history, round, start).await;
    }
    let query = Query {
        role: Role::Assigner,
        robot: None,
        messages: central::messages(prompts, &team_sight(env, task), &lines, history),
        schema_name: "joint_action",
        schema: central::schema(&lines),
        max_tokens: MAX_TOKENS,
        situation: Situation::now(task, env, None),
    };
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    let chosen = reply.and_then(|r| r.read(|text| central::choose(task, &lines, text)));
    match chosen {
        Ok((robot, action)) => decision::act(env, task, &mut round, robot, &action, String::new()),
        Err(e) => {
            round.outcome = e.outcome(Side::Executor);
            round.feedback = feedback::team("", &round.outcome);
        }
    }
    round.done = env.goal_satisfied();
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    Some(round)
}

/// A round of a parallel episode: the central model chooses at most one line per robot,
/// carried out together.
#[allow(clippy::too_many_arguments)]
async fn parallel(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    prompts: &Prompts,
    cancel: &Cancel,
    history: &[String],
    mut round: Round,
    start: Instant,
) -> Option<Round> {
    let lines = round.actions.clone();
    let query = Query {
        role: Role::Assigner,
        robot: None,
        messages: central::messages_parallel(prompts, &team_sight(env, task), &lines, history),
        schema_name: "joint_step",
        schema: central::schema_parallel(&lines),
        max_tokens: MAX_TOKENS,
        situation: Situation::now(task, env, None),
    };
    let reply = ask(backend, query, cancel, &mut round.calls).await?;
    match reply.and_then(|r| r.read(|text| central::choose_several(task, &lines, text))) {
        Ok((chosen, unused)) => {
            let parts = chosen
                .iter()
                .map(|(robot, action)| decision::part(env, *robot, action, String::new()))
                .collect();
            let note = (!unused.is_empty())
                .then(|| format!("Part of the answer was not used: {}.", unused.join("; ")));
            decision::act_jointly(env, task, &mut round, parts, note);
        }
        Err(e) => {
            round.outcome = e.outcome(Side::Executor);
            round.feedback = feedback::team("", &round.outcome);
            round.done = env.goal_satisfied();
        }
    }
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    Some(round)
}
