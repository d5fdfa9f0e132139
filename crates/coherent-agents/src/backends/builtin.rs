//! The built-in backend: the optimal planner plays both roles, so that the loop runs
//! on a fresh machine with no model. The assigner proposes the first step of a shortest
//! plan from the current state; the executor takes that step when it is in its list; a
//! central or dialogue method gets that step as its team action. In a parallel episode
//! the plan is one of the fewest joint steps (`coherent_core::makespan`): the assigner
//! gives its first joint step's actions to the idle robots among them, a central model
//! chooses that joint step, and each speaker of a dialogue its own action in it. Its
//! answers are the same JSON a model would give, and go through the same parsing.
//!
//! The simulated backend ([`BuiltinBackend::simulated`]) is the same planner making the
//! mistakes language models make, each at its own seeded rate
//! ([`crate::backends::simulated`]).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Instant;

use coherent_core::makespan::{self, JointStep};
use coherent_core::planner::{self, Limits, Step};
use coherent_core::task::predicate_holds;
use coherent_core::{Idx, PropSet, Relation, State, Task, rules};
use serde_json::json;

use crate::backends::simulated::{ErrorRates, Mistake, hallucinated, other_robot};
use crate::llm::{
    Answer, Backend, BackendInfo, BackendKind, BoxFuture, Finish, LlmError, LlmErrorKind,
    OutputMode, Query, Usage,
};
use crate::prompts::team_actions;
use crate::rng::Rng;

/// The first step `S` of a plan from each state seen, per task (by the task's address),
/// or why there is none. Planning once and following the plan costs one search per
/// episode instead of one per round; a state off the plan is planned afresh.
type Known<S> = HashMap<(usize, State), Result<S, String>>;

/// The next step of a shortest plan from each state seen.
type Plans = Known<Step>;

/// The first joint step of a plan of the fewest joint steps from each state seen.
type JointPlans = Known<JointStep>;

#[derive(Debug, Default)]
pub struct BuiltinBackend {
    inner: Arc<Planner>,
    /// The simulated backend's error model and its seeded draws; `None` for the
    /// built-in backend, which makes no mistakes.
    errors: Option<(ErrorRates, Arc<Draws>)>,
}

/// The simulated backend's random draws, taken by its calls in the order they were
/// asked: each call takes a ticket when it is first polled (a parallel round's executors
/// are polled in team order) and draws only when every call before it has drawn. The
/// searches run on blocking threads that finish in any order; without the tickets, a
/// parallel round's mistakes fell to whichever robot's thread locked the generator first,
/// and the same seed could give another episode.
#[derive(Debug)]
struct Draws {
    tickets: AtomicU64,
    /// The ticket whose turn it is, and the generator.
    turn: Mutex<(u64, Rng)>,
    next: Condvar,
}

impl Draws {
    fn new(seed: u64) -> Draws {
        Draws {
            tickets: AtomicU64::new(0),
            turn: Mutex::new((0, Rng::new(seed))),
            next: Condvar::new(),
        }
    }

    /// The next ticket, in the order calls ask.
    fn ticket(&self) -> u64 {
        self.tickets.fetch_add(1, Ordering::SeqCst)
    }

    /// Waits for `ticket`'s turn: the generator, until the turn is dropped.
    fn wait(&self, ticket: u64) -> Drawing<'_> {
        let turn = self.turn.lock().unwrap_or_else(PoisonError::into_inner);
        let guard = self
            .next
            .wait_while(turn, |(serving, _)| *serving != ticket)
            .unwrap_or_else(PoisonError::into_inner);
        Drawing {
            guard,
            next: &self.next,
        }
    }
}

/// One call's turn at the generator; dropped (even by a panic), it passes the turn on.
struct Drawing<'a> {
    guard: MutexGuard<'a, (u64, Rng)>,
    next: &'a Condvar,
}

impl Drawing<'_> {
    fn rng(&mut self) -> &mut Rng {
        &mut self.guard.1
    }
}

impl Drop for Drawing<'_> {
    fn drop(&mut self) {
        self.guard.0 += 1;
        self.next.notify_all();
    }
}

