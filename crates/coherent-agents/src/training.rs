//! Training data from the optimal planner (`coherent export sft`, `docs/training.md`):
//! every question a method's roles ask in an episode, with the answer the optimal
//! planner gives at the state it was asked in, written in the method's own answer
//! format.
//!
//! An episode runs under the one loop ([`crate::episode::play()`]) as any other, its
//! backend a [`Teacher`]: each question is answered by the episode's own backend (the
//! built-in planner, or the simulated backend with its mistakes, which leads the
//! episode off the optimal plans) and, apart, by the built-in planner without mistakes,
//! whose answer is the lesson's ([`Lesson`]). So a prompt is the one the method sends
//! at that state (the same templates, the same history window, the prompt set given),
//! because the method itself made it, and the answer is the best decision from there,
//! which after a mistake is the way back. [`read_back`] reads each answer with the
//! method's own parser.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use coherent_core::task::GoalPredicate;
use coherent_core::{Execution, NodeId, SymbolicEnv, Task, rules};

use crate::backends::builtin::BuiltinBackend;
use crate::episode::budget::Budget;
use crate::episode::cancel::Cancel;
use crate::episode::play::{Course, Episode, play};
use crate::error::Error;
use crate::llm::{Answer, Backend, BackendInfo, BoxFuture, Finish, LlmError, Message, Situation};
use crate::methods::assigner::TaskAssigner;
use crate::methods::executor::RobotExecutor;
use crate::methods::{central, dmrs, llm_pddl};
use crate::prompts::team_actions;
use crate::prompts::templates::Prompts;
use crate::run::settings::{Builtin, Settings};

/// The roles of each method that asks a model, as the data names them: PEFA's
/// `assigner` and `executor`, CMRS's `central` model, the DMRS `speaker`s, LLM-MCTS's
/// `prior` (its central prompt, sampled at each tree's root), LLM+P's `goal`.
pub fn roles(method: Builtin) -> &'static [&'static str] {
    match method {
        Builtin::Pefa | Builtin::PefaNoHistory => &["assigner", "executor"],
        Builtin::Cmrs => &["central"],
        Builtin::Dmrs1d | Builtin::Dmrs2d => &["speaker"],
        Builtin::LlmMcts => &["prior"],
        Builtin::LlmPddl => &["goal"],
        Builtin::Mcts | Builtin::Optimal | Builtin::Random => &[],
    }
}

/// The role a question of `method` with the answer format `schema` is asked of.
pub fn role(method: Builtin, schema: &str) -> &'static str {
    match schema {
        "decision" => "executor",
        "proposal" | "proposals" => "assigner",
        _ => roles(method).first().copied().unwrap_or("model"),
    }
}

/// One question of an episode and the optimal planner's answer to it.
#[derive(Clone, Debug)]
pub struct Lesson {
    /// The answer format the question asks for (the structured output's name).
    pub schema: &'static str,
    /// The robot asked, when the role is one robot's (an executor, a speaker).
    pub robot: Option<NodeId>,
    /// The prompt, as the method sent it.
    pub messages: Vec<Message>,
    /// The optimal planner's answer, or why it has none from this state (no plan reaches
    /// the goal, the goal holds already, a search stopped at its limit).
    pub answer: Result<String, String>,
    /// Where the episode stood.
    pub situation: Situation,
}

/// The backend of an episode that makes training data: the episode's own backend
/// answers, and the built-in planner's answer to the same question is kept as a
/// [`Lesson`].
#[derive(Debug)]
pub struct Teacher {
    planner: Arc<BuiltinBackend>,
    /// The simulated backend whose mistakes the episode follows; `None`: the planner's
    /// answers are the episode's.
    acting: Option<BuiltinBackend>,
    asked: AtomicU64,
    /// Each lesson with the number of its question, in the order asked.
    lessons: Mutex<Vec<(u64, Lesson)>>,
}

impl Teacher {
    /// `planner` answers every question as the lesson's answer; `acting` (the simulated
    /// backend) answers it for the episode, else the planner does.
    pub fn new(planner: Arc<BuiltinBackend>, acting: Option<BuiltinBackend>) -> Teacher {
        Teacher {
            planner,
            acting,
            asked: AtomicU64::new(0),
            lessons: Mutex::new(Vec::new()),
        }
    }

    /// The lessons so far, in the order their questions were asked (a parallel round's
    /// executors are asked at once, in team order), and none left.
    pub fn take(&self) -> Vec<Lesson> {
        let mut lessons =
            std::mem::take(&mut *self.lessons.lock().unwrap_or_else(PoisonError::into_inner));
        lessons.sort_by_key(|(n, _)| *n);
        lessons.into_iter().map(|(_, l)| l).collect()
    }
}

impl Backend for Teacher {
    fn info(&self) -> BackendInfo {
        match &self.acting {
            Some(acting) => acting.info(),
            None => self.planner.info(),
        }
    }

