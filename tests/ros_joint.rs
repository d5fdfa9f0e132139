//! Joint steps over ROS 2: the bridge sends a step's goals at once and awaits them
//! together, so a step lasts as long as its slowest robot; a robot that fails, refuses
//! or falls silent is its own part of the step's outcome; Ctrl-C cancels every goal in
//! flight.
//!
//! The bridge is driven directly, through the session's environment: the test binary
//! runs itself inside the test's network namespace (`common::netns`), that test alone
//! with [`INSIDE`] set to what it should play, connects to `coherent robots serve`
//! there, plays the demo's makespan-optimal plan (or its sequential optimum) and writes
//! what happened, timed, as JSON to a file that the test outside reads and judges.

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use coherent::session::engine::{Cancel, Limits, NodeId, Task};
use coherent::session::episode::environment;
use coherent::session::robots::Robots;
use coherent_core::{feasibility, makespan, planner, rules};
use common::netns::{LONG, Netns, Proc};
use serde_json::{Value, json};

/// Set for the test binary run inside the namespace: what it plays, as JSON.
const INSIDE: &str = "COHERENT_TEST_INSIDE_NETNS";
/// Each action's length on the servers, in seconds.
const DELAY: f64 = 0.5;

fn demo() -> Arc<Task> {
    let path = common::demo();
    Arc::new(coherent::session::tasks::pick_task(&path, None).expect("the demo task"))
}

/// The demo's plan as steps of `(robot, action)`: its makespan-optimal plan, or its
/// sequential optimum one action a step.
fn plan(task: &Task, joint: bool) -> Vec<Vec<(NodeId, String)>> {
    let limits = Limits::default();
    let label = |step: &planner::Step| {
        let r = task.robot(step.robot).expect("a robot of the task");
        (task.id(r.node), step.action.render(task))
    };
    if joint {
        let found = makespan::search(task, &task.robots, &task.goal, &limits);
        assert!(found.proven, "the demo's makespan is proven");
        let steps = found.plan.expect("a joint plan");
        steps
            .iter()
            .map(|s| s.iter().map(label).collect())
            .collect()
    } else {
        let found = planner::search(task, &task.robots, &task.goal, &limits);
        let steps = found.plan.expect("a plan");
        steps.iter().map(|s| vec![label(s)]).collect()
    }
}

/// Inside the namespace: connects to the robots under `what["namespace"]` and plays the
/// plan (joint steps through `step_joint`, or one action a step through `step`) until
/// the goal, a step with a part not carried out, or the bridge stopping; with
/// `cancel_after`, the episode's Ctrl-C is raised that many seconds in.
fn play(what: &Value) -> Value {
    let task = demo();
    let joint = what["joint"].as_bool().expect("joint");
    let timeout = what["timeout"].as_f64().expect("timeout");
    let namespace = what["namespace"].as_str().expect("namespace");
    // This test program is not the `coherent` binary that link processes are.
    coherent::session::robots::start_links_with(env!("CARGO_BIN_EXE_coherent").into(), Vec::new());
    let robots = Robots::ros2(namespace, timeout, 30.0).expect("robot settings");
    let cancel = Cancel::default();
    let mut env = environment(&task, false, &robots, &cancel).expect("the robots answer");
    if let Some(after) = what["cancel_after"].as_f64() {
        let cancel = cancel.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(after));
            cancel.cancel();
        });
    }
    let start = Instant::now();
    let mut steps = Vec::new();
    let mut expected = task.init.clone();
    for step in plan(&task, joint) {
        let pairs: Vec<(NodeId, &str)> = step.iter().map(|(r, a)| (*r, a.as_str())).collect();
        let clock = Instant::now();
        let parts: Vec<Value> = if joint {
            let outcome = env.step_joint(&pairs).expect("known robots");
            assert!(outcome.refused.is_none(), "{:?}", outcome.refused);
            let each = pairs.iter().zip(&outcome.parts);
            each.map(|(&(_, action), p)| part(p.robot, action, &p.infeasible, &p.report))
                .collect()
        } else {
            let (robot, action) = pairs[0];
            let o = env.step(robot, action).expect("a known robot");
            vec![part(robot, action, &o.infeasible, &o.report)]
        };
        // The rules' state follows the actions carried out, and those alone.
        for (p, &(robot, action)) in parts.iter().zip(&pairs) {
            if p["executed"] == true {
                let r = task.robot_by_id(robot).expect("a robot");
                let a = feasibility::check(&task, &expected, r, action).expect("offered");
                rules::apply(&task, &mut expected, r, a);
            }
        }
        assert!(
            env.state() == &expected,
            "the state after step {}",
            steps.len() + 1
        );
        let all = parts.iter().all(|p| p["executed"] == true);
        steps.push(json!({"seconds": clock.elapsed().as_secs_f64(), "parts": parts}));
        if !all || env.stopped().is_some() {
            break;
        }
    }
    json!({
        "seconds": start.elapsed().as_secs_f64(),
        "steps": steps,
        "done": env.goal_satisfied(),
        "stopped": env.stopped(),
    })
}