#[derive(Debug, Default)]
struct Planner {
    limits: Limits,
    plans: Mutex<Plans>,
    joint_plans: Mutex<JointPlans>,
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
            errors: None,
        }
    }

    /// The simulated backend: the planner's answers with mistakes at `rates`, drawn
    /// from `seed` (one backend per episode keeps an episode reproducible).
    pub fn simulated(limits: Limits, rates: ErrorRates, seed: u64) -> BuiltinBackend {
        BuiltinBackend {
            errors: Some((rates, Arc::new(Draws::new(seed)))),
            ..BuiltinBackend::new(limits)
        }
    }

    /// The simulated backend with mistakes at `rates` drawn from `seed`, planning with
    /// this backend's planner: the plans either finds are known to both (the training
    /// data's episodes, `crate::training`, label every call with the plans their
    /// mistakes are made from).
    pub fn with_errors(&self, rates: ErrorRates, seed: u64) -> BuiltinBackend {
        BuiltinBackend {
            inner: Arc::clone(&self.inner),
            errors: Some((rates, Arc::new(Draws::new(seed)))),
        }
    }
}

/// What a search from a state gave, for [`Planner::first_of`]: a plan (empty when the
/// goal already holds), none because none exists, or none because the search stopped at
/// a limit after this many states.
enum Searched<S> {
    Plan(Vec<S>),
    NoPlan,
    Stopped(usize),
}

impl Planner {
    /// The next step of a shortest plan from `state`, or why there is none.
    fn next_step(&self, task: &Arc<Task>, state: &State) -> Result<Step, String> {
        let search = || {
            let search = planner::search_from(task, state, &task.robots, &task.goal, &self.limits);
            match search.plan {
                Some(plan) => Searched::Plan(plan),
                // Cancelled or cut short: not an answer to remember.
                None if search.truncated => Searched::Stopped(search.states_expanded),
                None => Searched::NoPlan,
            }
        };
        self.first_of(&self.plans, task, state, search, |s, step| {
            if let Some(robot) = task.robot(step.robot) {
                rules::apply(task, s, *robot, step.action);
            }
        })
    }

    /// The first joint step of a plan of the fewest joint steps from `state` (the best
    /// the search finds within the limits), or why there is none.
    fn next_joint_step(&self, task: &Arc<Task>, state: &State) -> Result<JointStep, String> {
        let search = || {
            let (robots, goal, limits) = (&task.robots, &task.goal, &self.limits);
            let sequential = planner::search_from(task, state, robots, goal, limits);
            let plan = sequential.plan.as_deref();
            let search = makespan::search_with(task, state, robots, goal, plan, limits);
            match search.plan {
                Some(plan) => Searched::Plan(plan),
                None if search.stop.is_some() => Searched::Stopped(search.states_expanded),
                None => Searched::NoPlan,
            }
        };
        self.first_of(&self.joint_plans, task, state, search, |s, joint| {
            for step in joint {
                if let Some(robot) = task.robot(step.robot) {
                    rules::apply(task, s, *robot, step.action);
                }
            }
        })
    }

    /// The first step of a plan from `state`, as `plans` knows it from an earlier
    /// search, else from `search` (run only when the goal is not plainly out of reach):
    /// every step of the plan found is remembered from the state it starts in (`apply`
    /// moves a state past one), and so is a goal no plan reaches; a search stopped at a
    /// limit is not remembered.
    fn first_of<S: Clone>(
        &self,
        plans: &Mutex<Known<S>>,
        task: &Arc<Task>,
        state: &State,
        search: impl FnOnce() -> Searched<S>,
        apply: impl Fn(&mut State, &S),
    ) -> Result<S, String> {
        let key = (Arc::as_ptr(task) as usize, state.clone());
        if let Some(known) = plans
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get(&key)
        {
            return known.clone();
        }
        if let Some(why) = unreachable_goal(task, state) {
            return Err(why);
        }
        let searched = search();
        self.keep(task);
        let mut plans = plans.lock().unwrap_or_else(PoisonError::into_inner);
        let plan = match searched {
            Searched::Plan(plan) => plan,
            Searched::Stopped(states) => {
                return Err(format!(
                    "the search stopped after {states} states without a plan"
                ));
            }
            Searched::NoPlan => {
                let why = "no plan reaches the goal from here".to_owned();
                plans.insert(key, Err(why.clone()));
                return Err(why);
            }
        };
        let Some(first) = plan.first().cloned() else {
            return Err("the goal already holds".into());
        };
        let mut s = state.clone();
        for step in &plan {
            plans.insert((key.0, s.clone()), Ok(step.clone()));
            apply(&mut s, step);
        }
        Ok(first)
    }