    fn ask(&self, query: crate::llm::Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        // Numbered when asked, before the first await: the order the loop asks in.
        let number = self.asked.fetch_add(1, Ordering::SeqCst);
        Box::pin(async move {
            let taught = self.planner.ask(query.clone()).await;
            let answer = match &taught {
                Ok(a) if a.finish == Finish::Stop => Ok(a.text.clone()),
                Ok(a) => Err(match &a.finish {
                    Finish::Refusal(why) => why.clone(),
                    other => format!("the planner's answer ended with {other:?}"),
                }),
                Err(e) => Err(e.to_string()),
            };
            let lesson = Lesson {
                schema: query.schema_name,
                robot: query.robot,
                messages: query.messages.clone(),
                answer,
                situation: query.situation.clone(),
            };
            self.lessons
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push((number, lesson));
            match &self.acting {
                Some(acting) => acting.ask(query).await,
                None => taught,
            }
        })
    }
}

/// Runs one episode of `settings`' method on `task` in the rules, with `teacher` as its
/// backend, within the budget of its execution (2 x the optimum, or 2 x the makespan):
/// the episode, and its lessons.
pub async fn episode(
    task: &Arc<Task>,
    settings: &Settings,
    teacher: &Teacher,
    limits: &coherent_core::planner::Limits,
    cancel: &Cancel,
) -> Result<(Episode, Vec<Lesson>), Error> {
    let mut method = settings.build(task, cancel)?;
    let budget = Budget::searched(task, settings.execution, None, limits)?;
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let course = Course {
        execution: settings.execution,
        max_steps: budget.steps(),
        history: settings.history_window(),
        max_states: limits.max_states,
        seed: settings.seed.unwrap_or(0),
    };
    let episode = play(
        &mut env,
        task,
        method.as_mut(),
        teacher,
        course,
        cancel,
        &mut |_| Ok(()),
    )
    .await
    .map_err(|e| Error::Invalid(format!("the episode could not be played: {e}")))?;
    Ok((episode, teacher.take()))
}

/// What an answer decides, as the method reads it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Taken {
    /// Actions of robots, by the robot's id and the action as written: one (sequential),
    /// or a joint step's (a parallel central answer, a parallel assigner's subtasks).
    Actions(Vec<(NodeId, String)>),
    /// No action: an executor declines its subtask, a parallel speaker does nothing.
    Nothing,
    /// The goal LLM+P's model writes.
    Goal(Vec<GoalPredicate>),
}

/// Reads `answer`, given to a question of `method` (in `execution`, with the prompt set
/// `prompts`) asked where `lesson` stood, with the method's own parser: what it decides,
/// or why the method could not use it.
pub fn read_back(
    method: Builtin,
    prompts: &Prompts,
    lesson: &Lesson,
    answer: &str,
) -> Result<Taken, String> {
    let task = &lesson.situation.task;
    let state = &lesson.situation.state;
    let lines = || -> Vec<String> {
        team_actions::offered(task, state)
            .iter()
            .map(|a| a.line(task))
            .collect()
    };
    let own = |robot: NodeId| -> Vec<String> {
        task.robot_by_id(robot)
            .map(|r| rules::action_texts(task, state, r))
            .unwrap_or_default()
    };
    let robot = || lesson.robot.ok_or("the question names no robot".to_owned());
    match (lesson.schema, method) {
        ("goal", _) => llm_pddl::read_goal(task, answer).map(Taken::Goal),
        ("proposal", _) => TaskAssigner::new(task, prompts, 0)
            .parse(answer)
            .map(|p| Taken::Actions(vec![(p.robot, p.subtask)])),
        ("proposals", _) => TaskAssigner::new(task, prompts, 0)
            .parse_parallel(answer, &lesson.situation.robots)
            .map(|a| {
                Taken::Actions(
                    a.proposals
                        .into_iter()
                        .map(|p| (p.robot, p.subtask))
                        .collect(),
                )
            }),
        ("decision", _) => {
            let robot = robot()?;
            let executor = RobotExecutor::of(task, robot, prompts, 0).map_err(|e| e.to_string())?;
            let decision = executor.parse(&own(robot), answer)?;
            Ok(match decision.action {
                Some(action) if decision.can_do => Taken::Actions(vec![(robot, action)]),
                _ => Taken::Nothing,
            })
        }
        ("own_action", _) => {
            let robot = robot()?;
            Ok(
                match dmrs::own_action(task, robot, &own(robot), answer)?.0 {
                    Some(action) => Taken::Actions(vec![(robot, action)]),
                    None => Taken::Nothing,
                },
            )
        }
        ("joint_step", _) => central::choose_several(task, &lines(), answer)
            .map(|(chosen, _)| Taken::Actions(chosen)),
        (_, Builtin::LlmMcts) => {
            let lines = lines();
            crate::prompts::answer::match_line(&lines, answer)
                .ok_or_else(|| "the answer is none of the team's lines".to_owned())
                .and_then(|i| central::choose(task, &lines, &lines[i]))
                .map(|pick| Taken::Actions(vec![pick]))
        }
        _ => central::choose(task, &lines(), answer).map(|pick| Taken::Actions(vec![pick])),
    }
}

/// The executions a method runs (the tree searches are sequential only).
pub fn executions(method: Builtin) -> Vec<Execution> {
    [Execution::Sequential, Execution::Parallel]
        .into_iter()
        .filter(|&e| method.runs(e))
        .collect()
}