/// One robot's part of a step, as the run inside prints it.
fn part(
    robot: NodeId,
    action: &str,
    infeasible: &Option<coherent_core::Infeasible>,
    report: &Option<coherent_core::RobotReport>,
) -> Value {
    json!({
        "robot": robot.0,
        "action": action,
        "executed": infeasible.is_none(),
        "reason": infeasible.as_ref().map(|i| i.reason.name()),
        "message": infeasible.as_ref().map(|i| i.message.clone()),
        "report": report.as_ref().map(|r| json!({"robot": r.robot, "via": r.via, "message": r.message})),
    })
}

/// When this process is the run inside the namespace: plays what [`INSIDE`] says and
/// writes it to the file `what["out"]`; the caller then returns.
fn inside() -> bool {
    let Ok(what) = std::env::var(INSIDE) else {
        return false;
    };
    let what: Value = serde_json::from_str(&what).expect("INSIDE is JSON");
    let out = what["out"].as_str().expect("out");
    std::fs::write(out, play(&what).to_string()).expect("the result can be written");
    true
}

/// Runs the test `test` of this binary inside `ns` with [`INSIDE`] set to `what`, and
/// gives what it played; `server` is shown should it fail.
fn play_inside(ns: &Netns, test: &str, mut what: Value, server: &Proc) -> Value {
    let name = format!(
        "inside{}",
        what["namespace"]
            .as_str()
            .expect("namespace")
            .replace('/', "-")
    );
    let out = ns.path(&format!("{name}.json"));
    what["out"] = out.clone().into();
    let exe = std::env::current_exe().expect("the test binary");
    let mut command = ns.command(exe);
    command
        .args([test, "--exact", "--test-threads=1"])
        .env(INSIDE, what.to_string());
    let mut run = ns.spawn_command(&name, &mut command);
    assert_eq!(run.wait(LONG), 0, "{}\n{}", run.show(), server.show());
    let played = std::fs::read_to_string(&out)
        .unwrap_or_else(|e| panic!("nothing played ({e})\n{}", run.show()));
    serde_json::from_str(&played).expect("JSON")
}

/// `coherent robots serve` for the demo under `namespace`, up and serving.
fn serve(ns: &Netns, namespace: &str, faults: &[&str]) -> Proc {
    let demo = common::demo().display().to_string();
    let mut args = vec!["robots", "serve", &demo, "--namespace", namespace];
    args.extend_from_slice(faults);
    let mut server = ns.spawn(&format!("serve{}", namespace.replace('/', "-")), &args);
    server.wait_for("serving", LONG);
    server
}

fn parts(step: &Value) -> &Vec<Value> {
    step["parts"].as_array().expect("parts")
}

