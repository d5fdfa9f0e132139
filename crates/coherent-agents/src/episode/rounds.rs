//! The round loop every method shares: one round per step until the goal holds, the
//! budget is spent, the backend fails for good or the episode is cancelled; then the
//! summary.

use std::io;
use std::time::Instant;

use coherent_core::{Environment, Task};

use crate::episode::cancel::Cancel;
use crate::records::transcript::{Round, RoundOutcome, Status, Summary};

/// An episode as it ran.
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    pub rounds: Vec<Round>,
    pub summary: Summary,
}

/// The loop every method shares: `play` one round per step until the goal holds, the
/// budget is spent, a round ends in a backend failure or the method's error, or `cancel`
/// fires (`play` gives
/// `None` when cancelled during a round); then the summary. `on_round` sees each round
/// as it ends (the transcript writer, progress lines); its error stops the episode, so
/// that no round goes unrecorded.
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
    // What a method written outside the crate reported of its own clients' calls.
    let reported = rounds.iter().filter_map(|r| r.external.as_ref());
    let (prompt_tokens, completion_tokens, reported_calls) = reported
        .fold((prompt_tokens, completion_tokens, 0), |(p, c, n), e| {
            (p + e.prompt_tokens, c + e.completion_tokens, n + e.calls)
        });
    let summary = Summary {
        status,
        success: status == Status::Success,
        steps: rounds.len() as u32,
        gt_steps: task.meta.gt_steps,
        max_steps,
        llm_calls: rounds.iter().map(|r| r.calls.len() as u32).sum::<u32>() + reported_calls,
        prompt_tokens,
        completion_tokens,
        cached_tokens,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        error,
    };
    Ok(Episode { rounds, summary })
}
