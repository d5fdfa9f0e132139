//! The bridge's side of DDS: one node with one action client per robot, spun on the
//! runtime the caller hands in (the session's, the one place a runtime is built), and
//! the exchange of one step's goals, one per robot acting, all in flight at once (send
//! each, follow its feedback, take its result; cancel it on Ctrl-C or when its robot
//! falls silent) as a blocking call that works inside an async runtime as well as
//! outside one.

use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use futures::StreamExt;
use ros2_client::action::{ActionClient, GoalId, GoalStatusEnum};
use ros2_client::builtin_interfaces::Time;
use ros2_client::{Node, NodeName, NodeOptions, ServiceMapping};
use tokio::runtime::Handle;
use tokio::task::JoinHandle;
use tokio::time::{Instant, sleep, sleep_until, timeout};

use crate::error::Error;
use crate::wire::{self, ExecuteResult, Feedback, Goal};

type Client = ActionClient<Goal, ExecuteResult, Feedback>;

/// How often the wait for the robots' servers looks again.
const RECHECK: Duration = Duration::from_millis(100);
/// How often a goal in flight looks at the cancel flag.
const CANCEL_POLL: Duration = Duration::from_millis(20);
/// How long a cancelled goal waits for the robot's acknowledgement, then its result.
const CANCEL_WAIT: Duration = Duration::from_secs(2);

/// How one goal ended, seen from the bridge.
#[derive(Debug)]
pub(crate) enum Exchange {
    /// The result came, with the goal's end status.
    Result {
        status: GoalStatusEnum,
        result: ExecuteResult,
    },
    /// The server refused the goal.
    Rejected,
    /// Nothing came for the silence allowed: no answer to the goal, no feedback, no
    /// result; `last` is what was heard last.
    Silent { last: String },
    /// Cancelled (Ctrl-C) before a result came; whether the robot acknowledged it.
    Cancelled { acknowledged: bool },
    /// DDS could not send or receive.
    Failed(String),
}

impl Exchange {
    /// Whether the robot reports the action carried out (what it observes aside).
    pub(crate) fn succeeded(&self) -> bool {
        matches!(self, Exchange::Result { status, result }
            if *status == GoalStatusEnum::Succeeded && result.success)
    }
}

/// The bridge's DDS participant: a node and the robots' action clients.
pub(crate) struct Link {
    clients: Vec<Client>,
    node: Node,
    runtime: Handle,
    spinner: JoinHandle<()>,
}

impl std::fmt::Debug for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Link")
            .field("node", &self.node.fully_qualified_name())
            .field("clients", &self.clients.len())
            .finish()
    }
}

impl Link {
    /// Joins DDS, makes an action client for each of `robots` under `namespace`, spins
    /// the node on `runtime`, and waits up to `wait` for every robot's server to appear.
    pub(crate) fn connect(
        namespace: &str,
        robots: &[String],
        wait: Duration,
        runtime: Handle,
    ) -> Result<Link, Error> {
        let context = wire::context().map_err(Error::Dds)?;
        let name = NodeName::new(namespace, "coherent_bridge")
            .map_err(|e| Error::Dds(format!("node name: {e:?}")))?;
        let mut node = context
            .new_node(name, NodeOptions::new().enable_rosout(false))
            .map_err(|e| Error::Dds(format!("cannot make a node: {e:?}")))?;
        let spinner = node
            .spinner()
            .map_err(|e| Error::Dds(format!("cannot spin the node: {e:?}")))?;
        let spinner = runtime.spawn(async move {
            let _ = spinner.spin().await;
        });
        let mut clients = Vec::with_capacity(robots.len());
        for robot in robots {
            let action = wire::ros_action_name(namespace, robot).map_err(Error::Dds)?;
            let client = node
                .create_action_client(
                    ServiceMapping::Enhanced,
                    &action,
                    &wire::action_type(),
                    wire::client_qos(),
                )
                .map_err(|e| Error::Dds(format!("action client {robot}: {e:?}")))?;
            clients.push(client);
        }
        let link = Link {
            clients,
            node,
            runtime,
            spinner,
        };
        let found = link.block(async {
            let each = link
                .clients
                .iter()
                .map(|c| timeout(wait, served(c, &link.node)));
            futures::future::join_all(each).await
        });
        let missing: Vec<String> = robots
            .iter()
            .zip(found)
            .filter(|(_, found)| found.is_err())
            .map(|(r, _)| r.clone())
            .collect();
        if missing.is_empty() {
            Ok(link)
        } else {
            Err(Error::Missing {
                robots: missing,
                namespace: namespace.to_owned(),
                waited: wait,
            })
        }
    }

    /// Sends each goal to its robot (by number) at once and waits for every one's end:
    /// its result, a refusal, `silence` without a word, or `cancel` raised (then every
    /// goal still in flight is cancelled). One exchange per goal, in the order given; it
    /// takes as long as the slowest robot.
    pub(crate) fn exchange(
        &self,
        goals: Vec<(usize, Goal)>,
        silence: Duration,
        cancel: Option<&AtomicBool>,
    ) -> Vec<Exchange> {
        let each = goals
            .into_iter()
            .map(|(robot, goal)| follow_goal(&self.clients[robot], goal, silence, cancel));
        self.block(futures::future::join_all(each))
    }

