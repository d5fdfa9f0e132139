//! CMRS, the paper's centralised baseline (docs/methods.md, `cmrs`): each step one model
//! sees every robot's observation, the union of all robots' action lists and the last
//! executed actions, and answers one `<robot>: <action>` line, which is checked and run.
//! One model call per step.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, Task};

use crate::backends::llm::{Backend, Query, Role, Situation};
use crate::episode::ask::{Side, ask};
use crate::episode::cancel::Cancel;
use crate::episode::environment::team_sight;
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::joint::joint_actions;
use crate::methods::templates::Prompts;
use crate::methods::{central, decision, feedback};
use crate::records::transcript::Round;

/// Most tokens of one answer (a line and a little reasoning).
const MAX_TOKENS: u32 = 200;

/// Settings of a CMRS episode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CmrsConfig {
    /// Executed actions shown (the paper: 5).
    pub history: usize,
    /// The central template (`central.txt`) comes from here.
    pub prompts: Prompts,
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
        let r = round(
            env,
            task,
            backend,
            prompts,
            cancel,
            &history.entries(),
            step,
        )
        .await;
        if let Some(line) = r.as_ref().and_then(decision::executed_line) {
            history.push(line);
        }
        Ok(r)
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}

async fn round(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    backend: &dyn Backend,
    prompts: &Prompts,
    cancel: &Cancel,
    history: &[String],
    step: u32,
) -> Option<Round> {
    let start = Instant::now();
    let lines: Vec<String> = joint_actions(task, env.state())
        .iter()
        .map(|a| a.line(task))
        .collect();
    let mut round = Round::new(step);
    round.actions = lines.clone();
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
            round.feedback = feedback::joint("", &round.outcome);
        }
    }
    round.done = env.goal_satisfied();
    round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    Some(round)
}
