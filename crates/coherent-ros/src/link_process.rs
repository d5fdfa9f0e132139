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
//!
//! The parent never waits on the child without a bound: the child says it is alive
//! every [`HEARTBEAT`], and a child silent for as long as a robot may be (at least
//! [`MIN_QUIET`]; 30 s before its first line) is unresponsive (stopped, or hung) and is
//! killed; after a cancel it has 5 s to answer; and what the parent writes goes through
//! a thread of its own, so that a child that no longer reads cannot block it.

use std::ffi::OsString;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use tokio::runtime::Handle;

use crate::error::Error;
use crate::link::{Befell, CANCEL_WAIT, Exchange, Link};
use crate::wire::{BefallRequest, Goal};

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
/// each waiting for its acknowledgement then its result) before it is killed; and how
/// long, once a cancel is forwarded, it has to answer every goal in flight.
const GRACE: Duration = CANCEL_WAIT
    .saturating_mul(2)
    .saturating_add(Duration::from_secs(1));
/// How often the child says it is alive, whatever it is doing.
pub const HEARTBEAT: Duration = Duration::from_millis(250);
/// The least silence after which a child is unresponsive, however short the robots'
/// timeout: eight heartbeats, room for a busy machine to schedule it.
pub const MIN_QUIET: Duration = Duration::from_secs(2);
/// How long a child may take to say anything at all: to start (a Python interpreter
/// importing the package, on a busy machine), read its configuration and start its
/// heartbeat.
const START: Duration = Duration::from_secs(30);
/// The stack of the child's heartbeat thread, which only writes a short line: every
/// thread's stack counts against the child's memory limit.
const HEARTBEAT_STACK: usize = 64 << 10;

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
    /// Whether the task has events: the world's service is then needed too.
    events: bool,
    server_wait: Duration,
    memory_limit: u64,
}

/// What the parent asks for, once read: one exchange (the goals, robot by robot number,
/// and the silence allowed), or events carried out by the world's service.
enum Asked {
    Goals(Vec<(usize, Goal)>, Duration),
    World(BefallRequest, Duration),
}

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
    /// Ask the world's service to carry these events out, and answer how it ended.
    Befall {
        request: BefallRequest,
        silence: Duration,
    },
}

/// The child's lines: one for the connection, then one per goal of each exchange; that
/// it is alive, every [`HEARTBEAT`]; why it ends, when it ends on its own.
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Answer {
    Connected,
    Refused(Refusal),
    Exchanged(Exchange),
    Befell(Befell),
    Alive,
    Ends(String),
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

/// Why a line could not be read: the input failed, or it held something that is no line
/// of the protocol (too long, or not one of its values).
#[derive(Debug, PartialEq, Eq)]
enum Unread {
    Failed(String),
    Foreign(String),
}

impl std::fmt::Display for Unread {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unread::Failed(why) => write!(f, "cannot read a line: {why}"),
            Unread::Foreign(what) => f.write_str(what),
        }
    }
}

