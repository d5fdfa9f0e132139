//! A results file knows what it holds: `coherent bench` records each line's settings,
//! refuses to resume a file of other settings (naming each by its flag, before anything
//! runs, leaving the file as it was), resumes one of the same settings, and `--report`
//! gives each run of a file that holds several its own tables.

use std::path::Path;

mod common;

use common::{coherent, env0, scratch, show, utf8};

/// `bench` of paper40's env0 tasks with `methods` into `out`, and `more` flags.
fn bench(out: &Path, methods: &str, more: &[&str]) -> std::process::Output {
    let tasks = env0();
    let mut args = vec![
        "bench",
        "--tasks",
        utf8(&tasks),
        "--subset",
        "paper40",
        "--methods",
        methods,
        "--out",
        utf8(out),
    ];
    args.extend_from_slice(more);
    // The tasks path lives in `tasks`, which `args` borrows: run before it drops.
    coherent(&args)
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn stdout(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn resuming_with_other_settings_is_refused_naming_each_flag_and_nothing_runs() {
    let dir = scratch("settings-differ");
    let out = dir.join("results.jsonl");
    let first = bench(&out, "pefa", &["--backend", "builtin"]);
    assert_eq!(first.status.code(), Some(0), "{}", show(&first));
    let line: serde_json::Value = serde_json::from_str(
        std::fs::read_to_string(&out)
            .expect("results")
            .lines()
            .next()
            .expect("a line"),
    )
    .expect("JSON");
    let settings = &line["settings"];
    assert_eq!(settings["backend"], "builtin", "{line}");
    assert_eq!(settings["seeds"], 1, "{line}");
    assert_eq!(settings["history"], 5, "{line}");
    assert!(settings["max_steps"].is_null(), "{line}");
    assert_eq!(settings["coherent"], env!("CARGO_PKG_VERSION"), "{line}");
    let before = std::fs::read(&out).expect("results");

    // The case: the simulated backend at other error rates on the built-in file.
    let other = bench(
        &out,
        "pefa",
        &[
            "--backend",
            "simulated",
            "--sim-errors",
            "all=0.3",
            "--seeds",
            "2",
        ],
    );
    assert_eq!(other.status.code(), Some(2), "{}", show(&other));
    let err = stderr(&other);
    for said in [
        "holds episodes run with other settings",
        "--backend: builtin in the file, simulated now",
        "--sim-errors: none in the file, hallucinate=0.3,wrong_robot=0.3,malformed=0.3,suboptimal=0.3 now",
        "--seeds: 1 in the file, 2 now",
        "give this one another --out",
        "run with its settings",
    ] {
        assert!(err.contains(said), "no {said:?} in:\n{}", show(&other));
    }
    assert!(!err.contains("--history"), "{}", show(&other));
    assert!(
        !stdout(&other).contains("episodes:"),
        "nothing ran: {}",
        show(&other)
    );
    assert_eq!(
        std::fs::read(&out).expect("results"),
        before,
        "the file is as it was"
    );
    // A budget of its own is another setting too.
    let budget = bench(&out, "pefa", &["--backend", "builtin", "--max-steps", "30"]);
    assert_eq!(budget.status.code(), Some(2), "{}", show(&budget));
    assert!(
        stderr(&budget).contains("--max-steps: 2 x GT in the file, 30 now"),
        "{}",
        show(&budget)
    );

    // The same settings resume as before, and another method joins the same file.
    let again = bench(&out, "pefa,mcts", &["--backend", "builtin"]);
    assert_eq!(again.status.code(), Some(0), "{}", show(&again));
    assert!(
        stdout(&again).contains("16 episodes: 8 already finished, 8 finished now, 0 unfinished;"),
        "{}",
        show(&again)
    );
    assert!(
        stdout(&again).contains("Settings: backend builtin, sim_errors none, seeds 1"),
        "the tables say what they were computed with: {}",
        show(&again)
    );
}

#[test]
fn a_report_of_a_file_of_two_runs_gives_each_its_own_tables() {
    let dir = scratch("settings-report");
    let (a, b) = (dir.join("a.jsonl"), dir.join("b.jsonl"));
    let first = bench(&a, "pefa", &["--backend", "builtin"]);
    assert_eq!(first.status.code(), Some(0), "{}", show(&first));
    let second = bench(&b, "pefa", &["--sim-errors", "all=0.5", "--seeds", "2"]);
    assert_eq!(second.status.code(), Some(0), "{}", show(&second));
    // Two runs in one file, as earlier versions let resuming make them.
    let mixed = dir.join("mixed.jsonl");
    let mut text = std::fs::read_to_string(&a).expect("a");
    text.push_str(&std::fs::read_to_string(&b).expect("b"));
    std::fs::write(&mixed, text).expect("write");
    let report = coherent(&["bench", "--report", utf8(&mixed)]);
    assert_eq!(report.status.code(), Some(0), "{}", show(&report));
    let md = stdout(&report);
    assert!(
        md.contains("The results hold 2 runs of different settings"),
        "{md}"
    );
    assert!(
        md.contains("## Run 1 of 2") && md.contains("## Run 2 of 2"),
        "{md}"
    );
    assert!(
        md.contains("Settings: backend builtin, sim_errors none, seeds 1"),
        "{md}"
    );
    assert!(
        md.contains("Settings: backend simulated, sim_errors hallucinate=0.5"),
        "{md}"
    );
    // Each run's pefa row has its own numbers: the built-in backend solves all 8.
    let run1 = md.split("## Run 2 of 2").next().expect("run 1");
    assert!(run1.contains("| pefa | 1.000 / "), "{run1}");
    assert!(
        !run1.contains(" ± "),
        "one seed: no interval in run 1: {run1}"
    );
    let csv = coherent(&["bench", "--report", utf8(&mixed), "--format", "csv"]);
    let csv = stdout(&csv);
    assert_eq!(csv.matches("table,method,column").count(), 1, "{csv}");
    assert!(
        csv.lines()
            .next()
            .expect("header")
            .ends_with(",settings,cached_share"),
        "{csv}"
    );
    let json = coherent(&["bench", "--report", utf8(&mixed), "--format", "json"]);
    let value: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON");
    assert_eq!(value.as_array().map(Vec::len), Some(2), "{value}");
    assert_eq!(
        value[1]["settings"]["sim_errors"]
            .as_str()
            .map(|s| s.starts_with("hallucinate=0.5")),
        Some(true)
    );
}
