//! `coherent robots serve`: the reference robot servers of a task over ROS 2 (the flags
//! with which `run` and `bench` send their actions to robots are in `args.rs`).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::session::Error;
use crate::session::engine::{DEFAULT_NAMESPACE, SERVE_MEMORY_LIMIT};
use crate::session::robots::{self, ServeRequest};

#[derive(Args)]
pub(crate) struct RobotsArgs {
    #[command(subcommand)]
    command: RobotsCommand,
}

#[derive(Subcommand)]
enum RobotsCommand {
    /// Serve every robot of a task as a ROS 2 action server,
    /// `/<namespace>/<robot>/execute` (coherent_msgs/action/Execute), acting by the rules
    /// or in Rapier (--physics), until Ctrl-C. One line when the servers are up, one per
    /// goal.
    Serve(ServeArgs),
    /// The bridge's DDS side for a run over ROS 2, in a process of its own that `run`,
    /// `bench` and the Python package start: JSON lines on stdin and stdout.
    #[command(hide = true)]
    Link,
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
    /// The most memory (data segment, MiB) the servers may take: past it they end
    /// rather than take the machine's (a DDS participant flooding them with large
    /// samples), and their clients see silent robots. Raise it for a large physical
    /// world; from 64 (they need about 20) to 1048576 (1 TiB).
    #[arg(
        long,
        value_name = "MIB",
        default_value_t = SERVE_MEMORY_LIMIT >> 20,
        value_parser = clap::value_parser!(u64).range(64..=1 << 20)
    )]
    memory_limit: u64,
}

pub(crate) fn robots(args: RobotsArgs) -> Result<u8, Error> {
    match args.command {
        RobotsCommand::Serve(args) => serve(args),
        RobotsCommand::Link => robots::link().map(|()| 0),
    }
}

fn serve(args: ServeArgs) -> Result<u8, Error> {
    let request = ServeRequest {
        task_file: args.task_file,
        task_id: args.task_id,
        namespace: args.namespace,
        physics: args.physics,
        delay: args.delay,
        fail_rate: args.fail_rate,
        seed: args.seed,
        silent: args.silent,
        refuse: args.refuse,
        absent: args.absent,
        memory_limit: args.memory_limit.saturating_mul(1 << 20),
    };
    let log = |line: &str| println!("{line}");
    robots::serve(request, &log, shutdown())?;
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
