//! The benchmark harness and its tables: resume after a crash, reproducibility whatever
//! the concurrency, the paper40 selection, and report numbers worked out by hand.

use std::path::PathBuf;
use std::sync::Arc;

use coherent_agents::bench::{
    self, BackendChoice, BenchConfig, EpisodeSettings, ResultLine, Subset,
};
use coherent_agents::episode::{Method, MethodSpec};
use coherent_agents::llm::BackendInfo;
use coherent_agents::report;
use coherent_agents::transcript::Status;
use coherent_agents::{Cancel, ErrorRates, PriceTable};
use coherent_core::Task;

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-bench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

fn config(out: PathBuf, methods: Vec<Method>, backend: BackendChoice) -> BenchConfig {
    BenchConfig {
        episodes: EpisodeSettings::new(
            methods.into_iter().map(MethodSpec::from).collect(),
            backend,
        ),
        seeds: 1,
        concurrency: 2,
        out,
        max_results_bytes: bench::DEFAULT_MAX_RESULTS_BYTES,
    }
}

fn paper40_env0() -> Vec<Arc<Task>> {
    bench::select(common::scenes(&[0]), &Subset::Paper40)
        .expect("distinct tasks")
        .tasks
}

#[test]
fn paper40_selects_32_released_tasks_and_names_the_8_of_env4_as_missing() {
    let s = bench::select(common::scenes(&[0, 1, 2, 3]), &Subset::Paper40).expect("distinct tasks");
    assert_eq!(s.tasks.len(), 32);
    for scene in ["env0", "env1", "env2", "env3"] {
        let n = s.tasks.iter().filter(|t| t.meta.scene == scene).count();
        assert_eq!(n, 8, "{scene}");
    }
    let ids: Vec<i64> = s
        .tasks
        .iter()
        .filter(|t| t.meta.scene == "env2")
        .map(|t| t.meta.task_id)
        .collect();
    assert_eq!(ids, [3, 5, 6, 7, 10, 11, 16, 17]);
    assert_eq!(s.missing.len(), 8);
    assert!(s.missing.iter().all(|(scene, _)| scene == "env4"));
    assert_eq!(s.missing[0], ("env4".to_owned(), 0));
}

#[test]
fn a_subset_file_picks_its_pairs_and_reports_absent_ones() {
    let dir = scratch("subset");
    let path = dir.join("subset.txt");
    std::fs::write(
        &path,
        "# two tasks\nenv0 2\n\nenv0 4  # a comment\nenv9 1\n",
    )
    .expect("write");
    let subset = Subset::read_file(&path).expect("parses");
    let s = bench::select(common::scenes(&[0]), &subset).expect("distinct tasks");
    let ids: Vec<i64> = s.tasks.iter().map(|t| t.meta.task_id).collect();
    assert_eq!(ids, [2, 4]);
    assert_eq!(s.missing, [("env9".to_owned(), 1)]);
    std::fs::write(&path, "env0 2\nenv0 four\n").expect("write");
    let e = Subset::read_file(&path).expect_err("a bad id");
    assert!(e.contains("subset.txt: line 2"), "{e}");
}