/// Reads one line of at most `max` bytes (its newline aside); `None` at the end of the
/// input, an unfinished last line included (its writer ended while writing it). A
/// longer line is an error, read no further than `max` bytes and one.
fn read_line(input: &mut impl BufRead, max: usize) -> Result<Option<Vec<u8>>, Unread> {
    let mut line = Vec::new();
    let limit = u64::try_from(max).unwrap_or(u64::MAX).saturating_add(1);
    input
        .by_ref()
        .take(limit)
        .read_until(b'\n', &mut line)
        .map_err(|e| Unread::Failed(e.to_string()))?;
    if line.last() == Some(&b'\n') {
        line.pop();
        Ok(Some(line))
    } else if line.len() > max {
        Err(Unread::Foreign(format!("a line longer than {max} bytes")))
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
fn read_json<T: for<'de> Deserialize<'de>>(input: &mut impl BufRead) -> Result<Option<T>, Unread> {
    let Some(line) = read_line(input, MAX_LINE_BYTES)? else {
        return Ok(None);
    };
    serde_json::from_slice(&line)
        .map(Some)
        .map_err(|e| Unread::Foreign(format!("a line that is not the protocol's ({e})")))
}

/// The link process itself (`coherent robots link`): reads its configuration from
/// `input`, limits its own memory, takes a runtime from `runtime` (built only then, so
/// that it is within the limit), connects, then answers each request until `input`
/// ends, on `output`, saying every [`HEARTBEAT`] that it is alive. Ctrl-C and SIGTERM
/// are ignored: the parent decides. Returns once the parent is gone; an input that is
/// not the parent's requests ends it with an error, which it tells the parent first.
pub fn serve(
    mut input: impl BufRead + Send + 'static,
    output: impl Write + Send,
    runtime: impl FnOnce() -> Result<Handle, String>,
) -> Result<(), String> {
    let config: Config = read_json(&mut input)
        .map_err(|e| e.to_string())?
        .ok_or("no configuration on stdin")?;
    limit_memory(config.memory_limit)?;
    let runtime = runtime()?;
    ignore_signals(&runtime)?;
    let output = Mutex::new(output);
    let over = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let beating = std::thread::Builder::new()
            .name("heartbeat".into())
            .stack_size(HEARTBEAT_STACK)
            .spawn_scoped(scope, || heartbeat(&output, &over))
            .map_err(|e| format!("cannot start its heartbeat: {e}"))?;
        let served = work(input, &output, &config, runtime);
        over.store(true, Ordering::SeqCst);
        beating.thread().unpark();
        served
    })
}

/// Writes `answer` as one line of `output`, which the heartbeat shares.
fn say(output: &Mutex<impl Write>, answer: &Answer) -> Result<(), String> {
    let mut output = output.lock().unwrap_or_else(PoisonError::into_inner);
    write_line(&mut *output, answer).map_err(|e| e.to_string())
}

/// Says the process is alive every [`HEARTBEAT`] until `over`, so that the parent can
/// tell a link process at work (a robot may take minutes) from a stopped or hung one.
fn heartbeat(output: &Mutex<impl Write>, over: &AtomicBool) {
    while !over.load(Ordering::SeqCst) {
        std::thread::park_timeout(HEARTBEAT);
        if over.load(Ordering::SeqCst) || say(output, &Answer::Alive).is_err() {
            break;
        }
    }
}

