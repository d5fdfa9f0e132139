//! The ROS 2 link process: the bridge's DDS side (`Link`) in a child process of its
//! own, with a memory limit it sets on itself, so that whatever a DDS participant sends
//! it can end that process but never the run.
//!
//! RustDDS reassembles a fragmented sample before any reader sees it, in a buffer of the
//! size the sample's first fragment claims (up to 4 GiB, zeroed at once), and keeps a
//! number of incomplete samples per writer: the memory is spent before the bridge can
//! look at a field. So the participant lives in a child whose data segment is limited
//! ([`LINK_MEMORY_LIMIT`]); a flood makes an allocation fail there, the child aborts,
//! and the parent stops the bridge the way a silent robot stops it, naming the process.
//!
//! The parent (`LinkProcess`, inside [`crate::Ros2Env`]) starts the child with a
//! [`LinkCommand`] (this program, with its hidden subcommand), writes its configuration
//! and then its requests as JSON lines to the child's stdin, and reads one JSON line per
//! answer from its stdout; every line either side reads is bounded ([`MAX_LINE_BYTES`]),
//! and a longer one is the other side's failure. The child ([`serve`]) ignores Ctrl-C
//! and SIGTERM (the parent decides, and forwards a cancel), and ends when its stdin does.

use std::ffi::OsString;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use tokio::runtime::Handle;

use crate::error::Error;
use crate::link::{CANCEL_WAIT, Exchange, Link};
use crate::wire::Goal;

/// The data segment (heap and private writable mappings, `RLIMIT_DATA`) the link process
/// may take. Normally it holds about 60 MiB on a 16-core machine (the runtime's threads'
/// stacks and arenas, the DDS participant and its caches; measured in docs/robots.md),
/// whatever the number of robots; a flood of large samples asks for hundreds of MiB to
/// GiBs. `RLIMIT_AS` would count the libraries and the allocator's reserved but unused
/// address space too, which grow with the machine's cores, not with what is stored.
pub const LINK_MEMORY_LIMIT: u64 = 256 << 20;
/// The link process's async worker threads (its runtime would have one per core).
const LINK_WORKER_THREADS: usize = 2;
/// The longest line either side reads: one answer is one goal's end, whose result holds
/// at most [`crate::wire::MAX_RELATIONS`] relations of three words of
/// [`crate::wire::MAX_WORD_BYTES`] bytes each (about 3 MiB, up to six times that as JSON
/// escapes); a request is one step's goals, much smaller.
pub const MAX_LINE_BYTES: usize = 32 << 20;
/// The most of the child's stderr kept, its last words, for the message when it ends.
const STDERR_TAIL: usize = 4096;
/// How often the parent, waiting for an answer, looks at the episode's cancel flag.
const POLL: Duration = Duration::from_millis(20);
/// How long the child's last words on stderr may take to arrive once it has ended.
const LAST_WORDS: Duration = Duration::from_secs(1);
/// How long a child whose stdin is closed has to end (cancelling the goals in flight,
/// each waiting for its acknowledgement then its result) before it is killed.
const GRACE: Duration = CANCEL_WAIT
    .saturating_mul(2)
    .saturating_add(Duration::from_secs(1));

/// How to start a link process: a program and the arguments that make it one (the
/// `coherent` binary with `robots link`, or Python with `-m coherent._cli robots link`),
/// and the memory limit it sets on itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkCommand {
    pub program: PathBuf,
    pub args: Vec<OsString>,
    /// Bytes of data segment, [`LINK_MEMORY_LIMIT`] unless a caller needs otherwise.
    pub memory_limit: u64,
}

/// The child's first line: what to connect to, and its memory limit.
#[derive(Debug, Serialize, Deserialize)]
struct Config {
    namespace: String,
    robots: Vec<String>,
    server_wait: Duration,
    memory_limit: u64,
}

/// One exchange asked for: the goals, robot by robot number, and the silence allowed.
type Asked = (Vec<(usize, Goal)>, Duration);

