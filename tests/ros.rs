//! Robots over ROS 2, end to end: `coherent robots serve` and `coherent run --robots ros2`
//! as separate processes, in a network namespace of each test's own (`common::netns`).
//! Hostile robots are here too: two servers for one robot, at the start or mid-episode.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::netns::{LONG, Netns, actions, report, transcript};
use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_coherent");

fn demo() -> String {
    common::demo().display().to_string()
}

fn env0() -> String {
    common::env0().display().to_string()
}

#[test]
fn the_demo_over_ros2_takes_the_same_22_steps_as_without_it_by_the_rules_and_in_physics() {
    let ns = Netns::new("demo");
    let local = ns.path("local");
    let out = Command::new(BIN)
        .args(["run", &demo(), "--out", &local])
        .output()
        .expect("coherent runs");
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let expected = actions(&transcript(&local));
    assert_eq!(expected.len(), 22);
    let demo = demo();
    for (physics, namespace) in [(false, "/lab/rules"), (true, "/lab/physics")] {
        let mut serve_args = vec!["robots", "serve", &demo, "--namespace", namespace];
        if physics {
            serve_args.push("--physics");
        }
        let name = if physics { "physics" } else { "rules" };
        let mut server = ns.spawn(&format!("serve-{name}"), &serve_args);
        let runs = ns.path(&format!("runs-{name}"));
        let args = [
            "run",
            &demo,
            "--robots",
            "ros2",
            "--namespace",
            namespace,
            "--out",
            &runs,
        ];
        let mut run = ns.spawn(&format!("run-{name}"), &args);
        assert_eq!(run.wait(LONG), 0, "{}\n{}", run.show(), server.show());
        let t = transcript(&runs);
        assert_eq!(
            actions(&t),
            expected,
            "{name}: the same actions as without the bridge"
        );
        assert_eq!(t.summary["status"], "success");
        assert_eq!(t.summary["steps"], 22);
        assert_eq!(t.header["physics"], false, "physics is the server's");
        assert_eq!(
            t.header["robots"],
            serde_json::json!({"kind": "ros2", "namespace": namespace}),
            "the transcript says where the robots were"
        );
        for round in &t.rounds {
            let (robot, via, message) = report(round);
            assert_eq!(via, format!("ros2 {namespace}/{robot}/execute"));
            assert!(message.contains(" did ["), "{message}");
            assert_eq!(
                physics,
                message.contains("s of simulated time"),
                "{message}"
            );
        }
        let served = server.stdout();
        assert_eq!(served.matches("-> succeeded").count(), 22, "{served}");
        server.signal("TERM");
        assert_eq!(server.wait(LONG), 0, "{}", server.show());
    }
}

