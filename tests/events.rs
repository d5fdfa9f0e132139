//! Events from the command line (docs/dynamic.md): `coherent run --events FILE`, bad
//! events refused before the episode starts with the file, the JSON path and the value
//! (exit 2), events where they cannot run yet refused, and `coherent generate
//! --variants-of` writing the dynamic variants that `coherent bench` runs, its lines and
//! report carrying the reference.

use std::collections::{HashSet, VecDeque};
use std::path::Path;
use std::sync::Arc;

use coherent_agents::episode::prove;
use coherent_core::planner::Limits;
use coherent_core::{Execution, JsonPath, Schedule, State, Task, events, rules};
use coherent_generate::variants::variants;

mod common;

use common::{DEMO_KINDS, coherent, json_lines, scratch, show, utf8};

const DEMO: &str = "examples/tasks/demo.json";

fn events_file(dir: &Path, text: &str) -> String {
    let path = dir.join("events.json");
    std::fs::write(&path, text).expect("written");
    utf8(&path).to_owned()
}

#[test]
fn a_run_with_events_ends_in_the_reference_steps_and_its_transcript_says_what_happened() {
    let dir = scratch("events-run");
    let events = events_file(
        &dir,
        r#"{"events": [{"step": 3, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]}"#,
    );
    let runs = dir.join("runs");
    let out = coherent(&["run", DEMO, "--events", &events, "--out", utf8(&runs)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let lines = transcript_in(&runs);
    let summary = lines.last().expect("a summary");
    let reference = &summary["reference"];
    assert_eq!(summary["steps"], reference["steps"], "{summary}");
    assert_eq!(reference["kinds"], serde_json::json!(["object_moved"]));
    let round = &lines[3];
    assert_eq!(round["step"], 3);
    assert_eq!(
        round["events"][0]["told"],
        "Someone outside the team moved <apple>(9) onto <sofa>(14)."
    );
    // The task in the header has the events, so that a replay needs nothing else.
    assert_eq!(lines[0]["task"]["events"][0]["kind"], "object_moved");
}

#[test]
fn bad_events_are_refused_before_the_episode_naming_the_file_the_path_and_the_value() {
    let dir = scratch("events-bad");
    let cases = [
        (
            r#"[{"step": 3, "kind": "robot_down", "robot": 7}]"#,
            "$[0].robot: node 7 (<mug>(7)) is not a robot",
        ),
        (
            r#"[{"step": 3, "kind": "robot_down", "robot": 99}]"#,
            "$[0].robot: unknown node id 99",
        ),
        (
            r#"[{"step": 3, "kind": "meteor"}]"#,
            "$[0].kind: unknown event kind \"meteor\"",
        ),
        (
            r#"[{"step": 45, "kind": "robot_down", "robot": 13}]"#,
            "$[0].step: step 45 is past the episode's step budget (44)",
        ),
        (
            r#"[{"step": 2, "kind": "goal_changed", "add": [{"relation": "ON", "subject": 9, "target": 77}], "instruction": "x"}]"#,
            "$[0].add[0].target: unknown node id 77",
        ),
        (
            r#"[{"step": 2, "kind": "action_fails", "probability": 1.5}]"#,
            "$[0].probability: probability 1.5",
        ),
    ];
    for (text, expected) in cases {
        let events = events_file(&dir, text);
        let out = coherent(&["run", DEMO, "--events", &events, "--out", utf8(&dir)]);
        assert_eq!(out.status.code(), Some(2), "{text}: {}", show(&out));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&events), "{text}: {err}");
        assert!(err.contains(expected), "{text}: {err}");
    }
    // Physics does not carry a robot to where it joins: it joins where the task has it.
    let events = events_file(
        &dir,
        r#"[{"step": 2, "kind": "robot_up", "robot": 13, "room": 0}]"#,
    );
    let out = in_physics(&events, &dir);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "{events}: $[0].room: physics does not carry a robot"
        )),
        "{err}"
    );
}

/// The lines of the one transcript a run wrote into `runs`.
fn transcript_in(runs: &Path) -> Vec<serde_json::Value> {
    let file = std::fs::read_dir(runs)
        .expect("runs")
        .next()
        .expect("a transcript");
    json_lines(&file.expect("an entry").path())
}

