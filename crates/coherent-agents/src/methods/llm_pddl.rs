//! LLM+P (`--method llm-pddl`, docs/methods.md): the model reads the instruction and the
//! scene once and writes the task's goal as facts (`ON` / `INSIDE`, structured output);
//! the optimal planner plans for that goal (the shortest plan, or in joint steps the
//! fewest), and the robots carry the plan out under the one loop, a step per round. The
//! episode succeeds when the task's own goal holds, whatever the model wrote. One model
//! call per episode; an answer that cannot be read costs its round and is asked again.
//!
//! What fails is said in the rounds' outcome: a goal misread (the plan for the goal
//! written is carried out and the task's goal does not hold), a goal the planner cannot
//! reach, or an action refused on the way (physics, a robot): then the method plans
//! again from where the world is, for the same goal, with no model call.
//!
//! After Liu et al., *LLM+P: Empowering Large Language Models with Optimal Planning
//! Proficiency* (arXiv:2304.11477, 2023): there the model writes a PDDL problem and
//! Fast Downward plans; here it writes the goal of the problem, the domain and the
//! initial state being the rules' own (docs/pddl.md), and the planner is ours.

use std::io;
use std::sync::Arc;

use coherent_core::action::mentions;
use coherent_core::makespan::{self, JointStep};
use coherent_core::planner::{self, Limits, Step};
use coherent_core::relaxed;
use coherent_core::task::predicate_holds;
use coherent_core::{Execution, GoalPredicate, Relation, RobotKind, State, Task};
use serde_json::{Value, json};

use crate::episode::ask::{Side, ask};
use crate::episode::environment::team_sight;
use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::llm::{Message, Query, Role, Situation};
use crate::methods::decision;
use crate::prompts::answer::{field_text, json_object};
use crate::prompts::fill;
use crate::prompts::templates::{self, Prompts, Template};
use crate::records::transcript::{Round, RoundOutcome};

/// Most tokens of one answer: a goal of a few facts.
const MAX_TOKENS: u32 = 400;

/// The plan being carried out: a step per round, or a joint step per round.
#[derive(Debug)]
enum Plan {
    Steps(Vec<Step>),
    JointSteps(Vec<JointStep>),
}

/// LLM+P for one episode.
#[derive(Debug)]
pub struct LlmPddl {
    prompts: Prompts,
    limits: Limits,
    /// The goal the model wrote, once read.
    goal: Option<Vec<GoalPredicate>>,
    /// The plan for it and how far it has been carried out, or why there is none.
    plan: Option<Result<(Plan, usize), String>>,
    /// The last round's action did not run: plan again from where the world is.
    replan: bool,
}

impl LlmPddl {
    /// The method; `limits` bound its searches (their cancel flag stops one).
    pub fn new(prompts: Prompts, limits: Limits) -> LlmPddl {
        LlmPddl {
            prompts,
            limits,
            goal: None,
            plan: None,
            replan: false,
        }
    }
}

/// The goal prompt: the team, the instruction and the scene.
fn messages(prompts: &Prompts, turn: &Turn<'_>) -> Vec<Message> {
    let task = turn.task;
    let text = prompts.text(Template::Goal);
    let sight = team_sight(turn.env, task, turn.news);
    let team = fill::team(task);
    let seen = sight.values(text);
    let mut values = vec![
        ("team", team.as_str()),
        ("instruction", task.meta.instruction.as_str()),
    ];
    values.extend(seen.iter().map(|(k, v)| (*k, v.as_str())));
    let (system, user) = templates::split(text);
    let mut out = Vec::new();
    if !system.trim().is_empty() {
        out.push(Message::system(
            fill::fill(system, &values).trim().to_owned(),
        ));
    }
    out.push(Message::user(fill::fill(user, &values).trim().to_owned()));
    out
}

/// The answer: a list of facts, each naming two nodes of the scene.
pub(crate) fn schema(task: &Task) -> Value {
    let labels: Vec<String> = task.nodes.iter().map(|n| n.label()).collect();
    json!({
        "type": "object",
        "properties": {
            "goal": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "relation": {"type": "string", "enum": ["ON", "INSIDE"]},
                        "subject": {"type": "string", "enum": labels},
                        "target": {"type": "string", "enum": labels},
                        "count": {"type": "integer", "enum": [0, 1]},
                    },
                    "required": ["relation", "subject", "target", "count"],
                    "additionalProperties": false,
                },
            },
        },
        "required": ["goal"],
        "additionalProperties": false,
    })
}

