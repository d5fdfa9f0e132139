//! The benchmark's bookkeeping and its tables: the paper40 selection, subset files, the
//! results file read back, and report numbers worked out by hand. (Runs, resumed and
//! cancelled: the root package's `tests/bench_runs.rs`.)

use std::collections::BTreeMap;
use std::path::PathBuf;

use coherent_agents::PriceTable;
use coherent_agents::bench::{self, ResultLine, Subset};
use coherent_agents::llm::{BackendInfo, BackendKind};
use coherent_agents::report;
use coherent_agents::transcript::Status;
use coherent_core::Execution;

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-bench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
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
    let e = Subset::read_file(&path).expect_err("a bad id").to_string();
    assert!(e.contains("subset.txt: line 2"), "{e}");
}

/// A results line written by hand, field by field; what a test leaves out is the
/// default: pefa on env0 task 1 (mono, ground truth 5), seed 0, a success in 5 steps with
/// 10 model calls of 100 prompt and 10 completion tokens each, on the simulated backend.
#[derive(Clone, Copy)]
struct Hand {
    method: &'static str,
    scene: &'static str,
    task_id: i64,
    task_type: &'static str,
    gt: u32,
    seed: u32,
    status: Status,
    steps: u32,
    calls: u32,
}

impl Default for Hand {
    fn default() -> Hand {
        Hand {
            method: "pefa",
            scene: "env0",
            task_id: 1,
            task_type: "mono",
            gt: 5,
            seed: 0,
            status: Status::Success,
            steps: 5,
            calls: 10,
        }
    }
}

impl Hand {
    fn line(self) -> ResultLine {
        ResultLine {
            method: self.method.into(),
            execution: Execution::Sequential,
            scene: self.scene.into(),
            task_id: self.task_id,
            task_type: Some(self.task_type.into()),
            team_size: Some(3),
            seed: self.seed,
            episode_seed: 0,
            success: self.status == Status::Success,
            status: self.status,
            steps: self.steps,
            gt_steps: Some(self.gt),
            optimal_steps: Some(self.gt),
            max_steps: self.gt.saturating_mul(2),
            makespan: (self.status == Status::Success).then_some(self.steps),
            optimal_makespan: None,
            actions: Some(self.steps),
            llm_calls: self.calls,
            prompt_tokens: u64::from(self.calls) * 100,
            completion_tokens: u64::from(self.calls) * 10,
            cached_tokens: 0,
            cost_usd: None,
            wall_ms: 1.0,
            sim_seconds: None,
            backend: BackendInfo {
                kind: BackendKind::Simulated,
                model:
                    "optimal-planner with errors hallucinate=0.1,wrong_robot=0,malformed=0,suboptimal=0"
                        .into(),
                base_url: None,
            },
            // MCTS plans without a model.
            uses_model: self.method != "mcts",
            error: None,
            transcript: "t.jsonl".into(),
            settings: None,
            reference: None,
        }
    }

    /// The line as the results file holds it.
    fn jsonl(self) -> String {
        serde_json::to_string(&self.line()).expect("encodes") + "\n"
    }
}

#[test]
fn report_numbers_match_a_hand_computation() {
    use Status::{BackendError, Failure, Interrupted};
    let dir = scratch("report");
    let path = dir.join("r.jsonl");
    // Task A: env0 task 1 (mono, GT 5); task B: env1 task 2 (dual, GT 10).
    let a = Hand::default();
    let b = Hand {
        scene: "env1",
        task_id: 2,
        task_type: "dual",
        gt: 10,
        ..a
    };
    let mcts = |task: Hand| Hand {
        method: "mcts",
        calls: 0,
        ..task
    };
    let text = [
        // pefa, seed 0: A in 5; B fails: counts 21.
        Hand { steps: 5, ..a },
        Hand {
            status: Failure,
            steps: 20,
            calls: 40,
            ..b
        },
        // pefa, seed 1: A in 6; B first hit a backend error, then ran again in 10.
        Hand {
            seed: 1,
            steps: 6,
            calls: 12,
            ..a
        },
        Hand {
            seed: 1,
            status: BackendError,
            steps: 3,
            calls: 6,
            ..b
        },
        Hand {
            seed: 1,
            steps: 10,
            calls: 20,
            ..b
        },
        // An episode that never finished (env1 task 3, trio, GT 12): left out, counted as
        // unfinished.
        Hand {
            task_id: 3,
            task_type: "trio",
            gt: 12,
            status: Interrupted,
            steps: 2,
            calls: 4,
            ..b
        },
        // mcts, one seed: A fails (11), B fails (21).
        Hand {
            status: Failure,
            steps: 10,
            ..mcts(a)
        },
        Hand {
            status: Failure,
            steps: 20,
            ..mcts(b)
        },
    ]
    .map(Hand::jsonl)
    .concat();
    std::fs::write(&path, text).expect("write");
    let lines = bench::read_results(&path).expect("reads").lines;
    let r = report::build(&lines).expect("one run's lines");
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;

    assert_eq!(r.seeds, [0, 1]);
    assert_eq!(r.unfinished, 1);
    assert_eq!(r.table1.columns, ["mono", "dual", "trio", "Avg"]);
    assert_eq!(r.table1.tasks, [1, 1, 0, 2]);
    let methods: Vec<&str> = r.table1.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods, ["pefa", "mcts"], "rows in Builtin::ALL order");

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
    let good = Hand::default().jsonl();
    let bad = good.replace("\"steps\":5", "\"steps\":\"five\"");
    std::fs::write(&path, format!("{good}{bad}{good}")).expect("write");
    let e = bench::read_results(&path)
        .expect_err("a bad line")
        .to_string();
    assert!(e.contains("r.jsonl: line 2"), "{e}");
    assert!(e.contains("$.steps"), "{e}");
}