    /// Keeps `task` alive, so that the addresses in the keys of the plans stay its.
    fn keep(&self, task: &Arc<Task>) {
        let mut tasks = self.tasks.lock().unwrap_or_else(PoisonError::into_inner);
        if !tasks.iter().any(|t| Arc::ptr_eq(t, task)) {
            tasks.push(Arc::clone(task));
        }
    }

    /// The answer to a parallel episode's question (`proposals`, `joint_step`,
    /// `own_action`): from the first joint step of a plan of the fewest joint steps,
    /// unless `mistake` says which error to make instead.
    fn joint_answer(&self, q: &Query, mistake: Option<(Mistake, &mut Rng)>) -> Answer {
        let task = &q.situation.task;
        let state = &q.situation.state;
        let step = match self.next_joint_step(task, state) {
            Ok(step) => step,
            Err(why) => return answer(String::new(), Finish::Refusal(why)),
        };
        let listed = |robot: Idx| -> Vec<String> {
            task.robot(robot)
                .map(|r| rules::action_texts(task, state, *r))
                .unwrap_or_default()
        };
        let free = |robot: Idx| {
            q.situation.robots.is_empty() || q.situation.robots.contains(&task.id(robot))
        };
        let mut chosen: Vec<(Idx, String)> = step
            .iter()
            .filter(|s| free(s.robot))
            .map(|s| (s.robot, s.action.render(task)))
            .collect();
        let wrong = matches!(mistake, Some((Mistake::WrongRobot, _)));
        match mistake {
            Some((Mistake::WrongRobot, rng)) if !chosen.is_empty() => {
                chosen[0].0 = other_robot(task, chosen[0].0, rng);
            }
            Some((Mistake::Suboptimal, rng)) => {
                let offered: Vec<(Idx, String)> = team_actions::offered(task, state)
                    .into_iter()
                    .filter(|a| free(a.robot.node))
                    .map(|a| (a.robot.node, a.action.render(task)))
                    .collect();
                if !offered.is_empty() {
                    chosen = vec![offered[rng.below(offered.len())].clone()];
                }
            }
            Some((Mistake::Hallucinate, rng)) if !chosen.is_empty() => {
                chosen[0].1 = hallucinated(task, &listed(chosen[0].0), rng);
            }
            _ => {}
        }
        let reasoning = "The first joint step of a plan of the fewest joint steps from here.";
        let text = match q.schema_name {
            "proposals" => {
                let assignments: Vec<serde_json::Value> = chosen
                    .iter()
                    .map(|(r, a)| json!({"robot": task.node(*r).label(), "subtask": a}))
                    .collect();
                json!({"reasoning": reasoning, "assignments": assignments})
            }
            "joint_step" => {
                let lines: Vec<String> = chosen
                    .iter()
                    .map(|(r, a)| format!("{}: {a}", task.node(*r).label()))
                    .collect();
                json!({"actions": lines})
            }
            // A speaker's own action: its part of the step (another robot's after a
            // wrong-robot mistake), or none.
            _ => {
                let me = q.robot.and_then(|id| task.idx(id));
                let action = chosen
                    .iter()
                    .find(|(r, _)| (Some(*r) == me) != wrong)
                    .map_or("none".to_owned(), |(_, a)| a.clone());
                json!({"message": reasoning, "action": action})
            }
        };
        answer(text.to_string(), Finish::Stop)
    }

