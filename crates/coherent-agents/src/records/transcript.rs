//! Transcripts: one JSON-lines file per episode, a header, one line per round (prompts,
//! raw answers, parsed decisions, the action list, the outcome, tokens, latencies),
//! then a summary; each line is flushed as it is written, so a crash loses nothing that
//! ran. A transcript holds everything needed to replay its episode
//! ([`crate::run::replay`]).

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;

use coherent_core::RobotReport;
use coherent_core::files::{Limit, Lines, MIB, Opens};
use serde::{Deserialize, Serialize};

use coherent_core::{Execution, NodeId, Task, native};

use crate::error::Error;
use crate::llm::{Answer, BackendInfo, LlmError, Message, Role};
use crate::prompts::fill::robot_label;
use crate::prompts::templates::PromptRecord;
use crate::records::lock;

pub const FORMAT: &str = "coherent-transcript";
/// The version written; every version from 1 up to it is read.
pub const VERSION: u32 = 2;

/// The first line: what ran, on what, with which settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub format: String,
    pub version: u32,
    /// The version of coherent that wrote it.
    pub coherent: String,
    /// The task in the native format, so that a replay needs nothing else.
    pub task: serde_json::Value,
    pub task_name: String,
    pub method: String,
    /// Sequential (absent, as in transcripts written before parallel episodes) or
    /// parallel: its rounds are joint steps with a [`RobotPart`] per robot.
    #[serde(default, skip_serializing_if = "Execution::is_sequential")]
    pub execution: Execution,
    pub history: usize,
    pub max_steps: u32,
    pub gt_steps: Option<u32>,
    /// Whether every action was also carried out in physics.
    pub physics: bool,
    /// Who carried the actions out (local in transcripts written before it was kept).
    #[serde(default)]
    pub robots: RobotsRecord,
    pub backend: BackendInfo,
    pub temperature: Option<f32>,
    pub seed: Option<u64>,
    /// The prompt set: its hash and the files that replaced built-in templates (absent
    /// in transcripts written before prompt sets: the built-in templates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prompts: Option<PromptRecord>,
    /// Milliseconds since the Unix epoch.
    pub started_ms: u64,
    /// Whether the method was written outside the crate (a Python class, say): its
    /// rounds hold its decisions ([`Round::external`]), and a replay re-feeds them.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub external: bool,
    /// The most states the loop's own searches visited (the optimum proven again at each
    /// event of the task); absent for a task without events.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_states: Option<usize>,
}

/// One call to a role: what was sent and what came back (or why nothing did).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Call {
    pub role: Role,
    pub robot: Option<i64>,
    pub messages: Vec<Message>,
    pub answer: Option<Answer>,
    pub error: Option<LlmError>,
    /// The client a method written outside the crate called through (the project's
    /// `LLM`); absent for the episode's own backend.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub client: Option<BackendInfo>,
    /// The base URL that answered (the last one tried, when none did), for a backend
    /// with endpoints; absent otherwise, and in transcripts written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub endpoint: Option<String>,
    /// The characters at the start of its messages that are the same as at the start of
    /// the previous call of the same role and robot in the episode
    /// ([`crate::episode::prefix::shared_prefix`]): what a server's prompt cache could
    /// skip. Absent for the first call of each, and in transcripts written before it
    /// was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shared_prefix: Option<u64>,
}

/// Who carried an episode's actions out: this process (the rules, and Rapier with
/// `physics`), or one ROS 2 action server per robot under a namespace.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RobotsRecord {
    #[default]
    Local,
    Ros2 {
        namespace: String,
    },
}

/// The task assigner's proposal, as read from its answer
/// (`TaskAssigner::parse`, `crate::methods::assigner`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Proposal {
    pub robot: NodeId,
    pub subtask: String,
    pub reasoning: String,
}

/// A decision: an executor's, as read from its answer
/// (`RobotExecutor::parse`, `crate::methods::executor`), or the robot and action a
/// central, dialogue, tree-search, optimal, random or Python method chose.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Decision {
    /// The robot that is to act; `None` when the method chose no action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<NodeId>,
    pub can_do: bool,
    /// The action to run, as answered (matched to the list's spelling when it is one of
    /// them); `None` when the executor declines.
    pub action: Option<String>,
    /// The executor's own judgement that this action finishes the subtask.
    pub subtask_complete: bool,
    pub note: String,
}