fn hand_line(task: &Task, seed: u32, status: Status, steps: u32) -> ResultLine {
    ResultLine {
        method: "pefa".into(),
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        task_type: Some("mono".into()),
        seed,
        episode_seed: 0,
        success: status == Status::Success,
        status,
        steps,
        gt_steps: task.meta.gt_steps,
        optimal_steps: None,
        max_steps: 99,
        llm_calls: 0,
        prompt_tokens: 0,
        completion_tokens: 0,
        cached_tokens: 0,
        cost_usd: None,
        wall_ms: 0.0,
        backend: BackendInfo {
            kind: "builtin".into(),
            model: "optimal-planner".into(),
            base_url: None,
        },
        uses_model: true,
        error: None,
        transcript: String::new(),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn resume_skips_finished_episodes_reruns_unfinished_ones_and_repairs_a_cut_line() {
    let dir = scratch("resume");
    let out = dir.join("results.jsonl");
    let tasks: Vec<Arc<Task>> = paper40_env0().into_iter().take(3).collect();
    // Task 0 finished (with a step count no real run gives, to see it is kept), task 1
    // stopped on a backend error, and a line for task 2 was cut off by a crash.
    let finished = hand_line(&tasks[0], 0, Status::Success, 77);
    let failed = hand_line(&tasks[1], 0, Status::BackendError, 1);
    let mut text = String::new();
    for l in [&finished, &failed] {
        text.push_str(&serde_json::to_string(l).expect("encodes"));
        text.push('\n');
    }
    text.push_str(r#"{"method":"pefa","scene":"env0","task_id":"#);
    std::fs::write(&out, &text).expect("write");

    let config = config(out.clone(), vec![Method::Pefa], BackendChoice::Builtin);
    let mut events = 0;
    let outcome = bench::run(&tasks, &config, &Cancel::default(), &mut |_| events += 1)
        .await
        .expect("runs");
    assert_eq!(outcome.total, 3);
    assert_eq!(outcome.skipped, 1, "the finished episode is not run again");
    assert_eq!(
        outcome.written, 2,
        "the backend error and the cut-off one run"
    );
    assert_eq!(outcome.unfinished, 0);
    assert!(outcome.repaired_bytes > 0);
    assert_eq!(events, 1 + 2, "a start event and one per episode");

    let file = bench::read_results(&out).expect("a clean file now");
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
    let again = bench::run(&tasks, &config, &Cancel::default(), &mut |_| {})
        .await
        .expect("runs");
    assert_eq!((again.skipped, again.written), (3, 0));
    assert_eq!(bench::read_results(&out).expect("reads").lines.len(), 4);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancelled_run_writes_nothing_twice_and_the_rerun_finishes_the_rest() {
    let dir = scratch("cancel");
    let out = dir.join("results.jsonl");
    let tasks = paper40_env0();
    let mut config = config(
        out.clone(),
        vec![Method::Pefa, Method::Mcts],
        BackendChoice::Builtin,
    );
    config.concurrency = 1;
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let mut seen = 0;
    let first = bench::run(&tasks, &config, &cancel, &mut |e| {
        if matches!(e, bench::Event::Finished(_)) {
            seen += 1;
            if seen == 3 {
                stop.cancel();
            }
        }
    })
    .await
    .expect("runs");
    assert!(first.interrupted);
    assert!(first.written >= 3 && first.written < 16, "{first:?}");
    let second = bench::run(&tasks, &config, &Cancel::default(), &mut |_| {})
        .await
        .expect("runs");
    assert!(!second.interrupted);
    let lines = bench::read_results(&out).expect("reads").lines;
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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_seeds_give_the_same_lines_at_concurrency_1_and_4() {
    let dir = scratch("determinism");
    let tasks = paper40_env0();
    let rates = ErrorRates::parse("all=0.2").expect("valid rates");
    let mut lines = Vec::new();
    for concurrency in [1, 4] {
        let out = dir.join(format!("c{concurrency}.jsonl"));
        let mut config = config(
            out.clone(),
            vec![Method::Pefa, Method::PefaNoHistory, Method::Mcts],
            BackendChoice::Simulated(rates),
        );
        config.seeds = 2;
        config.concurrency = concurrency;
        bench::run(&tasks, &config, &Cancel::default(), &mut |_| {})
            .await
            .expect("runs");
        let mut got: Vec<ResultLine> = bench::read_results(&out)
            .expect("reads")
            .lines
            .into_iter()
            .map(|l| ResultLine {
                wall_ms: 0.0,
                transcript: String::new(),
                ..l
            })
            .collect();
        got.sort_by_key(ResultLine::key);
        lines.push(got);
    }
    assert_eq!(lines[0].len(), 8 * 3 * 2);
    assert_eq!(lines[0], lines[1]);
    // The errors bite: some model-using episode takes more steps than the optimum.
    assert!(
        lines[0]
            .iter()
            .any(|l| l.uses_model && l.optimal_steps.is_some_and(|o| l.steps > o)),
        "no simulated error changed any episode"
    );
    assert!(
        lines[0]
            .iter()
            .all(|l| l.backend.kind == "simulated" && l.is_final())
    );
    // Seeds differ: the two seeds of some episode differ.
    let differ = lines[0].windows(2).any(|w| {
        w[0].method == w[1].method && w[0].task_id == w[1].task_id && w[0].steps != w[1].steps
    });
    assert!(differ, "seed 0 and seed 1 ran alike everywhere");
}

#[allow(clippy::too_many_arguments)]
fn line(
    method: &str,
    scene: &str,
    task_id: i64,
    kind: Option<&str>,
    gt: u32,
    seed: u32,
    status: Status,
    steps: u32,
    calls: u32,
) -> String {
    let mut l = ResultLine {
        method: method.into(),
        scene: scene.into(),
        task_id,
        task_type: kind.map(Into::into),
        seed,
        episode_seed: 0,
        success: status == Status::Success,
        status,
        steps,
        gt_steps: Some(gt),
        optimal_steps: Some(gt),
        max_steps: gt.saturating_mul(2),
        llm_calls: calls,
        prompt_tokens: u64::from(calls) * 100,
        completion_tokens: u64::from(calls) * 10,
        cached_tokens: 0,
        cost_usd: None,
        wall_ms: 1.0,
        backend: BackendInfo {
            kind: "simulated".into(),
            model:
                "optimal-planner with errors hallucinate=0.1,wrong_robot=0,malformed=0,suboptimal=0"
                    .into(),
            base_url: None,
        },
        uses_model: true,
        error: None,
        transcript: "t.jsonl".into(),
    };
    if method == "mcts" {
        l.uses_model = false;
    }
    serde_json::to_string(&l).expect("encodes") + "\n"
}

#[test]
fn report_numbers_match_a_hand_computation() {
    use Status::{BackendError, Failure, Interrupted, Success};
    let dir = scratch("report");
    let path = dir.join("r.jsonl");
    let text = [
        // pefa, seed 0: A (mono, GT 5) in 5; B (dual, GT 10) fails: counts 21.
        line("pefa", "env0", 1, Some("mono"), 5, 0, Success, 5, 10),
        line("pefa", "env1", 2, Some("dual"), 10, 0, Failure, 20, 40),
        // pefa, seed 1: A in 6; B first hit a backend error, then ran again in 10.
        line("pefa", "env0", 1, Some("mono"), 5, 1, Success, 6, 12),
        line("pefa", "env1", 2, Some("dual"), 10, 1, BackendError, 3, 6),
        line("pefa", "env1", 2, Some("dual"), 10, 1, Success, 10, 20),
        // An episode that never finished: left out, counted as unfinished.
        line("pefa", "env1", 3, Some("trio"), 12, 0, Interrupted, 2, 4),
        // mcts, one seed: A fails (11), B fails (21).
        line("mcts", "env0", 1, Some("mono"), 5, 0, Failure, 10, 0),
        line("mcts", "env1", 2, Some("dual"), 10, 0, Failure, 20, 0),
    ]
    .concat();
    std::fs::write(&path, text).expect("write");
    let lines = bench::read_results(&path).expect("reads").lines;
    let r = report::build(&lines);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;

    assert_eq!(r.seeds, [0, 1]);
    assert_eq!(r.unfinished, 1);
    assert_eq!(r.table1.columns, ["mono", "dual", "trio", "Avg"]);
    assert_eq!(r.table1.tasks, [1, 1, 0, 2]);
    let methods: Vec<&str> = r.table1.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods, ["pefa", "mcts"], "rows in Method::ALL order");

    // pefa, Avg: SR per seed 0.5 and 1.0 -> mean 0.75, sd 0.353553, half-width
    // t(1) x sd / sqrt(2) = 12.706 x 0.25 = 3.1765. AS per seed (5+21)/2 = 13 and
    // (6+10)/2 = 8 -> mean 10.5, sd 3.535534, half-width 12.706 x 2.5 = 31.765.
    let avg = r.table1.rows[0].cells[3].as_ref().expect("pefa avg");
    assert_eq!(avg.episodes, 4);
    assert!(close(avg.sr.mean, 0.75));
    assert!(close(avg.sr.ci95.expect("two seeds"), 3.1765));
    assert!(close(avg.avg_steps.mean, 10.5));
    assert!(close(avg.avg_steps.ci95.expect("two seeds"), 31.765));
    // pefa, mono: SR 1 and 1 (half-width 0); AS 5 and 6 -> 5.5 +- 12.706 x 0.5.
    let mono = r.table1.rows[0].cells[0].as_ref().expect("pefa mono");
    assert!(close(mono.sr.mean, 1.0) && close(mono.sr.ci95.expect("ci"), 0.0));
    assert!(close(mono.avg_steps.mean, 5.5));
    assert!(close(mono.avg_steps.ci95.expect("ci"), 6.353));
    assert!(
        r.table1.rows[0].cells[2].is_none(),
        "no finished trio episode"
    );
    // mcts, one seed: no interval; AS (11 + 21) / 2 = 16.
    let mcts = r.table1.rows[1].cells[3].as_ref().expect("mcts avg");
    assert!(close(mcts.sr.mean, 0.0) && mcts.sr.ci95.is_none());
    assert!(close(mcts.avg_steps.mean, 16.0));
    // GT row: mono 5, dual 10, avg 7.5.
    assert_eq!(r.table1.gt, [Some(5.0), Some(10.0), None, Some(7.5)]);

    // Table II: env0 holds A, env1 holds B.
    assert_eq!(r.table2.columns, ["env0", "env1", "Avg"]);
    let env1 = r.table2.rows[0].cells[1].as_ref().expect("pefa env1");
    // SR 0 and 1 -> 0.5 +- 12.706 x 0.5; AS 21 and 10 -> 15.5 +- 12.706 x 5.5.
    assert!(close(env1.sr.mean, 0.5) && close(env1.sr.ci95.expect("ci"), 6.353));
    assert!(close(env1.avg_steps.mean, 15.5));
    assert!(close(env1.avg_steps.ci95.expect("ci"), 69.883));

    // Costs: pefa's final episodes made 10 + 40 + 12 + 20 = 82 calls in 41 steps.
    let cost = &r.costs[0];
    assert_eq!((cost.episodes, cost.steps, cost.llm_calls), (4, 41, 82));
    assert!(close(cost.calls_per_episode, 20.5));
    assert!(close(cost.calls_per_step.expect("steps"), 2.0));
    assert!(close(cost.tokens_per_step.expect("steps"), 220.0));
    // The simulated backend has no price: no cost.
    assert_eq!(
        (cost.cost_usd, cost.cost_per_task, cost.cost_per_success),
        (None, None, None)
    );

    let md = report::markdown(&r);
    assert!(
        md.contains("simulated: optimal-planner with errors hallucinate=0.1"),
        "{md}"
    );
    assert!(md.contains("| pefa | 1.000 ± 0.000 / 5.5 ± 6.4 |"), "{md}");
    assert!(md.contains("| mcts | 0.000 / 11.0 |"), "{md}");
    assert!(
        md.contains("| Ground truth | - / 5.0 | - / 10.0 | - / - | - / 7.5 |"),
        "{md}"
    );
    let csv = report::csv(&r);
    assert!(
        csv.contains("I,pefa,Avg,2,4,0.750000,3.176500,10.500000,31.765000,"),
        "{csv}"
    );
    let json: serde_json::Value = serde_json::from_str(&report::json(&r)).expect("JSON");
    assert_eq!(json["table1"]["rows"][0]["cells"][3]["sr"]["mean"], 0.75);
}

#[test]
fn a_bad_line_in_the_middle_is_an_error_naming_the_file_line_and_field() {
    let dir = scratch("badline");
    let path = dir.join("r.jsonl");
    let good = line(
        "pefa",
        "env0",
        1,
        Some("mono"),
        5,
        0,
        Status::Success,
        5,
        10,
    );
    let bad = good.replace("\"steps\":5", "\"steps\":\"five\"");
    std::fs::write(&path, format!("{good}{bad}{good}")).expect("write");
    let e = bench::read_results(&path).expect_err("a bad line");
    assert!(e.contains("r.jsonl: line 2"), "{e}");
    assert!(e.contains("$.steps"), "{e}");
}

/// A kill mid-episode leaves a transcript with no summary that no results line points to;
/// the next run renames it `*.jsonl.unfinished`, says so, runs that episode again, and
/// leaves the transcripts of finished episodes alone.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resumed_run_marks_the_transcripts_of_killed_episodes() {
    let dir = scratch("orphans");
    let out = dir.join("results.jsonl");
    let tasks = paper40_env0();
    let config = config(out.clone(), vec![Method::Optimal], BackendChoice::Builtin);
    let first = bench::run(&tasks[..2], &config, &Cancel::default(), &mut |_| {})
        .await
        .expect("runs");
    assert!(first.orphaned.is_empty());
    // What a kill leaves: a transcript with a header and no summary, and no line for it.
    let killed = bench::transcripts_dir(&out).join("seed0/env0-task99-optimal-killed.jsonl");
    std::fs::write(&killed, "{\"type\": \"header\"}\n").expect("write");
    let second = bench::run(&tasks[..3], &config, &Cancel::default(), &mut |_| {})
        .await
        .expect("runs");
    assert_eq!((second.skipped, second.written), (2, 1));
    let renamed = killed.with_extension("jsonl.unfinished");
    assert_eq!(second.orphaned, std::slice::from_ref(&renamed));
    assert!(renamed.exists() && !killed.exists());
    for line in bench::read_results(&out).expect("reads").lines {
        assert!(
            PathBuf::from(&line.transcript).exists(),
            "{}",
            line.transcript
        );
    }
}

/// A transcript whose episode still runs elsewhere (its writer holds it) is never taken
/// for one left over by a kill, while a leftover beside it is; and a second run on the
/// same results file, or on one that shares its transcripts folder, is refused naming
/// the first run's process.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_transcript_being_written_elsewhere_is_never_renamed_and_one_run_holds_a_results_file() {
    let dir = scratch("owned");
    let out = dir.join("results.jsonl");
    let seed0 = bench::transcripts_dir(&out).join("seed0");
    let task = &paper40_env0()[0];
    let live = seed0.join("env0-task2-pefa-live.jsonl");
    let header = coherent_agents::transcript::Header {
        format: coherent_agents::transcript::FORMAT.into(),
        version: coherent_agents::transcript::VERSION,
        coherent: "test".into(),
        task: coherent_core::native::to_value(task),
        task_name: task.meta.name.clone(),
        method: "pefa".into(),
        history: 5,
        max_steps: 10,
        gt_steps: task.meta.gt_steps,
        physics: false,
        backend: BackendInfo {
            kind: "builtin".into(),
            model: String::new(),
            base_url: None,
        },
        temperature: None,
        seed: None,
        prompts: None,
        started_ms: 0,
        external: false,
    };
    let writer = coherent_agents::transcript::Writer::create(&live, header).expect("created");
    let left = seed0.join("env0-task4-pefa-left.jsonl");
    std::fs::write(&left, "{\"type\": \"header\"}\n").expect("write");
    let marked = bench::mark_orphans(&out, &[]).expect("marked");
    assert_eq!(marked, [left.with_extension("jsonl.unfinished")]);
    assert!(live.exists(), "the live transcript keeps its name");
    drop(writer);
    let ledger = bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES).expect("the first");
    for other in [out.clone(), dir.join("results.json")] {
        let e = bench::Ledger::open(&other, bench::DEFAULT_MAX_RESULTS_BYTES)
            .expect_err("a second run");
        let pid = std::process::id();
        assert!(
            e.contains("another benchmark run is using it")
                && e.contains(&format!("process {pid}")),
            "{e}"
        );
    }
    drop(ledger);
    bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES).expect("free again");
}

