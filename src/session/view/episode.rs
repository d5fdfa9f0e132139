//! What an episode's page shows, as data: the header (task, method, backend, result),
//! one entry per step with the line `coherent run` printed for it and, per robot that
//! acted, the proposal, the decision, the outcome, the feedback and the action list, the
//! calls with their exact prompts and raw answers, and the scene at each step.
//!
//! Every text from outside (a task file, a model, a server) is [`shown_lines`] here, as
//! on a terminal: the page never sees a control character, and it puts every text in
//! as text.

use std::sync::Arc;

use coherent_agents::BackendKind;
use coherent_agents::llm::{Answer, BackendInfo, Finish, Role};
use coherent_agents::transcript::{
    Call, Decision, ExternalDecision, Proposal, RobotPart, Round, RoundOutcome as Outcome, Status,
    Transcript,
};
use coherent_agents::{ModelUse, PriceTable};
use coherent_core::Execution;
use coherent_core::text::{shown, shown_lines};
use coherent_core::{NodeId, RobotReport, Task};
use serde::Serialize;

use super::events::{self, EventView, ReferenceView};
use super::scene::{self, Scene};
use crate::session::lines;

/// An episode to show: its task, its transcript, and its cost when known.
#[derive(Debug)]
pub struct Given {
    pub task: Arc<Task>,
    pub transcript: Transcript,
    /// From a results line (priced as the run was); `None` prices the recorded tokens
    /// with the built-in table.
    pub cost_usd: Option<f64>,
    /// The number of the transcript's last line when it was cut in the middle (a crash,
    /// a full disk): left out, and the rounds before it shown.
    pub cut: Option<usize>,
}

/// An episode's page, as data.
#[derive(Debug, Serialize)]
pub struct EpisodeView {
    pub header: Header,
    pub result: Ending,
    pub scene: Scene,
    pub steps: Vec<Step>,
    /// What an episode with events is measured against (docs/dynamic.md); absent
    /// without events, so that such a page's data is what it was before them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<ReferenceView>,
}

/// The episode's settings.
#[derive(Debug, Serialize)]
pub struct Header {
    /// `scene task id`, as the benchmark names a task.
    pub task: String,
    pub name: String,
    pub instruction: String,
    pub method: String,
    /// `sequential` (one robot's action a step) or `parallel` (joint steps).
    pub execution: Execution,
    /// The backend and model, in words.
    pub backend: String,
    pub model: String,
    pub physics: bool,
    /// Whether the robots were reached over ROS 2 (their reports are in the rounds).
    pub ros2: bool,
    pub seed: Option<u64>,
    pub temperature: Option<f32>,
    pub history: usize,
    pub gt_steps: Option<u32>,
    pub max_steps: u32,
    /// The prompt set's hash and the files that replaced built-in templates.
    pub prompts: Option<String>,
    /// The version of coherent that ran it.
    pub coherent: String,
    pub started_ms: u64,
}

/// How the episode ended.
#[derive(Debug, Serialize)]
pub struct Ending {
    /// `success`, `failure`, `backend_error`, `interrupted`, `error`, or `unfinished`
    /// when the transcript has no summary.
    pub status: String,
    pub success: bool,
    pub steps: u32,
    pub llm_calls: u32,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    pub cached_tokens: u64,
    pub cost_usd: Option<f64>,
    pub wall_ms: f64,
    pub error: Option<String>,
}

/// One step (round).
#[derive(Debug, Serialize)]
pub struct Step {
    pub step: u32,
    /// The line `coherent run` printed for it (a joint step's lines, one under the
    /// other: the step's, then each robot's part).
    pub line: String,
    /// `goal`, `ok`, `refused`, `declined`, `unusable` or `failed`.
    pub status: &'static str,
    /// What each robot that acted (or was asked to) did: the one robot of a sequential
    /// step, every robot's part of a joint step.
    pub robots: Vec<Entry>,
    pub calls: Vec<CallView>,
    pub done: bool,
    pub wall_ms: f64,
    /// What happened before the step that the team did not do (the task's events);
    /// absent without.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<EventView>,
}

