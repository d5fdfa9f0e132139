//! `--execution parallel` on the command line: `coherent run` prints a joint step as a
//! line for the step and a line per robot, reports the makespan and the actions in its
//! summary and `--json`, and replays; the tree searches refuse it; `coherent bench
//! --execution sequential,parallel` runs every method both ways as one run (its
//! executions a setting), resumes by execution,
//! and its report compares them; with physics, the simulated seconds.

mod common;

use std::path::Path;

use common::{coherent, demo, json_lines, scratch, show, utf8};
use serde_json::{Value, json};

fn code(out: &std::process::Output) -> i32 {
    out.status.code().unwrap_or(-1)
}

fn stdout(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn run_parallel_prints_each_robots_part_reports_the_makespan_and_replays() {
    let dir = scratch("run-parallel");
    let out = coherent(&[
        "run",
        utf8(&demo()),
        "--execution",
        "parallel",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let text = stdout(&out);
    let printed: Vec<&str> = text.lines().collect();
    assert!(
        printed[1].contains("| method pefa | execution parallel |"),
        "{text}"
    );
    assert!(
        printed[1].ends_with("budget 26 joint steps (2 x the optimal makespan)"),
        "{text}"
    );
    assert_eq!(printed[2], "step  1/26  joint step, 3 robots  -> ok");
    assert_eq!(printed[3], "  <robot arm>(6)  [grab] <mug>(7)  -> ok");
    assert_eq!(
        printed[4],
        "  <quadrotor>(11)  [takeoff_from] <living room floor>(3)  -> ok"
    );
    assert_eq!(
        printed[5],
        "  <robot dog>(13)  [movetowards] <door>(4)  -> ok"
    );
    assert!(
        text.contains("step 13/26  joint step, 1 robot  -> ok, goal reached"),
        "{text}"
    );
    assert!(
        text.contains("success | goal holds | makespan 13 joint steps, 22 actions (GT 22 sequential steps, budget 26) | LLM calls 35 |"),
        "{text}"
    );

    let out = coherent(&[
        "run",
        utf8(&demo()),
        "--execution",
        "parallel",
        "--method",
        "cmrs",
        "--json",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let summary: Value = serde_json::from_str(stdout(&out).trim()).expect("a JSON summary");
    assert_eq!(summary["execution"], json!("parallel"));
    assert_eq!(summary["makespan"], json!(13));
    assert_eq!(summary["actions"], json!(22));
    assert_eq!(summary["llm_calls"], json!(13), "one central call a step");
    assert_eq!(summary["sim_seconds"], Value::Null);
    let transcript = summary["transcript"].as_str().expect("a path");
    let records = json_lines(Path::new(transcript));
    assert!(
        records.iter().all(|r| r.get("sim_seconds").is_none()),
        "no simulated time without physics"
    );
    assert_eq!(records[0]["execution"], json!("parallel"));
    let first = &records[1];
    assert_eq!(first["parts"].as_array().map(Vec::len), Some(3));
    assert_eq!(first["parts"][0]["robot"], json!(6));
    assert_eq!(
        first["parts"][0]["decision"]["action"],
        json!("[grab] <mug>(7)")
    );
    assert_eq!(first["parts"][0]["outcome"], json!({"kind": "executed"}));

    let again = coherent(&["run", "--replay", transcript, "--out", utf8(&dir)]);
    assert_eq!(code(&again), 0, "{}", show(&again));
    assert!(
        stdout(&again).contains("replay: all 13 rounds match the recording"),
        "{}",
        show(&again)
    );
    let refused = coherent(&[
        "run",
        "--replay",
        transcript,
        "--execution",
        "parallel",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(code(&refused), 2, "{}", show(&refused));
}

#[test]
fn the_tree_searches_refuse_parallel_execution() {
    let dir = scratch("mcts-parallel");
    for method in ["mcts", "llm-mcts"] {
        let out = coherent(&[
            "run",
            utf8(&demo()),
            "--execution",
            "parallel",
            "--method",
            method,
            "--out",
            utf8(&dir),
        ]);
        assert_eq!(code(&out), 2, "{}", show(&out));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!("{method} is sequential only")),
            "{err}"
        );
    }
    let out = coherent(&[
        "bench",
        "--tasks",
        utf8(&demo()),
        "--methods",
        "pefa,mcts",
        "--execution",
        "sequential,parallel",
        "--out",
        utf8(&dir.join("r.jsonl")),
    ]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(!dir.join("r.jsonl").exists(), "nothing ran");
}

#[test]
fn bench_runs_each_method_both_ways_as_one_run_resumes_by_execution_and_compares_them() {
    let dir = scratch("bench-parallel");
    let results = dir.join("r.jsonl");
    let bench = |executions: &str| {
        coherent(&[
            "bench",
            "--tasks",
            utf8(&demo()),
            "--methods",
            "pefa,optimal",
            "--execution",
            executions,
            "--out",
            utf8(&results),
        ])
    };
    let out = bench("sequential");
    assert_eq!(code(&out), 0, "{}", show(&out));
    assert!(
        !stdout(&out).contains("Makespan"),
        "no parallel episode, no makespan table"
    );
    assert!(
        json_lines(&results)
            .iter()
            .all(|l| l["settings"].get("executions").is_none()),
        "a sequential run records its settings as before parallel episodes"
    );
    // The executions are a setting of the run: a sequential run's file is not resumed
    // by a run of both, whose tables would count two runs as one.
    let out = bench("sequential,parallel");
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(
        show(&out).contains("--execution: sequential in the file, sequential,parallel now"),
        "{}",
        show(&out)
    );
    std::fs::remove_file(&results).expect("removed");
    let out = bench("sequential,parallel");
    assert_eq!(code(&out), 0, "{}", show(&out));
    let written = json_lines(&results);
    assert_eq!(written.len(), 4);
    for l in &written {
        let parallel = l["execution"] == json!("parallel");
        assert_eq!(
            l["settings"]["executions"],
            json!(["sequential", "parallel"])
        );
        assert_eq!(l["success"], json!(true), "{l}");
        assert_eq!(l["makespan"], json!(if parallel { 13 } else { 22 }), "{l}");
        assert_eq!(l["actions"], json!(22), "{l}");
        // A run with parallel episodes searches each task's makespan, which its
        // sequential lines are measured against too.
        assert_eq!(l["optimal_makespan"], json!(13), "{l}");
        assert_eq!(l["max_steps"], json!(if parallel { 26 } else { 44 }), "{l}");
    }
    // An episode is known by its execution too: without its parallel PEFA line, the
    // file resumes with that episode alone.
    let kept: Vec<String> = std::fs::read_to_string(&results)
        .expect("results")
        .lines()
        .filter(|l| {
            let v: Value = serde_json::from_str(l).expect("a line");
            !(v["method"] == json!("pefa") && v["execution"] == json!("parallel"))
        })
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&results, kept.concat()).expect("written");
    let out = bench("sequential,parallel");
    assert_eq!(code(&out), 0, "{}", show(&out));
    assert!(
        stdout(&out).contains("4 episodes: 3 already finished, 1 finished now, 0 unfinished"),
        "{}",
        show(&out)
    );
    assert_eq!(json_lines(&results).len(), 4);
    // Its tables: a row per method and execution, and the makespan table.
    let report = coherent(&["bench", "--report", utf8(&results)]);
    let text = stdout(&report);
    assert!(
        text.contains("| pefa (parallel) | - | - | 1.000 / 13.0 | 1.000 / 13.0 |"),
        "{text}"
    );
    assert!(text.contains("### Makespan: steps to the goal with robots acting at once"));
    assert!(
        text.contains(
            "| pefa (parallel) | Trio | 1 | 1.000 | 13.0 | 13.0 | 22.0 | 1.59 | - | 1.69x (n=1) |"
        ),
        "{text}"
    );
    let csv = stdout(&coherent(&[
        "bench",
        "--report",
        utf8(&results),
        "--format",
        "csv",
    ]));
    let header = csv.lines().next().expect("a header");
    assert!(header.ends_with(
        ",execution,makespan,optimal_makespan,actions,calls_per_action,sim_seconds,speedup"
    ));
    // The settings column is quoted, its commas inside the quotes.
    let fields = |l: &str| {
        l.split('"')
            .step_by(2)
            .map(|outside| outside.matches(',').count())
            .sum::<usize>()
            + 1
    };
    let columns = fields(header);
    assert!(csv.lines().all(|l| fields(l) == columns), "{csv}");
    assert!(header.contains(",seeds,backend,settings,cached_share,execution,"));
    assert!(
        csv.lines()
            .any(|l| l.starts_with("makespan,optimal (parallel),trio,"))
    );
    let json: Value = serde_json::from_str(&stdout(&coherent(&[
        "bench",
        "--report",
        utf8(&results),
        "--format",
        "json",
    ])))
    .expect("JSON");
    let rows = json["makespan"].as_array().expect("the makespan table");
    assert_eq!(rows.len(), 8, "two methods, two executions, trio and Avg");
}

#[test]
fn a_parallel_episode_in_physics_reports_its_simulated_seconds() {
    let dir = scratch("physics-parallel");
    let out = coherent(&[
        "run",
        utf8(&demo()),
        "--execution",
        "parallel",
        "--method",
        "optimal",
        "--physics",
        "--json",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let summary: Value = serde_json::from_str(stdout(&out).trim()).expect("a JSON summary");
    assert_eq!(summary["makespan"], json!(13));
    let seconds = summary["sim_seconds"].as_f64().expect("simulated seconds");
    assert!(seconds > 10.0, "{seconds}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("simulated {seconds:.2} s")), "{err}");
    // Each joint step's own, which add up to the episode's but for the world settling
    // before the first step.
    let transcript = summary["transcript"].as_str().expect("a path");
    let steps: Vec<f64> = json_lines(Path::new(transcript))
        .iter()
        .filter(|r| r["type"] == "round")
        .map(|r| {
            r["sim_seconds"]
                .as_f64()
                .expect("a round's simulated seconds")
        })
        .collect();
    assert_eq!(steps.len(), 13);
    assert!(steps.iter().all(|s| *s > 0.0), "{steps:?}");
    let settling = seconds - steps.iter().sum::<f64>();
    assert!((0.0..1.0).contains(&settling), "{steps:?} {seconds}");
}

#[test]
fn a_task_no_plan_solves_runs_in_parallel_within_twice_its_ground_truth_and_fails() {
    // env3 task 0 cannot be solved: the makespan search finds no plan to size the budget
    // from, so the episode gets the sequential rule's, and spends it.
    let dir = scratch("run-parallel-unsolvable");
    let env3 = common::released().join("env3.json");
    let out = coherent(&[
        "run",
        utf8(&env3),
        "--task",
        "0",
        "--execution",
        "parallel",
        "--json",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(code(&out), 1, "{}", show(&out));
    let summary: Value =
        serde_json::from_str(stdout(&out).lines().last().expect("the --json summary"))
            .expect("JSON");
    let gt = summary["gt_steps"].as_u64().expect("the task's GT");
    assert_eq!(summary["max_steps"].as_u64(), Some(2 * gt));
    assert_eq!(summary["status"], "failure");
    assert_eq!(summary["makespan"], Value::Null);
}
