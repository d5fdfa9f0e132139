//! Events from the command line (docs/dynamic.md): `coherent run --events FILE`, bad
//! events refused before the episode starts with the file, the JSON path and the value
//! (exit 2), events where they cannot run yet refused, and `coherent generate
//! --variants-of` writing the dynamic variants that `coherent bench` runs, its lines and
//! report carrying the reference.

use std::path::Path;

mod common;

use common::{coherent, json_lines, scratch, show, utf8};

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
    let file = std::fs::read_dir(&runs)
        .expect("runs")
        .next()
        .expect("a transcript");
    let lines = json_lines(&file.expect("an entry").path());
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
    let events = events_file(&dir, r#"[{"step": 2, "kind": "robot_down", "robot": 13}]"#);
    let out = coherent(&[
        "run",
        DEMO,
        "--events",
        &events,
        "--physics",
        "--out",
        utf8(&dir),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("physics does not carry events out"));
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
