//! Robots over ROS 2 in network namespaces of their own: DDS discovery rides on
//! multicast, which the loopback interface of a container may lack, so a test makes a
//! namespace (`unshare --net`, loopback up with multicast and a multicast route) and
//! starts its processes in it (`nsenter`); tests running at once never see each other.
//! This needs root (or the capabilities to make network namespaces); without them every
//! test fails saying so. The transcripts such tests read back are here too.

use std::ffi::OsStr;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_coherent");

/// How long a process in a namespace may take before the test gives up on it.
pub const LONG: Duration = Duration::from_secs(120);

/// Sets up the namespace's loopback for DDS, says so, then lives as long as its stdin.
const SETUP: &str = "ip link set lo up && ip link set lo multicast on && \
                     ip route add 224.0.0.0/4 dev lo && echo ready && exec cat >/dev/null";

/// A network namespace of its own, held open by a process, and a scratch folder.
pub struct Netns {
    holder: Child,
    /// Closing it ends the holder, even when the test process dies.
    _stdin: ChildStdin,
    pub dir: PathBuf,
}

impl Netns {
    pub fn new(test: &str) -> Netns {
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
    pub fn spawn(&self, name: &str, args: &[&str]) -> Proc {
        self.spawn_command(name, self.command(BIN).args(args))
    }

    /// A command that runs `program` inside the namespace.
    pub fn command(&self, program: impl AsRef<OsStr>) -> Command {
        let mut command = Command::new("nsenter");
        command
            .arg(format!("--net=/proc/{}/ns/net", self.holder.id()))
            .arg("--")
            .arg(program);
        command
    }

    /// Starts `command` (see [`Netns::command`]); stdout and stderr go to files named
    /// `name`.
    pub fn spawn_command(&self, name: &str, command: &mut Command) -> Proc {
        let out = self.dir.join(format!("{name}.out"));
        let err = self.dir.join(format!("{name}.err"));
        let child = command
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

    pub fn path(&self, name: &str) -> String {
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

/// A process in a namespace; killed when dropped.
pub struct Proc {
    child: Child,
    name: String,
    pub out: PathBuf,
    pub err: PathBuf,
}

impl Proc {
    pub fn stdout(&self) -> String {
        std::fs::read_to_string(&self.out).unwrap_or_default()
    }

    pub fn show(&self) -> String {
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
    pub fn wait(&mut self, limit: Duration) -> i32 {
        let status = self.ended(limit);
        status
            .code()
            .unwrap_or_else(|| panic!("killed by a signal\n{}", self.show()))
    }

    /// How the process ended, a signal included, waiting up to `limit`; beyond it the
    /// process is killed and the test fails.
    pub fn ended(&mut self, limit: Duration) -> std::process::ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().expect("the process can be waited on") {
                return status;
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
    pub fn wait_for(&mut self, text: &str, limit: Duration) {
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

    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// The process's children, waiting up to `limit` for it to have one.
    pub fn children(&self, limit: Duration) -> Vec<u32> {
        let start = Instant::now();
        loop {
            let listed = Command::new("pgrep")
                .args(["-P", &self.child.id().to_string()])
                .output()
                .expect("pgrep (procps) runs");
            let pids: Vec<u32> = String::from_utf8_lossy(&listed.stdout)
                .split_whitespace()
                .map(|p| p.parse().expect("a pid"))
                .collect();
            if !pids.is_empty() || start.elapsed() > limit {
                return pids;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    pub fn signal(&self, signal: &str) {
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
pub struct Transcript {
    pub header: Value,
    pub rounds: Vec<Value>,
    pub summary: Value,
}

pub fn transcript(dir: &str) -> Transcript {
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
pub fn actions(t: &Transcript) -> Vec<(i64, String)> {
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
pub fn report(round: &Value) -> (&str, &str, &str) {
    let r = &round["robot"];
    let text = |k: &str| {
        r[k].as_str()
            .unwrap_or_else(|| panic!("round {} has no robot report: {round}", round["step"]))
    };
    (text("robot"), text("via"), text("message"))
}
