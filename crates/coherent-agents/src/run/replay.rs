//! Setting up the replay of a recorded episode: the task, the settings and the budget
//! it ran with, a backend that answers from the recording (for a method written outside
//! the crate, a policy that gives the recorded decisions back, so that no Python is
//! needed), and afterwards the check that the replay did exactly what the recording did.
//! `coherent run --replay`, the Python `replay` and `coherent bench --backend replay` all
//! start here.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;

use coherent_core::planner::Limits;
use coherent_core::{Execution, Task, native};

use crate::backends::replay::ReplayBackend;
use crate::episode::budget::Budget;
use crate::episode::play::Episode;
use crate::episode::policy::{Act, Choice, MethodFailure, Policy, StepView};
use crate::error::Error;
use crate::llm::BoxFuture;
use crate::prompts::templates::Prompts;
use crate::records::transcript::{Call, RobotPart, Round, RoundOutcome, Summary, Transcript};
use crate::run::settings::{Builtin, External, MethodSpec, Settings};

/// What replaying a recorded episode needs: run `settings.method` on `task` with
/// `backend` and `budget`, then look for a [`Replay::difference`] from the recording.
#[derive(Debug)]
pub struct Replay {
    /// The task recorded in the transcript's header.
    pub task: Arc<Task>,
    /// The recorded method, history window, temperature, seed, physics, robots and
    /// prompt set.
    pub settings: Settings,
    /// The recorded budget, as given.
    pub budget: Budget,
    /// Answers every call from the recording, after checking that it is the recorded one.
    pub backend: Arc<ReplayBackend>,
    recording: Transcript,
}

impl Replay {
    /// The replay of `transcript`, read from `file` (which errors name).
    pub fn prepare(transcript: &Transcript, file: &Path) -> Result<Replay, Error> {
        let task = recorded_task(transcript, file)?;
        let (settings, budget) = recorded_settings(transcript)?;
        Ok(Replay {
            task: Arc::new(task),
            settings,
            budget,
            backend: Arc::new(ReplayBackend::new(transcript)),
            recording: transcript.clone(),
        })
    }

    /// Where `replayed` first differs from what the recording did, if it does (see
    /// [`difference`]).
    pub fn difference(&self, replayed: &Episode) -> Option<String> {
        difference(&self.recording, replayed)
    }
}

/// The settings and budget a transcript was recorded with, to replay it: the prompt set
/// is the recorded one (or an error when this version cannot render it again; the
/// paper's layout for a transcript from before prompt sets), and a
/// method written outside the crate replays its recorded decisions.
pub fn recorded_settings(t: &Transcript) -> Result<(Settings, Budget), Error> {
    let name = &t.header.method;
    let method = if t.header.external {
        let rounds: Arc<[Round]> = t.rounds.clone().into();
        let make = move |_: &Arc<Task>| -> Result<Box<dyn Policy>, MethodFailure> {
            Ok(Box::new(RecordedDecisions {
                rounds: rounds.iter().cloned().collect(),
            }))
        };
        MethodSpec::External(External::new(name, Arc::new(make))?)
    } else {
        Builtin::from_name(name)
            .ok_or_else(|| Error::Invalid(format!("unknown method {name:?} in the transcript")))?
            .into()
    };
    // A transcript without a record was written before prompt sets, when the paper's
    // layout was built in.
    let prompts = match &t.header.prompts {
        Some(record) => Prompts::from_record(record, t.header.execution)?,
        None => Prompts::paper_layout(),
    };
    let settings = Settings {
        method,
        execution: t.header.execution,
        history: t.header.history,
        temperature: t.header.temperature,
        seed: t.header.seed,
        physics: t.header.physics,
        robots: t.header.robots.clone(),
        prompts,
        max_states: t.header.max_states.unwrap_or(Limits::DEFAULT_MAX_STATES),
    };
    Ok((settings, Budget::Given(t.header.max_steps)))
}

/// The task a transcript was recorded on.
pub fn recorded_task(t: &Transcript, file: &Path) -> Result<Task, Error> {
    Ok(native::read(&file.display().to_string(), &t.header.task)?)
}

/// Where `replayed` first differs from what `recorded` did, if it does: a replay must
/// give the same rounds (calls, answers, decisions, outcomes, feedback) apart from
/// wall-clock time, and the same summary.
pub fn difference(recorded: &Transcript, replayed: &Episode) -> Option<String> {
    // What robots outside the process said is theirs, not the replay's to reproduce; a
    // call's shared prefix follows from the prompts compared (and transcripts written
    // before it was kept have none); simulated seconds count when the recording kept
    // them.
    let kept_sim = recorded.rounds.iter().any(|r| r.sim_seconds.is_some());
    let strip = |r: &Round| Round {
        wall_ms: 0.0,
        robot: None,
        sim_seconds: r.sim_seconds.filter(|_| kept_sim),
        parts: r
            .parts
            .iter()
            .map(|p| RobotPart {
                report: None,
                ..p.clone()
            })
            .collect(),
        calls: r
            .calls
            .iter()
            .map(|c| Call {
                shared_prefix: None,
                ..c.clone()
            })
            .collect(),
        ..r.clone()
    };
    if recorded.rounds.len() != replayed.rounds.len() {
        return Some(format!(
            "the recording has {} rounds, the replay {}",
            recorded.rounds.len(),
            replayed.rounds.len()
        ));
    }
    if let Some(a) = recorded
        .rounds
        .iter()
        .zip(&replayed.rounds)
        .find_map(|(a, b)| (strip(a) != strip(b)).then_some(a))
    {
        return Some(format!("round {} differs from the recording", a.step));
    }
    // Simulated seconds count when the recording kept them (it did not before they were).
    let timeless = |s: &Summary, sim: Option<f64>| Summary {
        wall_ms: 0.0,
        sim_seconds: sim.and(s.sim_seconds),
        ..s.clone()
    };
    match &recorded.summary {
        Some(s) if timeless(s, s.sim_seconds) != timeless(&replayed.summary, s.sim_seconds) => {
            Some("the summary differs from the recording".into())
        }
        _ => None,
    }
}

/// The decisions recorded in the rounds of a method written outside the crate, given
/// back one step at a time with the calls the method made then.
struct RecordedDecisions {
    rounds: VecDeque<Round>,
}

impl Policy for RecordedDecisions {
    fn act(&mut self, view: Arc<StepView>) -> BoxFuture<'_, Act> {
        let act = match self.rounds.pop_front() {
            None => Act {
                choices: Err(MethodFailure(format!(
                    "replay diverged: step {} is not in the recording",
                    view.step
                ))),
                calls: Vec::new(),
            },
            Some(round) => Act {
                choices: recorded_choices(&round, view.execution),
                calls: round.calls,
            },
        };
        Box::pin(async move { act })
    }
}

/// What the method gave in `round`: its decision, or in a parallel round each part's and
/// the round's own (what decisions naming no robot reported); the method's error when it
/// raised one.
fn recorded_choices(round: &Round, execution: Execution) -> Result<Vec<Choice>, MethodFailure> {
    if let RoundOutcome::MethodError { message } = &round.outcome {
        return Err(MethodFailure(message.clone()));
    }
    let parts = round.parts.iter().filter_map(|p| p.external.clone());
    let choices: Vec<Choice> = parts.chain(round.external.clone()).collect();
    if choices.is_empty() && execution == Execution::Sequential {
        return Err(MethodFailure(format!(
            "replay diverged: round {} of the recording holds no decision",
            round.step
        )));
    }
    Ok(choices)
}