/// The parent's later lines.
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Request {
    /// Send these goals (robot by number) and answer each one's end, in order.
    Exchange {
        goals: Vec<(usize, Goal)>,
        silence: Duration,
    },
    /// Cancel every goal in flight, and any sent later (the episode is over).
    Cancel,
}

/// The child's lines: one for the connection, then one per goal of each exchange.
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Answer {
    Connected,
    Refused(Refusal),
    Exchanged(Exchange),
}

/// Why [`Link::connect`] failed, by the kind the parent gives back as its [`Error`].
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Refusal {
    Invalid(String),
    Missing {
        robots: Vec<String>,
        namespace: String,
        waited: Duration,
    },
    Several {
        robot: String,
        namespace: String,
        servers: Vec<String>,
    },
    Dds(String),
    /// Anything else, which `Link::connect` does not return (physics is not its business).
    Other(String),
}

impl From<Error> for Refusal {
    fn from(e: Error) -> Refusal {
        match e {
            Error::Invalid(why) => Refusal::Invalid(why),
            Error::Missing {
                robots,
                namespace,
                waited,
            } => Refusal::Missing {
                robots,
                namespace,
                waited,
            },
            Error::Several {
                robot,
                namespace,
                servers,
            } => Refusal::Several {
                robot,
                namespace,
                servers,
            },
            Error::Dds(why) => Refusal::Dds(why),
            other => Refusal::Other(other.to_string()),
        }
    }
}

impl From<Refusal> for Error {
    fn from(r: Refusal) -> Error {
        match r {
            Refusal::Invalid(why) => Error::Invalid(why),
            Refusal::Missing {
                robots,
                namespace,
                waited,
            } => Error::Missing {
                robots,
                namespace,
                waited,
            },
            Refusal::Several {
                robot,
                namespace,
                servers,
            } => Error::Several {
                robot,
                namespace,
                servers,
            },
            Refusal::Dds(why) => Error::Dds(why),
            Refusal::Other(why) => Error::Link(why),
        }
    }
}

/// Reads one line of at most `max` bytes (its newline aside); `None` at the end of the
/// input, an unfinished last line included (its writer ended while writing it). A
/// longer line is an error, read no further than `max` bytes and one.
fn read_line(input: &mut impl BufRead, max: usize) -> Result<Option<Vec<u8>>, String> {
    let mut line = Vec::new();
    let limit = u64::try_from(max).unwrap_or(u64::MAX).saturating_add(1);
    input
        .by_ref()
        .take(limit)
        .read_until(b'\n', &mut line)
        .map_err(|e| format!("cannot read a line: {e}"))?;
    if line.last() == Some(&b'\n') {
        line.pop();
        Ok(Some(line))
    } else if line.len() > max {
        Err(format!("a line longer than {max} bytes"))
    } else {
        Ok(None)
    }
}

/// Writes `value` as one JSON line and flushes it.
fn write_line(output: &mut impl Write, value: &impl Serialize) -> std::io::Result<()> {
    let mut line = serde_json::to_vec(value).map_err(std::io::Error::other)?;
    line.push(b'\n');
    output.write_all(&line)?;
    output.flush()
}

/// Reads the next line of `input` as a `T`: `None` at the end, an error for a line too
/// long or not a `T`.
fn read_json<T: for<'de> Deserialize<'de>>(input: &mut impl BufRead) -> Result<Option<T>, String> {
    let Some(line) = read_line(input, MAX_LINE_BYTES)? else {
        return Ok(None);
    };
    serde_json::from_slice(&line)
        .map(Some)
        .map_err(|e| format!("a line that is not the protocol's: {e}"))
}

