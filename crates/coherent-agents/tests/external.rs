//! Methods written outside the crate, through the `Policy` trait: each fault (an action
//! outside the list, an unknown robot, no robot, an error) is a step as described, with
//! a complete transcript; a replay re-feeds the recorded decisions and checks every
//! outcome. (In a benchmark beside the built-in methods: the root package's
//! `tests/bench_runs.rs`.)

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use coherent_agents::episode::{
    Act, Budget, Choice, MakePolicy, MethodFailure, PastStep, Policy, StepView,
};
use coherent_agents::llm::BoxFuture;
use coherent_agents::transcript::{self, Reason, RoundOutcome, Status};
use coherent_agents::{BuiltinBackend, Cancel, Episode, Replay};
use coherent_agents::{External, MethodSpec, Settings};
use coherent_core::planner::Limits;
use coherent_core::{NodeId, SymbolicEnv, Task};

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-external-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Answers from a script, one entry per step, and keeps every view it was shown.
struct Scripted {
    script: VecDeque<Result<Choice, MethodFailure>>,
    views: Arc<Mutex<Vec<Arc<StepView>>>>,
}

impl Policy for Scripted {
    fn act(&mut self, view: Arc<StepView>) -> BoxFuture<'_, Act> {
        self.views.lock().expect("views").push(view);
        let choice = self
            .script
            .pop_front()
            .unwrap_or_else(|| Err("the script is over".into()));
        Box::pin(async move {
            Act {
                choices: choice.map(|c| vec![c]),
                calls: Vec::new(),
            }
        })
    }
}

fn scripted(
    name: &str,
    script: Vec<Result<Choice, MethodFailure>>,
    views: &Arc<Mutex<Vec<Arc<StepView>>>>,
) -> External {
    let views = Arc::clone(views);
    let make: Arc<MakePolicy> = Arc::new(
        move |_: &Arc<Task>| -> Result<Box<dyn Policy>, MethodFailure> {
            Ok(Box::new(Scripted {
                script: script.clone().into(),
                views: Arc::clone(&views),
            }))
        },
    );
    External::new(name, make).expect("a valid name")
}

