//! The reference robot servers: one ROS 2 action server per robot of a task, all acting
//! in one world of the project's own engine (the rules, or Rapier with physics). Each
//! goal is accepted (or refused), worked on with feedback, carried out, and answered with
//! the result and what the robot then observes. This is the test partner of the bridge
//! and the template of an adapter for a real robot: replace [`World::act`] with the
//! robot's own controller and [`relations::observed`] with its perception.

use std::future::Future;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use coherent_core::feasibility::{Infeasible, Reason};
use coherent_core::text::{cut, shown};
use coherent_core::{Idx, NodeId, Task};
use ros2_client::action::{AsyncActionServer, ExecutingGoalHandle, GoalEndStatus};
use ros2_client::{NodeName, NodeOptions, ServiceMapping};
use tokio::time::{Instant, interval, sleep_until, timeout};

use crate::befall;
use crate::error::Error;
use crate::faults::Faults;
use crate::relations;
use crate::wire::{self, BefallRequest, BefallResponse, ExecuteResult, Feedback, Goal};
use crate::world::World;

type Server = AsyncActionServer<Goal, ExecuteResult, Feedback>;
type Service = ros2_client::Server<BefallRequest, BefallResponse>;
type Executing = ExecutingGoalHandle<Goal>;

/// How often a robot at work sends feedback.
const FEEDBACK_EVERY: Duration = Duration::from_millis(100);
/// How long a result waits for the bridge to ask for it before it is dropped.
const RESULT_WAIT: Duration = Duration::from_secs(10);

/// The data segment `coherent robots serve` limits itself to by default (see
/// [`crate::link_process::limit_memory`]): it reads DDS like the link process, so a flood
/// of large samples would take the machine's memory; it needs about 20 MiB with the
/// rules or Rapier on the bundled scenes, and a physics server of a larger world may
/// need more than the link process's limit, hence a wider one (and a flag).
pub const SERVE_MEMORY_LIMIT: u64 = 1 << 30;

/// What to serve and how.
#[derive(Clone, Debug, Default)]
pub struct ServeOptions {
    /// The namespace of the actions (absolute, see [`wire::namespace`]).
    pub namespace: String,
    /// Carry the actions out in Rapier, not by the rules alone.
    pub physics: bool,
    pub faults: Faults,
}

/// One robot as its server knows it.
struct Me {
    name: String,
    node: Idx,
    id: NodeId,
    label: String,
}

/// Serves every robot of `task` under [`ServeOptions::namespace`] until `stop` resolves;
/// `log` gets one line when the servers are up and one per goal.
pub async fn serve(
    task: Arc<Task>,
    options: ServeOptions,
    log: &(dyn Fn(&str) + Sync),
    stop: impl Future<Output = ()>,
) -> Result<(), Error> {
    let names = wire::robot_names(&task);
    options.faults.check(&names)?;
    let world = Arc::new(Mutex::new(World::new(&task, options.physics)?));
    let context = wire::context().map_err(Error::Dds)?;
    let node_name = NodeName::new(&options.namespace, "coherent_robots")
        .map_err(|e| Error::Dds(format!("node name: {e:?}")))?;
    let mut node = context
        .new_node(node_name, NodeOptions::new().enable_rosout(false))
        .map_err(|e| Error::Dds(format!("cannot make a node: {e:?}")))?;
    let mut servers = Vec::new();
    for (r, name) in task.robots.iter().zip(&names) {
        if options.faults.is_absent(name) {
            continue;
        }
        let action = wire::ros_action_name(&options.namespace, name).map_err(Error::Dds)?;
        let server = node
            .create_action_server::<Goal, ExecuteResult, Feedback>(
                ServiceMapping::Enhanced,
                &action,
                &wire::action_type(),
                wire::server_qos(),
            )
            .map_err(|e| Error::Dds(format!("action server {name}: {e:?}")))?;
        let me = Me {
            name: name.clone(),
            node: r.node,
            id: task.id(r.node),
            label: task.node(r.node).label(),
        };
        servers.push((AsyncActionServer::new(server), me));
    }
    let service_name = wire::ros_service_name(&options.namespace).map_err(Error::Dds)?;
    let service: Service = node
        .create_server(
            ServiceMapping::Enhanced,
            &service_name,
            &wire::service_type(),
            wire::services(),
            wire::services(),
        )
        .map_err(|e| Error::Dds(format!("the world's service: {e:?}")))?;
    let actions: Vec<String> = servers
        .iter()
        .map(|(_, me)| wire::action_name(&options.namespace, &me.name))
        .collect();
    log(&format!(
        "serving {} robots of {} task {} ({}): {}; events at {}",
        actions.len(),
        task.meta.scene,
        task.meta.task_id,
        if options.physics { "physics" } else { "rules" },
        actions.join(" "),
        wire::service_name(&options.namespace)
    ));
    let robots = futures::future::join_all(servers.iter().map(|(server, me)| {
        let at = Robot {
            server,
            me,
            task: &task,
            world: &world,
            faults: &options.faults,
            log,
        };
        at.serve()
    }));
    let events = serve_events(&service, &task, &names, &world, log);
    tokio::select! {
        _ = robots => {}
        () = events => {}
        () = stop => {}
    }
    drop(service);
    drop(servers);
    drop(node);
    Ok(())
}