#[test]
fn every_solvable_task_of_env0_runs_over_ros2_to_success_in_its_optimal_steps() {
    let planned = Command::new(BIN)
        .args(["plan", &env0(), "--json"])
        .output()
        .expect("coherent plan runs");
    let plans: Vec<Value> = String::from_utf8_lossy(&planned.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per task"))
        .collect();
    let solvable: Vec<(i64, u64)> = plans
        .iter()
        .filter(|p| p["solvable"] == true)
        .map(|p| {
            (
                p["task_id"].as_i64().expect("id"),
                p["optimal_steps"].as_u64().expect("steps"),
            )
        })
        .collect();
    assert!(
        solvable.len() >= 20,
        "{} solvable tasks in env0",
        solvable.len()
    );
    let ns = Netns::new("env0");
    for (id, optimal) in solvable {
        let (task, namespace) = (id.to_string(), format!("/env0/task_{id}"));
        let mut server = ns.spawn(
            &format!("serve-{id}"),
            &[
                "robots",
                "serve",
                &env0(),
                "--task",
                &task,
                "--namespace",
                &namespace,
            ],
        );
        let runs = ns.path(&format!("runs-{id}"));
        let args = [
            "run",
            &env0(),
            "--task",
            &task,
            "--robots",
            "ros2",
            "--namespace",
            &namespace,
            "--out",
            &runs,
            "--json",
        ];
        let mut run = ns.spawn(&format!("run-{id}"), &args);
        assert_eq!(
            run.wait(LONG),
            0,
            "task {id}\n{}\n{}",
            run.show(),
            server.show()
        );
        let summary: Value = serde_json::from_str(&run.stdout()).expect("--json prints JSON");
        assert_eq!(summary["success"], true, "task {id}");
        assert_eq!(summary["steps"], optimal, "task {id}");
        let t = transcript(&runs);
        assert!(
            t.rounds
                .iter()
                .all(|r| report(r).1.starts_with("ros2 /env0/task_"))
        );
        server.signal("TERM");
        assert_eq!(server.wait(LONG), 0, "{}", server.show());
    }
}

#[test]
fn a_server_killed_mid_episode_fails_the_step_with_a_timeout_and_ends_the_run() {
    let ns = Netns::new("killed");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo(), "--delay", "0.2"]);
    let runs = ns.path("runs");
    let demo = demo();
    let args = [
        "run",
        &demo,
        "--robots",
        "ros2",
        "--robot-timeout",
        "2",
        "--out",
        &runs,
    ];
    let mut run = ns.spawn("run", &args);
    server.wait_for("step 4 [movetowards] <fridge>(8) -> accepted", LONG);
    server.signal("KILL");
    let killed = Instant::now();
    assert_eq!(run.wait(LONG), 5, "{}", run.show());
    assert!(
        killed.elapsed() < Duration::from_secs(10),
        "{:?}",
        killed.elapsed()
    );
    let said = run.stdout();
    assert!(
        said.contains("infeasible (timeout)")
            && said.contains("stopped: robot_dog_13 did not answer"),
        "{said}"
    );
    // The summary says what happened: a robot's silence, not an interruption.
    let summary = said
        .lines()
        .find(|l| l.contains("| goal not reached |"))
        .expect("a summary line");
    assert!(
        summary.starts_with("stopped: robot_dog_13 did not answer [movetowards] <fridge>(8)"),
        "{summary}"
    );
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted");
    assert_eq!(t.summary["steps"], 4);
    let error = t.summary["error"].as_str().expect("the summary says why");
    assert!(
        error.contains("robot_dog_13 did not answer [movetowards] <fridge>(8) within 2.0 s"),
        "{error}"
    );
    let (last, done) = t.rounds.split_last().expect("rounds");
    assert_eq!(last["outcome"]["reason"], "timeout");
    assert_eq!(report(last).2, error);
    assert!(done.iter().all(|r| r["outcome"]["kind"] == "executed"));
}

#[test]
fn a_robot_that_never_answers_times_out_and_ends_the_run() {
    let ns = Netns::new("silent");
    let server = ns.spawn(
        "serve",
        &["robots", "serve", &demo(), "--silent", "robot_arm_6"],
    );
    let runs = ns.path("runs");
    let demo = demo();
    let args = [
        "run",
        &demo,
        "--robots",
        "ros2",
        "--robot-timeout",
        "2",
        "--out",
        &runs,
    ];
    let mut run = ns.spawn("run", &args);
    assert_eq!(run.wait(LONG), 5, "{}\n{}", run.show(), server.show());
    let t = transcript(&runs);
    assert_eq!(t.rounds.len(), 1);
    assert_eq!(t.rounds[0]["outcome"]["reason"], "timeout");
    assert!(
        report(&t.rounds[0])
            .2
            .contains("robot_arm_6 did not answer [grab] <mug>(7) within 2.0 s")
    );
    assert!(
        server
            .stdout()
            .contains("robot_arm_6 step 1 [grab] <mug>(7) -> no answer, ever")
    );
}

#[test]
fn a_robot_that_refuses_its_goals_is_refused_every_step_it_is_sent() {
    let ns = Netns::new("refuse");
    let server = ns.spawn(
        "serve",
        &["robots", "serve", &demo(), "--refuse", "quadrotor_11"],
    );
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    assert_eq!(
        run.wait(LONG),
        1,
        "the budget runs out\n{}\n{}",
        run.show(),
        server.show()
    );
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "failure");
    assert_eq!(t.rounds.len(), 44);
    let mut refused = 0;
    for round in &t.rounds {
        let (robot, _, message) = report(round);
        if robot == "quadrotor_11" {
            refused += 1;
            assert_eq!(round["outcome"]["reason"], "rejected");
            assert!(
                message.starts_with("quadrotor_11 refused the goal ["),
                "{message}"
            );
        } else {
            assert_eq!(round["outcome"]["kind"], "executed");
        }
    }
    assert!(refused > 0);
    assert_eq!(
        server.stdout().matches("-> refused (--refuse)").count(),
        refused
    );
}