/// One robot's part in a step.
#[derive(Debug, Serialize)]
pub struct Entry {
    pub robot: Option<i64>,
    pub name: String,
    pub subtask: Option<String>,
    pub reasoning: Option<String>,
    pub decision: Option<DecisionView>,
    /// What the step did, in words; for a refused action, the engine's reason first.
    pub outcome: String,
    /// The engine's reason code for a refused action (`too_high`, ...).
    pub reason: Option<String>,
    pub feedback: String,
    /// The robot's action list at that moment.
    pub actions: Vec<String>,
    /// A method written outside the crate: its own words and the model use it reported.
    pub external: Option<String>,
    /// What the robot said over ROS 2: which robot, how, its message.
    pub report: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct DecisionView {
    pub can_do: bool,
    pub action: Option<String>,
    pub subtask_complete: bool,
    pub note: String,
}

/// One call to a role.
#[derive(Debug, Serialize)]
pub struct CallView {
    /// `assigner` or `executor`, and the robot asked.
    pub role: String,
    pub messages: Vec<(String, String)>,
    pub answer: Option<String>,
    /// Tokens, latency, attempts and how generation ended, in words.
    pub usage: String,
    pub error: Option<String>,
}

/// The page's data for the episode `e`: its cost when known (a results line's), else
/// priced with the built-in table; `ids` keeps its picture's ids apart from another's
/// in the same page; `progress` is told how many rounds of how many are followed.
pub fn view(e: &Given, ids: &str, progress: &mut dyn FnMut(usize, usize)) -> EpisodeView {
    let (task, t, cost_usd) = (&e.task, &e.transcript, e.cost_usd);
    let h = &t.header;
    let header = Header {
        task: format!("{} task {}", shown(&task.meta.scene), task.meta.task_id),
        name: shown(&h.task_name).into_owned(),
        instruction: shown_lines(&task.meta.instruction),
        method: shown(&h.method).into_owned(),
        execution: h.execution,
        backend: backend(&h.backend),
        model: shown(&h.backend.model).into_owned(),
        physics: h.physics,
        ros2: t.rounds.iter().any(|r| r.robot.is_some()),
        seed: h.seed,
        temperature: h.temperature,
        history: h.history,
        gt_steps: h.gt_steps,
        max_steps: h.max_steps,
        prompts: h.prompts.as_ref().map(|p| {
            let mut names: Vec<&str> = p.replaced.keys().map(String::as_str).collect();
            names.sort_unstable();
            if names.is_empty() {
                format!("{} (built-in templates)", shown(&p.hash))
            } else {
                format!(
                    "{} (replaced: {})",
                    shown(&p.hash),
                    shown(&names.join(", "))
                )
            }
        }),
        coherent: shown(&h.coherent).into_owned(),
        started_ms: h.started_ms,
    };
    let result = match &t.summary {
        Some(s) => Ending {
            status: status_name(s.status).to_owned(),
            success: s.success,
            steps: s.steps,
            llm_calls: s.llm_calls,
            prompt_tokens: s.prompt_tokens,
            completion_tokens: s.completion_tokens,
            cached_tokens: s.cached_tokens,
            cost_usd: cost_usd.or_else(|| recorded_cost(t)),
            wall_ms: s.wall_ms,
            error: s.error.as_deref().map(shown_lines),
        },
        None => {
            let answers = || {
                t.rounds
                    .iter()
                    .flat_map(|r| &r.calls)
                    .filter_map(|c| c.answer.as_ref())
            };
            Ending {
                status: "unfinished".into(),
                success: false,
                steps: t.rounds.len() as u32,
                llm_calls: t.rounds.iter().map(|r| r.calls.len() as u32).sum(),
                prompt_tokens: answers().map(|a| a.usage.prompt_tokens).sum(),
                completion_tokens: answers().map(|a| a.usage.completion_tokens).sum(),
                cached_tokens: answers().map(|a| a.usage.cached_tokens).sum(),
                cost_usd,
                wall_ms: t.rounds.iter().map(|r| r.wall_ms).sum(),
                error: Some(unfinished(e.cut, t.rounds.len())),
            }
        }
    };
    let steps = t
        .rounds
        .iter()
        .map(|r| step(task, r, h.max_steps, h.execution))
        .collect();
    EpisodeView {
        header,
        result,
        scene: scene::follow(task, t, ids, progress),
        steps,
        reference: t
            .summary
            .as_ref()
            .and_then(|s| s.reference.as_deref())
            .map(|r| events::reference(task, r, &t.rounds)),
    }
}

/// Why an episode has no summary, in words: it did not finish, and if the transcript's
/// last line (`cut`) was cut in the middle, that it was left out.
fn unfinished(cut: Option<usize>, rounds: usize) -> String {
    let why = "the transcript has no summary: the episode did not finish";
    match cut {
        Some(line) => format!(
            "{why}; its last line (line {line}) is cut short (the process stopped or the \
             disk filled while writing it): the {rounds} rounds written whole are shown"
        ),
        None => why.to_owned(),
    }
}

/// What the model calls of a recorded episode cost at the built-in prices, by the rule
/// they cost when it ran (`coherent.load_episode` prices it so).
fn recorded_cost(t: &Transcript) -> Option<f64> {
    let summary = t.summary.as_ref()?;
    ModelUse::of(&t.header, &t.rounds, summary).cost(&PriceTable::builtin())
}

fn status_name(s: Status) -> &'static str {
    match s {
        Status::Success => "success",
        Status::Failure => "failure",
        Status::BackendError => "backend_error",
        Status::Interrupted => "interrupted",
        Status::Error => "error",
        Status::Conceded => "conceded",
    }
}

