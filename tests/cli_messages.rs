//! Messages that help: a subset or a task id that does not exist is answered with the
//! valid ones, an unknown method with the methods, a transcript cut before its summary
//! replays as unfinished, `plan` takes several files, and the count of a benchmark's
//! episodes adds up.

mod common;

use common::{coherent, demo, env0, scratch, show, utf8};

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn stdout(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_subset_that_is_no_name_and_no_file_lists_the_subsets() {
    let dir = scratch("msg-subset");
    let out = dir.join("r.jsonl");
    let tasks = env0();
    let run = coherent(&[
        "bench",
        "--tasks",
        utf8(&tasks),
        "--subset",
        "paper41",
        "--methods",
        "pefa",
        "--out",
        utf8(&out),
    ]);
    assert_eq!(run.status.code(), Some(2), "{}", show(&run));
    assert!(
        stderr(&run).contains(
            "subset \"paper41\": no subset of that name (all, paper40, native40) and no file of that name"
        ),
        "{}",
        show(&run)
    );
    assert!(!out.exists(), "nothing ran");
}

#[test]
fn a_task_id_that_is_not_there_lists_the_ids() {
    let tasks = env0();
    let run = coherent(&["run", utf8(&tasks), "--task", "99"]);
    assert_eq!(run.status.code(), Some(2), "{}", show(&run));
    assert!(
        stderr(&run).contains("no well-formed task with task_id 99; its task ids: 0-"),
        "{}",
        show(&run)
    );
    let several = coherent(&["run", utf8(&tasks)]);
    assert_eq!(several.status.code(), Some(2), "{}", show(&several));
    assert!(
        stderr(&several).contains("choose one with --task ID (its task ids: 0-"),
        "{}",
        show(&several)
    );
    let plan = coherent(&["plan", utf8(&tasks), "--task", "99"]);
    assert_eq!(plan.status.code(), Some(2), "{}", show(&plan));
    assert!(
        stderr(&plan).contains("no task with task_id 99; its task ids: 0-"),
        "{}",
        show(&plan)
    );
}

#[test]
fn an_unknown_method_lists_the_methods() {
    let run = coherent(&["run", utf8(&demo()), "--method", "pefa2"]);
    assert_eq!(run.status.code(), Some(2), "{}", show(&run));
    assert!(
        stderr(&run).contains("the methods are pefa, "),
        "{}",
        show(&run)
    );
}

#[test]
fn plan_takes_several_files_as_validate_does() {
    let (demo, tasks) = (demo(), env0());
    let run = coherent(&["plan", utf8(&demo), utf8(&tasks), "--json"]);
    assert_eq!(run.status.code(), Some(0), "{}", show(&run));
    let text = stdout(&run);
    let lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    let one = coherent(&["plan", utf8(&tasks), "--json"]);
    assert_eq!(
        lines.len(),
        1 + stdout(&one).lines().count(),
        "the demo's plan and every env0 plan: {}",
        show(&run)
    );
}

#[test]
fn a_transcript_cut_before_its_summary_replays_as_unfinished() {
    let dir = scratch("msg-unfinished");
    let runs = dir.join("runs");
    let run = coherent(&["run", utf8(&demo()), "--out", utf8(&runs), "--json"]);
    assert_eq!(run.status.code(), Some(0), "{}", show(&run));
    let summary: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    let path = summary["transcript"]
        .as_str()
        .expect("a transcript")
        .to_owned();
    // As SIGTERM leaves it: the rounds so far, no summary line.
    let text = std::fs::read_to_string(&path).expect("transcript");
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.contains("\"type\":\"summary\""))
        .collect();
    let rounds = kept.len() - 1;
    let cut = dir.join("cut.jsonl");
    std::fs::write(&cut, kept.join("\n") + "\n").expect("write");
    let replay = coherent(&["run", "--replay", utf8(&cut), "--out", utf8(&runs)]);
    assert_eq!(replay.status.code(), Some(2), "{}", show(&replay));
    assert!(
        stderr(&replay).contains(&format!(
            "unfinished: the episode was stopped after {rounds} rounds"
        )),
        "{}",
        show(&replay)
    );
}

#[test]
fn plan_in_physics_over_many_tasks_tells_how_far_it_is() {
    let tasks = env0();
    let run = coherent(&["plan", utf8(&tasks), "--physics", "--json"]);
    let n = stdout(&run).lines().count();
    assert!(n > 10, "{}", show(&run));
    // Not a terminal: a line before every tenth of the tasks, with the time left.
    let told: Vec<String> = stderr(&run)
        .lines()
        .filter(|l| l.starts_with("planning in physics: "))
        .map(str::to_owned)
        .collect();
    assert_eq!(
        told.first().map(String::as_str),
        Some(format!("planning in physics: 0/{n} tasks, -, - left").as_str()),
        "{}",
        show(&run)
    );
    assert!(told.len() >= 5, "{}", show(&run));
    assert!(
        told[1].contains(" s/task, ") && told[1].ends_with(" left"),
        "{}",
        show(&run)
    );
}