#[test]
fn a_robot_that_reports_failure_is_heard_by_the_assigner_in_its_next_prompt() {
    let ns = Netns::new("fail");
    let args = [
        "robots",
        "serve",
        &demo(),
        "--fail-rate",
        "0.3",
        "--seed",
        "7",
    ];
    let server = ns.spawn("serve", &args);
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    assert_eq!(run.wait(LONG), 0, "{}\n{}", run.show(), server.show());
    let t = transcript(&runs);
    let failed: Vec<usize> = (0..t.rounds.len())
        .filter(|&i| t.rounds[i]["outcome"]["kind"] == "infeasible")
        .collect();
    assert!(!failed.is_empty(), "seed 7 fails some goals");
    assert_eq!(
        t.summary["steps"],
        22 + failed.len(),
        "each failure costs a step"
    );
    for i in failed {
        let round = &t.rounds[i];
        assert_eq!(round["outcome"]["reason"], "robot");
        let message = round["outcome"]["message"].as_str().expect("a message");
        assert!(
            message.contains("an injected failure (--fail-rate 0.3, --seed 7)"),
            "{message}"
        );
        assert_eq!(report(round).2, message);
        let next = &t.rounds[i + 1]["calls"][0];
        assert_eq!(next["role"], "assigner");
        let prompt: String = next["messages"]
            .as_array()
            .expect("messages")
            .iter()
            .filter_map(|m| m["content"].as_str())
            .collect();
        assert!(
            prompt.contains(message),
            "round {} does not hear: {message}",
            i + 2
        );
    }
}

/// `coherent bench --robots ros2` runs the demo's episode through the robots' servers:
/// the same 22 steps to success, its transcript saying where the robots were; asked for
/// more episodes at once, it runs one at a time and says so.
#[test]
fn a_benchmark_over_ros2_runs_the_demo_through_the_robots_servers() {
    let ns = Netns::new("bench");
    let demo = demo();
    let mut server = ns.spawn(
        "serve",
        &["robots", "serve", &demo, "--namespace", "/bench"],
    );
    server.wait_for("serving 3 robots", LONG);
    let results = ns.path("results.jsonl");
    let args = [
        "bench",
        "--tasks",
        &demo,
        "--methods",
        "pefa",
        "--robots",
        "ros2",
        "--namespace",
        "/bench",
        "--concurrency",
        "4",
        "--out",
        &results,
    ];
    let mut run = ns.spawn("bench", &args);
    assert_eq!(run.wait(LONG), 0, "{}\n{}", run.show(), server.show());
    let err = std::fs::read_to_string(&run.err).expect("stderr");
    assert!(err.contains("one episode at a time"), "{err}");
    let text = std::fs::read_to_string(&results).expect("a results file");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    assert_eq!(lines.len(), 1, "{text}");
    assert_eq!(lines[0]["status"], "success", "{text}");
    assert_eq!(lines[0]["steps"], 22, "{text}");
    let t = transcript(&ns.path("results.transcripts/seed0"));
    assert_eq!(
        t.header["robots"],
        serde_json::json!({"kind": "ros2", "namespace": "/bench"})
    );
    for round in &t.rounds {
        let (robot, via, _) = report(round);
        assert_eq!(via, format!("ros2 /bench/{robot}/execute"));
    }
    assert_eq!(server.stdout().matches("-> succeeded").count(), 22);
}

#[test]
fn a_robot_whose_server_never_starts_exits_2_naming_it() {
    let ns = Netns::new("absent");
    let mut server = ns.spawn(
        "serve",
        &["robots", "serve", &demo(), "--absent", "robot_dog_13"],
    );
    server.wait_for("serving 2 robots", LONG);
    let runs = ns.path("runs");
    let demo = demo();
    let args = [
        "run",
        &demo,
        "--robots",
        "ros2",
        "--server-wait",
        "2",
        "--out",
        &runs,
    ];
    let mut run = ns.spawn("run", &args);
    assert_eq!(run.wait(LONG), 2, "{}", run.show());
    let err = std::fs::read_to_string(&run.err).expect("stderr");
    assert!(
        err.contains("no ROS 2 action server for robot_dog_13 under /coherent within 2.0 s"),
        "{err}"
    );
    assert!(
        !err.contains("quadrotor_11") && !err.contains("robot_arm_6"),
        "{err}"
    );
    assert!(!Path::new(&runs).exists(), "no episode, no transcript");
}