/// A transcript whose episode still runs elsewhere (its writer holds it) is never taken
/// for one left over by a kill, while a leftover beside it is; and a second run on the
/// same results file, or on one that shares its transcripts folder, is refused naming
/// the first run's process.
#[test]
fn a_transcript_being_written_elsewhere_is_never_renamed_and_one_run_holds_a_results_file() {
    let dir = scratch("owned");
    let out = dir.join("results.jsonl");
    let seed0 = bench::transcripts_dir(&out).join("seed0");
    let task = &common::scenes(&[0])[0];
    let live = seed0.join("env0-task0-pefa-live.jsonl");
    let header = coherent_agents::transcript::Header {
        format: coherent_agents::transcript::FORMAT.into(),
        version: coherent_agents::transcript::VERSION,
        coherent: "test".into(),
        task: coherent_core::native::to_value(task),
        task_name: task.meta.name.clone(),
        method: "pefa".into(),
        execution: Execution::Sequential,
        history: 5,
        max_steps: 10,
        gt_steps: task.meta.gt_steps,
        physics: false,
        robots: coherent_agents::transcript::RobotsRecord::Local,
        backend: BackendInfo {
            kind: BackendKind::Builtin,
            model: String::new(),
            base_url: None,
        },
        temperature: None,
        seed: None,
        prompts: None,
        started_ms: 0,
        external: false,
        max_states: None,
    };
    std::fs::create_dir_all(&seed0).expect("a folder");
    let file = std::fs::File::create(&live).expect("created");
    let writer = coherent_agents::transcript::Writer::new(file, header).expect("written");
    let left = seed0.join("env0-task4-pefa-left.jsonl");
    std::fs::write(&left, "{\"type\": \"header\"}\n").expect("write");
    let marked = bench::mark_orphans(&out, &[]).expect("marked");
    assert_eq!(marked, [left.with_extension("jsonl.unfinished")]);
    assert!(live.exists(), "the live transcript keeps its name");
    drop(writer);
    let ledger = bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES, &BTreeMap::new())
        .expect("the first");
    for other in [out.clone(), dir.join("results.json")] {
        let e = bench::Ledger::open(&other, bench::DEFAULT_MAX_RESULTS_BYTES, &BTreeMap::new())
            .expect_err("a second run")
            .to_string();
        let pid = std::process::id();
        assert!(
            e.contains("another benchmark run is using it")
                && e.contains(&format!("process {pid}")),
            "{e}"
        );
    }
    drop(ledger);
    bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES, &BTreeMap::new())
        .expect("free again");
}

