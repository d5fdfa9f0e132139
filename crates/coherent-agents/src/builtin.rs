//! The built-in backend: the optimal planner plays both roles, so that the loop runs
//! on a fresh machine with no model. The assigner proposes the first step of a shortest
//! plan from the current state; the executor takes that step when it is in its list.
//! Its answers are the same JSON a model would give, and go through the same parsing.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use coherent_core::planner::{self, Limits, Step};
use coherent_core::task::predicate_holds;
use coherent_core::{State, Task, rules};
use serde_json::json;

use crate::llm::{
    Answer, Backend, BackendInfo, BoxFuture, Finish, LlmError, LlmErrorKind, OutputMode, Query,
    Role, Usage,
};

/// The next step of a shortest plan from each state seen, per task, or why there is
/// none. Planning once and following the plan costs one search per episode instead of
/// one per round; a state off the plan is planned afresh.
type Plans = HashMap<(usize, State), Result<Step, String>>;

#[derive(Debug, Default)]
pub struct BuiltinBackend {
    inner: Arc<Planner>,
}

#[derive(Debug, Default)]
struct Planner {
    limits: Limits,
    plans: Mutex<Plans>,
    /// The tasks planned for, kept alive so that the addresses in the keys stay theirs.
    tasks: Mutex<Vec<Arc<Task>>>,
}

impl BuiltinBackend {
    /// `limits` bound each search; its cancel flag stops one in flight.
    pub fn new(limits: Limits) -> BuiltinBackend {
        BuiltinBackend {
            inner: Arc::new(Planner {
                limits,
                ..Planner::default()
            }),
        }
    }
}

impl Planner {
    fn next_step(&self, task: &Arc<Task>, state: &State) -> Result<Step, String> {
        let key = (Arc::as_ptr(task) as usize, state.clone());
        if let Some(known) = self
            .plans
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get(&key)
        {
            return known.clone();
        }
        // A goal no action can ever reach (a goal container that is no container, say)
        // is refused at once, without exhausting the state space. A predicate that holds
        // already is no obstacle: nothing could have moved it there, nor can move it away.
        let obstacle = task
            .goal
            .iter()
            .filter(|p| !predicate_holds(state, p))
            .find_map(|p| {
                planner::static_obstacle(task, p)
                    .map(|why| format!("{}: {why}", task.predicate_label(p)))
            });
        if let Some(why) = obstacle {
            return Err(why);
        }
        let search = planner::search_from(task, state, &task.robots, &task.goal, &self.limits);
        let mut plans = self.plans.lock().unwrap_or_else(PoisonError::into_inner);
        let mut tasks = self.tasks.lock().unwrap_or_else(PoisonError::into_inner);
        if !tasks.iter().any(|t| Arc::ptr_eq(t, task)) {
            tasks.push(Arc::clone(task));
        }
        let plan = match search.plan {
            Some(plan) if !plan.is_empty() => plan,
            Some(_) => return Err("the goal already holds".into()),
            // Cancelled or cut short: not an answer to remember.
            None if search.truncated => {
                return Err(format!(
                    "the search stopped after {} states without a plan",
                    search.states_expanded
                ));
            }
            None => {
                let why = "no plan reaches the goal from here".to_owned();
                plans.insert(key, Err(why.clone()));
                return Err(why);
            }
        };
        let mut s = state.clone();
        for step in &plan {
            plans.insert((key.0, s.clone()), Ok(*step));
            if let Some(robot) = task.robot(step.robot) {
                rules::apply(task, &mut s, *robot, step.action);
            }
        }
        Ok(plan[0])
    }

    fn answer(&self, q: &Query) -> Answer {
        let task = &q.situation.task;
        let state = &q.situation.state;
        let (text, finish) = match q.role {
            Role::Assigner => match self.next_step(task, state) {
                Ok(step) => (
                    json!({
                        "reasoning": "The first step of a shortest plan from here.",
                        "robot": task.node(step.robot).label(),
                        "subtask": step.action.render(task),
                    })
                    .to_string(),
                    Finish::Stop,
                ),
                Err(why) => (String::new(), Finish::Refusal(why)),
            },
            Role::Executor => {
                let subtask = q.situation.subtask.as_deref().unwrap_or_default();
                let robot = q.robot.and_then(|id| task.robot_by_id(id).ok());
                let offered = robot.is_some_and(|r| {
                    rules::actions(task, state, r)
                        .iter()
                        .any(|a| a.render(task) == subtask)
                });
                let answer = if offered {
                    json!({"action": subtask, "subtask_complete": true, "note": ""})
                } else {
                    json!({
                        "action": "none",
                        "subtask_complete": false,
                        "note": "the subtask is not one of my actions now",
                    })
                };
                (answer.to_string(), Finish::Stop)
            }
        };
        Answer {
            text,
            finish,
            usage: Usage::default(),
            latency_ms: 0.0,
            attempts: 1,
            mode: OutputMode::JsonSchema,
        }
    }
}

impl Backend for BuiltinBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: "builtin".into(),
            model: "optimal-planner".into(),
            base_url: None,
        }
    }

    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        let planner = Arc::clone(&self.inner);
        Box::pin(async move {
            let start = Instant::now();
            // A search can take a second or two: keep it off the async workers.
            let mut answer = tokio::task::spawn_blocking(move || planner.answer(&query))
                .await
                .map_err(|e| {
                    LlmError::new(LlmErrorKind::Internal, format!("the planner failed: {e}"))
                })?;
            answer.latency_ms = start.elapsed().as_secs_f64() * 1e3;
            Ok(answer)
        })
    }
}