/// The link process itself (`coherent robots link`): reads its configuration from
/// `input`, limits its own memory, takes a runtime from `runtime` (built only then, so
/// that it is within the limit), connects, then answers each request until `input`
/// ends, on `output`. Ctrl-C and SIGTERM are ignored: the parent decides. Returns once
/// the parent is gone.
pub fn serve(
    mut input: impl BufRead + Send + 'static,
    mut output: impl Write,
    runtime: impl FnOnce() -> Result<Handle, String>,
) -> Result<(), String> {
    let config: Config = read_json(&mut input)?.ok_or("no configuration on stdin")?;
    limit_memory(config.memory_limit)?;
    let runtime = runtime()?;
    ignore_signals(&runtime)?;
    let link = match Link::connect(
        &config.namespace,
        &config.robots,
        config.server_wait,
        runtime,
    ) {
        Ok(link) => link,
        Err(e) => {
            let refused = Answer::Refused(e.into());
            return write_line(&mut output, &refused).map_err(|e| e.to_string());
        }
    };
    write_line(&mut output, &Answer::Connected).map_err(|e| e.to_string())?;
    let cancel = Arc::new(AtomicBool::new(false));
    let requests = read_requests(input, Arc::clone(&cancel));
    for request in requests {
        let (goals, silence) = request?;
        if let Some((n, _)) = goals.iter().find(|(n, _)| *n >= config.robots.len()) {
            return Err(format!(
                "from the bridge, a goal for robot number {n} of {}",
                config.robots.len()
            ));
        }
        for exchange in link.exchange(goals, silence, Some(&cancel)) {
            write_line(&mut output, &Answer::Exchanged(exchange)).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// Sets the soft limit of this process's data segment to `bytes` (no higher than the
/// hard limit), so that an allocation past it fails and the process aborts ("memory
/// allocation of N bytes failed") rather than taking the machine's memory: the link
/// process's, and `coherent robots serve`'s (which reads DDS too).
pub fn limit_memory(bytes: u64) -> Result<(), String> {
    use rustix::process::{Resource, Rlimit, getrlimit, setrlimit};
    let now = getrlimit(Resource::Data);
    let current = now.maximum.map_or(bytes, |hard| hard.min(bytes));
    setrlimit(
        Resource::Data,
        Rlimit {
            current: Some(current),
            maximum: now.maximum,
        },
    )
    .map_err(|e| format!("cannot limit its memory to {bytes} bytes: {e}"))
}

/// Takes SIGINT and SIGTERM over for good, so that they no longer end the process: a
/// Ctrl-C reaches the whole foreground process group, and the parent decides what it
/// means.
fn ignore_signals(runtime: &Handle) -> Result<(), String> {
    use tokio::signal::unix::{SignalKind, signal};
    let _inside = runtime.enter();
    for kind in [SignalKind::interrupt(), SignalKind::terminate()] {
        // The handler stays installed once the stream is gone; nothing listens.
        drop(signal(kind).map_err(|e| format!("cannot take signals over: {e}"))?);
    }
    Ok(())
}

/// The exchanges `input` asks for, read on a thread of their own so that a cancel, or
/// the end of the input (the parent gone), raises `cancel` while an exchange is in
/// flight; an unreadable line is an error, after which nothing more is read.
fn read_requests(
    mut input: impl BufRead + Send + 'static,
    cancel: Arc<AtomicBool>,
) -> Receiver<Result<Asked, String>> {
    let (sender, requests) = mpsc::channel();
    std::thread::spawn(move || {
        loop {
            match read_json::<Request>(&mut input) {
                Ok(Some(Request::Exchange { goals, silence })) => {
                    if sender.send(Ok((goals, silence))).is_err() {
                        break;
                    }
                }
                Ok(Some(Request::Cancel)) => cancel.store(true, Ordering::SeqCst),
                Ok(None) => break,
                Err(why) => {
                    let _ = sender.send(Err(format!("from the bridge, {why}")));
                    break;
                }
            }
        }
        cancel.store(true, Ordering::SeqCst);
    });
    requests
}

/// The parent's side: the link process, its answers and its last words.
#[derive(Debug)]
pub(crate) struct LinkProcess {
    child: Child,
    /// Closed to tell the child to end.
    stdin: Option<ChildStdin>,
    /// The answers read so far (in a mutex only so that the bridge may be shared
    /// between threads; it is read through `&mut self`).
    answers: Mutex<Receiver<Result<Answer, String>>>,
    stderr: Arc<Mutex<Vec<u8>>>,
    /// The thread that reads the child's stderr, done once the child and its pipe are.
    stderr_read: Option<std::thread::JoinHandle<()>>,
    memory_limit: u64,
    /// Why the process can no longer be used, once it cannot.
    ended: Option<String>,
}

impl LinkProcess {
    /// Starts the link process with `command` and has it connect as [`Link::connect`]
    /// does; its errors keep their kind, and a process that cannot start or ends
    /// before it answers is [`Error::Link`].
    pub(crate) fn connect(
        command: &LinkCommand,
        namespace: &str,
        robots: &[String],
        server_wait: Duration,
    ) -> Result<LinkProcess, Error> {
        let mut child = Command::new(&command.program)
            .args(&command.args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            // Its DDS traffic needs few threads, and each one's stack counts against its
            // memory limit: a fixed number keeps what it needs apart from the machine's
            // cores (tokio reads this for the session's runtime).
            .env("TOKIO_WORKER_THREADS", LINK_WORKER_THREADS.to_string())
            // Its failures are told by the message that names it; a backtrace of the
            // allocation that failed would only bury that.
            .env("RUST_BACKTRACE", "0")
            // Out of the terminal's foreground group: Ctrl-C is the parent's to forward.
            .process_group(0)
            .spawn()
            .map_err(|e| {
                Error::Link(format!(
                    "cannot start the ROS 2 link process ({}): {e}",
                    command.program.display()
                ))
            })?;
        let stdout = child.stdout.take().map(BufReader::new);
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let stderr_read = child
            .stderr
            .take()
            .map(|err| drain(err, Arc::clone(&stderr)));
        let mut process = LinkProcess {
            stdin: child.stdin.take(),
            answers: Mutex::new(read_answers(stdout)),
            child,
            stderr,
            stderr_read,
            memory_limit: command.memory_limit,
            ended: None,
        };
        let config = Config {
            namespace: namespace.to_owned(),
            robots: robots.to_vec(),
            server_wait,
            memory_limit: command.memory_limit,
        };
        process.send(&config);
        match process.answer(None) {
            Ok(Answer::Connected) => Ok(process),
            Ok(Answer::Refused(why)) => Err(why.into()),
            Ok(Answer::Exchanged(_)) => {
                Err(Error::Link(process.failed("answered before it connected")))
            }
            Err(why) => Err(Error::Link(why)),
        }
    }

    /// [`Link::exchange`] in the link process; `cancel` raised is forwarded to it. When
    /// the process ends or fails, every goal it has not answered fails with a message
    /// that names it (or is cancelled, once `cancel` is raised), and so do later ones.
    pub(crate) fn exchange(
        &mut self,
        goals: Vec<(usize, Goal)>,
        silence: Duration,
        cancel: Option<&AtomicBool>,
    ) -> Vec<Exchange> {
        let count = goals.len();
        self.send(&Request::Exchange { goals, silence });
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            match self.answer(cancel) {
                Ok(Answer::Exchanged(exchange)) => out.push(exchange),
                Ok(_) => {
                    self.failed("answered an exchange out of turn");
                    break;
                }
                Err(_) => break,
            }
        }
        let why = self.ended.clone().unwrap_or_default();
        let cancelled = cancel.is_some_and(|flag| flag.load(Ordering::SeqCst));
        out.resize_with(count, || {
            if cancelled {
                Exchange::Cancelled {
                    acknowledged: false,
                }
            } else {
                Exchange::Failed(why.clone())
            }
        });
        out
    }

    /// Writes `value` to the child; a child that no longer reads has ended, which the
    /// next answer tells.
    fn send(&mut self, value: &impl Serialize) {
        if let Some(stdin) = &mut self.stdin
            && write_line(stdin, value).is_err()
        {
            self.stdin = None;
        }
    }

    /// The child's next answer, forwarding `cancel` once it rises; the reason it ended
    /// or failed, as [`LinkProcess::ended`] keeps it, when no answer comes.
    fn answer(&mut self, cancel: Option<&AtomicBool>) -> Result<Answer, String> {
        if let Some(why) = &self.ended {
            return Err(why.clone());
        }
        let mut forwarded = false;
        loop {
            let answers = self
                .answers
                .get_mut()
                .unwrap_or_else(PoisonError::into_inner);
            match answers.recv_timeout(POLL) {
                Ok(Ok(answer)) => return Ok(answer),
                Ok(Err(why)) => return Err(self.failed(&why)),
                Err(RecvTimeoutError::Disconnected) => return Err(self.failed("")),
                Err(RecvTimeoutError::Timeout) => {
                    if !forwarded && cancel.is_some_and(|flag| flag.load(Ordering::SeqCst)) {
                        forwarded = true;
                        self.send(&Request::Cancel);
                    }
                }
            }
        }
    }

    /// Ends the child, if it has not ended, and keeps (and returns) why it can no longer
    /// be used: `what` it did wrong, if anything, how it ended, and its last words. A
    /// child that did nothing wrong has closed its stdout to end: it is given time to.
    fn failed(&mut self, what: &str) -> String {
        let status = self.end(if what.is_empty() {
            GRACE
        } else {
            Duration::ZERO
        });
        // Its last words may still be on their way from the pipe.
        let deadline = Instant::now() + LAST_WORDS;
        while self.stderr_read.as_ref().is_some_and(|t| !t.is_finished())
            && Instant::now() < deadline
        {
            std::thread::sleep(POLL);
        }
        let how = match status {
            Some(status) => ended_by(status),
            None => "could not be reaped".to_owned(),
        };
        let mut why = if what.is_empty() {
            format!("the ROS 2 link process ended ({how})")
        } else {
            format!("the ROS 2 link process {what} and was ended ({how})")
        };
        if what.is_empty() {
            why.push_str(&format!(
                "; it holds the bridge's DDS participant within a memory limit of {} MiB, \
                 which a flood of large DDS samples makes it reach",
                self.memory_limit >> 20
            ));
        }
        let tail = self
            .stderr
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        let said = String::from_utf8_lossy(&tail);
        let said = said.trim();
        if !said.is_empty() {
            why.push_str(&format!(
                "; its last words: {}",
                coherent_core::text::shown(said)
            ));
        }
        self.ended.get_or_insert(why).clone()
    }

    /// Closes the child's stdin, waits up to `grace` for it to end, then kills it (at
    /// once without a grace period); its exit status, unless it cannot be had.
    fn end(&mut self, grace: Duration) -> Option<ExitStatus> {
        if grace.is_zero() {
            let _ = self.child.kill();
        }
        self.stdin = None;
        let deadline = Instant::now() + grace;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return Some(status),
                Ok(None) if Instant::now() < deadline => std::thread::sleep(POLL),
                Ok(None) => break,
                Err(_) => return None,
            }
        }
        let _ = self.child.kill();
        self.child.wait().ok()
    }
}

impl Drop for LinkProcess {
    /// The child cancels what it has in flight when its stdin closes, then ends; it is
    /// killed if it takes longer than that could.
    fn drop(&mut self) {
        self.end(GRACE);
    }
}

/// How a process ended, in words: `exit status 3`, `killed by SIGKILL`.
fn ended_by(status: ExitStatus) -> String {
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit status {code}"),
        (None, Some(signal)) => {
            let name = match signal {
                1 => "SIGHUP",
                2 => "SIGINT",
                6 => "SIGABRT",
                9 => "SIGKILL",
                11 => "SIGSEGV",
                15 => "SIGTERM",
                _ => return format!("killed by signal {signal}"),
            };
            format!("killed by {name}")
        }
        (None, None) => status.to_string(),
    }
}