/// Runs `method` on `task` by the rules, within `budget` steps, its transcript in `out`:
/// the episode and the transcript's path.
async fn play(task: &Arc<Task>, method: External, budget: u32, out: &Path) -> (Episode, PathBuf) {
    let mut env = SymbolicEnv::new(Arc::clone(task));
    common::run(
        task,
        &mut env,
        &BuiltinBackend::new(Limits::default()),
        &Settings::new(MethodSpec::External(method)),
        Budget::Given(budget),
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs")
}

fn choice(robot: Option<i64>, action: &str) -> Result<Choice, MethodFailure> {
    Ok(Choice {
        robot: robot.map(NodeId),
        action: Some(action.to_owned()),
        note: format!("trying {action}"),
        prompt_tokens: 10,
        completion_tokens: 2,
        calls: 1,
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn faults_are_steps_and_an_error_ends_the_episode() {
    let out = scratch("faults");
    // env0 task 0: quadrotor 22 flies from the child room to the kitchen table.
    let task = common::task("env0", 0);
    let views = Arc::new(Mutex::new(Vec::new()));
    let script = vec![
        choice(Some(22), "[grab] <high kitchen table>(35)"),
        choice(Some(999), "[takeoff_from] <childroom floor>(3)"),
        Ok(Choice::default()),
        choice(Some(22), "[takeoff_from] <childroom floor>(3)"),
        Err("ValueError: no idea".into()),
    ];
    let method = scripted("scripted", script, &views);
    let (e, path) = play(&task, method, 10, &out).await;
    let outcomes: Vec<&RoundOutcome> = e.rounds.iter().map(|r| &r.outcome).collect();
    assert!(
        matches!(outcomes[0], RoundOutcome::Infeasible { reason, .. } if *reason != Reason::Error)
    );
    assert!(
        matches!(outcomes[1], RoundOutcome::Infeasible { reason, message } if *reason == Reason::UnknownRobot && message.contains("999 is not a robot"))
    );
    assert_eq!(outcomes[2], &RoundOutcome::Declined);
    assert_eq!(outcomes[3], &RoundOutcome::Executed);
    assert_eq!(
        outcomes[4],
        &RoundOutcome::MethodError {
            message: "ValueError: no idea".into()
        }
    );
    let s = &e.summary;
    assert_eq!((s.status, s.steps, s.success), (Status::Error, 5, false));
    assert_eq!(s.error.as_deref(), Some("ValueError: no idea"));
    // The reported model use counts: three steps reported one call of 10 + 2 tokens each.
    assert_eq!(
        (s.llm_calls, s.prompt_tokens, s.completion_tokens),
        (3, 30, 6)
    );
    // The views: the step, the budget, the actions now, the history so far.
    let views = views.lock().expect("views").clone();
    assert_eq!(views.len(), 5);
    let last = &views[4];
    assert_eq!((last.step, last.max_steps), (5, 10));
    let quadrotor = last.robot(NodeId(22)).expect("the quadrotor");
    assert!(
        quadrotor
            .actions
            .contains(&"[movetowards] <livingroom>(4)".to_owned())
    );
    assert!(views[0].robot(NodeId(22)).expect("22").actions[0].starts_with("[takeoff_from]"));
    let history: Vec<(Option<i64>, bool)> = last
        .history
        .iter()
        .map(|h| (h.robot.map(|r| r.0), h.ok))
        .collect();
    assert_eq!(
        history,
        [
            (Some(22), false),
            (Some(999), false),
            (None, false),
            (Some(22), true)
        ]
    );
    assert!(
        last.history[1]
            .reason
            .as_deref()
            .is_some_and(|r| r.contains("999"))
    );
    assert_eq!(
        last.history[3],
        PastStep {
            robot: Some(NodeId(22)),
            action: Some("[takeoff_from] <childroom floor>(3)".into()),
            ok: true,
            reason: None
        }
    );
    let text = last.observation_text(Some(NodeId(22))).expect("a text");
    assert!(text.contains("<quadrotor>(22)"), "{text}");
    assert!(last.observation_text(Some(NodeId(999))).is_none());
    // The transcript is complete, and replays without the script.
    let recorded = transcript::read(&path).expect("reads back");
    assert!(recorded.header.external);
    assert_eq!(recorded.rounds, e.rounds);
    assert_eq!(recorded.summary.as_ref(), Some(&e.summary));
    let replay = Replay::prepare(&recorded, &path).expect("a replay");
    assert_eq!(replay.settings.method.name(), "scripted");
    assert_eq!(common::replay(&recorded, &path, &out).await, None);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_that_comes_out_differently_says_so() {
    let out = scratch("diverge");
    let task = common::task("env0", 0);
    let views = Arc::new(Mutex::new(Vec::new()));
    let script = vec![choice(Some(22), "[takeoff_from] <childroom floor>(3)")];
    let method = scripted("once", script, &views);
    let (_, path) = play(&task, method, 1, &out).await;
    // The recording says the action ran; make it say it was another.
    let mut recorded = transcript::read(&path).expect("reads back");
    let decision = recorded.rounds[0].external.as_mut().expect("a decision");
    decision.action = Some("[grab] <high kitchen table>(35)".into());
    assert_eq!(
        common::replay(&recorded, &path, &out).await.as_deref(),
        Some("round 1 differs from the recording")
    );
}

#[test]
fn names_are_checked() {
    let make: Arc<MakePolicy> = Arc::new(|_: &Arc<Task>| Err("never made".into()));
    for bad in ["", "pefa", "optimal", "my method", "a/b", ".hidden"] {
        let e = External::new(bad, Arc::clone(&make))
            .expect_err(bad)
            .to_string();
        assert!(e.contains(&format!("{bad:?}")), "{e}");
    }
    let fine = External::new("My_Method-2.0", make).expect("a valid name");
    assert_eq!(fine.name(), "My_Method-2.0");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_methods_texts_of_any_length_are_cut_so_that_its_transcript_reads_back() {
    let out = scratch("long-texts");
    let task = common::task("env0", 0);
    let views = Arc::new(Mutex::new(Vec::new()));
    let long_note = Choice {
        robot: Some(NodeId(22)),
        action: Some(format!("[takeoff_from] <{}>(3)", "x".repeat(1 << 20))),
        note: "n".repeat(3 << 20),
        ..Choice::default()
    };
    let traceback = format!("{}\nValueError: at the end", "  frame\n".repeat(1 << 18));
    let method = scripted("long", vec![Ok(long_note), Err(traceback.into())], &views);
    let (e, path) = play(&task, method, 10, &out).await;
    // 64 KiB kept (docs/architecture.md), and the note of the whole length.
    let limit = (64 << 10) + 64;
    let chosen = e.rounds[0].external.as_ref().expect("the method's choice");
    assert!(chosen.note.len() < limit && chosen.note.ends_with("bytes in all]"));
    assert!(chosen.action.as_ref().expect("an action").len() < limit);
    let error = e.summary.error.as_deref().expect("the method's error");
    assert!(error.len() < limit, "{} bytes", error.len());
    assert!(
        error.ends_with("ValueError: at the end"),
        "the exception is kept"
    );
    let back = transcript::read(&path).expect("reads back");
    assert_eq!(back.rounds, e.rounds);
}

/// What a method says is cut to 64 KiB, the note of the whole length included, and the
/// action as cut is the one carried out and recorded: the episode's own transcript
/// replays. A 12 MiB action used to be cut to 64 KiB and a note, recorded so, and cut
/// again when the replay gave it back (64 KiB of it and another note): "round 1 differs
/// from the recording".
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_method_answering_a_12_mib_action_replays_from_its_own_transcript() {
    let out = scratch("long-replay");
    let task = common::task("env0", 0);
    let views = Arc::new(Mutex::new(Vec::new()));
    let takeoff = "[takeoff_from] <childroom floor>(3)";
    let long = Choice {
        robot: Some(NodeId(22)),
        action: Some(format!("{takeoff}{}", " ".repeat(12 << 20))),
        note: "n".repeat(3 << 20),
        ..Choice::default()
    };
    let traceback = format!("{}\nValueError: at the end", "  frame\n".repeat(1 << 18));
    let script = vec![Ok(long), choice(Some(22), takeoff), Err(traceback.into())];
    let method = scripted("long-replay", script, &views);
    let (e, path) = play(&task, method, 10, &out).await;
    let recorded = transcript::read(&path).expect("reads back");
    assert_eq!(common::replay(&recorded, &path, &out).await, None);
    let chosen = e.rounds[0].external.as_ref().expect("the method's choice");
    let action = chosen.action.as_deref().expect("an action");
    assert!(action.len() <= 64 << 10 && chosen.note.len() <= 64 << 10);
    assert!(
        action.ends_with("… [cut: 12582947 bytes in all]"),
        "{} bytes",
        action.len()
    );
    assert_eq!(
        e.rounds[0]
            .decision
            .as_ref()
            .and_then(|d| d.action.as_deref()),
        Some(action)
    );
    assert!(matches!(e.rounds[1].outcome, RoundOutcome::Executed));
    assert!(
        e.summary
            .error
            .as_ref()
            .is_some_and(|why| why.len() <= 64 << 10)
    );
}

/// Never answers: its step's future stays pending.
struct Silent;

impl Policy for Silent {
    fn act(&mut self, _view: Arc<StepView>) -> BoxFuture<'_, Act> {
        Box::pin(std::future::pending())
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_step_over_the_time_limit_ends_the_episode_as_the_methods_error() {
    let out = scratch("step-timeout");
    let task = common::task("env0", 0);
    let make: Arc<MakePolicy> = Arc::new(|_: &Arc<Task>| Ok(Box::new(Silent) as Box<dyn Policy>));
    let method = External::new("silent", make)
        .expect("a valid name")
        .with_step_timeout(Some(std::time::Duration::from_millis(200)));
    let (e, _) = play(&task, method, 10, &out).await;
    assert_eq!(e.summary.status, Status::Error);
    assert_eq!(e.rounds.len(), 1);
    let error = e.summary.error.as_deref().expect("why");
    assert!(
        error.contains("took longer than its time limit of 0.2 s"),
        "{error}"
    );
}