/// The world's service: each request carries events out in `world` ([`befall::carry_out`])
/// and is answered, forever. A request larger than any the bridge sends is refused
/// unread; what is logged of one is shown escaped.
async fn serve_events(
    service: &Service,
    task: &Arc<Task>,
    names: &[String],
    world: &Arc<Mutex<World>>,
    log: &(dyn Fn(&str) + Sync),
) {
    loop {
        let (id, request) = match service.async_receive_request().await {
            Ok(received) => received,
            Err(e) => {
                log(&format!("events: cannot read a request: {e:?}"));
                continue;
            }
        };
        let said = format!("events before step {}", request.step);
        let mut words = request.team.iter().chain(&request.locked);
        let carried = if request.team.len() > names.len() || request.locked.len() > task.nodes.len()
        {
            Err("a request larger than the task".to_owned())
        } else if let Some(w) = words.find(|w| w.len() > wire::MAX_WORD_BYTES) {
            Err(format!("a name of {} bytes", w.len()))
        } else if let Err(why) = wire::relations_checked("the request", &request.moved) {
            Err(why)
        } else {
            let (task, names, world) = (Arc::clone(task), names.to_vec(), Arc::clone(world));
            tokio::task::spawn_blocking(move || {
                let mut world = world.lock().unwrap_or_else(PoisonError::into_inner);
                befall::carry_out(&task, &names, &mut world, &request)
            })
            .await
            .unwrap_or_else(|e| Err(format!("the world failed: {e}")))
        };
        let response = match carried {
            Ok((message, relations)) => {
                log(&format!("{said} -> done: {}", shown(&message)));
                BefallResponse {
                    accepted: true,
                    message,
                    relations,
                }
            }
            Err(why) => {
                let why = shown(&cut(&why, wire::MAX_MESSAGE_BYTES)).into_owned();
                log(&format!("{said} -> refused: {why}"));
                BefallResponse {
                    accepted: false,
                    message: why,
                    relations: Vec::new(),
                }
            }
        };
        if service.async_send_response(id, response).await.is_err() {
            log(&format!("{said} -> the answer could not be delivered"));
        }
    }
}

/// One robot's server at work.
struct Robot<'a> {
    server: &'a Server,
    me: &'a Me,
    task: &'a Arc<Task>,
    world: &'a Arc<Mutex<World>>,
    faults: &'a Faults,
    log: &'a (dyn Fn(&str) + Sync),
}