/// The backend in words.
fn backend(b: &BackendInfo) -> String {
    let model = shown(&b.model);
    match (b.kind, &b.base_url) {
        (BackendKind::Builtin, _) => "built-in (the optimal planner plays every role)".to_owned(),
        (BackendKind::Simulated, _) => format!("simulated: {model}"),
        (BackendKind::None, _) => "none (the method asks no model)".to_owned(),
        (kind, Some(url)) => format!("{} {model} at {}", kind.name(), shown(url)),
        (kind, None) => format!("{} {model}", kind.name()),
    }
}

fn step(task: &Task, r: &Round, max_steps: u32, execution: Execution) -> Step {
    let status = match &r.outcome {
        Outcome::Executed if r.done => "goal",
        Outcome::Executed => "ok",
        Outcome::Infeasible { .. } => "refused",
        Outcome::Declined => "declined",
        Outcome::NoProposal { .. } | Outcome::NoDecision { .. } => "unusable",
        Outcome::BackendError { .. } | Outcome::MethodError { .. } => "failed",
    };
    Step {
        step: r.step,
        line: lines::round(task, r, max_steps, execution).join("\n"),
        status,
        robots: match execution {
            Execution::Sequential => vec![entry(task, r)],
            Execution::Parallel => r.parts.iter().map(|p| part(task, p)).collect(),
        },
        calls: r.calls.iter().map(|c| call(task, c)).collect(),
        done: r.done,
        wall_ms: r.wall_ms,
        events: r.events.iter().map(|h| events::happened(task, h)).collect(),
    }
}

/// The round's robot and what it did.
fn entry(task: &Task, r: &Round) -> Entry {
    let (robot, _) = r.chosen();
    let (outcome, reason) = outcome(&r.outcome, r.done);
    Entry {
        robot: robot.map(|id| id.0),
        name: robot_name(task, robot),
        subtask: r.proposal.as_ref().map(|p| shown_lines(&p.subtask)),
        reasoning: r.proposal.as_ref().map(|p| shown_lines(&p.reasoning)),
        decision: r.decision.as_ref().map(decision),
        outcome,
        reason,
        feedback: shown_lines(&r.feedback),
        actions: r.actions.iter().map(|a| shown(a).into_owned()).collect(),
        external: r.external.as_ref().map(external),
        report: r.robot.as_ref().map(report),
    }
}

/// One robot's part of a joint step: its subtask (marked when kept from an earlier
/// round), its decision, what came of its action, what it heard.
fn part(task: &Task, p: &RobotPart) -> Entry {
    let (outcome, reason) = outcome(&p.outcome, false);
    let subtask = |proposal: &Proposal| {
        let subtask = shown_lines(&proposal.subtask);
        if p.kept {
            format!("{subtask} (kept from an earlier step)")
        } else {
            subtask
        }
    };
    Entry {
        robot: Some(p.robot.0),
        name: robot_name(task, Some(p.robot)),
        subtask: p.proposal.as_ref().map(subtask),
        reasoning: p.proposal.as_ref().map(|p| shown_lines(&p.reasoning)),
        decision: p.decision.as_ref().map(decision),
        outcome,
        reason,
        feedback: shown_lines(&p.feedback),
        actions: p.actions.iter().map(|a| shown(a).into_owned()).collect(),
        external: p.external.as_ref().map(external),
        report: p.report.as_ref().map(report),
    }
}

