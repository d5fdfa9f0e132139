//! `coherent view` on the command line: the pages it writes hold what they must, and bad
//! input is an error that names the file. (The pages in a real browser: the tests of
//! python/tests/test_view*.py.)

mod common;

use std::path::Path;

use common::{coherent, demo, embedded, scratch, show, utf8};
use serde_json::Value;

/// `coherent run` on the demo: its step lines and its transcript.
fn run_demo(dir: &Path, extra: &[&str]) -> (Vec<String>, String) {
    let demo = demo();
    let mut args = vec!["run", utf8(&demo), "--out", utf8(dir)];
    args.extend(extra);
    let out = coherent(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let steps = stdout
        .lines()
        .filter(|l| l.starts_with("step "))
        .map(str::to_owned)
        .collect();
    let transcript = stdout
        .lines()
        .find_map(|l| l.strip_prefix("transcript: "))
        .unwrap_or_else(|| panic!("no transcript line\n{}", show(&out)))
        .to_owned();
    (steps, transcript)
}

#[test]
fn an_episode_page_holds_the_step_lines_run_printed_and_a_scene_per_step() {
    let dir = scratch("view-episode");
    let (steps, transcript) = run_demo(&dir, &[]);
    let page = dir.join("demo.html");
    let out = coherent(&["view", &transcript, "-o", utf8(&page)]);
    assert!(out.status.success(), "{}", show(&out));
    let data = embedded(&page);
    let ep = &data["episodes"][0];
    let lines: Vec<&str> = ep["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .map(|s| s["line"].as_str().expect("a line"))
        .collect();
    assert_eq!(lines, steps);
    // The start, then one moment per step, each robot placed.
    let moments = ep["scene"]["moments"].as_array().expect("moments");
    assert_eq!(moments.len(), steps.len() + 1);
    assert!(
        moments
            .iter()
            .all(|m| m["robots"].as_array().expect("robots").len() == 3)
    );
    let html = std::fs::read_to_string(&page).expect("the page");
    assert!(html.contains("<template id=\"a-picture-0\"><svg"));
    assert!(
        html.contains(
            "Content-Security-Policy\" content=\"default-src 'none'; script-src 'sha256-"
        )
    );
}

#[test]
fn side_by_side_names_the_first_round_whose_decisions_differ() {
    let dir = scratch("view-compare");
    let (_, a) = run_demo(&dir.join("a"), &[]);
    let (_, b) = run_demo(
        &dir.join("b"),
        &["--sim-errors", "wrong_robot=0.5", "--seed", "4"],
    );
    let page = dir.join("both.html");
    let out = coherent(&["view", &a, &b, "-o", utf8(&page)]);
    assert!(out.status.success(), "{}", show(&out));
    let data = embedded(&page);
    assert_eq!(data["kind"], "compare");
    // Read here from the transcripts: the robot and the action of each round.
    let decided = |path: &str| -> Vec<(Value, Value)> {
        std::fs::read_to_string(path)
            .expect("a transcript")
            .lines()
            .map(|l| serde_json::from_str::<Value>(l).expect("JSON"))
            .filter(|r| r["type"] == "round")
            .map(|r| {
                (
                    r["proposal"]["robot"].clone(),
                    r["decision"]["action"].clone(),
                )
            })
            .collect()
    };
    let (da, db) = (decided(&a), decided(&b));
    let expected = da
        .iter()
        .zip(&db)
        .position(|(x, y)| x != y)
        .or((da.len() != db.len()).then(|| da.len().min(db.len())))
        .map(|i| i as u64 + 1);
    assert!(expected.is_some(), "the two episodes decide differently");
    assert_eq!(data["first_difference"].as_u64(), expected);
}

#[test]
fn viewing_a_file_that_is_neither_a_transcript_nor_results_names_it() {
    let dir = scratch("view-bad");
    let bad = dir.join("notes.jsonl");
    std::fs::write(&bad, "this is not JSON\n").expect("write");
    let out = coherent(&["view", utf8(&bad)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(utf8(&bad)) && stderr.contains("line 1"),
        "{stderr}"
    );
    let missing = dir.join("missing.jsonl");
    let out = coherent(&["view", utf8(&missing)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(utf8(&missing)));
}

#[test]
fn the_robot_a_central_method_names_in_its_decision_is_the_one_that_moves() {
    // CMRS records `<robot label>: <action>` with no proposal.
    let dir = scratch("view-central");
    let (_, transcript) = run_demo(&dir, &["--method", "cmrs"]);
    let page = dir.join("cmrs.html");
    let out = coherent(&["view", &transcript, "-o", utf8(&page)]);
    assert!(out.status.success(), "{}", show(&out));
    let data = embedded(&page);
    let ep = &data["episodes"][0];
    let steps = ep["steps"].as_array().expect("steps");
    assert!(steps.iter().all(|s| s["robots"][0]["robot"].is_i64()));
    let moments = ep["scene"]["moments"].as_array().expect("moments");
    let at = |m: &Value, robot: &Value| {
        m["robots"]
            .as_array()
            .expect("robots")
            .iter()
            .find(|r| &r["id"] == robot)
            .map(|r| r["at"].clone())
    };
    let moves = steps
        .iter()
        .enumerate()
        .filter(|(k, s)| {
            let robot = &s["robots"][0]["robot"];
            at(&moments[*k], robot) != at(&moments[k + 1], robot)
        })
        .count();
    assert!(moves > 0, "the robots move");
    // coherent render draws their paths too.
    let svg = dir.join("cmrs.svg");
    let out = coherent(&["render", "--transcript", &transcript, "-o", utf8(&svg)]);
    assert!(out.status.success(), "{}", show(&out));
    let drawn = std::fs::read_to_string(&svg).expect("the picture");
    assert!(drawn.contains("class=\"path\""), "no path drawn");
}

#[test]
fn a_parallel_episode_page_shows_every_robots_part_of_each_joint_step() {
    let dir = scratch("view-parallel");
    let out = coherent(&[
        "run",
        utf8(&demo()),
        "--execution",
        "parallel",
        "--out",
        utf8(&dir),
    ]);
    assert!(out.status.success(), "{}", show(&out));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    // Each step as printed: its line, then its robots' indented lines under it.
    let mut printed: Vec<String> = Vec::new();
    for l in stdout.lines() {
        if l.starts_with("step ") {
            printed.push(l.to_owned());
        } else if l.starts_with("  ") {
            let step = printed.last_mut().expect("a robot's line under a step");
            step.push('\n');
            step.push_str(l);
        }
    }
    let transcript = stdout
        .lines()
        .find_map(|l| l.strip_prefix("transcript: "))
        .expect("the transcript line");
    let page = dir.join("parallel.html");
    let out = coherent(&["view", transcript, "-o", utf8(&page)]);
    assert!(out.status.success(), "{}", show(&out));
    let data = embedded(&page);
    let ep = &data["episodes"][0];
    assert_eq!(ep["header"]["execution"], "parallel");
    let steps = ep["steps"].as_array().expect("steps");
    let lines: Vec<&str> = steps
        .iter()
        .map(|s| s["line"].as_str().expect("a line"))
        .collect();
    assert_eq!(lines, printed);
    let rounds: Vec<Value> = std::fs::read_to_string(transcript)
        .expect("the transcript")
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("JSON"))
        .filter(|r| r["type"] == "round")
        .collect();
    let moments = ep["scene"]["moments"].as_array().expect("moments");
    let at = |m: &Value, robot: &Value| {
        let robots = m["robots"].as_array().expect("robots");
        let r = robots.iter().find(|r| &r["id"] == robot).expect("placed");
        r["at"]
            .as_array()
            .expect("drawn")
            .iter()
            .map(|v| v.as_f64().expect("a number"))
            .collect::<Vec<f64>>()
    };
    let mut together = 0;
    for (k, (step, round)) in steps.iter().zip(&rounds).enumerate() {
        let entries = step["robots"].as_array().expect("robots");
        let parts = round["parts"].as_array().expect("parts");
        assert!(!parts.is_empty(), "step {}: a robot with a subtask", k + 1);
        assert_eq!(
            entries.len(),
            parts.len(),
            "an entry per part, step {}",
            k + 1
        );
        let mut acted = 0;
        for (entry, part) in entries.iter().zip(parts) {
            assert_eq!(entry["robot"], part["robot"]);
            assert_eq!(entry["decision"]["action"], part["decision"]["action"]);
            let executed = part["outcome"]["kind"] == "executed";
            acted += usize::from(executed);
            let action = part["decision"]["action"].as_str().unwrap_or("");
            let (before, after) = (
                at(&moments[k], &part["robot"]),
                at(&moments[k + 1], &part["robot"]),
            );
            let moved = before
                .iter()
                .zip(&after)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                > 0.25;
            // A robot's own move takes it elsewhere; a landing may shift it onto the
            // surface below; nothing else moves a robot on the floor plan.
            if executed && action.starts_with("[movetowards]") {
                assert!(moved, "step {}: {action}", k + 1);
            }
            if moved {
                let its_own = ["[movetowards]", "[land_on]"]
                    .iter()
                    .any(|a| action.starts_with(a));
                assert!(executed && its_own, "step {}: {action}", k + 1);
            }
        }
        together += usize::from(acted >= 2);
    }
    assert!(together > 0, "some step moves several robots");
}
