//! Events over ROS 2 (docs/dynamic.md, docs/robots.md): `coherent run --events FILE
//! --robots ros2` against `coherent robots serve`, separate processes in a network
//! namespace of the test's own. The bridge tells the world's service,
//! `/<namespace>/befall`, what each event changed; the servers carry it out in their
//! world (the rules, or Rapier) and answer where each thing moved now is.

mod common;

use std::process::Command;

use common::netns::{LONG, Netns, Proc, Transcript, transcript};
use common::{DEMO_KINDS, show};
use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_coherent");

/// What each round proposed and decided: a run's course, rounds without a proposal too.
fn course(t: &Transcript) -> Vec<(Value, Value)> {
    t.rounds
        .iter()
        .map(|r| (r["proposal"].clone(), r["decision"].clone()))
        .collect()
}

/// `coherent run TASK --events EVENTS --robots ros2 --namespace NAMESPACE --out OUT` in
/// the namespace, started as `name`.
fn run_over_ros2(
    ns: &Netns,
    name: &str,
    task: &str,
    events: &str,
    namespace: &str,
    out: &str,
) -> Proc {
    let args = [
        "run",
        task,
        "--events",
        events,
        "--robots",
        "ros2",
        "--namespace",
        namespace,
        "--out",
        out,
    ];
    ns.spawn(name, &args)
}

/// Each kind of event on the demo ([`DEMO_KINDS`]), the servers acting by the rules and
/// in Rapier: the run over ROS 2 goes round by round as the run without the bridge does
/// and ends in the reference steps, and the servers' world carried each event out (the
/// team, the locked doors, the things moved, in its log), refusing nothing.
#[test]
fn every_kind_of_event_runs_over_ros2_as_it_runs_without_the_bridge() {
    let ns = Netns::new("events");
    let demo = common::demo().display().to_string();
    for (i, (kind, text)) in DEMO_KINDS.into_iter().enumerate() {
        let events = ns.path(&format!("events-{i}.json"));
        std::fs::write(&events, text).expect("written");
        let local = ns.path(&format!("local-{i}"));
        let out = Command::new(BIN)
            .args(["run", &demo, "--events", &events, "--out", &local])
            .output()
            .expect("coherent runs");
        assert_eq!(out.status.code(), Some(0), "{kind}: {}", show(&out));
        let expected = course(&transcript(&local));
        for physics in [false, true] {
            let world = if physics { "physics" } else { "rules" };
            let namespace = format!("/events{i}/{world}");
            let mut serve_args = vec!["robots", "serve", &demo, "--namespace", &namespace];
            if physics {
                serve_args.push("--physics");
            }
            let mut server = ns.spawn(&format!("serve-{i}-{world}"), &serve_args);
            let runs = ns.path(&format!("runs-{i}-{world}"));
            let name = format!("run-{i}-{world}");
            let mut run = run_over_ros2(&ns, &name, &demo, &events, &namespace, &runs);
            assert_eq!(
                run.wait(LONG),
                0,
                "{kind} {world}\n{}\n{}",
                run.show(),
                server.show()
            );
            let t = transcript(&runs);
            assert_eq!(
                course(&t),
                expected,
                "{kind} {world}: as without the bridge"
            );
            assert_eq!(t.summary["status"], "success", "{kind} {world}");
            assert_eq!(
                t.summary["steps"], t.summary["reference"]["steps"],
                "{kind} {world}"
            );
            server.signal("TERM");
            assert_eq!(server.wait(LONG), 0, "{}", server.show());
            let log = server.stdout();
            let told: Vec<&str> = log
                .lines()
                .filter(|l| l.starts_with("events before step"))
                .collect();
            assert!(
                !told.is_empty(),
                "{kind} {world}: the world is told at the start\n{log}"
            );
            assert!(
                told.iter().all(|l| l.contains(" -> done: the team: ")),
                "{kind} {world}: nothing refused\n{log}"
            );
            let seen = |what: &str| told.iter().any(|l| l.contains(what));
            match kind {
                "robot_down" => assert!(seen("the team: quadrotor_11, robot_dog_13;"), "{log}"),
                "robot_up" => {
                    assert!(seen("the team: robot_arm_6, quadrotor_11;"), "{log}");
                    assert!(
                        seen("the team: robot_arm_6, quadrotor_11, robot_dog_13;"),
                        "{log}"
                    );
                }
                "object_moved" => assert!(seen("moved: <") && seen(" ON <sofa>(14)"), "{log}"),
                "blocked" => {
                    assert!(seen("doors locked: <door>(4);"), "{log}");
                    assert!(
                        told.last()
                            .is_some_and(|l| l.contains("doors locked: none;")),
                        "{log}"
                    );
                }
                _ => {}
            }
        }
    }
}

/// A world that cannot carry an event out (its task has no sofa to move the apple onto)
/// refuses it; the bridge stops as for a silent robot: exit 5, the transcript kept as
/// interrupted with the world's reason, and no round after the refusal asks anything.
#[test]
fn a_world_that_refuses_an_event_stops_the_run_saying_why() {
    let ns = Netns::new("events-refused");
    let demo = common::demo();
    let mut task: Value =
        serde_json::from_str(&std::fs::read_to_string(&demo).expect("the demo")).expect("JSON");
    let sofa = |v: &Value| v["id"] == 14 || v["from_id"] == 14 || v["to_id"] == 14;
    for list in ["nodes", "edges"] {
        let kept: Vec<Value> = task["graph"][list]
            .as_array()
            .expect("a list")
            .iter()
            .filter(|v| !sofa(v))
            .cloned()
            .collect();
        assert!(kept.len() < task["graph"][list].as_array().expect("a list").len());
        task["graph"][list] = Value::Array(kept);
    }
    let served = ns.path("no-sofa.json");
    std::fs::write(&served, task.to_string()).expect("written");
    let events = ns.path("events.json");
    let moved =
        r#"[{"step": 3, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]"#;
    std::fs::write(&events, moved).expect("written");
    let mut server = ns.spawn(
        "serve",
        &["robots", "serve", &served, "--namespace", "/lab"],
    );
    let runs = ns.path("runs");
    let demo = demo.display().to_string();
    let mut run = run_over_ros2(&ns, "run", &demo, &events, "/lab", &runs);
    assert_eq!(run.wait(LONG), 5, "{}\n{}", run.show(), server.show());
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted", "{:?}", t.summary);
    let error = t.summary["error"].as_str().expect("the reason");
    assert!(
        error.starts_with("the world (/lab/befall) refused the events: ")
            && error.contains("<sofa>(14)"),
        "{error}"
    );
    assert_eq!(
        t.rounds.len(),
        2,
        "the run ends before round 3 asks anything"
    );
    server.signal("TERM");
    assert_eq!(server.wait(LONG), 0, "{}", server.show());
}