fn robot_name(task: &Task, robot: Option<NodeId>) -> String {
    robot.map_or("-".to_owned(), |id| match task.idx(id) {
        Some(n) => shown(&task.node(n).label()).into_owned(),
        None => format!("unknown robot {}", id.0),
    })
}

/// What came of an action, in words, and the engine's reason code when it was refused.
fn outcome(o: &Outcome, done: bool) -> (String, Option<String>) {
    match o {
        Outcome::Executed if done => ("executed; the goal holds".to_owned(), None),
        Outcome::Executed => ("executed".to_owned(), None),
        Outcome::Infeasible { reason, message } => (
            format!("refused ({}): {}", reason.name(), shown_lines(message)),
            Some(reason.name().to_owned()),
        ),
        Outcome::Declined => (
            "declined: the executor cannot do the subtask now".to_owned(),
            None,
        ),
        Outcome::NoProposal { why } => (format!("no usable proposal: {}", shown_lines(why)), None),
        Outcome::NoDecision { why } => (format!("no usable decision: {}", shown_lines(why)), None),
        Outcome::BackendError { message } => (
            format!("the backend failed: {}", shown_lines(message)),
            None,
        ),
        Outcome::MethodError { message } => {
            (format!("the method failed: {}", shown_lines(message)), None)
        }
    }
}

fn decision(d: &Decision) -> DecisionView {
    DecisionView {
        can_do: d.can_do,
        action: d.action.as_deref().map(|a| shown(a).into_owned()),
        subtask_complete: d.subtask_complete,
        note: shown_lines(&d.note),
    }
}

fn external(e: &ExternalDecision) -> String {
    format!(
        "{} (its own model use: {} calls, {} prompt + {} completion tokens)",
        shown_lines(&e.note),
        e.calls,
        e.prompt_tokens,
        e.completion_tokens
    )
}

fn report(rep: &RobotReport) -> String {
    format!(
        "{} via {}: {}",
        shown(&rep.robot),
        shown(&rep.via),
        shown_lines(&rep.message)
    )
}

fn call(task: &Task, c: &Call) -> CallView {
    let role = match c.role {
        Role::Assigner => "task assigner",
        Role::Executor => "robot executor",
    };
    let role = match c.robot.and_then(|id| task.idx(NodeId(id))) {
        Some(n) => format!("{role} for {}", shown(&task.node(n).label())),
        None => role.to_owned(),
    };
    let mut usage = match &c.answer {
        Some(a) => answer_usage(a),
        None => String::new(),
    };
    if let Some(url) = &c.endpoint {
        usage.push_str(&format!(", endpoint {}", shown(url)));
    }
    if let Some(client) = &c.client {
        usage.push_str(&format!(", through {}", backend(client)));
    }
    CallView {
        role,
        messages: c
            .messages
            .iter()
            .map(|m| (shown(&m.role).into_owned(), shown_lines(&m.content)))
            .collect(),
        answer: c.answer.as_ref().map(|a| shown_lines(&a.text)),
        usage,
        error: c.error.as_ref().map(|e| {
            format!(
                "{:?} after {} attempts: {}",
                e.kind,
                e.attempts,
                shown_lines(&e.message)
            )
        }),
    }
}

fn answer_usage(a: &Answer) -> String {
    let finish = match &a.finish {
        Finish::Stop => "stop".to_owned(),
        Finish::Length => "cut at max_tokens".to_owned(),
        Finish::Refusal(why) => format!("refused: {}", shown(why)),
        Finish::ContentFilter => "content filter".to_owned(),
        Finish::Other(what) => shown(what).into_owned(),
    };
    let cached = if a.usage.cached_tokens > 0 {
        format!(" ({} cached)", a.usage.cached_tokens)
    } else {
        String::new()
    };
    format!(
        "{} prompt{cached} + {} completion tokens, {:.0} ms, {} attempt{}, {finish}",
        a.usage.prompt_tokens,
        a.usage.completion_tokens,
        a.latency_ms,
        a.attempts,
        if a.attempts == 1 { "" } else { "s" }
    )
}