/// A results line with a key twice is refused, naming the line and the key (serde_json
/// alone keeps the last one, so `"success": true, "success": false` would count as a
/// failure unseen).
#[test]
fn a_results_line_with_a_key_twice_is_refused() {
    let dir = scratch("duplicate-key");
    let path = dir.join("r.jsonl");
    let good = line(
        "pefa",
        "env0",
        1,
        Some("mono"),
        5,
        0,
        Status::Success,
        5,
        10,
    );
    let twice = good.replacen('{', "{\"success\":false,", 1);
    std::fs::write(&path, format!("{good}{twice}")).expect("write");
    let e = bench::read_results(&path).expect_err("a key twice");
    assert!(
        e.contains("r.jsonl: line 2") && e.contains("duplicate key \"success\" at $.success"),
        "{e}"
    );
}

/// A failed episode counts 2 x GT + 1 steps, worked out without wrapping for the
/// largest ground truth a results line can hold.
#[test]
fn a_huge_ground_truth_counts_without_wrapping() {
    let dir = scratch("huge-gt");
    let path = dir.join("r.jsonl");
    let text = line(
        "pefa",
        "env0",
        1,
        Some("mono"),
        u32::MAX,
        0,
        Status::Failure,
        5,
        10,
    );
    std::fs::write(&path, text).expect("write");
    let lines = bench::read_results(&path).expect("reads").lines;
    assert_eq!(
        report::counted_steps(&lines[0]),
        2.0 * f64::from(u32::MAX) + 1.0
    );
}