/// [`serve`] once configured: connects, then answers each request of `input`; a line
/// that is not a request ends it, told to the parent as [`Answer::Ends`].
fn work(
    input: impl BufRead + Send + 'static,
    output: &Mutex<impl Write>,
    config: &Config,
    runtime: Handle,
) -> Result<(), String> {
    let link = match Link::connect(
        &config.namespace,
        &config.robots,
        config.events,
        config.server_wait,
        runtime,
    ) {
        Ok(link) => link,
        Err(e) => return say(output, &Answer::Refused(e.into())),
    };
    say(output, &Answer::Connected)?;
    let ends = |why: String| {
        // Its last word on the protocol; it may be unable to say it (the parent gone).
        let _ = say(output, &Answer::Ends(why.clone()));
        Err(why)
    };
    let cancel = Arc::new(AtomicBool::new(false));
    let requests = read_requests(input, Arc::clone(&cancel));
    // What came while an exchange was in flight, read to see whether it ended it.
    let mut came = None;
    loop {
        let (goals, silence) = match came.take().map_or_else(|| requests.recv(), Ok) {
            Ok(Ok(Asked::Goals(goals, silence))) => (goals, silence),
            Ok(Ok(Asked::World(request, silence))) => {
                say(output, &Answer::Befell(link.befall(request, silence)))?;
                continue;
            }
            Ok(Err(why)) => return ends(why),
            // The input ended: the parent is gone.
            Err(_) => return Ok(()),
        };
        if let Some((n, _)) = goals.iter().find(|(n, _)| *n >= config.robots.len()) {
            return ends(format!(
                "from the bridge, a goal for robot number {n} of {}",
                config.robots.len()
            ));
        }
        let exchanges = link.exchange(goals, silence, Some(&cancel));
        // A line that is not a request cancels the goals in flight (nothing more can be
        // asked); they fail with it rather than look cancelled by the run. A request
        // that came meanwhile is answered next.
        came = requests.try_recv().ok();
        let foreign = match &came {
            Some(Err(why)) => Some(why.clone()),
            _ => None,
        };
        for exchange in exchanges {
            let exchange = match (&foreign, exchange) {
                (Some(why), Exchange::Cancelled { .. }) => {
                    Exchange::Failed(format!("the ROS 2 link process ends: {why}"))
                }
                (_, exchange) => exchange,
            };
            say(output, &Answer::Exchanged(exchange))?;
        }
        if let Some(why) = foreign {
            return ends(why);
        }
    }
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
                    if sender.send(Ok(Asked::Goals(goals, silence))).is_err() {
                        break;
                    }
                }
                Ok(Some(Request::Befall { request, silence })) => {
                    if sender.send(Ok(Asked::World(request, silence))).is_err() {
                        break;
                    }
                }
                Ok(Some(Request::Cancel)) => cancel.store(true, Ordering::SeqCst),
                Ok(None) => break,
                Err(Unread::Foreign(what)) => {
                    let _ = sender.send(Err(format!(
                        "its stdin held {what}, which the run never writes: something other \
                         than the run wrote to the link process's stdin"
                    )));
                    break;
                }
                Err(Unread::Failed(why)) => {
                    let _ = sender.send(Err(format!("cannot read its stdin: {why}")));
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
    /// The lines for the child's stdin, written by a thread of their own; dropped to
    /// close it, which tells the child to end.
    stdin: Option<Sender<Vec<u8>>>,
    /// The answers read so far (in a mutex only so that the bridge may be shared
    /// between threads; it is read through `&mut self`).
    answers: Mutex<Receiver<Result<Answer, Unread>>>,
    /// When the child last wrote a line, its heartbeat included; `None` before its first.
    heard: Arc<Mutex<Option<Instant>>>,
    /// The silence after which the child is unresponsive: the robots' timeout, at least
    /// [`MIN_QUIET`].
    quiet: Duration,
    stderr: Arc<Mutex<Vec<u8>>>,
    /// The thread that reads the child's stderr, done once the child and its pipe are.
    stderr_read: Option<std::thread::JoinHandle<()>>,
    memory_limit: u64,
    /// Why the process can no longer be used, once it cannot.
    ended: Option<String>,
}