/// What came of one round (of the step it is): whether its action ran, and if not, why.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RoundOutcome {
    /// The action ran.
    Executed,
    /// The action was checked and refused (core's feasibility reason; physics when on).
    Infeasible { reason: Reason, message: String },
    /// The executor said it cannot do the subtask now.
    Declined,
    /// The assigner's answer could not be used.
    NoProposal { why: String },
    /// The executor's answer could not be used.
    NoDecision { why: String },
    /// The backend failed for good; the episode ends here.
    BackendError { message: String },
    /// A method written outside the crate raised an error instead of deciding; the
    /// episode ends here.
    MethodError { message: String },
}

/// Why an action, or a joint step, did not run: the engine's reason (the rules', the
/// physical world's or a robot's, `coherent_core::Reason`; `step_refused` for a joint
/// step refused as a whole), or one of the loop's own. Written as its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum Reason {
    Engine(coherent_core::Reason),
    /// The environment could not take the action at all: an error, not a refusal (over
    /// ROS 2, a robot without a server).
    Error,
    /// The decision names a robot that is not in the team.
    UnknownRobot,
    /// The action failed by an event of the task (`action_fails`): nothing changed.
    ActionFailed,
}

impl Reason {
    /// A stable snake_case name, as transcripts, results and step lines write it.
    pub fn name(self) -> &'static str {
        match self {
            Reason::Engine(r) => r.name(),
            Reason::Error => "error",
            Reason::UnknownRobot => "unknown_robot",
            Reason::ActionFailed => "action_failed",
        }
    }
}

impl From<coherent_core::Reason> for Reason {
    fn from(r: coherent_core::Reason) -> Reason {
        Reason::Engine(r)
    }
}

impl From<Reason> for String {
    fn from(r: Reason) -> String {
        r.name().to_owned()
    }
}

impl TryFrom<String> for Reason {
    type Error = String;

    fn try_from(name: String) -> Result<Reason, String> {
        match name.as_str() {
            "error" => Ok(Reason::Error),
            "unknown_robot" => Ok(Reason::UnknownRobot),
            "action_failed" => Ok(Reason::ActionFailed),
            other => coherent_core::Reason::from_name(other)
                .map(Reason::Engine)
                .ok_or_else(|| format!("unknown reason {:?}", coherent_core::text::shown(other))),
        }
    }
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The headline of an error's text: for a Python traceback, the exception's first line
/// and where it was raised (`ZeroDivisionError: division by zero (mine.py, line 12, in
/// act)`); for any other text, its first line that is not blank.
pub fn headline(error: &str) -> String {
    let lines: Vec<&str> = error.lines().collect();
    let Some(at) = lines
        .iter()
        .rposition(|l| l.trim_start().starts_with("File \"") && l.starts_with(' '))
    else {
        return lines
            .iter()
            .map(|l| l.trim())
            .find(|l| !l.is_empty())
            .unwrap_or("")
            .to_owned();
    };
    // After the last frame: its source lines (indented), then the exception.
    let exception = lines[at + 1..]
        .iter()
        .find(|l| !l.starts_with(' ') && !l.trim().is_empty())
        .map_or("", |l| l.trim());
    let frame = lines[at].trim().trim_start_matches("File ");
    let place = match frame.split_once("\", ") {
        Some((file, rest)) => {
            let file = file.trim_start_matches('"');
            let base = file.rsplit(['/', '\\']).next().unwrap_or(file);
            format!("{base}, {rest}")
        }
        None => frame.to_owned(),
    };
    format!("{exception} ({place})")
}

/// What a method written outside the crate decided in one round
/// ([`crate::episode::policy`]), as it gave it, and the model use it reported itself
/// (calls through its own clients; those through the project's are in [`Round::calls`]).
/// A method gives it as its `Choice` ([`crate::episode::Choice`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExternalDecision {
    /// The robot that acts; `None` for no action this step (the step still counts).
    pub robot: Option<NodeId>,
    /// The action, as written: one outside the robot's list is checked like any other
    /// and refused with the reason.
    pub action: Option<String>,
    /// The method's own words about the step.
    pub note: String,
    /// Model use the method reports itself (calls through its own clients).
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    pub calls: u32,
}