#[test]
fn costs_per_task_and_per_success_come_from_the_priced_lines() {
    let dir = scratch("costs");
    let path = dir.join("r.jsonl");
    // pefa on a model priced 1 USD per million prompt tokens and 10 per million
    // completion tokens: an episode of c calls costs c x (100 + 10 x 10) / 1e6 USD.
    let prices = PriceTable::parse_json(
        r#"{"m": {"input": 1.0, "cached_input": 0.5, "output": 10.0}}"#,
        "p.json",
    )
    .expect("a table");
    let on_m = |text: String| {
        let mut l: ResultLine = serde_json::from_str(&text).expect("a line");
        l.backend.model = "m".into();
        l
    };
    let lines = vec![
        on_m(line(
            "pefa",
            "env0",
            1,
            Some("mono"),
            5,
            0,
            Status::Success,
            5,
            10,
        )),
        on_m(line(
            "pefa",
            "env1",
            2,
            Some("dual"),
            10,
            0,
            Status::Failure,
            20,
            30,
        )),
        on_m(line(
            "mcts",
            "env0",
            1,
            Some("mono"),
            5,
            0,
            Status::Success,
            5,
            0,
        )),
        on_m(line(
            "cmrs",
            "env0",
            1,
            Some("mono"),
            5,
            0,
            Status::Success,
            5,
            4,
        )),
    ];
    let mut priced: Vec<ResultLine> = lines.into_iter().map(|l| l.priced(&prices)).collect();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(
        priced[0].cost_usd.expect("priced"),
        10.0 * 200.0 / 1e6
    ));
    // A method that asks no model and used no tokens costs nothing.
    assert_eq!(priced[2].cost_usd, Some(0.0));
    // A line on a model without a price has no cost, and neither has its method's row.
    priced[3] = ResultLine {
        backend: BackendInfo {
            model: "unpriced".into(),
            ..priced[3].backend.clone()
        },
        ..priced[3].clone()
    }
    .priced(&prices);
    assert_eq!(priced[3].cost_usd, None);
    let text: String = priced
        .iter()
        .map(|l| serde_json::to_string(l).expect("encodes") + "\n")
        .collect();
    std::fs::write(&path, text).expect("write");
    let back = bench::read_results(&path).expect("reads").lines;
    assert_eq!(back, priced, "cost_usd round-trips through the file");
    let r = report::build(&back);
    let row = |m: &str| r.costs.iter().find(|c| c.method == m).expect("a row");
    // pefa: 40 calls x 200 tokens-worth = 0.008 USD over 2 tasks, 1 success.
    let pefa = row("pefa");
    assert!(close(pefa.cost_usd.expect("all priced"), 0.008));
    assert!(close(pefa.cost_per_task.expect("all priced"), 0.004));
    assert!(close(pefa.cost_per_success.expect("a success"), 0.008));
    assert_eq!(row("mcts").cost_per_task, Some(0.0));
    assert_eq!(row("cmrs").cost_per_task, None);
    let md = report::markdown(&r);
    assert!(md.contains("| 0.004000 | 0.008000 |"), "{md}");
    let csv = report::csv(&r);
    assert!(csv.contains(",0.004,0.008,1,"), "{csv}");
    assert!(
        csv.lines()
            .any(|l| l.starts_with("costs,cmrs,all,") && l.contains(",,,1,")),
        "{csv}"
    );
}
