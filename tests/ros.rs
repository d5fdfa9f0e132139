//! Robots over ROS 2, end to end: `coherent robots serve` and `coherent run --robots ros2`
//! as separate processes. DDS discovery rides on multicast, which the loopback interface
//! of a container may lack, so each test makes a network namespace of its own (`unshare
//! --net`, loopback up with multicast and a multicast route) and starts its processes in
//! it (`nsenter`); tests running at once never see each other. This needs root (or the
//! capabilities to make network namespaces); without them every test fails saying so.
//! Hostile robots are here too: two servers for one robot, at the start or mid-episode.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_coherent");

fn demo() -> String {
    format!("{}/examples/tasks/demo.json", env!("CARGO_MANIFEST_DIR"))
}

/// The released env0 tasks (`COHERENT_ORIGINAL_ENV`, set in `.cargo/config.toml`).
fn env0() -> String {
    format!("{}/env0.json", env!("COHERENT_ORIGINAL_ENV"))
}

/// Sets up the namespace's loopback for DDS, says so, then lives as long as its stdin.
const SETUP: &str = "ip link set lo up && ip link set lo multicast on && \
                     ip route add 224.0.0.0/4 dev lo && echo ready && exec cat >/dev/null";

/// A network namespace of its own, held open by a process, and a scratch folder.
struct Netns {
    holder: Child,
    /// Closing it ends the holder, even when the test process dies.
    _stdin: ChildStdin,
    dir: PathBuf,
}

impl Netns {
    fn new(test: &str) -> Netns {
        let dir = std::env::temp_dir().join(format!("coherent-ros-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a scratch folder can be made");
        let mut holder = Command::new("unshare")
            .args(["--net", "sh", "-c", SETUP])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("cannot run `unshare` (util-linux) for a network namespace: {e}")
            });
        let mut line = String::new();
        let stdout = holder.stdout.take().expect("piped");
        let _ = BufReader::new(stdout).read_line(&mut line);
        if line.trim() != "ready" {
            let _ = holder.kill();
            let out = holder.wait_with_output().expect("unshare ends");
            panic!(
                "cannot make a network namespace with multicast on its loopback, which DDS \
                 discovery needs: `unshare --net` and `ip` need root (or CAP_SYS_ADMIN and \
                 CAP_NET_ADMIN); they said: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        let stdin = holder.stdin.take().expect("piped");
        Netns {
            holder,
            _stdin: stdin,
            dir,
        }
    }

    /// `coherent ARGS` inside the namespace; stdout and stderr go to files named `name`.
    fn spawn(&self, name: &str, args: &[&str]) -> Proc {
        let out = self.dir.join(format!("{name}.out"));
        let err = self.dir.join(format!("{name}.err"));
        let child = Command::new("nsenter")
            .arg(format!("--net=/proc/{}/ns/net", self.holder.id()))
            .arg("--")
            .arg(BIN)
            .args(args)
            .stdout(File::create(&out).expect("a log file can be made"))
            .stderr(File::create(&err).expect("a log file can be made"))
            .spawn()
            .unwrap_or_else(|e| panic!("cannot run `nsenter` (util-linux): {e}"));
        Proc {
            child,
            name: name.to_owned(),
            out,
            err,
        }
    }

    fn path(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        let _ = self.holder.kill();
        let _ = self.holder.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// A `coherent` process in a namespace; killed when dropped.
struct Proc {
    child: Child,
    name: String,
    out: PathBuf,
    err: PathBuf,
}

impl Proc {
    fn stdout(&self) -> String {
        std::fs::read_to_string(&self.out).unwrap_or_default()
    }

    fn show(&self) -> String {
        format!(
            "--- {} stdout\n{}--- {} stderr\n{}",
            self.name,
            self.stdout(),
            self.name,
            std::fs::read_to_string(&self.err).unwrap_or_default()
        )
    }

    /// The exit status, waiting up to `limit`; beyond it the process is killed and the
    /// test fails.
    fn wait(&mut self, limit: Duration) -> i32 {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().expect("the process can be waited on") {
                return status
                    .code()
                    .unwrap_or_else(|| panic!("killed by a signal\n{}", self.show()));
            }
            if start.elapsed() > limit {
                let _ = self.child.kill();
                panic!(
                    "{} did not end within {limit:?}\n{}",
                    self.name,
                    self.show()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Waits up to `limit` for a line of stdout that contains `text`.
    fn wait_for(&mut self, text: &str, limit: Duration) {
        let start = Instant::now();
        while !self.stdout().lines().any(|l| l.contains(text)) {
            if start.elapsed() > limit {
                panic!("no line with {text:?} within {limit:?}\n{}", self.show());
            }
            if let Ok(Some(status)) = self.child.try_wait() {
                panic!(
                    "{} ended ({status}) before {text:?}\n{}",
                    self.name,
                    self.show()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn signal(&self, signal: &str) {
        let sent = Command::new("kill")
            .args([&format!("-{signal}"), &self.child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(sent.success(), "kill -{signal} {}", self.name);
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The header, the rounds and the summary of the one transcript in `dir`.
struct Transcript {
    header: Value,
    rounds: Vec<Value>,
    summary: Value,
}

fn transcript(dir: &str) -> Transcript {
    let files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.expect("a folder entry").path())
        .collect();
    assert_eq!(files.len(), 1, "one transcript in {dir}: {files:?}");
    let text = std::fs::read_to_string(&files[0]).expect("the transcript is readable");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("each line is JSON"))
        .collect();
    assert_eq!(lines[0]["type"], "header", "{}", files[0].display());
    let (summary, rounds) = lines[1..].split_last().expect("a summary line");
    assert_eq!(summary["type"], "summary", "the transcript is complete");
    assert!(rounds.iter().all(|r| r["type"] == "round"));
    Transcript {
        header: lines[0].clone(),
        rounds: rounds.to_vec(),
        summary: summary.clone(),
    }
}

/// Each round's robot and action.
fn actions(t: &Transcript) -> Vec<(i64, String)> {
    t.rounds
        .iter()
        .map(|r| {
            (
                r["proposal"]["robot"].as_i64().expect("a proposal"),
                r["decision"]["action"]
                    .as_str()
                    .expect("an action")
                    .to_owned(),
            )
        })
        .collect()
}

/// The round's robot report: which robot over which action, and its message.
fn report(round: &Value) -> (&str, &str, &str) {
    let r = &round["robot"];
    let text = |k: &str| {
        r[k].as_str()
            .unwrap_or_else(|| panic!("round {} has no robot report: {round}", round["step"]))
    };
    (text("robot"), text("via"), text("message"))
}

const LONG: Duration = Duration::from_secs(120);

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