/// One robot's part of a parallel round: what it was asked, what it decided, and what
/// came of its action in the round's joint step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotPart {
    pub robot: NodeId,
    /// PEFA: the subtask the robot works on, given this round or kept from an earlier one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub proposal: Option<Proposal>,
    /// Whether that subtask was given in an earlier round (the robot kept it).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub kept: bool,
    /// The robot's action list at that moment.
    #[serde(default)]
    pub actions: Vec<String>,
    /// Its decision: its executor's (PEFA), or the action a central, dialogue or Python
    /// method chose for it (the action alone: the robot is [`RobotPart::robot`]).
    pub decision: Option<Decision>,
    /// What came of its action: executed, or why not (a refused joint step refuses every
    /// action of it, each part saying what that means for its robot).
    pub outcome: RoundOutcome,
    /// What the method hears about this robot's part from the next round on.
    pub feedback: String,
    /// The decision of a method written outside the crate, as it gave it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<ExternalDecision>,
    /// What the robot said, when the action was sent to one outside this process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<RobotReport>,
}

impl RobotPart {
    /// `robot`'s part before anything happened in it.
    pub fn new(robot: NodeId) -> RobotPart {
        RobotPart {
            robot,
            proposal: None,
            kept: false,
            actions: Vec::new(),
            decision: None,
            outcome: RoundOutcome::Declined,
            feedback: String::new(),
            external: None,
            report: None,
        }
    }

    /// The action it was to carry out: its decision's, when it decided on one.
    pub fn action(&self) -> Option<&str> {
        self.decision
            .as_ref()
            .filter(|d| d.can_do)
            .and_then(|d| d.action.as_deref())
    }
}

/// One round, which is one step: in a sequential episode one robot's (PEFA's proposal and
/// decision, or a method's decision, and the outcome), in a parallel one a joint step,
/// each robot's part in [`Round::parts`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Round {
    pub step: u32,
    /// Every model call of the round, in the order asked (a parallel round's executors,
    /// asked at once, in team order).
    pub calls: Vec<Call>,
    /// A sequential round: the assigner's proposal (PEFA).
    pub proposal: Option<Proposal>,
    /// A sequential round: the executor's action list at that moment.
    pub actions: Vec<String>,
    /// A sequential round: the decision.
    pub decision: Option<Decision>,
    /// A sequential round: what came of its one action. A parallel round: what came of
    /// the step as a whole: `executed` (its joint step ran), `infeasible` (the rules
    /// refused it, and why), `declined` (no robot acted), `no_proposal` (the assigner's
    /// answer could not be used) or `no_decision` (the central or dialogue answer could
    /// not be used), or how the episode ended (`backend_error`, `method_error`).
    pub outcome: RoundOutcome,
    /// What the method is told about this round from the next round on (a parallel
    /// round: about the step, then each part's, in team order).
    pub feedback: String,
    /// Whether the goal holds after this round.
    pub done: bool,
    /// Time the round took, model time included.
    pub wall_ms: f64,
    /// The decision of a method written outside the crate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<ExternalDecision>,
    /// What the robot said when the action was sent to one outside this process (over
    /// ROS 2): which robot, how, and its result's message.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<RobotReport>,
    /// A parallel round: each robot's part of its joint step, in team order (empty in a
    /// sequential round, and in transcripts written before parallel episodes).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<RobotPart>,
    /// The simulated seconds the round's actions took, where the world simulates time
    /// (physics); absent otherwise, and in transcripts written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sim_seconds: Option<f64>,
    /// What happened to the world before the round's decision that the team did not do
    /// (the task's events, docs/dynamic.md), each with the optimum proven from there;
    /// absent without events.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<Happened>,
}

/// An event of the task as it happened in an episode (or the end of its span: a door
/// unlocked, failures over), and the optimum from the state it left.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Happened {
    /// The event's index in the task's `events`.
    pub event: usize,
    pub kind: String,
    /// Whether this is the end of the event's span.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub ended: bool,
    /// What the team was told (empty: nothing; failing actions are noticed as they fail).
    pub told: String,
    /// Why the event changed nothing, when it could not happen as written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub void: Option<String>,
    /// The optimum from the state the event left.
    pub optimum: Proof,
}

/// The optimum from a state, as the planner proved it: the fewest steps (and, in a
/// parallel episode, joint steps), or that the goal cannot be reached and why, or that
/// the search stopped before it could say.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Proof {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub makespan: Option<u32>,
    /// Why no plan reaches the goal from there (proven).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unreachable: Option<String>,
    /// Why the optimum is not known (a search stopped at its limit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
}

