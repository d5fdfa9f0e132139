//! Running one episode end to end: the step budget, the transcript file, the method, and
//! checking that a replay reproduced its recording. The CLI, Python and the benchmark
//! harness all go through here.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use coherent_core::planner::{self, Limits};
use coherent_core::{Environment, Task, native};

use crate::dmrs::{self, DmrsConfig};
use crate::llm::{Backend, BackendInfo};
use crate::mcts::{self, MctsConfig};
use crate::pefa::{self, Cancel, Episode, PefaConfig};
use crate::transcript::{self, Header, Record, Round, Summary, Transcript, Writer};
use crate::{cmrs, optimal};

/// A planning method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// COHERENT's loop with the assigner's history window.
    Pefa,
    /// The paper's "w/o history" ablation: the window is 0.
    PefaNoHistory,
    /// One central model choosing one robot's action per step.
    Cmrs,
    /// Decentralised dialogue, one round per step.
    Dmrs1d,
    /// Decentralised dialogue, two rounds per step.
    Dmrs2d,
    /// Primitive MCTS with the authors' settings; no model.
    Mcts,
    /// MCTS with a language-model prior at the root of each step's tree.
    LlmMcts,
    /// The optimal planner's plan: the ground-truth row; no model.
    Optimal,
}

impl Method {
    pub const ALL: [Method; 8] = [
        Method::Pefa,
        Method::PefaNoHistory,
        Method::Cmrs,
        Method::Dmrs1d,
        Method::Dmrs2d,
        Method::Mcts,
        Method::LlmMcts,
        Method::Optimal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Pefa => "pefa",
            Method::PefaNoHistory => "pefa-no-history",
            Method::Cmrs => "cmrs",
            Method::Dmrs1d => "dmrs-1d",
            Method::Dmrs2d => "dmrs-2d",
            Method::Mcts => "mcts",
            Method::LlmMcts => "llm-mcts",
            Method::Optimal => "optimal",
        }
    }

    /// Whether the method asks a model (the backend) at all.
    pub fn uses_model(self) -> bool {
        !matches!(self, Method::Mcts | Method::Optimal)
    }

    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// How an episode is run, as recorded in its transcript's header.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub method: Method,
    /// Rounds of history the assigner sees (ignored by `pefa-no-history`); for the
    /// baselines, the executed actions in their prompts (the paper: 5 for both).
    pub history: usize,
    pub temperature: Option<f32>,
    /// The model's sampling seed; also the MCTS search's and the DMRS speaking order's
    /// (0 when unset).
    pub seed: Option<u64>,
    /// Whether the environment is physical (recorded; the caller builds the environment).
    pub physics: bool,
}

impl Settings {
    pub fn new(method: Method) -> Settings {
        Settings {
            method,
            history: 5,
            temperature: None,
            seed: None,
            physics: false,
        }
    }
}

/// Where a step budget came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// 2 x the task's ground truth, the paper's rule.
    TwiceGroundTruth(u32),
    /// Set by the caller.
    Given(u32),
    /// The task has no ground truth: 2 x the optimum the planner finds.
    TwiceOptimum(u32),
}

impl Budget {
    pub fn steps(self) -> u32 {
        match self {
            Budget::TwiceGroundTruth(n) | Budget::Given(n) | Budget::TwiceOptimum(n) => n,
        }
    }

    /// The budget of `task`: `max_steps` when given, else 2 x GT, else 2 x the optimum.
    pub fn of(task: &Task, max_steps: Option<u32>, limits: &Limits) -> Result<Budget, String> {
        if let Some(n) = max_steps {
            return Ok(Budget::Given(n));
        }
        if let Some(gt) = task.meta.gt_steps {
            return Ok(Budget::TwiceGroundTruth(2 * gt));
        }
        let search = planner::search(task, &task.robots, &task.goal, limits);
        match search.plan {
            Some(plan) => Ok(Budget::TwiceOptimum(2 * plan.len().max(1) as u32)),
            None => Err(
                "the task has no ground truth and the planner finds no plan to size a budget \
                 from: pass a step budget (--max-steps)"
                    .into(),
            ),
        }
    }
}

/// `<out>/<scene>-task<id>-<method>-<UTC time>.jsonl`, with a counter when that exists.
pub fn transcript_path(out: &Path, task: &Task, method: Method) -> PathBuf {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let stem = format!(
        "{}-task{}-{}-{}",
        task.meta.scene.replace(['/', '\\'], "_"),
        task.meta.task_id,
        method.name(),
        utc_stamp(secs)
    );
    let mut path = out.join(format!("{stem}.jsonl"));
    let mut n = 2;
    while path.exists() {
        path = out.join(format!("{stem}-{n}.jsonl"));
        n += 1;
    }
    path
}