impl Robot<'_> {
    /// Takes goals one at a time, forever.
    async fn serve(self) {
        let name = &self.me.name;
        let mut draws = self.faults.draws(name);
        loop {
            let handle = match self.server.receive_new_goal().await {
                Ok(handle) => handle,
                Err(e) => {
                    (self.log)(&format!("{name}: cannot read a goal: {e:?}"));
                    continue;
                }
            };
            let Some(goal) = self.server.get_new_goal(handle.clone()) else {
                continue;
            };
            // A goal comes from any participant: what is logged of it is shown escaped
            // and short, and an action longer than any of the grammar is refused.
            let said = format!(
                "{name} step {} {}",
                goal.step,
                shown(&cut(&goal.action, wire::MAX_WORD_BYTES))
            );
            if goal.action.len() > wire::MAX_WORD_BYTES {
                let _ = self.server.reject_goal(handle).await;
                (self.log)(&format!(
                    "{said} -> refused: an action of {} bytes",
                    goal.action.len()
                ));
                continue;
            }
            if !self.in_team() {
                let _ = self.server.reject_goal(handle).await;
                (self.log)(&format!(
                    "{said} -> refused: {} is out of the team (an event)",
                    self.me.label
                ));
                continue;
            }
            if self.faults.refuses(name) {
                let _ = self.server.reject_goal(handle).await;
                (self.log)(&format!("{said} -> refused (--refuse)"));
                continue;
            }
            let executing = match self.server.accept_goal(handle).await {
                Ok(accepted) => self.server.start_executing_goal(accepted).await,
                Err(e) => Err(e),
            };
            let Ok(executing) = executing else {
                (self.log)(&format!("{said} -> cannot accept the goal"));
                continue;
            };
            (self.log)(&format!("{said} -> accepted"));
            if self.faults.is_silent(name) {
                (self.log)(&format!("{said} -> no answer, ever (--silent)"));
                continue;
            }
            let fails = draws.fails();
            let (end, result) = self.work(&executing, &goal, fails).await;
            (self.log)(&format!(
                "{said} -> {}: {}",
                match end {
                    GoalEndStatus::Succeeded => "succeeded",
                    GoalEndStatus::Aborted => "failed",
                    GoalEndStatus::Canceled => "cancelled",
                },
                result.message
            ));
            let sent = timeout(
                RESULT_WAIT,
                self.server.send_result_response(executing, end, result),
            )
            .await;
            if !matches!(sent, Ok(Ok(()))) {
                (self.log)(&format!("{said} -> the result could not be delivered"));
            }
        }
    }

    /// Whether the robot is in the team as events have left it (down, or not joined
    /// yet: it refuses goals).
    fn in_team(&self) -> bool {
        let world = self.world.lock().unwrap_or_else(PoisonError::into_inner);
        world.task().robots.iter().any(|r| r.node == self.me.node)
    }

    async fn feedback(&self, goal: &Executing, stage: &str, progress: f32) {
        let feedback = Feedback {
            stage: stage.to_owned(),
            progress,
        };
        let _ = self.server.publish_feedback(goal.clone(), feedback).await;
    }

    /// Works on `goal`: the delay (feedback all along, cancellable), then the action in
    /// the world (or an injected failure when `fails`).
    async fn work(
        &self,
        handle: &Executing,
        goal: &Goal,
        fails: bool,
    ) -> (GoalEndStatus, ExecuteResult) {
        let me = &self.me.label;
        let action = &goal.action;
        self.feedback(handle, wire::STAGE_STARTED, 0.0).await;
        let delay = self.faults.delay;
        let start = Instant::now();
        let mut tick = interval(FEEDBACK_EVERY);
        let mut progress = 0.0;
        while start.elapsed() < delay {
            tokio::select! {
                _ = tick.tick() => {
                    progress = (start.elapsed().as_secs_f32() / delay.as_secs_f32()).min(1.0);
                    self.feedback(handle, wire::STAGE_WORKING, progress).await;
                }
                () = sleep_until(start + delay) => {}
                cancel = self.server.receive_cancel_request() => {
                    let Ok(cancel) = cancel else { continue };
                    let mine = cancel.contains_goal(&handle.goal_id());
                    let goals = mine.then(|| handle.goal_id());
                    let _ = self.server.respond_to_cancel_requests(&cancel, goals.into_iter()).await;
                    if mine {
                        let message = format!("{me} stopped before {action}: cancelled");
                        return (GoalEndStatus::Canceled, self.result(false, "cancelled", message));
                    }
                }
            }
        }
        if fails {
            let message = format!(
                "{me} could not carry out {action}: an injected failure (--fail-rate {}, --seed {})",
                self.faults.fail_rate, self.faults.seed
            );
            return (GoalEndStatus::Aborted, self.result(false, "robot", message));
        }
        let done = self.act(handle, action, progress).await;
        match done {
            Ok(message) => {
                self.feedback(handle, wire::STAGE_FINISHED, 1.0).await;
                (GoalEndStatus::Succeeded, self.result(true, "", message))
            }
            Err(why) => (
                GoalEndStatus::Aborted,
                self.result(false, why.reason.name(), why.message),
            ),
        }
    }

    /// Carries the action out on a blocking thread (physics takes a while), with
    /// feedback meanwhile; too late to cancel now, so cancel requests are refused.
    async fn act(
        &self,
        handle: &Executing,
        action: &str,
        progress: f32,
    ) -> Result<String, Infeasible> {
        let world = Arc::clone(self.world);
        let (robot, action) = (self.me.id, action.to_owned());
        let job = tokio::task::spawn_blocking(move || {
            let mut world = world.lock().unwrap_or_else(PoisonError::into_inner);
            world.act(robot, &action)
        });
        tokio::pin!(job);
        let mut tick = interval(FEEDBACK_EVERY);
        loop {
            tokio::select! {
                done = &mut job => {
                    return done.unwrap_or_else(|e| Err(Infeasible {
                        reason: Reason::Robot,
                        message: format!("the robot's controller failed: {e}"),
                    }));
                }
                _ = tick.tick() => self.feedback(handle, wire::STAGE_WORKING, progress).await,
                cancel = self.server.receive_cancel_request() => {
                    if let Ok(cancel) = cancel {
                        let none = std::iter::empty();
                        let _ = self.server.respond_to_cancel_requests(&cancel, none).await;
                    }
                }
            }
        }
    }

    /// A result with what the robot observes now.
    fn result(&self, success: bool, reason: &str, message: String) -> ExecuteResult {
        let world = self.world.lock().unwrap_or_else(PoisonError::into_inner);
        ExecuteResult {
            success,
            reason: reason.to_owned(),
            message,
            relations: relations::observed(self.task, world.state(), self.me.node),
        }
    }
}