#[test]
fn two_servers_for_one_robot_are_refused_at_the_start_naming_them() {
    let ns = Netns::new("two-at-start");
    let mut first = ns.spawn("serve-a", &["robots", "serve", &demo()]);
    let mut second = ns.spawn("serve-b", &["robots", "serve", &demo()]);
    first.wait_for("serving 3 robots", LONG);
    second.wait_for("serving 3 robots", LONG);
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    assert_eq!(run.wait(LONG), 2, "{}", run.show());
    let err = std::fs::read_to_string(&run.err).expect("stderr");
    let servers = err
        .split("2 ROS 2 action servers for robot_arm_6 under /coherent (")
        .nth(1)
        .unwrap_or_else(|| panic!("{err}"));
    assert_eq!(servers.matches("participant ").count(), 2, "{err}");
    assert!(err.contains("stop all but one"), "{err}");
    assert!(!Path::new(&runs).exists(), "no episode, no transcript");
    for server in [&first, &second] {
        assert!(!server.stdout().contains("accepted"), "{}", server.show());
    }
}

#[test]
fn a_second_server_that_takes_a_goal_mid_episode_stops_the_bridge() {
    let ns = Netns::new("two-mid-episode");
    let mut first = ns.spawn("serve-a", &["robots", "serve", &demo(), "--delay", "0.5"]);
    first.wait_for("serving 3 robots", LONG);
    let runs = ns.path("runs");
    let demo = demo();
    let args = ["run", &demo, "--robots", "ros2", "--out", &runs];
    let mut run = ns.spawn("run", &args);
    first.wait_for("step 2 [movetowards] <door>(4) -> accepted", LONG);
    let mut second = ns.spawn("serve-b", &["robots", "serve", &demo, "--delay", "0.5"]);
    second.wait_for("serving 3 robots", LONG);
    assert_eq!(
        run.wait(LONG),
        5,
        "{}\n{}\n{}",
        run.show(),
        first.show(),
        second.show()
    );
    let said = run.stdout();
    assert!(
        said.contains("two servers accepted the goal, participant "),
        "{said}"
    );
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted");
    let error = t.summary["error"].as_str().expect("why");
    assert!(error.contains("two servers accepted the goal"), "{error}");
    assert!(second.stdout().contains("-> accepted"), "{}", second.show());
}

#[test]
fn ctrl_c_during_an_action_cancels_the_goal() {
    let ns = Netns::new("ctrl-c");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo(), "--delay", "30"]);
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    server.wait_for("robot_arm_6 step 1 [grab] <mug>(7) -> accepted", LONG);
    run.signal("INT");
    let interrupted = Instant::now();
    assert_eq!(run.wait(LONG), 130, "{}", run.show());
    assert!(
        interrupted.elapsed() < Duration::from_secs(10),
        "{:?}",
        interrupted.elapsed()
    );
    server.wait_for("robot_arm_6 step 1 [grab] <mug>(7) -> cancelled", LONG);
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted");
    assert_eq!(t.summary["error"], Value::Null, "Ctrl-C, not the robots");
    assert_eq!(t.rounds.len(), 1);
    assert_eq!(t.rounds[0]["outcome"]["reason"], "cancelled");
    let (robot, _, message) = report(&t.rounds[0]);
    assert_eq!(robot, "robot_arm_6");
    assert!(
        message.contains("cancelled (the robot acknowledged it)"),
        "{message}"
    );
}