/// The demo's makespan-optimal plan with every action taking 0.5 s on its robot: the
/// episode lasts about its makespan x 0.5 s, where its sequential optimum, through the
/// same bridge and servers, lasts its actions x 0.5 s.
#[test]
fn the_demos_joint_plan_over_ros2_lasts_its_makespan_in_delays_not_its_actions() {
    const TEST: &str =
        "the_demos_joint_plan_over_ros2_lasts_its_makespan_in_delays_not_its_actions";
    if inside() {
        return;
    }
    let ns = Netns::new("joint-delay");
    let delay = DELAY.to_string();
    let mut seconds = Vec::new();
    for (joint, namespace) in [(true, "/parallel"), (false, "/sequential")] {
        let mut server = serve(&ns, namespace, &["--delay", &delay]);
        let what = json!({"namespace": namespace, "joint": joint, "timeout": 10.0});
        let played = play_inside(&ns, TEST, what, &server);
        assert_eq!(played["done"], true, "{played}\n{}", server.show());
        let steps = played["steps"].as_array().expect("steps");
        let actions: usize = steps.iter().map(|s| parts(s).len()).sum();
        for step in steps {
            for p in parts(step) {
                assert_eq!(p["executed"], true, "{p}");
                let report = &p["report"];
                let via = format!(
                    "ros2 {namespace}/{}/execute",
                    report["robot"].as_str().expect("robot")
                );
                assert_eq!(report["via"], via.as_str());
                assert!(
                    report["message"]
                        .as_str()
                        .expect("message")
                        .contains(" did [")
                );
            }
            // No step is shorter than one action on its robots.
            assert!(
                step["seconds"].as_f64().expect("seconds") >= DELAY,
                "{step}"
            );
        }
        assert_eq!(server.stdout().matches("-> succeeded").count(), actions);
        server.signal("TERM");
        assert_eq!(server.wait(LONG), 0, "{}", server.show());
        seconds.push((
            steps.len(),
            actions,
            played["seconds"].as_f64().expect("seconds"),
        ));
    }
    let [
        (makespan, actions, parallel),
        (sequential_steps, sequential, in_turn),
    ] = seconds[..]
    else {
        unreachable!("two runs")
    };
    assert_eq!(sequential_steps, sequential);
    assert_eq!(actions, sequential, "both plans do the same 22 actions");
    assert!(
        makespan < actions,
        "{makespan} joint steps, {actions} actions"
    );
    let (short, long) = (makespan as f64 * DELAY, actions as f64 * DELAY);
    eprintln!(
        "demo over ROS 2, --delay {DELAY}: {makespan} joint steps in {parallel:.2} s \
         ({short:.1} s of delays), {actions} actions in turn in {in_turn:.2} s ({long:.1} s)"
    );
    assert!(in_turn >= long, "{in_turn} s");
    // Closer to the makespan's delays than to the actions': the goals overlap.
    assert!(
        parallel >= short && parallel < (short + long) / 2.0,
        "{parallel:.2} s for {makespan} joint steps ({short} s) and {actions} actions ({long} s)"
    );
}

/// The demo's robots by their ROS names, in the order of the first joint step.
fn first_step_robots(task: &Task) -> Vec<String> {
    let names = coherent_ros::wire::robot_names(task);
    let first = &plan(task, true)[0];
    assert!(
        first.len() >= 2,
        "the demo's first joint step has several robots"
    );
    first
        .iter()
        .map(|(id, _)| {
            let n = task.robots.iter().position(|r| task.id(r.node) == *id);
            names[n.expect("a robot")].clone()
        })
        .collect()
}

