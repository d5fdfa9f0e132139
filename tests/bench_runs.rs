//! Benchmark runs through the session's local executor and its one episode runner:
//! resume after a crash, Ctrl-C, reproducibility whatever the concurrency, the
//! transcripts of killed episodes, methods written outside the crates beside the
//! built-in ones, and episodes in physics agreeing with the rules.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent::session::backend::{BackendName, BackendRequest};
use coherent::session::bench::{self, BenchConfig, EpisodesRequest};
use coherent::session::engine::{
    Act, BenchOutcome, BoxFuture, Builtin, Cancel, Choice, DEFAULT_MAX_RESULTS_BYTES,
    DEFAULT_MAX_TRANSCRIPT_BYTES, ErrorRates, Event, Execution, External, MakePolicy,
    MethodFailure, MethodSpec, NodeId, Policy, ResultLine, Status, StepView, Subset, Task,
    Transcript, read_results, transcripts_dir,
};
use coherent::session::episode;
use coherent_agents::BackendKind;
use coherent_agents::llm::BackendInfo;
use coherent_agents::report;
use coherent_core::planner::{self, Limits};

mod common;

/// The first tasks of the paper's subset in the released `env0.json`.
fn paper40_env0() -> Vec<Arc<Task>> {
    bench::choose(&common::env0(), &Subset::Paper40)
        .expect("env0 reads")
        .selection
        .tasks
}

/// `methods` on the `backend`, `seeds` seeds, `concurrency` at once, into `out`.
fn config(
    out: &Path,
    methods: Vec<MethodSpec>,
    backend: BackendRequest,
    seeds: u32,
    concurrency: usize,
) -> BenchConfig {
    let episodes = EpisodesRequest {
        backend,
        ..EpisodesRequest::new(methods)
    };
    BenchConfig {
        episodes: episodes.prepare().expect("valid settings"),
        seeds,
        concurrency,
        out: out.to_owned(),
        max_results_bytes: DEFAULT_MAX_RESULTS_BYTES,
    }
}

fn builtin() -> BackendRequest {
    BackendRequest {
        name: BackendName::Builtin,
        ..BackendRequest::default()
    }
}

fn builtin_methods(methods: &[Builtin]) -> Vec<MethodSpec> {
    methods.iter().map(|&m| m.into()).collect()
}

/// Runs the benchmark to its end on a runtime of the test's own.
fn run(tasks: &[Arc<Task>], config: &BenchConfig) -> BenchOutcome {
    run_with(tasks, config, &Cancel::default(), &mut |_| {})
}

