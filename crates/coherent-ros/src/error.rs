//! Why the robots over ROS 2 could not be set up or reached: one variant per kind, so
//! that a caller decides by the kind (an exit status, an exception class).

use std::time::Duration;

/// Why the bridge or the robot servers could not start.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A setting that cannot be used: a namespace, a fault naming no robot of the task, a
    /// failure rate out of range.
    Invalid(String),
    /// These robots had no action server within the time given.
    Missing {
        robots: Vec<String>,
        namespace: String,
        waited: Duration,
    },
    /// A robot has more than one action server: each would carry out every goal.
    Several {
        robot: String,
        namespace: String,
        /// The servers' DDS participants, as `participant 0f1e...`.
        servers: Vec<String>,
    },
    /// DDS could not be set up.
    Dds(String),
    /// The ROS 2 link process, which holds the bridge's DDS side, could not be started
    /// or ended before it connected (the message names it and says how).
    Link(String),
    /// The robots' physical world cannot be built for the task.
    Physics(coherent_sim::PhysicsError),
}

impl Error {
    /// The error's text, naming the setting of the wait for the servers as `wait` (a
    /// front end's flag, `--server-wait`, or argument, `server_wait=`).
    pub fn with_wait_named(&self, wait: &str) -> String {
        match self {
            Error::Missing {
                robots,
                namespace,
                waited,
            } => format!(
                "no ROS 2 action server for {} under {namespace} within {:.1} s (start the \
                 robots' servers, e.g. `coherent robots serve TASK --namespace {namespace}`, \
                 or wait longer with {wait})",
                robots.join(", "),
                waited.as_secs_f64()
            ),
            other => other.to_string(),
        }
    }
}

/// The command line's words: the wait is `--server-wait`.
impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Invalid(why) => f.write_str(why),
            Error::Missing { .. } => f.write_str(&self.with_wait_named("--server-wait")),
            Error::Several {
                robot,
                namespace,
                servers,
            } => write!(
                f,
                "{} ROS 2 action servers for {robot} under {namespace} ({}): each would carry \
                 out every goal, and the robot's world and the rules' would part; stop all \
                 but one",
                servers.len(),
                servers.join(", ")
            ),
            Error::Dds(why) => write!(f, "ROS 2: {why}"),
            Error::Link(why) => f.write_str(why),
            Error::Physics(e) => write!(f, "physics: {e}"),
        }
    }
}

impl std::error::Error for Error {}