/// `YYYYmmddTHHMMSSZ` for Unix seconds (the civil calendar from days, after H. Hinnant's
/// public-domain date algorithms).
fn utc_stamp(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}T{:02}{:02}{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// Runs `method` on `env` with `backend`, writing the transcript to `transcript` (header
/// first, then each round as it ends, then the summary). `progress` sees each round.
/// Returns the episode and the transcript's header, so that a caller holds the whole
/// transcript without reading it back.
#[allow(clippy::too_many_arguments)]
pub async fn run(
    task: &Arc<Task>,
    env: &mut (dyn Environment + Send),
    backend: &dyn Backend,
    settings: &Settings,
    budget: Budget,
    transcript: &Path,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(&Round) + Send),
) -> Result<(Episode, Header), String> {
    let history = match settings.method {
        Method::PefaNoHistory => 0,
        _ => settings.history,
    };
    let backend_info = if settings.method.uses_model() {
        backend.info()
    } else {
        BackendInfo {
            kind: "none".into(),
            model: String::new(),
            base_url: None,
        }
    };
    let header = Header {
        format: transcript::FORMAT.into(),
        version: transcript::VERSION,
        coherent: env!("CARGO_PKG_VERSION").into(),
        task: native::to_value(task),
        task_name: task.meta.name.clone(),
        method: settings.method.name().into(),
        history,
        max_steps: budget.steps(),
        gt_steps: task.meta.gt_steps,
        physics: settings.physics,
        backend: backend_info,
        temperature: settings.temperature,
        seed: settings.seed,
        started_ms: SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64),
    };
    let io = |e: std::io::Error| format!("{}: {e}", transcript.display());
    let mut writer = Writer::create(transcript, header.clone()).map_err(io)?;
    let mut on_round = |r: &Round| {
        progress(r);
        writer.write(&Record::Round(Box::new(r.clone())))
    };
    let mcts = MctsConfig {
        seed: settings.seed.unwrap_or(0),
        history,
        ..MctsConfig::default()
    };
    let steps = budget.steps();
    let episode = match settings.method {
        Method::Pefa | Method::PefaNoHistory => {
            let config = PefaConfig {
                history,
                ..PefaConfig::new(steps)
            };
            pefa::run(env, task, backend, &config, cancel, &mut on_round).await
        }
        Method::Cmrs => cmrs::run(env, task, backend, history, steps, cancel, &mut on_round).await,
        Method::Dmrs1d | Method::Dmrs2d => {
            let config = DmrsConfig {
                dialogue_rounds: if settings.method == Method::Dmrs1d {
                    1
                } else {
                    2
                },
                history,
                seed: settings.seed.unwrap_or(0),
            };
            dmrs::run(env, task, backend, &config, steps, cancel, &mut on_round).await
        }
        Method::Mcts => mcts::run(env, task, None, &mcts, steps, cancel, &mut on_round).await,
        Method::LlmMcts => {
            let model = Some(backend);
            mcts::run(env, task, model, &mcts, steps, cancel, &mut on_round).await
        }
        Method::Optimal => {
            let limits = Limits {
                cancel: Some(cancel.flag()),
                ..Limits::default()
            };
            optimal::run(env, task, &limits, steps, cancel, &mut on_round).await
        }
    }
    .map_err(io)?;
    writer
        .write(&Record::Summary(episode.summary.clone()))
        .map_err(io)?;
    Ok((episode, header))
}

/// The settings and budget a transcript was recorded with, to replay it.
pub fn recorded_settings(t: &Transcript) -> Result<(Settings, Budget), String> {
    let method = Method::from_name(&t.header.method)
        .ok_or_else(|| format!("unknown method {:?} in the transcript", t.header.method))?;
    let settings = Settings {
        method,
        history: t.header.history,
        temperature: t.header.temperature,
        seed: t.header.seed,
        physics: t.header.physics,
    };
    Ok((settings, Budget::Given(t.header.max_steps)))
}

/// The task a transcript was recorded on.
pub fn recorded_task(t: &Transcript, file: &Path) -> Result<Task, String> {
    native::read(&file.display().to_string(), &t.header.task).map_err(|e| e.to_string())
}

/// Whether `replayed` did exactly what `recorded` did: the same rounds (calls, answers,
/// decisions, outcomes, feedback) apart from wall-clock time, and the same summary.
pub fn check_replay(recorded: &Transcript, replayed: &Episode) -> Result<(), String> {
    // What robots outside the process said is theirs, not the replay's to reproduce.
    let strip = |r: &Round| Round {
        wall_ms: 0.0,
        robot: None,
        ..r.clone()
    };
    if recorded.rounds.len() != replayed.rounds.len() {
        return Err(format!(
            "the recording has {} rounds, the replay {}",
            recorded.rounds.len(),
            replayed.rounds.len()
        ));
    }
    for (a, b) in recorded.rounds.iter().zip(&replayed.rounds) {
        if strip(a) != strip(b) {
            return Err(format!("round {} differs from the recording", a.step));
        }
    }
    let timeless = |s: &Summary| Summary {
        wall_ms: 0.0,
        ..s.clone()
    };
    if let Some(s) = &recorded.summary
        && timeless(s) != timeless(&replayed.summary)
    {
        return Err("the summary differs from the recording".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamps() {
        assert_eq!(utc_stamp(0), "19700101T000000Z");
        assert_eq!(utc_stamp(951_782_400), "20000229T000000Z");
        assert_eq!(utc_stamp(1_795_323_508), "20261122T045828Z");
    }
}