/// The goal an answer writes; an error saying what cannot be read.
pub(crate) fn read_goal(task: &Task, text: &str) -> Result<Vec<GoalPredicate>, String> {
    let object = json_object(text).ok_or("the answer is not a JSON object")?;
    let facts = object
        .get("goal")
        .and_then(Value::as_array)
        .ok_or("the answer has no \"goal\" list")?;
    let node = |fact: &Value, key: &str| {
        let said = fact
            .get(key)
            .and_then(Value::as_str)
            .map(field_text)
            .ok_or(format!("a fact without a {key}"))?;
        let mention = match mentions(&said).as_slice() {
            [one] => one.clone(),
            _ => return Err(format!("{said:?} is not one <name>(id)")),
        };
        task.idx(mention.id)
            .filter(|&n| task.node(n).class_name == mention.name)
            .ok_or(format!("{said:?} is not a node of the scene"))
    };
    let mut goal = Vec::new();
    for fact in facts {
        let relation = match fact.get("relation").and_then(Value::as_str) {
            Some(r) if r.eq_ignore_ascii_case("on") => Relation::On,
            Some(r) if r.eq_ignore_ascii_case("inside") => Relation::Inside,
            other => return Err(format!("the relation {other:?} is neither ON nor INSIDE")),
        };
        let count = match fact.get("count").and_then(Value::as_u64) {
            Some(c @ (0 | 1)) => c as u32,
            None => 1,
            Some(c) => return Err(format!("a count of {c}: a fact holds (1) or not (0)")),
        };
        goal.push(GoalPredicate {
            relation,
            subject: node(fact, "subject")?,
            target: node(fact, "target")?,
            count,
        });
    }
    if goal.is_empty() {
        return Err("the goal has no fact".to_owned());
    }
    Ok(goal)
}

/// The goal in words, as the rounds say it: `on_<apple>(3)_<table>(5)`, ...
fn goal_words(task: &Task, goal: &[GoalPredicate]) -> String {
    let facts: Vec<String> = goal
        .iter()
        .map(|p| {
            let fact = task.predicate_label(p);
            if p.count == 0 {
                format!("not {fact}")
            } else {
                fact
            }
        })
        .collect();
    facts.join(", ")
}

/// A plan for `goal` from `state`: the shortest, or the fewest joint steps; or why
/// there is none (the goal cannot be reached, or a search limit). A goal that no action
/// can ever reach (a predicate that does not hold with an obstacle visible without
/// search, or one the relaxed analysis cannot derive with the whole team) is refused
/// before searching: a misread goal's state space can take minutes to exhaust.
fn search(
    task: &Task,
    state: &State,
    goal: &[GoalPredicate],
    limits: &Limits,
    execution: Execution,
) -> Result<Plan, String> {
    let obstacle = goal
        .iter()
        .filter(|p| !predicate_holds(state, p))
        .find_map(|p| {
            planner::static_obstacle(task, p)
                .map(|why| format!("{}: {why}", task.predicate_label(p)))
        });
    if let Some(why) = obstacle {
        return Err(format!("goal unreachable: {why}"));
    }
    let kinds: Vec<RobotKind> = task.robots.iter().map(|r| r.kind).collect();
    if !relaxed::may_reach(task, &kinds, goal) {
        return Err(format!(
            "goal unreachable: no plan of the team reaches the goal written ({}), not even with every action's deletions ignored",
            goal_words(task, goal)
        ));
    }
    let sequential = planner::search_from(task, state, &task.robots, goal, limits);
    let unreachable = |stopped: bool| {
        if stopped {
            "the search for a plan to the goal written stopped at a limit".to_owned()
        } else {
            format!(
                "goal unreachable: no plan reaches the goal written ({})",
                goal_words(task, goal)
            )
        }
    };
    match execution {
        Execution::Sequential => sequential
            .plan
            .map(Plan::Steps)
            .ok_or_else(|| unreachable(sequential.truncated)),
        Execution::Parallel => {
            let plan = sequential.plan.as_deref();
            let joint = makespan::search_with(task, state, &task.robots, goal, plan, limits);
            joint
                .plan
                .map(Plan::JointSteps)
                .ok_or_else(|| unreachable(joint.stop.is_some()))
        }
    }
}