/// Reads the child's answers on a thread of their own; a line too long or not an answer
/// is sent as the child's failure, and nothing more is read.
fn read_answers(stdout: Option<impl BufRead + Send + 'static>) -> Receiver<Result<Answer, String>> {
    let (sender, answers) = mpsc::channel();
    if let Some(mut stdout) = stdout {
        std::thread::spawn(move || {
            loop {
                match read_json::<Answer>(&mut stdout) {
                    Ok(Some(answer)) => {
                        if sender.send(Ok(answer)).is_err() {
                            break;
                        }
                    }
                    Ok(None) => break,
                    Err(why) => {
                        let _ = sender.send(Err(format!("wrote {why}")));
                        break;
                    }
                }
            }
        });
    }
    answers
}

/// Reads the child's stderr to its end on a thread of its own, keeping its last
/// [`STDERR_TAIL`] bytes in `tail`.
fn drain(
    mut stderr: impl Read + Send + 'static,
    tail: Arc<Mutex<Vec<u8>>>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let mut chunk = [0; 1024];
        while let Ok(n) = stderr.read(&mut chunk) {
            if n == 0 {
                break;
            }
            let mut kept = tail.lock().unwrap_or_else(PoisonError::into_inner);
            kept.extend_from_slice(&chunk[..n]);
            let over = kept.len().saturating_sub(STDERR_TAIL);
            kept.drain(..over);
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_longer_than_the_limit_is_an_error_read_no_further() {
        let mut input = std::io::Cursor::new(b"12345\n123456\n12345678\n".to_vec());
        assert_eq!(read_line(&mut input, 6), Ok(Some(b"12345".to_vec())));
        assert_eq!(read_line(&mut input, 6), Ok(Some(b"123456".to_vec())));
        assert_eq!(
            read_line(&mut input, 6),
            Err("a line longer than 6 bytes".to_owned())
        );
        assert_eq!(input.position(), 13 + 7, "no more than the limit and one");
        // A line cut short by the end of the input: its writer ended.
        let mut input = std::io::Cursor::new(b"{\"exchanged\"".to_vec());
        assert_eq!(read_line(&mut input, 64), Ok(None));
    }

    #[test]
    fn the_errors_of_a_connection_keep_their_kind_across_the_process() {
        let errors = [
            Error::Invalid("bad".into()),
            Error::Missing {
                robots: vec!["robot_arm_6".into()],
                namespace: "/lab".into(),
                waited: Duration::from_millis(2500),
            },
            Error::Several {
                robot: "robot_arm_6".into(),
                namespace: "/lab".into(),
                servers: vec!["participant 01".into(), "participant 02".into()],
            },
            Error::Dds("cannot join".into()),
        ];
        for e in errors {
            let line = serde_json::to_vec(&Answer::Refused(e.clone().into())).expect("JSON");
            let back: Answer = serde_json::from_slice(&line).expect("an answer");
            let Answer::Refused(refusal) = back else {
                panic!("{back:?}");
            };
            assert_eq!(Error::from(refusal), e);
        }
    }

    /// A child that writes a line longer than the protocol's is ended and named, and the
    /// parent reads no more of it than the limit.
    #[test]
    fn a_child_that_writes_a_line_too_long_is_ended_and_named() {
        let command = LinkCommand {
            program: "sh".into(),
            args: ["-c", "head -c 33554433 /dev/zero; exec sleep 60"]
                .map(OsString::from)
                .to_vec(),
            memory_limit: LINK_MEMORY_LIMIT,
        };
        let error = LinkProcess::connect(&command, "/lab", &[], Duration::ZERO)
            .expect_err("not a link process");
        let Error::Link(why) = error else {
            panic!("{error:?}");
        };
        assert!(
            why.starts_with(
                "the ROS 2 link process wrote a line longer than 33554432 bytes and was \
                 ended (killed by SIGKILL)"
            ),
            "{why}"
        );
    }

    #[test]
    fn how_a_process_ended_is_said_with_the_signals_name() {
        assert_eq!(ended_by(ExitStatus::from_raw(6)), "killed by SIGABRT");
        assert_eq!(ended_by(ExitStatus::from_raw(9)), "killed by SIGKILL");
        assert_eq!(ended_by(ExitStatus::from_raw(3 << 8)), "exit status 3");
    }
}