/// `coherent run` of the demo with the events in file `events`, in Rapier.
fn in_physics(events: &str, out: &Path) -> std::process::Output {
    coherent(&[
        "run",
        DEMO,
        "--events",
        events,
        "--physics",
        "--out",
        utf8(out),
    ])
}

/// One event of each kind on the demo task in Rapier ([`DEMO_KINDS`]): the built-in
/// backend ends in the reference steps, the bodies agreeing with the rules after every
/// step and every event (a disagreement is a failed step).
#[test]
fn every_kind_of_event_runs_in_physics_in_the_reference_steps() {
    let dir = scratch("events-physics");
    for (i, (kind, text)) in DEMO_KINDS.into_iter().enumerate() {
        let events = events_file(&dir, text);
        let runs = dir.join(format!("{i}-{kind}"));
        let out = in_physics(&events, &runs);
        assert_eq!(out.status.code(), Some(0), "{kind}: {}", show(&out));
        let lines = transcript_in(&runs);
        let summary = lines.last().expect("a summary");
        assert_eq!(summary["status"], "success", "{kind}: {summary}");
        assert_eq!(
            summary["steps"], summary["reference"]["steps"],
            "{kind}: {summary}"
        );
        let happened = lines
            .iter()
            .filter_map(|l| l["events"].as_array())
            .flatten()
            .count();
        assert!(happened >= 1, "{kind}: no event happened");
        // Every step was carried out in Rapier: none failed but by an event.
        for l in &lines[1..lines.len() - 1] {
            assert!(
                !l.to_string().contains("physics:"),
                "{kind}: a physical failure: {l}"
            );
        }
    }
}