#[test]
fn bad_robot_flags_exit_2_before_anything_runs() {
    let demo = demo();
    for (args, says) in [
        (
            vec!["--robots", "ros2", "--physics"],
            "pass --physics to `coherent robots serve`",
        ),
        (
            vec!["--robots", "ros2", "--namespace", "/2lab"],
            "\"/2lab\" is not a ROS namespace",
        ),
        (
            vec!["--robots", "ros2", "--robot-timeout=-1"],
            "the robot timeout must be seconds from 0 to 1.8e19, not -1",
        ),
    ] {
        let out = Command::new(BIN)
            .args(["run", &demo, "--out", "/nonexistent/never-written"])
            .args(&args)
            .output()
            .expect("coherent runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let out = Command::new(BIN)
        .args(["robots", "serve", &demo, "--refuse", "drone_1"])
        .output()
        .expect("coherent runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no robot named drone_1 in the task; its robots: robot_arm_6, quadrotor_11, robot_dog_13"), "{err}");
}

/// `coherent run --execution parallel --robots ros2`: a joint step's goals go to the
/// robots' servers at once and are awaited together. With every server taking 0.5 s an
/// action, the demo's 13 joint steps of 22 actions last about 13 x 0.5 s, under the 11 s
/// that its 22 actions in turn take at the least; and the servers' log shows every robot
/// of a joint step accepting its goal before any of them is done.
#[test]
fn a_parallel_run_over_ros2_lasts_its_joint_steps_not_its_actions() {
    const DELAY: f64 = 0.5;
    let ns = Netns::new("parallel");
    let (demo, namespace) = (demo(), "/lab/parallel");
    let serve = [
        "robots",
        "serve",
        &demo,
        "--namespace",
        namespace,
        "--delay",
        "0.5",
    ];
    let mut server = ns.spawn("serve", &serve);
    let runs = ns.path("runs");
    let args = [
        "run",
        &demo,
        "--execution",
        "parallel",
        "--robots",
        "ros2",
        "--namespace",
        namespace,
        "--out",
        &runs,
    ];
    let mut run = ns.spawn("run", &args);
    assert_eq!(run.wait(LONG), 0, "{}\n{}", run.show(), server.show());
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "success", "{}", run.show());
    let sizes: Vec<usize> = t
        .rounds
        .iter()
        .map(|r| r["parts"].as_array().map_or(0, Vec::len))
        .collect();
    let actions: usize = sizes.iter().sum();
    assert_eq!((sizes.len(), actions), (13, 22), "the makespan plan's");
    let wall = t.summary["wall_ms"]
        .as_f64()
        .expect("the episode's wall time")
        / 1e3;
    eprintln!("13 joint steps of 22 actions at {DELAY} s each: {wall:.2} s");
    assert!(
        (13.0 * DELAY..22.0 * DELAY).contains(&wall),
        "{wall:.2} s for 13 joint steps of 22 actions at {DELAY} s each"
    );
    // A goal's `step` is the count of the actions sent, its own included.
    let served = server.stdout();
    let lines: Vec<&str> = served.lines().collect();
    let at = |step: usize, end: &str| {
        let mark = format!(" step {step} [");
        lines
            .iter()
            .position(|l| l.contains(&mark) && l.contains(end))
            .unwrap_or_else(|| panic!("no goal {step} {end} in\n{served}"))
    };
    let mut first = 1;
    for (k, &n) in sizes.iter().enumerate() {
        let goals = first..first + n;
        let accepted = goals.clone().map(|s| at(s, "-> accepted")).max();
        let done = goals.map(|s| at(s, "-> succeeded")).min();
        assert!(
            accepted < done,
            "joint step {}: a goal done before the others were sent\n{served}",
            k + 1
        );
        first += n;
    }
    server.signal("TERM");
    assert_eq!(server.wait(LONG), 0, "{}", server.show());
}

/// The bridge's DDS side runs in a link process of its own, with a memory limit, a child
/// of the run; killed (as a flood of DDS samples would end it), the run stops the way a
/// silent robot stops it: exit 5, the transcript kept as interrupted with the reason.
#[test]
fn a_link_process_killed_mid_episode_stops_the_run_with_exit_5_naming_it() {
    let ns = Netns::new("link-killed");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo(), "--delay", "0.5"]);
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    server.wait_for("step 4 [movetowards] <fridge>(8) -> accepted", LONG);
    let link = link_process(&run);
    std::process::Command::new("kill")
        .args(["-KILL", &link.to_string()])
        .status()
        .expect("kill runs");
    assert_eq!(run.wait(LONG), 5, "{}", run.show());
    let said = run.stdout();
    let summary = said
        .lines()
        .find(|l| l.contains("| goal not reached |"))
        .unwrap_or_else(|| panic!("a summary line\n{said}"));
    assert!(
        summary
            .starts_with("stopped: robot_dog_13: the ROS 2 link process ended (killed by SIGKILL)"),
        "{summary}"
    );
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted");
    assert_eq!(t.summary["steps"], 4);
    let error = t.summary["error"].as_str().expect("the summary says why");
    assert!(
        error.contains("the ROS 2 link process ended (killed by SIGKILL)")
            && error.contains("memory limit of 256 MiB"),
        "{error}"
    );
    let (last, done) = t.rounds.split_last().expect("rounds");
    assert_eq!(last["outcome"]["reason"], "robot");
    assert!(done.iter().all(|r| r["outcome"]["kind"] == "executed"));
}

