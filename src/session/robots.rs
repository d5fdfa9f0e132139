//! Who carries an episode's actions out: this process (the rules, and Rapier with
//! physics) or robots over ROS 2, one action server per robot; and the reference robot
//! servers (`coherent robots serve`).

use coherent_core::text::number;
use std::ffi::OsString;
use std::future::Future;
use std::io::BufReader;
use std::path::PathBuf;
use std::sync::{Arc, PoisonError, RwLock};
use std::time::Duration;

use coherent_agents::transcript::RobotsRecord;
use coherent_ros::{Faults, LINK_MEMORY_LIMIT, LinkCommand, ServeOptions};

use crate::session::error::Error;
use crate::session::tasks;

/// Who carries an episode's actions out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Robots {
    /// This process: the rules, and Rapier too with physics.
    #[default]
    Local,
    /// One ROS 2 action server per robot (`coherent robots serve`, or real robots).
    Ros2(coherent_ros::BridgeOptions),
}

impl Robots {
    /// Robots over ROS 2 under `namespace` (made absolute), each allowed `robot_timeout`
    /// seconds of silence in a step, all awaited `server_wait` seconds before the first.
    pub fn ros2(namespace: &str, robot_timeout: f64, server_wait: f64) -> Result<Robots, Error> {
        let seconds = |what: &str, s: f64| {
            std::time::Duration::try_from_secs_f64(s).map_err(|_| {
                Error::Invalid(format!(
                    "{what} must be seconds from 0 to 1.8e19, not {}",
                    number(s)
                ))
            })
        };
        let namespace =
            coherent_ros::wire::namespace(namespace).map_err(|e| Error::Invalid(e.to_string()))?;
        Ok(Robots::Ros2(coherent_ros::BridgeOptions {
            namespace,
            robot_timeout: seconds("the robot timeout", robot_timeout)?,
            server_wait: seconds("the wait for the servers", server_wait)?,
            link: link_command()?,
        }))
    }

    /// How a transcript records these robots.
    pub fn record(&self) -> RobotsRecord {
        match self {
            Robots::Local => RobotsRecord::Local,
            Robots::Ros2(options) => RobotsRecord::Ros2 {
                namespace: options.namespace.clone(),
            },
        }
    }
}

/// The words after the program that make it a link process: the command line's hidden
/// `coherent robots link`.
pub const LINK_SUBCOMMAND: [&str; 2] = ["robots", "link"];

/// The program that starts link processes and its arguments before [`LINK_SUBCOMMAND`],
/// when this process is not the `coherent` binary (see [`start_links_with`]).
static LINK_PROGRAM: RwLock<Option<(PathBuf, Vec<OsString>)>> = RwLock::new(None);

/// Has robots over ROS 2 start their link process as `program args... robots link`
/// rather than with this process's own executable: for a front end whose executable is
/// not the `coherent` binary (the Python package, where it is Python; a test program).
pub fn start_links_with(program: PathBuf, args: Vec<OsString>) {
    *LINK_PROGRAM.write().unwrap_or_else(PoisonError::into_inner) = Some((program, args));
}

/// How this process starts a link process: [`start_links_with`]'s program, else this
/// very executable, with [`LINK_SUBCOMMAND`] and the default memory limit.
fn link_command() -> Result<LinkCommand, Error> {
    let set = LINK_PROGRAM
        .read()
        .unwrap_or_else(PoisonError::into_inner)
        .clone();
    let (program, mut args) = match set {
        Some(set) => set,
        None => {
            let program = std::env::current_exe().map_err(|e| {
                Error::Internal(format!(
                    "cannot find this program to start the ROS 2 link process with: {e}"
                ))
            })?;
            (program, Vec::new())
        }
    };
    args.extend(LINK_SUBCOMMAND.map(OsString::from));
    Ok(LinkCommand {
        program,
        args,
        memory_limit: LINK_MEMORY_LIMIT,
    })
}

/// Runs this process as a link process (`coherent robots link`): the bridge's DDS side,
/// configured and asked over stdin, answering on stdout, until stdin ends.
pub fn link() -> Result<(), Error> {
    let runtime = || {
        super::runtime()
            .map(|r| r.handle().clone())
            .map_err(|e| e.to_string())
    };
    coherent_ros::link_process::serve(BufReader::new(std::io::stdin()), std::io::stdout(), runtime)
        .map_err(|why| Error::Robots(coherent_ros::Error::Link(why)))
}

/// A `coherent-ros` error as the session's: a setting that cannot be used, a world
/// that cannot be built, or robots that cannot be reached.
pub(crate) fn ros_error(e: coherent_ros::Error) -> Error {
    match e {
        coherent_ros::Error::Invalid(why) => Error::Invalid(why),
        coherent_ros::Error::Physics(e) => Error::Physics(e),
        e => Error::Robots(e),
    }
}

/// The reference robot servers of a task, as `coherent robots serve` asks for them.
#[derive(Debug)]
pub struct ServeRequest {
    /// A native task file, or an original env file with `task_id`.
    pub task_file: PathBuf,
    pub task_id: Option<i64>,
    /// The namespace of the robots' actions.
    pub namespace: String,
    /// Carry the actions out in Rapier, checked against the rules.
    pub physics: bool,
    /// Fault: seconds each action takes, with feedback all along.
    pub delay: f64,
    /// Fault: the chance (0 to 1) that a robot reports failure instead of acting.
    pub fail_rate: f64,
    /// Seeds the failures of `fail_rate`.
    pub seed: u64,
    /// Fault: robots (ROS names) that accept goals and never answer.
    pub silent: Vec<String>,
    /// Fault: robots whose server refuses every goal.
    pub refuse: Vec<String>,
    /// Fault: robots whose server is not started.
    pub absent: Vec<String>,
    /// The data segment this process limits itself to, in bytes, since it reads DDS
    /// (see [`coherent_ros::SERVE_MEMORY_LIMIT`]).
    pub memory_limit: u64,
}

/// Serves every robot of the task `request` names as a ROS 2 action server until `stop`
/// resolves; `log` gets one line when the servers are up and one per goal. The whole
/// process is limited to [`ServeRequest::memory_limit`] from then on.
pub fn serve(
    request: ServeRequest,
    log: &(dyn Fn(&str) + Sync),
    stop: impl Future<Output = ()>,
) -> Result<(), Error> {
    let task = tasks::pick_task(&request.task_file, request.task_id)?;
    coherent_ros::link_process::limit_memory(request.memory_limit)
        .map_err(|why| Error::Invalid(format!("--memory-limit: {why}")))?;
    let options = ServeOptions {
        namespace: coherent_ros::wire::namespace(&request.namespace).map_err(ros_error)?,
        physics: request.physics,
        faults: Faults {
            delay: Duration::try_from_secs_f64(request.delay).map_err(|_| {
                Error::Invalid(format!(
                    "--delay must be seconds from 0 to 1.8e19, not {}",
                    number(request.delay)
                ))
            })?,
            fail_rate: request.fail_rate,
            seed: request.seed,
            silent: request.silent,
            refuse: request.refuse,
            absent: request.absent,
        },
    };
    super::block_on(coherent_ros::serve(Arc::new(task), options, log, stop))?.map_err(ros_error)
}
