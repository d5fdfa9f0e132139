//! The one loop every method runs under ([`play`]): one round per step until the goal
//! holds, the budget is spent, the backend fails for good, the method fails or the
//! episode is cancelled; then the summary. Each round the method decides
//! ([`Method::decide`]), the loop carries out what it decided (one robot's action, or in a
//! parallel episode a joint step of several), the method concludes the round
//! ([`Method::conclude`]), and the history window keeps what the method recalls of it
//! ([`Method::recall`], [`History`]). A new execution, or anything that happens to every
//! method alike, is a change to this loop, not to the methods.

use std::collections::VecDeque;
use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, Execution, Task};

use crate::episode::cancel::Cancel;
use crate::episode::environment::execute;
use crate::episode::events::{self, Dynamics};
use crate::episode::joint;
use crate::episode::method::{Closing, Decided, Method, Turn};
use crate::episode::prefix::LastPrompts;
use crate::llm::Backend;
use crate::records::transcript::{Reason, Round, RoundOutcome, Status, Summary};

/// An episode as it ran.
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    pub rounds: Vec<Round>,
    pub summary: Summary,
}

/// How an episode's rounds go: how its robots step, its step budget, and how many entries
/// of the method's history its prompts recall.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Course {
    pub execution: Execution,
    pub max_steps: u32,
    /// The history window ([`HISTORY_WINDOW`]; 0 is the paper's "w/o history").
    pub history: usize,
    /// The most states one search of the loop's own may visit: the optimum proven
    /// again at each event of the task (docs/dynamic.md).
    pub max_states: usize,
    /// The seed of the task's failing actions (the episode's seed, 0 when unset).
    pub seed: u64,
}

/// Runs `method` on `env` round by round until the goal holds, the budget is spent, a
/// round ends in a backend failure or the method's error, or `cancel` fires (a method
/// cancelled during a round gives `None`, and nothing of the round is kept); then the
/// summary. Each call of a round gets its shared prefix with the previous call of its
/// role and robot ([`crate::episode::prefix`]). `on_round` sees each round as it ends
/// (the transcript writer, progress lines); its error stops the episode, so that no
/// round goes unrecorded.
pub async fn play(
    env: &mut (dyn Environment + Send + Sync),
    task: &Arc<Task>,
    method: &mut dyn Method,
    backend: &dyn Backend,
    course: Course,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let start = Instant::now();
    let mut rounds: Vec<Round> = Vec::new();
    let mut history = History::new(course.history);
    let mut prompts = LastPrompts::default();
    let mut dynamics = Dynamics::new(task, course.execution, course.max_states, course.seed);
    let mut world = Arc::clone(task);
    if let Some(d) = &mut dynamics {
        world = d.start(env).await?;
    }
    let mut closing = Vec::new();
    let mut status = if env.goal_satisfied() {
        Status::Success
    } else {
        Status::Failure
    };
    let mut error = None;
    while status == Status::Failure && rounds.len() < course.max_steps as usize {
        if cancel.is_cancelled() {
            status = Status::Interrupted;
            break;
        }
        let began = Instant::now();
        let mut round = Round::new(rounds.len() as u32 + 1);
        if let Some(d) = &mut dynamics
            && let Some(ended) = meet_events(d, env, &mut round, &mut world).await?
        {
            (status, error) = ended;
            closing = std::mem::take(&mut round.events);
            break;
        }
        let news = events::news(&round.events);
        let recalled = history.entries();
        let turn = Turn {
            task: &world,
            env: &*env,
            backend,
            cancel,
            step: round.step,
            max_steps: course.max_steps,
            execution: course.execution,
            history: &recalled,
            rounds: &rounds,
            news: &news,
        };
        let Some(decided) = method.decide(turn, &mut round).await? else {
            status = Status::Interrupted;
            break;
        };
        let sim_before = env.sim_seconds();
        round.outcome = match decided {
            Decided::CarryOut => {
                carry_out(env, &world, course.execution, dynamics.as_ref(), &mut round)
            }
            Decided::Ends(outcome) => outcome,
        };
        round.sim_seconds = env.sim_seconds().zip(sim_before).map(|(t, t0)| t - t0);
        let closed = Closing {
            task: &world,
            state: env.state(),
            execution: course.execution,
        };
        method.conclude(closed, &mut round);
        round.done = env.goal_satisfied();
        round.wall_ms = began.elapsed().as_secs_f64() * 1e3;
        prompts.mark(&mut round.calls);
        on_round(&round)?;
        if let Some(line) = method.recall(&world, &round) {
            history.push(line);
        }
        if let Some(d) = &mut dynamics {
            d.after(&round, &*env, &world).await?;
        }
        let conceded = dynamics.as_ref().and_then(Dynamics::unreachable).is_some()
            && round.actions_executed() == 0;
        match &round.outcome {
            RoundOutcome::BackendError { message } => {
                status = Status::BackendError;
                error = Some(message.clone());
            }
            RoundOutcome::MethodError { message } => {
                status = Status::Error;
                error = Some(message.clone());
            }
            _ if round.done => status = Status::Success,
            // The goal is out of reach, and the team stopped acting: right.
            _ if conceded => status = Status::Conceded,
            _ => {
                // An environment that can go on no longer (a robot that stopped
                // answering) ends the episode, saying why.
                if let Some(why) = env.stopped() {
                    status = Status::Interrupted;
                    error = Some(why);
                }
            }
        }
        rounds.push(round);
    }
    let answers = rounds
        .iter()
        .flat_map(|r| &r.calls)
        .filter_map(|c| c.answer.as_ref());
    let (prompt_tokens, completion_tokens, cached_tokens) =
        answers.fold((0, 0, 0), |(p, c, k), a| {
            (
                p + a.usage.prompt_tokens,
                c + a.usage.completion_tokens,
                k + a.usage.cached_tokens,
            )
        });
    // What a method written outside the crate reported of its own clients' calls (in a
    // parallel round, with each robot's part).
    let reported = rounds.iter().flat_map(|r| {
        let parts = r.parts.iter().filter_map(|p| p.external.as_ref());
        r.external.iter().chain(parts)
    });
    let (prompt_tokens, completion_tokens, reported_calls) = reported
        .fold((prompt_tokens, completion_tokens, 0), |(p, c, n), e| {
            (p + e.prompt_tokens, c + e.completion_tokens, n + e.calls)
        });
    let reference = dynamics.as_ref().map(|d| Box::new(d.reference(closing)));
    let summary = Summary {
        status,
        success: matches!(status, Status::Success | Status::Conceded),
        steps: rounds.len() as u32,
        gt_steps: task.meta.gt_steps,
        max_steps: course.max_steps,
        llm_calls: rounds.iter().map(|r| r.calls.len() as u32).sum::<u32>() + reported_calls,
        prompt_tokens,
        completion_tokens,
        cached_tokens,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        error,
        sim_seconds: env.sim_seconds(),
        reference,
    };
    Ok(Episode { rounds, summary })
}