/// The link process of `run` (its one child), once it has the memory limit it sets on
/// itself at start: a data segment of 256 MiB.
fn link_process(run: &common::netns::Proc) -> u32 {
    let children = run.children(LONG);
    let [link] = children[..] else {
        panic!("one link process, not {children:?}\n{}", run.show());
    };
    let cmdline = std::fs::read(format!("/proc/{link}/cmdline")).expect("its command line");
    assert!(
        String::from_utf8_lossy(&cmdline).ends_with("robots\0link\0"),
        "{cmdline:?}"
    );
    let limits = std::fs::read_to_string(format!("/proc/{link}/limits")).expect("its limits");
    let data = limits
        .lines()
        .find(|l| l.starts_with("Max data size"))
        .expect("a data limit");
    assert_eq!(
        data.split_whitespace().nth(3),
        Some("268435456"),
        "{limits}"
    );
    link
}

/// A benchmark whose link process is killed keeps the episode's results line (status
/// `interrupted`, the reason in `error`), and the next run of the same results file runs
/// that episode again, to the goal.
#[test]
fn a_benchmark_whose_link_process_is_killed_keeps_its_line_and_resumes() {
    let ns = Netns::new("bench-link-killed");
    let demo = demo();
    let results = ns.path("results.jsonl");
    let args = [
        "bench",
        "--tasks",
        &demo,
        "--methods",
        "pefa",
        "--robots",
        "ros2",
        "--out",
        &results,
    ];
    {
        let mut server = ns.spawn("serve", &["robots", "serve", &demo, "--delay", "0.5"]);
        let mut bench = ns.spawn("bench", &args);
        server.wait_for("step 2 ", LONG);
        let link = link_process(&bench);
        std::process::Command::new("kill")
            .args(["-KILL", &link.to_string()])
            .status()
            .expect("kill runs");
        assert_eq!(bench.wait(LONG), 0, "{}", bench.show());
    }
    let lines = |text: &str| -> Vec<Value> {
        text.lines()
            .map(|l| serde_json::from_str(l).expect("JSON"))
            .collect()
    };
    let text = std::fs::read_to_string(&results).expect("a results file");
    let first = lines(&text);
    assert_eq!(first.len(), 1, "{text}");
    assert_eq!(first[0]["status"], "interrupted", "{text}");
    let error = first[0]["error"].as_str().unwrap_or_default();
    assert!(
        error.contains("the ROS 2 link process ended (killed by SIGKILL)"),
        "{text}"
    );
    // A fresh world for the episode run again.
    let mut server = ns.spawn("serve-again", &["robots", "serve", &demo]);
    server.wait_for("serving 3 robots", LONG);
    let mut again = ns.spawn("bench-again", &args);
    assert_eq!(again.wait(LONG), 0, "{}", again.show());
    let text = std::fs::read_to_string(&results).expect("a results file");
    let last = lines(&text).pop().expect("a line");
    assert_eq!(last["status"], "success", "{text}");
    assert_eq!(last["steps"], 22, "{text}");
}

/// The link process sets its memory limit on itself before it starts anything: with
/// one far below what it needs, it ends before it connects, and the bridge's error names
/// it, how it ended and its last words (no network needed: it never reaches DDS).
#[test]
fn a_link_process_whose_memory_limit_is_reached_ends_and_the_bridge_says_so() {
    use coherent::session::engine::Cancel;
    use coherent::session::episode::environment;
    use coherent::session::robots::{Robots, start_links_with};
    start_links_with(BIN.into(), Vec::new());
    let task = std::sync::Arc::new(
        coherent::session::tasks::pick_task(&common::demo(), None).expect("the demo task"),
    );
    let Robots::Ros2(mut options) = Robots::ros2("/tiny", 1.0, 1.0).expect("settings") else {
        panic!("robots over ROS 2");
    };
    options.link.memory_limit = 1 << 20;
    let error = match environment(&task, false, &Robots::Ros2(options), &Cancel::default()) {
        Ok(_) => panic!("a link process within 1 MiB connected"),
        Err(e) => e.to_string(),
    };
    assert!(
        error.starts_with("the ROS 2 link process ended (")
            && error.contains("within a memory limit of 1 MiB")
            && error.contains("; its last words: "),
        "{error}"
    );
    let words = error.split("; its last words: ").nth(1).unwrap_or_default();
    assert!(
        words.contains("memory allocation of") || words.contains("can't spawn"),
        "{error}"
    );
}