#[test]
fn dynamic_variants_are_written_and_benchmarked_against_their_reference() {
    let dir = scratch("events-variants");
    let variants = dir.join("variants");
    let out = coherent(&["generate", "--variants-of", DEMO, "--out", utf8(&variants)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let manifest = json_lines(&variants.join("manifest.jsonl"));
    let kinds: Vec<&str> = manifest.iter().filter_map(|l| l["kind"].as_str()).collect();
    assert_eq!(
        kinds,
        [
            "robot_down",
            "robot_up",
            "object_moved",
            "goal_changed",
            "blocked",
            "action_fails"
        ]
    );
    let results = dir.join("results.jsonl");
    let out = coherent(&[
        "bench",
        "--tasks",
        utf8(&variants),
        "--methods",
        "pefa,optimal",
        "--out",
        utf8(&results),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        report.contains("### Events: success and recovery"),
        "{report}"
    );
    for line in json_lines(&results) {
        let reference = &line["reference"];
        assert!(line["success"].as_bool().expect("success"), "{line}");
        if line["status"] == "success" {
            assert_eq!(line["steps"], reference["steps"], "{line}");
            // A variant's ground truth is its reference (failing actions aside: their
            // draws are the episode's).
            if reference["kinds"][0] != "action_fails" {
                assert_eq!(line["gt_steps"], line["steps"], "{line}");
            }
        } else {
            assert_eq!(line["status"], "conceded", "{line}");
            assert!(reference["unreachable"].is_string(), "{line}");
        }
    }
}

/// The fewest steps from `s` to `task`'s goal by breadth-first search over every action
/// of every robot of its team (`None`: no state reached holds it), or `Err` once the
/// search has seen `max` states.
fn bfs(task: &Task, s: &State, max: usize) -> Result<Option<u32>, usize> {
    let mut seen: HashSet<State> = HashSet::from([s.clone()]);
    let mut queue = VecDeque::from([(s.clone(), 0u32)]);
    while let Some((state, d)) = queue.pop_front() {
        if task.goal_satisfied(&state) {
            return Ok(Some(d));
        }
        for r in &task.robots {
            for a in rules::actions(task, &state, *r) {
                let mut next = state.clone();
                rules::apply(task, &mut next, *r, a);
                if seen.insert(next.clone()) {
                    queue.push_back((next, d + 1));
                }
            }
        }
        if seen.len() >= max {
            return Err(seen.len());
        }
    }
    Ok(None)
}

/// What comparing the optimum with a breadth-first search found: states compared, and
/// states where the search stopped at its limit first.
#[derive(Default)]
struct Compared {
    equal: usize,
    beyond: usize,
}

/// Follows an optimal plan of `task`'s world as it is at each step; at the start and
/// after each event, the optimum the episode reports (`prove`) must equal a breadth-first
/// search from that state (up to `max` states).
fn compare_with_bfs(task: &Arc<Task>, max: usize, what: &str) -> Compared {
    let limits = Limits::default();
    let mut schedule = Schedule::new(Arc::clone(task));
    let mut state = task.init.clone();
    let mut out = Compared::default();
    let budget = 2 * task.meta.gt_steps.unwrap_or(20).max(10);
    for step in 1..=budget {
        let changes = schedule.before_step(step, &mut state);
        let world = schedule.world();
        if !changes.is_empty() || step == 1 {
            let proof = prove(&world, &state, &limits, Execution::Sequential);
            match bfs(&world, &state, max) {
                Ok(steps) => {
                    assert_eq!(proof.steps, steps, "{what} at step {step}: {proof:?}");
                    out.equal += 1;
                }
                Err(_) => out.beyond += 1,
            }
        }
        if world.goal_satisfied(&state) {
            break;
        }
        let plan = coherent_core::planner::search_from(
            &world,
            &state,
            &world.robots,
            &world.goal,
            &limits,
        )
        .plan;
        match plan.as_deref() {
            Some([first, ..]) => {
                let robot = world.robot(first.robot).copied().expect("a team robot");
                rules::apply(&world, &mut state, robot, first.action);
            }
            _ if schedule.may_help_later() => {}
            _ => break,
        }
    }
    out
}

/// The dynamic variants of the released tasks, every `every`-th task of each scene.
fn released_variants(every: usize) -> Vec<(String, Arc<Task>)> {
    let mut out = Vec::new();
    for scene in ["env0", "env1", "env2", "env3"] {
        let path = common::released().join(format!("{scene}.json"));
        let tasks = coherent_core::read_tasks(&path).expect("the released tasks");
        // The file's one malformed task (a node id twice) is not a task.
        for task in tasks.iter().flatten().step_by(every) {
            for v in variants(task, &Limits::default()) {
                let what = format!("{scene} task {} {}", task.meta.task_id, v.kind);
                out.push((what, Arc::new(v.task)));
            }
        }
    }
    out
}

#[test]
fn the_optimum_after_each_event_is_what_a_breadth_first_search_finds() {
    for (kind, text) in DEMO_KINDS {
        let list: serde_json::Value = serde_json::from_str(text).expect("JSON");
        let mut task = coherent_core::load_tasks(Path::new(DEMO))
            .expect("the demo")
            .remove(0);
        task.events = events::read(&task, &list, kind, JsonPath::root()).expect("events");
        let c = compare_with_bfs(&Arc::new(task), 3_000_000, kind);
        assert!(
            c.equal >= 2 && c.beyond == 0,
            "{kind}: at the start and after the event"
        );
    }

    // A sample of the released tasks' variants: every twelfth task of each scene.
    let mut total = Compared::default();
    for (what, task) in released_variants(12) {
        let c = compare_with_bfs(&task, 200_000, &what);
        total.equal += c.equal;
        total.beyond += c.beyond;
    }
    println!(
        "{} compared, {} beyond the search's limit",
        total.equal, total.beyond
    );
    assert!(
        total.equal >= 30,
        "{} compared, {} beyond",
        total.equal,
        total.beyond
    );
}

/// Every variant of every released task (minutes): the counts for the notes, with
/// `cargo test --release --test events -- --ignored --nocapture`.
#[test]
#[ignore]
fn every_released_variant_against_a_breadth_first_search() {
    let variants = released_variants(1);
    let mut total = Compared::default();
    for (what, task) in &variants {
        let c = compare_with_bfs(task, 5_000_000, what);
        total.equal += c.equal;
        total.beyond += c.beyond;
    }
    println!(
        "{} variants: {} optima equal to a breadth-first search, {} beyond its 5,000,000 states, none differ",
        variants.len(),
        total.equal,
        total.beyond
    );
}