fn run_with(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> BenchOutcome {
    coherent::session::block_on(bench::run(tasks, config, cancel, progress))
        .expect("a runtime")
        .expect("the run")
}

fn lines(out: &Path) -> Vec<ResultLine> {
    read_results(out).expect("results").lines
}

/// A results line written by hand, of PEFA with the run's settings `config`.
fn hand_line(
    task: &Task,
    seed: u32,
    status: Status,
    steps: u32,
    config: &BenchConfig,
) -> ResultLine {
    ResultLine {
        method: "pefa".into(),
        execution: Execution::Sequential,
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        task_type: Some("mono".into()),
        team_size: Some(task.robots.len() as u32),
        seed,
        episode_seed: 0,
        success: status == Status::Success,
        status,
        steps,
        gt_steps: task.meta.gt_steps,
        optimal_steps: None,
        max_steps: 99,
        makespan: None,
        optimal_makespan: None,
        actions: None,
        llm_calls: 0,
        prompt_tokens: 0,
        completion_tokens: 0,
        cached_tokens: 0,
        cost_usd: None,
        wall_ms: 0.0,
        sim_seconds: None,
        backend: BackendInfo {
            kind: BackendKind::Builtin,
            model: "optimal-planner".into(),
            base_url: None,
        },
        uses_model: true,
        error: None,
        transcript: String::new(),
        settings: config.episodes.record(config.seeds).remove("pefa"),
        reference: None,
    }
}

#[test]
fn resume_skips_finished_episodes_reruns_unfinished_ones_and_repairs_a_cut_line() {
    let out = common::scratch("bench-resume").join("results.jsonl");
    let tasks: Vec<Arc<Task>> = paper40_env0().into_iter().take(3).collect();
    // Task 0 finished (with a step count no real run gives, to see it is kept), task 1
    // stopped on a backend error, and a line for task 2 was cut off by a crash.
    let config = config(&out, builtin_methods(&[Builtin::Pefa]), builtin(), 1, 2);
    let finished = hand_line(&tasks[0], 0, Status::Success, 77, &config);
    let failed = hand_line(&tasks[1], 0, Status::BackendError, 1, &config);
    let mut text = String::new();
    for l in [&finished, &failed] {
        text.push_str(&serde_json::to_string(l).expect("encodes"));
        text.push('\n');
    }
    text.push_str(r#"{"method":"pefa","scene":"env0","task_id":"#);
    std::fs::write(&out, &text).expect("write");

    let mut events = 0;
    let outcome = run_with(&tasks, &config, &Cancel::default(), &mut |_| events += 1);
    assert_eq!(outcome.total, 3);
    assert_eq!(outcome.skipped, 1, "the finished episode is not run again");
    assert_eq!(
        outcome.written, 2,
        "the backend error and the cut-off one run"
    );
    assert_eq!(outcome.unfinished, 0);
    assert!(outcome.repaired_bytes > 0);
    assert_eq!(events, 1 + 2, "a start event and one per episode");

    let file = read_results(&out).expect("a clean file now");
    assert_eq!(file.truncated_bytes, 0);
    assert_eq!(file.lines.len(), 4);
    let (finals, unfinished) = report::final_lines(&file.lines);
    assert_eq!((finals.len(), unfinished), (3, 0));
    let kept = finals
        .iter()
        .find(|l| l.task_id == tasks[0].meta.task_id)
        .expect("task 0");
    assert_eq!(kept.steps, 77);
    assert!(finals.iter().all(|l| l.status == Status::Success));

    // Everything is finished: a third run runs nothing.
    let again = run(&tasks, &config);
    assert_eq!((again.skipped, again.written), (3, 0));
    assert_eq!(lines(&out).len(), 4);
}

#[test]
fn a_cancelled_run_writes_nothing_twice_and_the_rerun_finishes_the_rest() {
    let out = common::scratch("bench-cancel").join("results.jsonl");
    let tasks = paper40_env0();
    let methods = builtin_methods(&[Builtin::Pefa, Builtin::Mcts]);
    let config = config(&out, methods, builtin(), 1, 1);
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let mut seen = 0;
    let first = run_with(&tasks, &config, &cancel, &mut |e| {
        if matches!(e, Event::Finished(_)) {
            seen += 1;
            if seen == 3 {
                stop.cancel();
            }
        }
    });
    assert!(first.interrupted);
    assert!(first.written >= 3 && first.written < 16, "{first:?}");
    let second = run(&tasks, &config);
    assert!(!second.interrupted);
    let lines = lines(&out);
    let (finals, unfinished) = report::final_lines(&lines);
    assert_eq!((finals.len(), unfinished), (16, 0));
    let finished_first = lines[..first.written]
        .iter()
        .filter(|l| l.is_final())
        .count();
    assert_eq!(second.skipped, finished_first);
    // No episode has two final lines.
    let finals_written = lines.iter().filter(|l| l.is_final()).count();
    assert_eq!(finals_written, 16);
}

#[test]
fn the_same_seeds_give_the_same_lines_at_concurrency_1_and_4() {
    let dir = common::scratch("bench-determinism");
    let tasks = paper40_env0();
    let simulated = BackendRequest {
        name: BackendName::Simulated,
        sim_errors: Some(ErrorRates::parse("all=0.2").expect("valid rates")),
        ..BackendRequest::default()
    };
    let methods = builtin_methods(&[Builtin::Pefa, Builtin::PefaNoHistory, Builtin::Mcts]);
    let mut runs = Vec::new();
    for concurrency in [1, 4] {
        let out = dir.join(format!("c{concurrency}.jsonl"));
        run(
            &tasks,
            &config(&out, methods.clone(), simulated.clone(), 2, concurrency),
        );
        let mut got: Vec<ResultLine> = lines(&out)
            .into_iter()
            .map(|l| ResultLine {
                wall_ms: 0.0,
                transcript: String::new(),
                ..l
            })
            .collect();
        got.sort_by_key(ResultLine::key);
        runs.push(got);
    }
    assert_eq!(runs[0].len(), 8 * 3 * 2);
    assert_eq!(runs[0], runs[1]);
    // The errors bite: some model-using episode takes more steps than the optimum.
    assert!(
        runs[0]
            .iter()
            .any(|l| l.uses_model && l.optimal_steps.is_some_and(|o| l.steps > o)),
        "no simulated error changed any episode"
    );
    assert!(
        runs[0]
            .iter()
            .all(|l| l.backend.kind == BackendKind::Simulated && l.is_final())
    );
    // Seeds differ: the two seeds of some episode differ.
    let differ = runs[0].windows(2).any(|w| {
        w[0].method == w[1].method && w[0].task_id == w[1].task_id && w[0].steps != w[1].steps
    });
    assert!(differ, "seed 0 and seed 1 ran alike everywhere");
}

/// A kill mid-episode leaves a transcript with no summary that no results line points to;
/// the next run renames it `*.jsonl.unfinished`, says so, runs that episode again, and
/// leaves the transcripts of finished episodes alone.
#[test]
fn a_resumed_run_marks_the_transcripts_of_killed_episodes() {
    let out = common::scratch("bench-orphans").join("results.jsonl");
    let tasks = paper40_env0();
    let config = config(&out, builtin_methods(&[Builtin::Optimal]), builtin(), 1, 2);
    let first = run(&tasks[..2], &config);
    assert!(first.orphaned.is_empty());
    // What a kill leaves: a transcript with a header and no summary, and no line for it.
    let killed = transcripts_dir(&out).join("seed0/env0-task99-optimal-killed.jsonl");
    std::fs::write(&killed, "{\"type\": \"header\"}\n").expect("write");
    let second = run(&tasks[..3], &config);
    assert_eq!((second.skipped, second.written), (2, 1));
    let renamed = killed.with_extension("jsonl.unfinished");
    assert_eq!(second.orphaned, std::slice::from_ref(&renamed));
    assert!(renamed.exists() && !killed.exists());
    for line in lines(&out) {
        assert!(
            PathBuf::from(&line.transcript).exists(),
            "{}",
            line.transcript
        );
    }
}

/// Gives the steps of the task's shortest plan one by one.
struct FollowPlan {
    plan: VecDeque<(NodeId, String)>,
}

impl Policy for FollowPlan {
    fn act(&mut self, _view: Arc<StepView>) -> BoxFuture<'_, Act> {
        let choice = match self.plan.pop_front() {
            Some((robot, action)) => Choice {
                robot: Some(robot),
                action: Some(action),
                note: "the plan's next step".into(),
                ..Choice::default()
            },
            None => Choice::default(),
        };
        Box::pin(async move {
            Act {
                choices: Ok(vec![choice]),
                calls: Vec::new(),
            }
        })
    }
}

fn follow_plan(task: &Arc<Task>) -> Result<Box<dyn Policy>, MethodFailure> {
    let plan = planner::search(task, &task.robots, &task.goal, &Limits::default())
        .plan
        .ok_or(MethodFailure::from("no plan"))?;
    let plan = plan
        .iter()
        .map(|s| (task.id(s.robot), s.action.render(task)))
        .collect();
    Ok(Box::new(FollowPlan { plan }))
}

fn external(name: &str, make: Arc<MakePolicy>) -> MethodSpec {
    MethodSpec::External(External::new(name, make).expect("a valid name"))
}

#[test]
fn a_policy_that_follows_the_plan_is_a_method_like_optimal() {
    let out = common::scratch("bench-follow").join("results.jsonl");
    let tasks = bench::choose(&common::released(), &Subset::Paper40)
        .expect("the released tasks read")
        .selection
        .tasks;
    let methods = vec![
        Builtin::Optimal.into(),
        external("follow-plan", Arc::new(follow_plan)),
    ];
    let outcome = run(&tasks, &config(&out, methods, builtin(), 1, 4));
    assert_eq!((outcome.total, outcome.written), (64, 64));
    let lines = lines(&out);
    for l in &lines {
        assert_eq!(
            l.status,
            Status::Success,
            "{} {} {}",
            l.method,
            l.scene,
            l.task_id
        );
        assert_eq!(Some(l.steps), l.optimal_steps, "{} {}", l.scene, l.task_id);
        assert_eq!((l.llm_calls, l.prompt_tokens), (0, 0));
    }
    let followed: Vec<_> = lines.iter().filter(|l| l.method == "follow-plan").collect();
    assert_eq!(followed.len(), 32);
    assert!(
        followed
            .iter()
            .all(|l| !l.uses_model && l.backend.kind == BackendKind::None)
    );
    let recorded = episode::recorded(
        Path::new(&followed[0].transcript),
        DEFAULT_MAX_TRANSCRIPT_BYTES,
    )
    .expect("a transcript");
    let transcript: &Transcript = &recorded.transcript;
    assert!(transcript.header.external);
    assert!(transcript.rounds.iter().all(|r| r.external.is_some()));
    let r = report::build(&lines).expect("one run's lines");
    let rows: Vec<&str> = r.table1.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(rows, ["optimal", "follow-plan"]);
    assert_eq!(r.table1.rows[0].cells, r.table1.rows[1].cells);
}

#[test]
fn an_error_does_not_count_and_runs_again_on_resume() {
    let out = common::scratch("bench-error").join("results.jsonl");
    let tasks: Vec<Arc<Task>> = ["env0", "env1"]
        .iter()
        .map(|scene| common::released_task(scene, 1))
        .collect();
    // The policy fails on env1's task only.
    let make: Arc<MakePolicy> = Arc::new(
        |task: &Arc<Task>| -> Result<Box<dyn Policy>, MethodFailure> {
            if task.meta.scene == "env1" {
                return Err("RuntimeError: env1 is not for me".into());
            }
            follow_plan(task)
        },
    );
    let methods = vec![Builtin::Pefa.into(), external("picky", make)];
    let cfg = config(&out, methods, builtin(), 1, 2);
    let first = run(&tasks, &cfg);
    assert_eq!((first.written, first.unfinished), (4, 1));
    let lines = lines(&out);
    let failed: Vec<_> = lines.iter().filter(|l| l.status == Status::Error).collect();
    assert_eq!(failed.len(), 1);
    assert_eq!(
        (failed[0].method.as_str(), failed[0].scene.as_str()),
        ("picky", "env1")
    );
    assert_eq!(
        failed[0].error.as_deref(),
        Some("RuntimeError: env1 is not for me")
    );
    assert_eq!(failed[0].steps, 1);
    assert!(
        lines
            .iter()
            .filter(|l| l.status != Status::Error)
            .all(|l| l.success)
    );
    let r = report::build(&lines).expect("one run's lines");
    assert_eq!((r.unfinished, r.errors), (1, 1));
    let failure = &r.failures[0];
    assert_eq!((failure.method.as_str(), failure.episodes), ("picky", 1));
    assert_eq!(failure.first_error, "RuntimeError: env1 is not for me");
    let md = report::markdown(&r);
    assert!(
        md.contains("1 episode(s) failed with an error (the method's own,"),
        "{md}"
    );
    assert!(!md.contains("run the same command again"), "{md}");
    assert!(
        md.contains("| picky | 1 | RuntimeError: env1 is not for me |"),
        "{md}"
    );
    // On resume only the error episode runs again.
    let second = run(&tasks, &cfg);
    assert_eq!((second.skipped, second.written), (3, 1));
}

/// Every action of every episode in Rapier too agrees with the rules: the optimal plan
/// and PEFA (on the built-in backend) take the same steps to the same ends on the demo
/// and on env0's tasks of the paper's subset, each transcript saying it ran in physics.
#[test]
fn a_benchmark_in_physics_writes_the_lines_the_rules_give() {
    let dir = common::scratch("bench-physics");
    let mut tasks = bench::choose(&common::demo(), &Subset::All)
        .expect("the demo reads")
        .selection
        .tasks;
    tasks.extend(paper40_env0());
    let methods = builtin_methods(&[Builtin::Optimal, Builtin::Pefa]);
    let mut runs = Vec::new();
    for physics in [false, true] {
        let out = dir.join(format!("physics-{physics}.jsonl"));
        let episodes = EpisodesRequest {
            backend: builtin(),
            physics,
            ..EpisodesRequest::new(methods.clone())
        };
        let config = BenchConfig {
            episodes: episodes.prepare().expect("valid settings"),
            seeds: 1,
            concurrency: 2,
            out: out.clone(),
            max_results_bytes: DEFAULT_MAX_RESULTS_BYTES,
        };
        run(&tasks, &config);
        let mut got = lines(&out);
        for l in &got {
            let recorded =
                episode::recorded(Path::new(&l.transcript), DEFAULT_MAX_TRANSCRIPT_BYTES)
                    .expect("a transcript");
            assert_eq!(
                recorded.transcript.header.physics, physics,
                "{}",
                l.transcript
            );
        }
        // Physics times each episode; the rules alone do not.
        assert!(got.iter().all(|l| l.sim_seconds.is_some() == physics));
        // The lines record physics on or off, and are the same otherwise.
        assert!(
            got.iter()
                .all(|l| l.settings.as_ref().map(|s| s.physics) == Some(physics))
        );
        got = got
            .into_iter()
            .map(|l| ResultLine {
                wall_ms: 0.0,
                transcript: String::new(),
                sim_seconds: None,
                settings: None,
                ..l
            })
            .collect();
        got.sort_by_key(ResultLine::key);
        runs.push(got);
    }
    assert_eq!(runs[0].len(), 9 * 2);
    assert!(runs[1].iter().all(|l| l.success), "{:?}", runs[1]);
    assert_eq!(runs[0], runs[1]);
}