    /// The answer to `q`: the first step of a shortest plan, as the request's schema
    /// wants it, unless `mistake` says which error to make instead.
    fn answer(&self, q: &Query, mistake: Option<(Mistake, &mut Rng)>) -> Answer {
        let task = &q.situation.task;
        let state = &q.situation.state;
        let text = match q.schema_name {
            "proposals" | "joint_step" | "own_action" => return self.joint_answer(q, mistake),
            "goal" => goal_answer(task, mistake),
            "decision" => {
                let subtask = q.situation.subtask.as_deref().unwrap_or_default();
                let actions: Vec<String> = q
                    .robot
                    .and_then(|id| task.robot_by_id(id).ok())
                    .map(|r| rules::action_texts(task, state, r))
                    .unwrap_or_default();
                let offered = actions.iter().any(|a| a == subtask);
                let chosen = match mistake {
                    Some((Mistake::Hallucinate, rng)) => Some(hallucinated(task, &actions, rng)),
                    Some((Mistake::Suboptimal, rng)) if !actions.is_empty() => {
                        Some(actions[rng.below(actions.len())].clone())
                    }
                    _ if offered => Some(subtask.to_owned()),
                    _ => None,
                };
                match chosen {
                    Some(action) => {
                        json!({"action": action, "subtask_complete": true, "note": ""})
                    }
                    None => json!({
                        "action": "none",
                        "subtask_complete": false,
                        "note": "the subtask is not one of my actions now",
                    }),
                }
                .to_string()
            }
            // The assigner's proposal, or one team action (CMRS, DMRS, LLM-MCTS).
            kind => {
                let step = match self.next_step(task, state) {
                    Ok(step) => step,
                    Err(why) => return answer(String::new(), Finish::Refusal(why)),
                };
                let (mut robot, mut action) = (step.robot, step.action.render(task));
                match mistake {
                    Some((Mistake::WrongRobot, rng)) => robot = other_robot(task, robot, rng),
                    Some((Mistake::Suboptimal, rng)) => {
                        let team: Vec<(Idx, String)> = team_actions::offered(task, state)
                            .into_iter()
                            .map(|j| (j.robot.node, j.action.render(task)))
                            .collect();
                        (robot, action) = team[rng.below(team.len())].clone();
                    }
                    Some((Mistake::Hallucinate, rng)) => {
                        let listed: Vec<String> = task
                            .robot(robot)
                            .map(|r| rules::action_texts(task, state, *r))
                            .unwrap_or_default();
                        action = hallucinated(task, &listed, rng);
                    }
                    _ => {}
                }
                let label = task.node(robot).label();
                if kind == "proposal" {
                    json!({
                        "reasoning": "The first step of a shortest plan from here.",
                        "robot": label,
                        "subtask": action,
                    })
                } else {
                    json!({"reasoning": "The first step of a shortest plan from here.", "action": format!("{label}: {action}")})
                }
                .to_string()
            }
        };
        answer(text, Finish::Stop)
    }
}

/// The goal LLM+P asks for (`llm-pddl`): the task's own, unless `mistake` makes it a
/// misread one. The simulated backend's kinds of mistake become the ways a model
/// misreads a goal: a hallucination names another thing as a fact's subject, a wrong
/// robot another place as its target, a suboptimal answer leaves a fact out (or, with
/// one fact, names another place).
fn goal_answer(task: &Task, mistake: Option<(Mistake, &mut Rng)>) -> String {
    let mut facts: Vec<(Relation, Idx, Idx, u32)> = task
        .goal
        .iter()
        .map(|p| (p.relation, p.subject, p.target, p.count))
        .collect();
    let pick = |of: &dyn Fn(Idx) -> bool, not: Idx, rng: &mut Rng| {
        let some: Vec<Idx> = task.indices().filter(|&n| n != not && of(n)).collect();
        (!some.is_empty()).then(|| some[rng.below(some.len())])
    };
    let has = |n: Idx, p: PropSet| task.node(n).properties.contains(p);
    let place = |n: Idx| has(n, PropSet::SURFACES) || has(n, PropSet::CONTAINERS);
    if let Some((mistake, rng)) = mistake
        && !facts.is_empty()
    {
        let i = rng.below(facts.len());
        match mistake {
            Mistake::Hallucinate => {
                let thing = |n: Idx| has(n, PropSet::GRABABLE);
                if let Some(n) = pick(&thing, facts[i].1, rng) {
                    facts[i].1 = n;
                }
            }
            Mistake::Suboptimal if facts.len() > 1 => {
                facts.remove(i);
            }
            _ => {
                if let Some(n) = pick(&place, facts[i].2, rng) {
                    facts[i].2 = n;
                }
            }
        }
    }
    let goal: Vec<serde_json::Value> = facts
        .iter()
        .map(|&(relation, subject, target, count)| {
            json!({
                "relation": relation.name(),
                "subject": task.node(subject).label(),
                "target": task.node(target).label(),
                "count": count,
            })
        })
        .collect();
    json!({"goal": goal}).to_string()
}