/// How the parent found the link process unusable.
enum Gone<'a> {
    /// Its stdout ended without a word of why: it ended, or was ended, from outside the
    /// protocol (a flood reaching its memory limit, a kill).
    Ended,
    /// It said why it ends.
    Said(&'a str),
    /// It did what a link process never does (a line too long, an answer out of turn);
    /// it is ended.
    Misbehaved(&'a str),
    /// Nothing from it, not even its heartbeat, for this long: stopped or hung; it is
    /// ended.
    Silent(Duration),
}

impl LinkProcess {
    /// Starts the link process with `command` and has it connect as [`Link::connect`]
    /// does; its errors keep their kind, and a process that cannot start, ends before
    /// it answers or falls silent for `quiet` (the robots' timeout; at least
    /// [`MIN_QUIET`]) is [`Error::Link`].
    pub(crate) fn connect(
        command: &LinkCommand,
        namespace: &str,
        (robots, events): (&[String], bool),
        server_wait: Duration,
        quiet: Duration,
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
        let heard = Arc::new(Mutex::new(None));
        let mut process = LinkProcess {
            stdin: child.stdin.take().map(write_requests),
            answers: Mutex::new(read_answers(stdout, Arc::clone(&heard))),
            heard,
            quiet: quiet.max(MIN_QUIET),
            child,
            stderr,
            stderr_read,
            memory_limit: command.memory_limit,
            ended: None,
        };
        let config = Config {
            namespace: namespace.to_owned(),
            robots: robots.to_vec(),
            events,
            server_wait,
            memory_limit: command.memory_limit,
        };
        process.send(&config);
        match process.answer(None) {
            Ok(Answer::Connected) => Ok(process),
            Ok(Answer::Refused(why)) => Err(why.into()),
            Ok(_) => Err(Error::Link(
                process.failed(Gone::Misbehaved("answered before it connected")),
            )),
            Err(why) => Err(Error::Link(why)),
        }
    }

    /// [`Link::exchange`] in the link process; `cancel` raised is forwarded to it. When
    /// the process ends, fails or falls silent, every goal it has not answered fails
    /// with a message that names it (or is cancelled, once `cancel` is raised), and so
    /// do later ones.
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
                    self.failed(Gone::Misbehaved("answered an exchange out of turn"));
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

    /// [`Link::befall`] in the link process: the world's answer, or how it failed (the
    /// process ended, failed or fell silent; a cancel waits for the answer all the same,
    /// which comes within `silence`).
    pub(crate) fn befall(&mut self, request: BefallRequest, silence: Duration) -> Befell {
        self.send(&Request::Befall { request, silence });
        match self.answer(None) {
            Ok(Answer::Befell(befell)) => befell,
            Ok(_) => Befell::Failed(self.failed(Gone::Misbehaved(
                "answered a request for events out of turn",
            ))),
            Err(why) => Befell::Failed(why),
        }
    }

    /// Hands `value` to the thread that writes the child's stdin; a child that no
    /// longer reads has ended, which the next answer tells.
    fn send(&mut self, value: &impl Serialize) {
        let mut line = Vec::new();
        if write_line(&mut line, value).is_err() {
            return;
        }
        if let Some(stdin) = &self.stdin
            && stdin.send(line).is_err()
        {
            self.stdin = None;
        }
    }

    /// The child's next answer, forwarding `cancel` once it rises; the reason it ended,
    /// failed or fell silent, as [`LinkProcess::ended`] keeps it, when no answer comes.
    /// Silent for [`LinkProcess::quiet`], or still answering [`GRACE`] after a cancel,
    /// it is unresponsive and is killed: the wait has a bound whatever the child does.
    fn answer(&mut self, cancel: Option<&AtomicBool>) -> Result<Answer, String> {
        if let Some(why) = &self.ended {
            return Err(why.clone());
        }
        let mut forwarded: Option<Instant> = None;
        let mut heard = *self.heard.lock().unwrap_or_else(PoisonError::into_inner);
        let (mut silent, mut looked) = (Duration::ZERO, Instant::now());
        loop {
            let answers = self
                .answers
                .get_mut()
                .unwrap_or_else(PoisonError::into_inner);
            match answers.recv_timeout(POLL) {
                Ok(Ok(Answer::Ends(why))) => return Err(self.failed(Gone::Said(&why))),
                Ok(Ok(answer)) => return Ok(answer),
                Ok(Err(why)) => {
                    return Err(self.failed(Gone::Misbehaved(&format!("wrote {why}"))));
                }
                Err(RecvTimeoutError::Disconnected) => return Err(self.failed(Gone::Ended)),
                Err(RecvTimeoutError::Timeout) => {
                    if forwarded.is_none() && cancel.is_some_and(|flag| flag.load(Ordering::SeqCst))
                    {
                        forwarded = Some(Instant::now());
                        self.send(&Request::Cancel);
                    }
                    // The silence counts the time this run waited and looked, each look
                    // at most a few polls long: a run that was itself stopped (Ctrl-Z)
                    // has not read what came meanwhile, and its own pause is not the
                    // child's silence.
                    let now = Instant::now();
                    let last = *self.heard.lock().unwrap_or_else(PoisonError::into_inner);
                    if last == heard {
                        silent += (now - looked).min(POLL * 5);
                    } else {
                        (heard, silent) = (last, Duration::ZERO);
                    }
                    looked = now;
                    // Once cancelled, the run is to end soon: a few heartbeats missed
                    // are enough. Before its first line, it may still be starting.
                    let quiet = match (forwarded, heard) {
                        (_, None) => self.quiet.max(START),
                        (Some(_), _) => self.quiet.min(MIN_QUIET),
                        (None, _) => self.quiet,
                    };
                    if silent > quiet {
                        return Err(self.failed(Gone::Silent(quiet)));
                    }
                    if forwarded.is_some_and(|at| at.elapsed() > GRACE) {
                        let what = format!(
                            "did not answer within {} s of a cancel",
                            GRACE.as_secs_f64()
                        );
                        return Err(self.failed(Gone::Misbehaved(&what)));
                    }
                }
            }
        }
    }

    /// Ends the child, if it has not ended, and keeps (and returns) why it can no longer
    /// be used: how the parent found it unusable (`gone`), how it ended, and its last
    /// words. A child that ended on its own has closed its stdout: it is given time to.
    fn failed(&mut self, gone: Gone<'_>) -> String {
        let on_its_own = matches!(gone, Gone::Ended | Gone::Said(_));
        let status = self.end(if on_its_own { GRACE } else { Duration::ZERO });
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
        let mut why = match gone {
            Gone::Ended => format!(
                "the ROS 2 link process ended ({how}); it holds the bridge's DDS participant \
                 within a memory limit of {} MiB, which a flood of large DDS samples makes it \
                 reach",
                self.memory_limit >> 20
            ),
            // What it said is what its stderr says too.
            Gone::Said(said) => {
                let why = format!("the ROS 2 link process ended ({how}): {said}");
                return self.ended.get_or_insert(why).clone();
            }
            Gone::Misbehaved(what) => {
                format!("the ROS 2 link process {what} and was ended ({how})")
            }
            Gone::Silent(quiet) => format!(
                "the ROS 2 link process is unresponsive: nothing from it for {} s, though it \
                 says it is alive every {} s (stopped, or hung); it was ended ({how})",
                quiet.as_secs_f64(),
                HEARTBEAT.as_secs_f64()
            ),
        };
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

/// Reads the child's answers on a thread of their own, noting in `heard` when each line
/// came; its heartbeats go no further. A line too long or not an answer is sent as the
/// child's failure, and nothing more is read.
fn read_answers(
    stdout: Option<impl BufRead + Send + 'static>,
    heard: Arc<Mutex<Option<Instant>>>,
) -> Receiver<Result<Answer, Unread>> {
    let (sender, answers) = mpsc::channel();
    if let Some(mut stdout) = stdout {
        std::thread::spawn(move || {
            loop {
                let line = read_json::<Answer>(&mut stdout);
                *heard.lock().unwrap_or_else(PoisonError::into_inner) = Some(Instant::now());
                match line {
                    Ok(Some(Answer::Alive)) => {}
                    Ok(Some(answer)) => {
                        if sender.send(Ok(answer)).is_err() {
                            break;
                        }
                    }
                    Ok(None) => break,
                    Err(why) => {
                        let _ = sender.send(Err(why));
                        break;
                    }
                }
            }
        });
    }
    answers
}

/// Writes the parent's lines to the child's stdin on a thread of its own, so that a
/// child that no longer reads (stopped, hung) never blocks the run; the stdin closes
/// once the sender is gone and every line sent is written, or the child has ended.
fn write_requests(mut stdin: ChildStdin) -> Sender<Vec<u8>> {
    let (sender, lines) = mpsc::channel::<Vec<u8>>();
    std::thread::spawn(move || {
        for line in lines {
            if stdin.write_all(&line).and_then(|()| stdin.flush()).is_err() {
                break;
            }
        }
    });
    sender
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
            Err(Unread::Foreign("a line longer than 6 bytes".to_owned()))
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
        let error = LinkProcess::connect(&command, "/lab", (&[], false), Duration::ZERO, MIN_QUIET)
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