/// Carries out the events due before `round` on `env` (the task as they leave it in
/// `world`), kept in the round; how the episode ends there, if it does: interrupted when
/// the world could not carry them out (robots over ROS 2: nobody is asked anything
/// more), a success when they themselves left the goal holding (nothing is left to do).
async fn meet_events(
    dynamics: &mut Dynamics,
    env: &mut (dyn Environment + Send + Sync),
    round: &mut Round,
    world: &mut Arc<Task>,
) -> io::Result<Option<(Status, Option<String>)>> {
    round.events = dynamics.before(round.step, env, world).await?;
    Ok(if let Some(why) = env.stopped() {
        Some((Status::Interrupted, Some(why)))
    } else if env.goal_satisfied() {
        Some((Status::Success, None))
    } else {
        None
    })
}

/// Carries out what a round decided: a sequential round's decision (its robot's action,
/// when it can do and names one; a robot that is not in the team is refused as such), or
/// a parallel round's parts as one joint step ([`joint::carry_out`]); an action that a
/// failing-actions event makes fail does not run. Returns the round's outcome.
fn carry_out(
    env: &mut (dyn Environment + Send + Sync),
    task: &Task,
    execution: Execution,
    dynamics: Option<&Dynamics>,
    round: &mut Round,
) -> RoundOutcome {
    let step = round.step;
    let fails = |robot| dynamics.and_then(|d| d.fails(task, step, robot));
    if execution == Execution::Parallel {
        return joint::carry_out(env, task, &mut round.parts, &fails);
    }
    let act = round
        .decision
        .as_ref()
        .filter(|d| d.can_do)
        .and_then(|d| Some((d.robot?, d.action.clone()?)));
    match act {
        None => RoundOutcome::Declined,
        Some((robot, action)) => match task.robot_by_id(robot) {
            Ok(_) => match fails(robot) {
                Some(message) => RoundOutcome::Infeasible {
                    reason: Reason::ActionFailed,
                    message,
                },
                None => execute(env, round, robot, &action),
            },
            Err(e) => RoundOutcome::Infeasible {
                reason: Reason::UnknownRobot,
                message: e.to_string(),
            },
        },
    }
}

/// Rounds of history the methods' prompts recall unless told otherwise: the paper's 5,
/// for PEFA's task assigner and the baselines alike (`pefa-no-history` is 0).
pub const HISTORY_WINDOW: usize = 5;

/// The last entries of a method's history, oldest first, at most `keep` of them (none
/// when `keep` is 0, the paper's "w/o history").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct History<T> {
    entries: VecDeque<T>,
    keep: usize,
}

impl<T: Clone> History<T> {
    /// A history that keeps the last `keep` entries.
    pub fn new(keep: usize) -> History<T> {
        History {
            entries: VecDeque::new(),
            keep,
        }
    }

    /// A history that keeps every entry (what a method written outside the crate is
    /// shown: it picks its own window).
    pub fn whole() -> History<T> {
        History::new(usize::MAX)
    }

    /// Adds the newest entry, forgetting the oldest beyond the window.
    pub fn push(&mut self, entry: T) {
        if self.keep == 0 {
            return;
        }
        self.entries.push_back(entry);
        while self.entries.len() > self.keep {
            self.entries.pop_front();
        }
    }

    /// The entries kept, oldest first.
    pub fn entries(&self) -> Vec<T> {
        self.entries.iter().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_keeps_the_newest_entries_and_zero_keeps_none() {
        let mut h = History::new(2);
        for i in 1..=3 {
            h.push(i);
        }
        assert_eq!(h.entries(), [2, 3]);
        let mut none = History::new(0);
        none.push(1);
        assert!(none.entries().is_empty());
        let mut whole = History::whole();
        for i in 0..100 {
            whole.push(i);
        }
        assert_eq!(whole.entries().len(), 100);
    }
}