/// `coherent robots serve` reads DDS too: it limits its own memory, 1 GiB unless
/// `--memory-limit` says otherwise, so that a flood ends it (its clients then see silent
/// robots) instead of taking the machine's memory.
#[test]
fn the_robot_servers_limit_their_own_memory() {
    let ns = Netns::new("serve-limit");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo()]);
    server.wait_for("serving 3 robots", LONG);
    let limits =
        std::fs::read_to_string(format!("/proc/{}/limits", server.id())).expect("its limits");
    let data = limits
        .lines()
        .find(|l| l.starts_with("Max data size"))
        .expect("a data limit");
    assert_eq!(
        data.split_whitespace().nth(3),
        Some("1073741824"),
        "{limits}"
    );
    // A limit too small to start under is refused before anything starts, not a crash.
    for small in ["0", "1", "63"] {
        let mut tiny = ns.spawn(
            "serve-tiny",
            &["robots", "serve", &demo(), "--memory-limit", small],
        );
        assert_eq!(tiny.ended(LONG).code(), Some(2), "{}", tiny.show());
        assert!(!tiny.stdout().contains("serving"), "{}", tiny.show());
        assert!(
            tiny.show().contains(&format!(
                "invalid value '{small}' for '--memory-limit <MIB>'"
            )),
            "{}",
            tiny.show()
        );
    }
}

/// A link process never outlives its run: the run killed (SIGKILL, so that it cannot
/// clean up), the link process sees its stdin end, cancels the goal in flight and ends.
#[test]
fn a_link_process_cancels_its_goal_and_ends_when_its_run_is_killed() {
    let ns = Netns::new("run-killed");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo(), "--delay", "30"]);
    let runs = ns.path("runs");
    let demo = demo();
    let mut run = ns.spawn("run", &["run", &demo, "--robots", "ros2", "--out", &runs]);
    server.wait_for("robot_arm_6 step 1 [grab] <mug>(7) -> accepted", LONG);
    let link = link_process(&run);
    run.signal("KILL");
    assert!(!run.ended(LONG).success());
    server.wait_for("robot_arm_6 step 1 [grab] <mug>(7) -> cancelled", LONG);
    let start = Instant::now();
    while Path::new(&format!("/proc/{link}")).exists() {
        // A zombie until its new parent reaps it: ended all the same.
        let status = std::fs::read_to_string(format!("/proc/{link}/status")).unwrap_or_default();
        if status.contains("State:\tZ") {
            break;
        }
        assert!(start.elapsed() < LONG, "the link process outlived its run");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Sends `signal` to process `pid`.
fn kill(signal: &str, pid: u32) {
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success(), "kill -{signal} {pid}");
}

/// A link process stopped by the test (SIGSTOP), killed when the test ends however it
/// ends: a stopped process would outlive it.
struct Stopped(u32);

impl Stopped {
    fn new(pid: u32) -> Stopped {
        kill("STOP", pid);
        Stopped(pid)
    }
}

impl Drop for Stopped {
    fn drop(&mut self) {
        // It may have been killed already: by the run, as it should be.
        let _ = Command::new("kill")
            .args(["-KILL", &self.0.to_string()])
            .stderr(Stdio::null())
            .status();
    }
}

/// The demo's robot servers in `ns`, each action taking `delay` seconds, and a run of the
/// demo over them with the flags `extra`, its transcript in `runs`; once the servers' log
/// has `until`.
fn demo_over_ros2(
    ns: &Netns,
    delay: &str,
    extra: &[&str],
    runs: &str,
    until: &str,
) -> (common::netns::Proc, common::netns::Proc) {
    let demo = demo();
    let mut server = ns.spawn("serve", &["robots", "serve", &demo, "--delay", delay]);
    let mut args = vec!["run", &demo, "--robots", "ros2", "--out", runs];
    args.extend(extra);
    let run = ns.spawn("run", &args);
    server.wait_for(until, LONG);
    (server, run)
}

/// A link process that is stopped (SIGSTOP: alive, but it answers nothing, not even its
/// heartbeat) is unresponsive once it has been silent as long as a robot may be: the run
/// kills it and stops, exit 5, naming it, within the robot timeout and a little. It used
/// to wait for it for ever (SIGCONT let it go on, blaming the robot).
#[test]
fn a_stopped_link_process_ends_the_run_within_the_robot_timeout_naming_it() {
    let ns = Netns::new("link-stopped");
    let runs = ns.path("runs");
    let accepted = "step 2 [movetowards] <door>(4) -> accepted";
    let (_server, mut run) = demo_over_ros2(&ns, "0.5", &["--robot-timeout", "3"], &runs, accepted);
    let _stopped = Stopped::new(link_process(&run));
    let stopped = Instant::now();
    assert_eq!(run.wait(LONG), 5, "{}", run.show());
    assert!(
        stopped.elapsed() < Duration::from_secs(8),
        "{:?} after the link process was stopped\n{}",
        stopped.elapsed(),
        run.show()
    );
    let said = run.stdout();
    assert!(
        said.contains(": the ROS 2 link process is unresponsive: nothing from it for 3 s"),
        "{said}"
    );
    let t = transcript(&runs);
    assert_eq!(t.summary["status"], "interrupted");
    let error = t.summary["error"].as_str().expect("the summary says why");
    assert!(
        error.contains("killed by SIGKILL") && !error.contains("flood"),
        "{error}"
    );
}