/// What an episode with events is measured against (docs/dynamic.md): an oracle that
/// knows nothing of events to come and replans at each one. Its steps are the steps
/// taken until the last event plus the optimum from there, plus what the actions that
/// failed after it cost: a step each in a sequential episode; in a parallel one, the
/// joint steps they lost (a joint step whose failed actions were on the critical path).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// The kinds of the task's events, in its order.
    #[serde(default)]
    pub kinds: Vec<String>,
    /// The oracle's steps (joint steps in a parallel episode); absent when the goal
    /// cannot be reached, or its optimum is unknown.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u32>,
    /// Why the goal cannot be reached anymore, when an event made it so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unreachable: Option<String>,
    /// The optimum at the start, before any event (robots that join later out of the
    /// team).
    pub start: Proof,
    /// How the team recovered from each event that changed the world.
    pub recoveries: Vec<Recovery>,
    /// Events that left the goal holding before the next step (the episode ended
    /// there, with no round to record them in).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub closing: Vec<Happened>,
}

/// How the team recovered from one event.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Recovery {
    /// The event's index in the task's `events`.
    pub event: usize,
    /// The step before which it happened.
    pub step: u32,
    /// Rounds from the event until the team first carried out an action that brought the
    /// goal nearer (the optimum from the state fell), that round included; absent when
    /// it never did (or the goal was out of reach).
    pub rounds: Option<u32>,
    /// Actions carried out meanwhile that did not bring the goal nearer.
    pub wasted: u32,
    /// Model calls of those rounds.
    pub calls: u32,
}

impl Round {
    /// The robot the round chose and the action it chose for it, whatever came of it:
    /// its decision's (PEFA's executor's robot is the proposal's), else the robot a
    /// proposal named or a method written outside the crate gave.
    pub fn chosen(&self) -> (Option<NodeId>, Option<&str>) {
        let decision = self.decision.as_ref();
        let robot = decision
            .and_then(|d| d.robot)
            .or(self.proposal.as_ref().map(|p| p.robot))
            .or(self.external.as_ref().and_then(|e| e.robot));
        (robot, decision.and_then(|d| d.action.as_deref()))
    }

    /// The robot and the action the round carried out, if it carried one out.
    pub fn executed(&self) -> Option<(NodeId, &str)> {
        match (&self.outcome, self.chosen()) {
            (RoundOutcome::Executed, (Some(robot), Some(action))) => Some((robot, action)),
            _ => None,
        }
    }

    /// Every robot's action the round carried out, in team order: [`Round::executed`]'s
    /// one in a sequential round, each executed part's in a parallel one (a joint step's
    /// actions do not interfere, so carried out one after another in this order they
    /// give the step's state).
    pub fn carried_out(&self) -> Vec<(NodeId, &str)> {
        if self.parts.is_empty() {
            return self.executed().into_iter().collect();
        }
        self.parts
            .iter()
            .filter(|p| p.outcome == RoundOutcome::Executed)
            .filter_map(|p| p.action().map(|a| (p.robot, a)))
            .collect()
    }

    /// Round `step` before anything happened in it.
    pub fn new(step: u32) -> Round {
        Round {
            step,
            calls: Vec::new(),
            proposal: None,
            actions: Vec::new(),
            decision: None,
            outcome: RoundOutcome::Declined,
            feedback: String::new(),
            done: false,
            wall_ms: 0.0,
            external: None,
            robot: None,
            parts: Vec::new(),
            sim_seconds: None,
            events: Vec::new(),
        }
    }

    /// The actions carried out in this round: 0 or 1 in a sequential round, one per
    /// executed part in a parallel one.
    pub fn actions_executed(&self) -> u32 {
        if self.parts.is_empty() {
            u32::from(self.outcome == RoundOutcome::Executed)
        } else {
            let executed = self
                .parts
                .iter()
                .filter(|p| p.outcome == RoundOutcome::Executed);
            executed.count() as u32
        }
    }

    /// The actions of this round that an event of the task made fail
    /// (`action_failed`, docs/dynamic.md): 0 or 1 in a sequential round, one per such part
    /// in a parallel one.
    pub fn failed_actions(&self) -> u32 {
        let failed = |o: &RoundOutcome| {
            matches!(
                o,
                RoundOutcome::Infeasible {
                    reason: Reason::ActionFailed,
                    ..
                }
            )
        };
        if self.parts.is_empty() {
            u32::from(failed(&self.outcome))
        } else {
            self.parts.iter().filter(|p| failed(&p.outcome)).count() as u32
        }
    }
}