impl LlmPddl {
    /// The model's goal, asked when it has not been read yet: `Err` ends the round with
    /// the outcome (an answer that cannot be used), `None` when cancelled.
    async fn goal(
        &mut self,
        turn: &Turn<'_>,
        round: &mut Round,
    ) -> Option<Result<Vec<GoalPredicate>, RoundOutcome>> {
        if let Some(goal) = &self.goal {
            return Some(Ok(goal.clone()));
        }
        let task = turn.task;
        let query = Query {
            role: Role::Assigner,
            robot: None,
            messages: messages(&self.prompts, turn),
            schema_name: "goal",
            schema: schema(task),
            max_tokens: MAX_TOKENS,
            situation: Situation::now(task, turn.env, None),
        };
        let reply = ask(turn.backend, query, turn.cancel, &mut round.calls).await?;
        Some(
            match reply.and_then(|r| r.read(|text| read_goal(task, text))) {
                Ok(goal) => {
                    self.goal = Some(goal.clone());
                    Ok(goal)
                }
                Err(e) => Err(e.outcome(Side::Assigner)),
            },
        )
    }
}

impl Method for LlmPddl {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let task = Arc::clone(turn.task);
            if !turn.news.is_empty() {
                // The world changed under the plan (the task's events): the goal is read
                // again from the instruction as it stands, and planned afresh.
                self.goal = None;
                self.replan = true;
            }
            let goal = match self.goal(&turn, round).await {
                None => return Ok(None),
                Some(Err(outcome)) => return Ok(Some(Decided::Ends(outcome))),
                Some(Ok(goal)) => goal,
            };
            if self.replan {
                self.plan = None;
                self.replan = false;
            }
            let plan = match &mut self.plan {
                Some(plan) => plan,
                unplanned @ None => {
                    let (t, s, g) = (Arc::clone(&task), turn.env.state().clone(), goal.clone());
                    let (l, execution) = (self.limits.clone(), turn.execution);
                    let found =
                        tokio::task::spawn_blocking(move || search(&t, &s, &g, &l, execution))
                            .await
                            .map_err(io::Error::other)?;
                    unplanned.insert(found.map(|plan| (plan, 0)))
                }
            };
            let why = match plan {
                Ok((Plan::Steps(steps), next)) => match steps.get(*next) {
                    Some(s) => {
                        *next += 1;
                        let action = s.action.render(&task);
                        decision::choose(round, task.id(s.robot), &action, String::new());
                        return Ok(Some(Decided::CarryOut));
                    }
                    None => misread(&task, &goal),
                },
                Ok((Plan::JointSteps(steps), next)) => match steps.get(*next) {
                    Some(joint) => {
                        *next += 1;
                        round.parts = joint
                            .iter()
                            .map(|s| {
                                let action = s.action.render(&task);
                                decision::part(turn.env, task.id(s.robot), &action, String::new())
                            })
                            .collect();
                        return Ok(Some(Decided::CarryOut));
                    }
                    None => misread(&task, &goal),
                },
                Err(why) => why.clone(),
            };
            Ok(Some(Decided::Ends(RoundOutcome::NoDecision { why })))
        })
    }

    /// What ran, as the team methods hear it; an action that did not run has the plan
    /// made again, from where the world is, for the same goal.
    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        let acted = round.decision.is_some() || !round.parts.is_empty();
        if acted {
            let ran = if round.parts.is_empty() {
                round.outcome == RoundOutcome::Executed
            } else {
                round
                    .parts
                    .iter()
                    .all(|p| p.outcome == RoundOutcome::Executed)
            };
            self.replan = !ran;
            let note = (!ran).then(|| {
                "execution failed: the plan is made again from here, for the same goal".to_owned()
            });
            decision::team_feedback(closing.task, round, note);
        }
    }

    fn recall(&self, _: &Task, _: &Round) -> Option<String> {
        None
    }
}

/// The plan for the goal written is carried out and the task's goal does not hold.
fn misread(task: &Task, goal: &[GoalPredicate]) -> String {
    format!(
        "goal misread: the plan for the goal written ({}) is carried out, and the task's goal does not hold",
        goal_words(task, goal)
    )
}