/// SIGTERM and Ctrl-C end a run at any time, its link process stopped too: the cancel
/// is forwarded, and a link process that misses its heartbeats then is ended at once.
#[test]
fn sigterm_and_ctrl_c_end_a_run_whose_link_process_is_stopped() {
    for (signal, status) in [("TERM", 143), ("INT", 130)] {
        let ns = Netns::new(&format!("link-stopped-{signal}"));
        let runs = ns.path("runs");
        let accepted = "robot_arm_6 step 1 [grab] <mug>(7) -> accepted";
        let extra = ["--robot-timeout", "60"];
        let (_server, mut run) = demo_over_ros2(&ns, "30", &extra, &runs, accepted);
        let _stopped = Stopped::new(link_process(&run));
        std::thread::sleep(Duration::from_millis(500));
        run.signal(signal);
        let signalled = Instant::now();
        assert_eq!(run.wait(LONG), status, "{}", run.show());
        assert!(
            signalled.elapsed() < Duration::from_secs(6),
            "{:?} after SIG{signal}\n{}",
            signalled.elapsed(),
            run.show()
        );
        let t = transcript(&runs);
        assert_eq!(t.summary["status"], "interrupted");
        assert_eq!(t.rounds[0]["outcome"]["reason"], "cancelled");
    }
}

/// Lines on the link process's stdin that the run did not write end it, and the run
/// says so (exit 5), not that a flood reached its memory limit.
#[test]
fn garbage_on_the_link_processs_stdin_is_named_as_such() {
    let ns = Netns::new("link-garbage");
    let runs = ns.path("runs");
    let accepted = "step 2 [movetowards] <door>(4) -> accepted";
    let (_server, mut run) = demo_over_ros2(&ns, "0.5", &[], &runs, accepted);
    let link = link_process(&run);
    std::fs::write(format!("/proc/{link}/fd/0"), "garbage\n").expect("its stdin is a pipe");
    assert_eq!(run.wait(LONG), 5, "{}", run.show());
    let t = transcript(&runs);
    let error = t.summary["error"].as_str().expect("the summary says why");
    // Between two steps it ends at once; during one, the goal in flight fails with it.
    assert!(
        (error.contains("the ROS 2 link process ended (exit status 2): its stdin held")
            || error.contains("the ROS 2 link process ends: its stdin held"))
            && error.contains("a line that is not the protocol's")
            && error.contains("something other than the run wrote to the link process's stdin")
            && !error.contains("memory limit")
            && !error.contains("flood"),
        "{error}"
    );
}

/// Two runs of one task in one namespace and domain: each one's goals change the robots'
/// world under the other, and the first to hear of the other's goal (a reply of a
/// robot's server to a goal it did not send) stops, naming the other client. The first
/// run used to refuse 26 steps until its budget was spent, never naming it.
#[test]
fn a_second_client_of_the_robots_servers_stops_the_run_naming_it() {
    let ns = Netns::new("two-clients");
    let mut server = ns.spawn("serve", &["robots", "serve", &demo(), "--delay", "0.3"]);
    let (first_runs, second_runs) = (ns.path("first"), ns.path("second"));
    let demo = demo();
    let mut first = ns.spawn(
        "first",
        &["run", &demo, "--robots", "ros2", "--out", &first_runs],
    );
    server.wait_for("step 3 ", LONG);
    let mut second = ns.spawn(
        "second",
        &["run", &demo, "--robots", "ros2", "--out", &second_runs],
    );
    assert_eq!(first.wait(LONG), 5, "{}\n{}", first.show(), second.show());
    let said = first.stdout();
    assert!(
        said.contains("another client, participant ")
            && said.contains("sends goals to this robot's action server"),
        "{said}\n{}",
        second.show()
    );
    let t = transcript(&first_runs);
    assert_eq!(t.summary["status"], "interrupted");
    assert!(t.rounds.len() < 22, "{} rounds", t.rounds.len());
    let _ = second.ended(LONG);
}