/// How an episode ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The goal holds.
    Success,
    /// The step budget is spent.
    Failure,
    /// The backend failed for good (see the last round).
    BackendError,
    /// Stopped from outside (Ctrl-C), or by the environment when it could go on no
    /// longer (a robot that stopped answering; `error` says why).
    Interrupted,
    /// The method raised an error (see the last round and the summary's `error`).
    Error,
    /// An event put the goal out of reach, and the team stopped acting: right, as the
    /// task cannot be done anymore (docs/dynamic.md).
    Conceded,
}

/// The last line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub status: Status,
    pub success: bool,
    pub steps: u32,
    pub gt_steps: Option<u32>,
    pub max_steps: u32,
    pub llm_calls: u32,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    /// The part of `prompt_tokens` read from the server's prompt cache.
    #[serde(default)]
    pub cached_tokens: u64,
    pub wall_ms: f64,
    pub error: Option<String>,
    /// The simulated seconds the episode took, where its world simulates time (physics);
    /// absent otherwise, and in transcripts written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sim_seconds: Option<f64>,
    /// What an episode with events is measured against, and how the team recovered;
    /// absent without events.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Box<Reference>>,
}

/// The actions carried out in `rounds` ([`Round::actions_executed`]).
pub fn actions(rounds: &[Round]) -> u32 {
    rounds.iter().map(Round::actions_executed).sum()
}

/// A line of a transcript.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Record {
    Header(Box<Header>),
    Round(Box<Round>),
    Summary(Summary),
}

/// Writes a transcript line by line, flushing each; the file is locked while it is
/// written ([`crate::records::lock`]), so that no benchmark takes it for one left over.
#[derive(Debug)]
pub struct Writer {
    file: File,
}

impl Writer {
    /// Writes into `file`, made for it (its name is the episode's alone: see
    /// `crate::run::new_transcript`): locks it and writes the header.
    pub fn new(file: File, header: Header) -> io::Result<Writer> {
        // A file just made is nobody else's: the lock is only for the others to see.
        lock::try_exclusive(&file)?;
        let mut w = Writer { file };
        w.write(&Record::Header(Box::new(header)))?;
        Ok(w)
    }

    pub fn write(&mut self, record: &Record) -> io::Result<()> {
        let mut line = serde_json::to_vec(record).map_err(io::Error::other)?;
        line.push(b'\n');
        self.file.write_all(&line)?;
        self.file.flush()
    }
}

/// A transcript as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Transcript {
    pub header: Header,
    pub rounds: Vec<Round>,
    /// Absent when the episode did not finish (a crash, a kill).
    pub summary: Option<Summary>,
}

/// The most a transcript may hold unless told otherwise: a PEFA episode of 100 steps
/// with the built-in prompts takes a few MiB.
pub const DEFAULT_MAX_BYTES: u64 = 64 * MIB;

/// The limit of a transcript of at most `bytes` (any one line as much).
pub fn limit(bytes: u64) -> Limit {
    Limit {
        bytes,
        what: "a transcript",
        raise: Some("--max-transcript-mib"),
    }
}

/// Reads a transcript of at most [`DEFAULT_MAX_BYTES`]; errors name the file and the
/// line.
pub fn read(path: &Path) -> Result<Transcript, Error> {
    read_within(path, DEFAULT_MAX_BYTES)
}

/// Reads a transcript of at most `max_bytes`; errors name the file and the line.
pub fn read_within(path: &Path, max_bytes: u64) -> Result<Transcript, Error> {
    let lines = Lines::open(path, limit(max_bytes), limit(max_bytes)).map_err(Error::file)?;
    read_lines(lines, path, false).map(|read| read.transcript)
}

/// A transcript read to be shown, which may end in a line cut short.
#[derive(Clone, Debug, PartialEq)]
pub struct Shown {
    pub transcript: Transcript,
    /// The number of a last line cut in the middle (no newline, and not a record): the
    /// episode's process died or the disk filled while it was written. The lines before
    /// it are read as usual.
    pub cut: Option<usize>,
}