/// Why no action can ever reach the goal from `state`, when a predicate that does not
/// hold has a static obstacle (a goal container that is no container, say): refused at
/// once, without exhausting the state space. A predicate that holds already is no
/// obstacle: nothing could have moved it there, nor can move it away.
fn unreachable_goal(task: &Task, state: &State) -> Option<String> {
    task.goal
        .iter()
        .filter(|p| !predicate_holds(state, p))
        .find_map(|p| {
            planner::static_obstacle(task, p)
                .map(|why| format!("{}: {why}", task.predicate_label(p)))
        })
}

fn answer(text: String, finish: Finish) -> Answer {
    Answer {
        text,
        finish,
        usage: Usage::default(),
        latency_ms: 0.0,
        attempts: 1,
        mode: OutputMode::JsonSchema,
    }
}

impl Backend for BuiltinBackend {
    fn info(&self) -> BackendInfo {
        match &self.errors {
            None => BackendInfo {
                kind: BackendKind::Builtin,
                model: "optimal-planner".into(),
                base_url: None,
            },
            Some((rates, _)) => BackendInfo {
                kind: BackendKind::Simulated,
                model: format!("optimal-planner with errors {}", rates.label()),
                base_url: None,
            },
        }
    }

    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        let planner = Arc::clone(&self.inner);
        let errors = self.errors.clone();
        Box::pin(async move {
            let start = Instant::now();
            // Taken before the first await: in the order the calls were asked.
            let ticket = errors.as_ref().map(|(_, draws)| draws.ticket());
            // A search can take a second or two: keep it off the async workers.
            let mut answer = tokio::task::spawn_blocking(move || match (errors, ticket) {
                (Some((rates, draws)), Some(ticket)) => {
                    let mut drawing = draws.wait(ticket);
                    let rng = drawing.rng();
                    match rates.draw(rng) {
                        Some(Mistake::Malformed) => {
                            answer("{\"robot\": <the one that".to_owned(), Finish::Stop)
                        }
                        Some(m) => planner.answer(&query, Some((m, rng))),
                        None => planner.answer(&query, None),
                    }
                }
                _ => planner.answer(&query, None),
            })
            .await
            .map_err(|e| {
                LlmError::new(LlmErrorKind::Internal, format!("the planner failed: {e}"))
            })?;
            answer.latency_ms = start.elapsed().as_secs_f64() * 1e3;
            Ok(answer)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Calls that reach the generator in the reverse of the order they asked (the later
    /// ones' threads ready first) still draw in the order they asked.
    #[test]
    fn draws_go_in_the_order_the_calls_asked_whatever_order_their_threads_come() {
        let draws = Arc::new(Draws::new(7));
        let tickets: Vec<u64> = (0..6).map(|_| draws.ticket()).collect();
        let mut expected = Rng::new(7);
        let expected: Vec<u64> = tickets.iter().map(|_| expected.next_u64()).collect();
        let drawn = Arc::new(Mutex::new(Vec::new()));
        let threads: Vec<_> = tickets
            .into_iter()
            .rev()
            .map(|ticket| {
                let (draws, drawn) = (Arc::clone(&draws), Arc::clone(&drawn));
                std::thread::spawn(move || {
                    let mut drawing = draws.wait(ticket);
                    let n = drawing.rng().next_u64();
                    drawn.lock().expect("no panic").push((ticket, n));
                })
            })
            .collect();
        for t in threads {
            t.join().expect("a thread");
        }
        let drawn = drawn.lock().expect("no panic").clone();
        let order: Vec<u64> = drawn.iter().map(|(t, _)| *t).collect();
        assert_eq!(order, [0, 1, 2, 3, 4, 5]);
        let numbers: Vec<u64> = drawn.iter().map(|(_, n)| *n).collect();
        assert_eq!(
            numbers, expected,
            "the one stream, as a single caller draws it"
        );
    }
}
