//! `coherent robots serve`: the reference robot servers of a task over ROS 2, and the
//! flags with which `coherent run` sends its actions to robots over ROS 2.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand, ValueEnum};
use coherent_core::text::number;
use coherent_ros::wire::{self, DEFAULT_NAMESPACE};
use coherent_ros::{Faults, ServeOptions};

use crate::session::episode::Robots;
use crate::session::{self, tasks};

#[derive(Args)]
pub(crate) struct RobotsArgs {
    #[command(subcommand)]
    command: RobotsCommand,
}

#[derive(Subcommand)]
enum RobotsCommand {
    /// Serve every robot of a task as a ROS 2 action server, /<namespace>/<robot>/execute
    /// (coherent_msgs/action/Execute), acting by the rules or in Rapier (--physics), until
    /// Ctrl-C. One line when the servers are up, one per goal.
    Serve(ServeArgs),
}

#[derive(Args)]
struct ServeArgs {
    /// A native task file, or an original env file with --task.
    task_file: PathBuf,
    /// Which task of the file (its task_id).
    #[arg(long = "task")]
    task_id: Option<i64>,
    /// Carry the actions out in Rapier, checked against the rules.
    #[arg(long)]
    physics: bool,
    /// The namespace of the robots' actions.
    #[arg(long, default_value = DEFAULT_NAMESPACE)]
    namespace: String,
    /// Fault: seconds each action takes, with feedback all along.
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    delay: f64,
    /// Fault: the chance (0 to 1) that a robot reports failure instead of acting.
    #[arg(long, default_value_t = 0.0, value_name = "RATE")]
    fail_rate: f64,
    /// Seeds the failures of --fail-rate.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Fault: a robot (ROS name, e.g. quadrotor_11) that accepts goals and never
    /// answers; repeatable.
    #[arg(long = "silent", value_name = "ROBOT")]
    silent: Vec<String>,
    /// Fault: a robot (ROS name) whose server refuses every goal; repeatable.
    #[arg(long = "refuse", value_name = "ROBOT")]
    refuse: Vec<String>,
    /// Fault: a robot (ROS name) whose server is not started; repeatable.
    #[arg(long = "absent", value_name = "ROBOT")]
    absent: Vec<String>,
}

/// Who carries `coherent run`'s actions out.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum RobotsKind {
    /// This process: the rules, or Rapier too with --physics.
    Local,
    /// One ROS 2 action server per robot (`coherent robots serve`, or real robots).
    Ros2,
}

/// `coherent run`'s flags for robots over ROS 2.
#[derive(Args)]
pub(crate) struct RobotFlags {
    /// Who carries the actions out: `local` (this process), or `ros2` (one ROS 2 action
    /// server per robot at /<namespace>/<robot>/execute).
    #[arg(long, value_enum, default_value = "local")]
    robots: RobotsKind,
    /// With --robots ros2: the namespace of the robots' actions.
    #[arg(long, default_value = DEFAULT_NAMESPACE)]
    namespace: String,
    /// With --robots ros2: seconds a robot may stay silent during a step (no answer, no
    /// feedback, no result) before the step fails and the episode stops (exit 4).
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    robot_timeout: f64,
    /// With --robots ros2: seconds to wait for every robot's server before the first
    /// step; exit 2 naming the robots without one.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    server_wait: f64,
}

impl RobotFlags {
    pub(crate) fn robots(&self) -> Result<Robots, String> {
        match self.robots {
            RobotsKind::Local => Ok(Robots::Local),
            RobotsKind::Ros2 => Robots::ros2(&self.namespace, self.robot_timeout, self.server_wait),
        }
    }
}

pub(crate) fn robots(args: RobotsArgs) -> Result<u8, String> {
    match args.command {
        RobotsCommand::Serve(args) => serve(args),
    }
}

fn serve(args: ServeArgs) -> Result<u8, String> {
    let task = tasks::pick_task(&args.task_file, args.task_id)?;
    let options = ServeOptions {
        namespace: wire::namespace(&args.namespace)?,
        physics: args.physics,
        faults: Faults {
            delay: Duration::try_from_secs_f64(args.delay).map_err(|_| {
                format!(
                    "--delay must be seconds from 0 to 1.8e19, not {}",
                    number(args.delay)
                )
            })?,
            fail_rate: args.fail_rate,
            seed: args.seed,
            silent: args.silent,
            refuse: args.refuse,
            absent: args.absent,
        },
    };
    let log = |line: &str| println!("{line}");
    session::block_on(coherent_ros::serve(
        std::sync::Arc::new(task),
        options,
        &log,
        shutdown(),
    ))??;
    Ok(0)
}

/// Resolves on Ctrl-C or SIGTERM.
async fn shutdown() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        if let Ok(mut term) = signal(SignalKind::terminate()) {
            tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                _ = term.recv() => {}
            }
            return;
        }
    }
    let _ = tokio::signal::ctrl_c().await;
}