/// Reads a transcript of at most `max_bytes` to show it, opening only what `opens`
/// allows: as [`read_within`], except that a last line cut in the middle is left out
/// and reported ([`Shown::cut`]) instead of refusing the rounds written whole before it.
pub fn read_to_show(path: &Path, max_bytes: u64, opens: Opens) -> Result<Shown, Error> {
    let lines =
        Lines::open_as(path, limit(max_bytes), limit(max_bytes), opens).map_err(Error::file)?;
    read_lines(lines, path, true)
}

/// The records of `lines` (the file `path`); `cut_allowed`: a last line without its
/// newline that is no record is reported, not refused.
fn read_lines(mut lines: Lines, path: &Path, cut_allowed: bool) -> Result<Shown, Error> {
    let mut header = None;
    let mut rounds = Vec::new();
    let mut summary = None;
    let mut cut = None;
    while let Some(line) = lines.next_line().map_err(Error::file)? {
        let i = line.number - 1;
        let at = |message: String| Error::at_line(path, i + 1, message);
        let record = std::str::from_utf8(line.bytes)
            .map_err(|e| e.to_string())
            .and_then(|text| {
                if text.trim().is_empty() {
                    return Ok(None);
                }
                serde_json::from_str::<Record>(text)
                    .map(Some)
                    .map_err(|e| e.to_string())
            });
        let record = match record {
            Ok(Some(record)) => record,
            Ok(None) => continue,
            // Nothing follows a line without its newline: it is the last.
            Err(_) if cut_allowed && !line.complete() => {
                cut = Some(line.number);
                continue;
            }
            Err(why) => return Err(at(why)),
        };
        match record {
            Record::Header(h) if i == 0 => {
                if h.format != FORMAT || !(1..=VERSION).contains(&h.version) {
                    return Err(at(format!(
                        "format {:?} version {} (this reads {FORMAT} versions 1 to {VERSION})",
                        h.format, h.version
                    )));
                }
                header = Some(*h);
            }
            Record::Round(r) if header.is_some() && summary.is_none() => rounds.push(*r),
            Record::Summary(s) if header.is_some() && summary.is_none() => summary = Some(s),
            _ => return Err(at("a line out of order".into())),
        }
    }
    let header = header.ok_or_else(|| Error::Format {
        file: path.display().to_string(),
        line: None,
        message: match cut {
            Some(_) => "no header line: the first line is cut short".into(),
            None => "no header line".into(),
        },
    })?;
    if header.version == 1 {
        let task = native::read(&path.display().to_string(), &header.task)?;
        for round in &mut rounds {
            upgrade_v1(&task, round);
        }
    }
    Ok(Shown {
        transcript: Transcript {
            header,
            rounds,
            summary,
        },
        cut,
    })
}

/// A round of a version 1 transcript as version 2 records it: each decision names its
/// robot. Version 1 named it only through the round's proposal (PEFA), its part (a joint
/// step) or, for the other methods, in front of the action as `<robot label>: `, which is
/// taken off here (the method written outside the crate's own robot first, for a robot
/// that is not in the team).
pub fn upgrade_v1(task: &Task, round: &mut Round) {
    for part in &mut round.parts {
        if let Some(d) = &mut part.decision {
            d.robot = Some(part.robot);
        }
    }
    let Some(d) = &mut round.decision else {
        return;
    };
    if let Some(p) = &round.proposal {
        d.robot = Some(p.robot);
        return;
    }
    let Some(line) = &d.action else {
        return;
    };
    let own = round.external.as_ref().and_then(|e| e.robot);
    let team = task.robots.iter().map(|r| task.id(r.node));
    for robot in own.into_iter().chain(team) {
        if let Some(action) = line.strip_prefix(&format!("{}: ", robot_label(task, robot))) {
            d.action = Some(action.to_owned());
            d.robot = Some(robot);
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::headline;

    #[test]
    fn a_traceback_s_headline_is_the_exception_and_where_it_was_raised() {
        let traceback = "Traceback (most recent call last):\n  File \"/work/x/coherent/_methods.py\", line 40, in call\n    return f()\n  File \"/home/me/mine.py\", line 12, in act\n    return 1 / 0\n           ~~^~~\nZeroDivisionError: division by zero";
        assert_eq!(
            headline(traceback),
            "ZeroDivisionError: division by zero (mine.py, line 12, in act)"
        );
    }

    #[test]
    fn other_errors_keep_their_first_line() {
        assert_eq!(
            headline("\nTypeError: act returned 3\nmore"),
            "TypeError: act returned 3"
        );
        assert_eq!(headline(""), "");
    }
}