/// In a joint step, a robot that never answers and a robot that refuses its goal are
/// each their own part of the outcome, with the robot's report, while the other robots'
/// actions are carried out and the rules' state follows them; silence stops the bridge
/// after the step (the world can no longer be known), a refusal does not.
#[test]
fn a_robot_that_is_silent_or_refuses_in_a_joint_step_fails_its_part_alone() {
    const TEST: &str = "a_robot_that_is_silent_or_refuses_in_a_joint_step_fails_its_part_alone";
    if inside() {
        return;
    }
    let robots = first_step_robots(&demo());
    let faulty = robots[0].as_str();
    let ns = Netns::new("joint-faults");
    for (fault, namespace) in [("--silent", "/silent"), ("--refuse", "/refuse")] {
        let server = serve(&ns, namespace, &["--delay", "0.2", fault, faulty]);
        let what = json!({"namespace": namespace, "joint": true, "timeout": 2.0});
        let played = play_inside(&ns, TEST, what, &server);
        let steps = played["steps"].as_array().expect("steps");
        assert_eq!(steps.len(), 1, "{played}");
        let step = &steps[0];
        assert_eq!(parts(step).len(), robots.len());
        for (p, robot) in parts(step).iter().zip(&robots) {
            let report = &p["report"];
            assert_eq!(report["robot"], robot.as_str(), "{p}");
            if robot == faulty {
                assert_eq!(p["executed"], false, "{p}");
                let message = p["message"].as_str().expect("why");
                assert_eq!(report["message"], message, "the robot's report says why");
                let action = p["action"].as_str().expect("action");
                if fault == "--silent" {
                    assert_eq!(p["reason"], "timeout", "{p}");
                    let says = format!("{faulty} did not answer {action} within 2.0 s");
                    assert!(message.starts_with(&says), "{message}");
                } else {
                    assert_eq!(p["reason"], "rejected", "{p}");
                    assert_eq!(message, format!("{faulty} refused the goal {action}"));
                }
            } else {
                assert_eq!(p["executed"], true, "{p}");
                assert!(
                    report["message"]
                        .as_str()
                        .expect("message")
                        .contains(" did [")
                );
            }
        }
        let seconds = step["seconds"].as_f64().expect("seconds");
        if fault == "--silent" {
            assert!(
                (2.0..10.0).contains(&seconds),
                "the robot timeout, {seconds} s"
            );
            let stopped = played["stopped"].as_str().expect("the bridge stopped");
            assert!(
                stopped.starts_with(&format!("{faulty} did not answer")),
                "{stopped}"
            );
        } else {
            assert!(seconds < 10.0, "{seconds} s");
            assert_eq!(played["stopped"], Value::Null, "a refusal does not stop it");
        }
    }
}

/// Ctrl-C during a joint step cancels every goal in flight: each robot of the step
/// acknowledges, and the step ends at once rather than after its 30 s actions.
#[test]
fn ctrl_c_during_a_joint_step_cancels_every_goal_in_flight() {
    const TEST: &str = "ctrl_c_during_a_joint_step_cancels_every_goal_in_flight";
    if inside() {
        return;
    }
    let robots = first_step_robots(&demo());
    let ns = Netns::new("joint-cancel");
    let mut server = serve(&ns, "/cancel", &["--delay", "30"]);
    let what = json!({"namespace": "/cancel", "joint": true, "timeout": 60.0, "cancel_after": 2.0});
    let played = play_inside(&ns, TEST, what, &server);
    let steps = played["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), 1, "{played}");
    // Cancelled 2 s after the bridge connected, and the step started just after that.
    let seconds = steps[0]["seconds"].as_f64().expect("seconds");
    assert!((1.5..10.0).contains(&seconds), "{seconds} s");
    for (p, robot) in parts(&steps[0]).iter().zip(&robots) {
        assert_eq!(p["reason"], "cancelled", "{p}");
        let message = p["message"].as_str().expect("why");
        assert!(
            message.contains("cancelled (the robot acknowledged it)"),
            "{message}"
        );
        assert_eq!(p["report"]["robot"], robot.as_str());
        let action = p["action"].as_str().expect("action");
        server.wait_for(&format!("{action} -> cancelled"), LONG);
    }
    assert_eq!(
        played["stopped"],
        Value::Null,
        "Ctrl-C ends the episode, not the bridge"
    );
}