/// A run's one read of an existing results file does both checks, in this order: its
/// size within the limit first (a file too large is refused for that, whatever its
/// settings), then its settings, and both only under the lock (a file held by another run
/// is refused for that); a refused file is left as it was.
#[test]
fn resuming_reads_the_file_once_under_the_lock_size_first_then_settings() {
    let dir = scratch("limits-then-settings");
    let out = dir.join("results.jsonl");
    // Written before lines had settings: other settings than any run's now.
    let text = Hand::default().jsonl();
    std::fs::write(&out, &text).expect("write");
    let settings = bench::RunSettings {
        backend: BackendKind::Builtin,
        model: None,
        sim_errors: None,
        temperature: None,
        model_seed: None,
        seeds: 1,
        prompts: "built-in".into(),
        history: 5,
        max_steps: None,
        max_states: 100_000,
        physics: false,
        robots: "local".into(),
        coherent: "test".into(),
        executions: vec![Execution::Sequential],
        method: BTreeMap::new(),
    };
    let now = BTreeMap::from([("pefa".to_owned(), settings)]);
    let small = (text.len() - 1) as u64;
    let e = bench::Ledger::open(&out, small, &now)
        .expect_err("too large")
        .to_string();
    assert!(
        e.contains("--max-results-mib") && !e.contains("other settings"),
        "{e}"
    );
    // Another run (of no settings to compare) holds the file: the lock is asked first.
    let holder = bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES, &BTreeMap::new())
        .expect("the holder");
    let e = bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES, &now)
        .expect_err("held")
        .to_string();
    assert!(e.contains("another benchmark run is using it"), "{e}");
    drop(holder);
    let e = bench::Ledger::open(&out, bench::DEFAULT_MAX_RESULTS_BYTES, &now)
        .expect_err("other settings")
        .to_string();
    assert!(e.contains("holds episodes run with other settings"), "{e}");
    assert_eq!(std::fs::read_to_string(&out).expect("read"), text);
}

/// A results line with a key twice is refused, naming the line and the key (serde_json
/// alone keeps the last one, so `"success": true, "success": false` would count as a
/// failure unseen).
#[test]
fn a_results_line_with_a_key_twice_is_refused() {
    let dir = scratch("duplicate-key");
    let path = dir.join("r.jsonl");
    let good = Hand::default().jsonl();
    let twice = good.replacen('{', "{\"success\":false,", 1);
    std::fs::write(&path, format!("{good}{twice}")).expect("write");
    let e = bench::read_results(&path)
        .expect_err("a key twice")
        .to_string();
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
    let text = Hand {
        gt: u32::MAX,
        status: Status::Failure,
        ..Hand::default()
    }
    .jsonl();
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
    let on_m = |hand: Hand| {
        let mut l = hand.line();
        l.backend.model = "m".into();
        l
    };
    let lines = vec![
        on_m(Hand::default()),
        on_m(Hand {
            scene: "env1",
            task_id: 2,
            task_type: "dual",
            gt: 10,
            status: Status::Failure,
            steps: 20,
            calls: 30,
            ..Hand::default()
        }),
        on_m(Hand {
            method: "mcts",
            calls: 0,
            ..Hand::default()
        }),
        on_m(Hand {
            method: "cmrs",
            calls: 4,
            ..Hand::default()
        }),
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
    let r = report::build(&back).expect("one run's lines");
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

#[test]
fn the_cached_share_and_the_cost_of_cached_tokens_come_from_the_lines() {
    // Two pefa episodes of 10 and 30 calls (1,000 and 3,000 prompt tokens), of which the
    // server read 600 and 2,700 from its cache: 3,300 of 4,000, 0.825.
    let prices = PriceTable::parse_json(
        r#"{"m": {"input": 1.0, "cached_input": 0.25, "output": 10.0}}"#,
        "p.json",
    )
    .expect("a table");
    let lines: Vec<ResultLine> = [(10, 600), (30, 2700)]
        .into_iter()
        .map(|(calls, cached)| {
            let mut l = Hand {
                task_id: i64::from(calls),
                calls,
                ..Hand::default()
            }
            .line();
            l.backend.model = "m".into();
            l.cached_tokens = cached;
            l.priced(&prices)
        })
        .collect();
    // 400 fresh x 1 + 600 cached x 0.25 + 100 completion x 10, per million.
    let cost = lines[0].cost_usd.expect("priced");
    assert!(
        (cost - (400.0 + 150.0 + 1000.0) / 1e6).abs() < 1e-15,
        "{cost}"
    );
    let r = report::build(&lines).expect("one run's lines");
    let pefa = r.costs.iter().find(|c| c.method == "pefa").expect("a row");
    assert_eq!((pefa.prompt_tokens, pefa.cached_tokens), (4000, 3300));
    assert_eq!(pefa.cached_share, Some(0.825));
    assert!(
        report::markdown(&r).contains("| 0.82 |"),
        "{}",
        report::markdown(&r)
    );
    let csv = report::csv(&r);
    let row = csv
        .lines()
        .find(|l| l.starts_with("costs,pefa,"))
        .expect("a costs row");
    assert!(row.ends_with(",0.825000"), "{row}");
}