    /// Runs `future` to its end on the link's runtime, from a thread of its own, so that
    /// the caller may be inside a runtime (an episode's) or in none.
    fn block<T: Send>(&self, future: impl Future<Output = T> + Send) -> T {
        let handle = &self.runtime;
        std::thread::scope(|s| {
            s.spawn(|| handle.block_on(future))
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    }
}

impl Drop for Link {
    /// Stops the spinner without waiting (allowed inside a runtime).
    fn drop(&mut self) {
        self.node.stop_spinner();
        self.spinner.abort();
    }
}

/// Resolves once the robot's goal, result and cancel services have a server. A wait of
/// ros2-client sees the matches made before it starts and then only the graph events
/// that reach it (its queue drops some in a burst of discovery), so it is started anew
/// every [`RECHECK`] until all three are there.
async fn served(client: &Client, node: &Node) {
    loop {
        let all = async {
            client.goal_client().wait_for_service(node).await;
            client.result_client().wait_for_service(node).await;
            client.cancel_client().wait_for_service(node).await;
        };
        if timeout(RECHECK, all).await.is_ok() {
            return;
        }
    }
}

/// Resolves once `flag` is raised; never without one.
async fn raised(flag: Option<&AtomicBool>) {
    match flag {
        Some(flag) => {
            while !flag.load(Ordering::SeqCst) {
                sleep(CANCEL_POLL).await;
            }
        }
        None => std::future::pending().await,
    }
}

/// Sends `goal` to `client`'s robot and follows it to its end: its feedback, its result,
/// a refusal, `silence` without a word, or `cancel` raised (the goal is then cancelled).
async fn follow_goal(
    client: &Client,
    goal: Goal,
    silence: Duration,
    cancel: Option<&AtomicBool>,
) -> Exchange {
    if cancel.is_some_and(|flag| flag.load(Ordering::SeqCst)) {
        return Exchange::Cancelled {
            acknowledged: false,
        };
    }
    let cancelled = raised(cancel);
    tokio::pin!(cancelled);
    // Sent at once, so that the goal's id is known should it have to be cancelled.
    let (request, goal_id) = match client.send_goal(goal) {
        Ok(sent) => sent,
        Err(e) => return Exchange::Failed(format!("cannot send the goal: {e}")),
    };
    let response = tokio::select! {
        answer = client.goal_client().async_receive_response(request) => match answer {
            Ok(response) => response,
            Err(e) => return Exchange::Failed(format!("cannot read the goal's answer: {e}")),
        },
        () = sleep(silence) => {
            let _ = client.cancel_goal(goal_id);
            return Exchange::Silent { last: "nothing: the goal was never answered".into() };
        }
        () = &mut cancelled => {
            return cancel_goal(client, goal_id, client.async_request_result(goal_id)).await;
        }
    };
    if !response.accepted {
        return Exchange::Rejected;
    }
    let result = client.async_request_result(goal_id);
    tokio::pin!(result);
    let feedback = client.feedback_stream(goal_id);
    tokio::pin!(feedback);
    let mut last = "the goal's acceptance".to_owned();
    let mut deadline = Instant::now() + silence;
    loop {
        tokio::select! {
            r = &mut result => {
                return match r {
                    Ok((status, result)) => Exchange::Result { status, result },
                    Err(e) => Exchange::Failed(format!("cannot read the result: {e}")),
                };
            }
            Some(f) = feedback.next() => {
                if let Ok(f) = f {
                    last = format!("feedback {:?} at {:.0}%", f.stage, f.progress * 100.0);
                }
                deadline = Instant::now() + silence;
            }
            () = sleep_until(deadline) => {
                // Best effort: a robot that wakes up should not go on with it.
                let _ = client.cancel_goal(goal_id);
                return Exchange::Silent { last };
            }
            () = &mut cancelled => return cancel_goal(client, goal_id, result).await,
        }
    }
}

/// Cancels `goal_id` and waits a little for the robot's acknowledgement and its result;
/// a result other than "cancelled" that comes all the same (the robot finished first,
/// or refused to stop) is the goal's result.
async fn cancel_goal(
    client: &Client,
    goal_id: GoalId,
    result: impl Future<Output = Result<(GoalStatusEnum, ExecuteResult), impl std::fmt::Display>>,
) -> Exchange {
    let answer = timeout(CANCEL_WAIT, client.async_cancel_goal(goal_id, Time::ZERO)).await;
    let acknowledged = matches!(answer, Ok(Ok(r)) if !r.goals_canceling.is_empty());
    match timeout(CANCEL_WAIT, result).await {
        Ok(Ok((status, result))) if status != GoalStatusEnum::Canceled => {
            Exchange::Result { status, result }
        }
        _ => Exchange::Cancelled { acknowledged },
    }
}
