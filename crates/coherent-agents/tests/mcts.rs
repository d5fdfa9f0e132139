//! Primitive MCTS and LLM-MCTS: the search's formulas on tiny cases, seeded determinism,
//! episodes on released tasks, the LLM prior (mixing, matching, malformed answers), and
//! the full measurement of primitive MCTS (ignored; run in release).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use coherent_agents::answer::{match_line, read_line};
use coherent_agents::episode::{self, Course};
use coherent_agents::llm::{
    Answer, Backend, BackendInfo, BackendKind, BoxFuture, Finish, LlmError, LlmErrorKind,
    OutputMode, Query, Role, Usage,
};
use coherent_agents::mcts::{self, Mcts, MctsConfig, mix_prior, puct, softmax_q};
use coherent_agents::prompts::fill::action_line;
use coherent_agents::rng::Rng;
use coherent_agents::team_actions::{self, TeamAction};
use coherent_agents::transcript::{RoundOutcome, Status};
use coherent_agents::{BuiltinBackend, Cancel, Episode, HISTORY_WINDOW};
use coherent_core::planner::{self, Limits};
use coherent_core::{Execution, State, SymbolicEnv, Task, rules};
use serde_json::json;

mod common;

/// A sequential episode of `max_steps` with the paper's history window.
fn sequential(max_steps: u32) -> Course {
    Course {
        execution: Execution::Sequential,
        max_steps,
        history: HISTORY_WINDOW,
        max_states: Limits::DEFAULT_MAX_STATES,
        seed: 0,
    }
}

fn gt(task: &Task) -> u32 {
    task.meta
        .gt_steps
        .expect("original tasks have a ground truth")
}

async fn episode(
    task: &Arc<Task>,
    backend: Option<&dyn Backend>,
    config: &MctsConfig,
    max_steps: u32,
) -> Episode {
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let (mut method, no_model) = match backend {
        Some(_) => (Mcts::llm(config.clone()), None),
        None => (
            Mcts::primitive(config.clone()),
            Some(BuiltinBackend::default()),
        ),
    };
    let backend = backend.or(no_model.as_ref().map(|b| b as &dyn Backend));
    let course = sequential(max_steps);
    let backend = backend.expect("a backend or none needed");
    episode::play(
        &mut env,
        task,
        &mut method,
        backend,
        course,
        &Cancel::default(),
        &mut |_| Ok(()),
    )
    .await
    .expect("the episode runs")
}

fn chosen(e: &Episode) -> Vec<String> {
    e.rounds
        .iter()
        .map(|r| {
            r.decision
                .as_ref()
                .and_then(|d| d.action.clone())
                .unwrap_or_default()
        })
        .collect()
}

/// A "model" that always answers the first step of a shortest plan from the state it is
/// asked in, as a team action line.
#[derive(Debug, Default)]
struct Oracle {
    known: Mutex<HashMap<State, String>>,
}

impl Oracle {
    fn line(&self, task: &Task, s: &State) -> String {
        let mut known = self.known.lock().unwrap_or_else(PoisonError::into_inner);
        known
            .entry(s.clone())
            .or_insert_with(|| {
                let plan =
                    planner::search_from(task, s, &task.robots, &task.goal, &Limits::default())
                        .plan
                        .unwrap_or_default();
                plan.first().map_or_else(String::new, |step| {
                    let robot = *task.robot(step.robot).expect("a robot of the team");
                    TeamAction {
                        robot,
                        action: step.action,
                    }
                    .line(task)
                })
            })
            .clone()
    }
}

fn answer(text: String, finish: Finish) -> Answer {
    Answer {
        text,
        finish,
        usage: Usage {
            prompt_tokens: 100,
            completion_tokens: 10,
            cached_tokens: 0,
        },
        latency_ms: 0.0,
        attempts: 1,
        mode: OutputMode::JsonSchema,
    }
}

impl Backend for Oracle {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::Builtin,
            model: "oracle".into(),
            base_url: None,
        }
    }

    fn ask(&self, q: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        Box::pin(async move {
            assert_eq!(q.role, Role::Assigner);
            let line = self.line(&q.situation.task, &q.situation.state);
            Ok(answer(json!({ "action": line }).to_string(), Finish::Stop))
        })
    }
}

/// A "model" whose answers are all unusable, in turn: not JSON, JSON without an action,
/// an action no robot has, a refusal, an empty answer, a malformed response.
#[derive(Debug, Default)]
struct Garbage {
    n: Mutex<usize>,
}

impl Backend for Garbage {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::Simulated,
            model: "garbage".into(),
            base_url: None,
        }
    }

    fn ask(&self, _q: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        let n = {
            let mut n = self.n.lock().unwrap_or_else(PoisonError::into_inner);
            *n += 1;
            *n
        };
        Box::pin(async move {
            Ok(match n % 6 {
                0 => answer(
                    "I think the robots should work together.".into(),
                    Finish::Stop,
                ),
                1 => answer(r#"{"reason": "no action here"}"#.into(), Finish::Stop),
                2 => answer(
                    r#"{"action": "<spaceship>(999): [launch] <moon>(1000)"}"#.into(),
                    Finish::Stop,
                ),
                3 => answer(String::new(), Finish::Refusal("no".into())),
                4 => answer("   ".into(), Finish::Stop),
                _ => {
                    return Err(LlmError::new(
                        LlmErrorKind::Malformed,
                        "not a chat completion",
                    ));
                }
            })
        })
    }
}

#[test]
fn softmax_q_leans_towards_the_best_returns() {
    let t = 10.0;
    assert_eq!(softmax_q(&[], t), 0.0, "no returns: the value of a failure");
    assert!((softmax_q(&[4.0, 4.0, 4.0], t) - 4.0).abs() < 1e-12);
    // Weights e^0 and e^1: 10 e / (1 + e).
    let e = std::f64::consts::E;
    assert!((softmax_q(&[0.0, 10.0], t) - 10.0 * e / (1.0 + e)).abs() < 1e-12);
    let mean = 5.0;
    assert!(softmax_q(&[0.0, 10.0], t) > mean);
    assert!(softmax_q(&[0.0, 10.0], t) < 10.0);
    // A low temperature is nearly the maximum, a high one nearly the mean.
    assert!((softmax_q(&[0.0, 10.0], 0.1) - 10.0).abs() < 1e-6);
    assert!((softmax_q(&[0.0, 10.0], 1e6) - mean).abs() < 1e-3);
    // Large returns do not overflow.
    assert!((softmax_q(&[1e5, 1e5], 1.0) - 1e5).abs() < 1e-6);
}

#[test]
fn puct_adds_the_prior_scaled_exploration_to_q() {
    // 2 + 24 * 0.5 * sqrt(16) / (1 + 3) = 14.
    assert!((puct(2.0, 0.5, 16, 3, 24.0) - 14.0).abs() < 1e-12);
    // On a node's first visit only Q counts.
    assert_eq!(puct(1.5, 0.9, 0, 0, 24.0), 1.5);
    // An unvisited action with a larger prior beats one with a smaller prior...
    assert!(puct(0.0, 0.6, 9, 0, 24.0) > puct(0.0, 0.1, 9, 0, 24.0));
    // ...and visits wear the bonus down.
    assert!(puct(0.0, 0.6, 9, 5, 24.0) < puct(0.0, 0.1, 9, 0, 24.0));
}

#[test]
fn the_prior_is_half_the_model_and_half_uniform() {
    let p = mix_prior(&[3, 2, 0, 0], 0.5);
    let expected = [0.5 * 0.6 + 0.125, 0.5 * 0.4 + 0.125, 0.125, 0.125];
    for (a, b) in p.iter().zip(expected) {
        assert!((a - b).abs() < 1e-12, "{p:?}");
    }
    assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert_eq!(
        mix_prior(&[0, 0], 0.5),
        vec![0.5, 0.5],
        "no sample: uniform"
    );
    assert_eq!(mix_prior(&[5, 0], 0.5), vec![0.75, 0.25]);
    assert!(mix_prior(&[], 0.5).is_empty());
}

#[test]
fn samples_are_matched_to_the_nearest_team_action_or_dropped() {
    let lines: Vec<String> = [
        "<quadrotor>(1): [takeoff_from] <table>(5)",
        "<robot dog>(2): [movetowards] <apple>(7)",
        "<robot dog>(2): [movetowards] <kitchen>(3)",
        "<robot arm>(4): [grab] <apple>(7)",
    ]
    .map(str::to_owned)
    .to_vec();
    // Exact, however spaced and cased.
    assert_eq!(
        match_line(&lines, "<robot dog>(2):  [MoveTowards] <apple>(7)"),
        Some(1)
    );
    // A robot label and a near action: the best of that robot's actions.
    assert_eq!(
        match_line(&lines, "<robot dog>(2): go [movetowards] <kitchen>(3) now"),
        Some(2)
    );
    assert_eq!(
        match_line(&lines, "<robot dog>(2) [movetowards] <apple>"),
        Some(1)
    );
    // No robot named: the nearest action of any robot.
    assert_eq!(match_line(&lines, "[grab] <apple>(7)"), Some(3));
    // The named robot has nothing like it: dropped, not given to another robot.
    assert_eq!(
        match_line(&lines, "<quadrotor>(1): [grab] <apple>(7)"),
        None
    );
    // Nothing like any action.
    assert_eq!(match_line(&lines, "let the dog do it"), None);
    assert_eq!(match_line(&lines, ""), None);
    assert_eq!(match_line(&[], "[grab] <apple>(7)"), None);

    assert_eq!(
        read_line(r#"{"action": "<robot arm>(4): [grab] <apple>(7)"}"#),
        lines[3]
    );
    assert_eq!(
        read_line(
            "Sure: ```json\n{\"robot\": \"<robot arm>(4)\", \"subtask\": \"[grab] <apple>(7)\"}\n```"
        ),
        lines[3]
    );
    assert_eq!(read_line("  just text "), "just text");
}

/// The state one step before the goal of `task`'s shortest plan, and that last step.
fn one_step_before_the_goal(task: &Task) -> (State, TeamAction) {
    let plan = planner::analyse(task, &Limits::default())
        .plan
        .expect("a solvable task");
    let (last, before) = plan.split_last().expect("a plan of at least one step");
    let mut s = task.init.clone();
    for step in before {
        let robot = *task.robot(step.robot).expect("a robot of the team");
        rules::apply(task, &mut s, robot, step.action);
    }
    let robot = *task.robot(last.robot).expect("a robot of the team");
    (
        s,
        TeamAction {
            robot,
            action: last.action,
        },
    )
}

#[test]
fn one_step_from_the_goal_the_root_statistics_follow_the_formulas() {
    let task = common::task("env0", 1);
    let (s, last) = one_step_before_the_goal(&task);
    let reaches = |a: &TeamAction| {
        let mut after = s.clone();
        rules::apply(&task, &mut after, a.robot, a.action);
        task.goal_satisfied(&after)
    };
    let config = MctsConfig::default();
    let stats = mcts::search(&task, &s, None, &config, &mut Rng::new(0), None);
    assert_eq!(stats.simulations, 50);
    assert_eq!(stats.actions, team_actions::offered(&task, &s));
    assert!(stats.actions.contains(&last));
    assert_eq!(
        stats.visits.iter().sum::<u32>(),
        50,
        "every simulation takes a root action"
    );
    let n = stats.actions.len() as f64;
    assert!(
        stats.prior.iter().all(|&p| (p - 1.0 / n).abs() < 1e-12),
        "uniform"
    );
    for (i, a) in stats.actions.iter().enumerate() {
        let (q, v) = (stats.q[i], stats.visits[i]);
        assert!((0.0..=config.reward).contains(&q), "{i}: {q}");
        if v == 0 {
            assert_eq!(q, 0.0, "{i}: never taken, no returns");
        } else if reaches(a) {
            // Every return through a goal step is exactly the reward.
            assert!((q - config.reward).abs() < 1e-12, "{i}: {q}");
        } else {
            // At best the goal one step later.
            assert!(q <= config.discount * config.reward + 1e-12, "{i}: {q}");
        }
    }
    // Greedy: the most visited, ties by Q, then by order.
    let i = stats.choice.expect("an action");
    for j in 0..stats.actions.len() {
        let (vi, vj) = (stats.visits[i], stats.visits[j]);
        assert!(
            vi > vj
                || (vi == vj && (stats.q[i] > stats.q[j] || (stats.q[i] == stats.q[j] && i <= j)))
        );
    }

    // The goal is only 5% better than a detour, and c = 24 dwarfs that: with 50
    // simulations an early lucky detour can keep most visits. Given time, or a prior
    // that points at the goal step, the search settles on a goal step.
    let long = MctsConfig {
        simulations: 400,
        ..config.clone()
    };
    let stats = mcts::search(&task, &s, None, &long, &mut Rng::new(0), None);
    assert!(reaches(&stats.actions[stats.choice.expect("an action")]));
    let mut counts = vec![0; stats.actions.len()];
    let at = stats
        .actions
        .iter()
        .position(|a| *a == last)
        .expect("the plan's step");
    counts[at] = 5;
    let prior = mix_prior(&counts, 0.5);
    let stats = mcts::search(&task, &s, Some(&prior), &config, &mut Rng::new(0), None);
    assert_eq!(stats.prior, prior);
    assert_eq!(stats.choice, Some(at));
    // A prior of the wrong length is ignored.
    let stats = mcts::search(&task, &s, Some(&[1.0]), &config, &mut Rng::new(0), None);
    assert!(stats.prior.iter().all(|&p| (p - 1.0 / n).abs() < 1e-12));
}

#[tokio::test]
async fn the_same_seed_gives_the_same_actions() {
    let task = common::task("env1", 3);
    let config = MctsConfig::default();
    let a = episode(&task, None, &config, 6).await;
    let b = episode(&task, None, &config, 6).await;
    assert_eq!(a.rounds.len(), 6);
    assert_eq!(chosen(&a), chosen(&b));
    let notes = |e: &Episode| -> Vec<String> {
        e.rounds
            .iter()
            .filter_map(|r| r.decision.as_ref().map(|d| d.note.clone()))
            .collect()
    };
    assert_eq!(notes(&a), notes(&b), "same visits and values");
    // Some other seed explores differently.
    let mut differs = false;
    for seed in 1..6 {
        let other = episode(
            &task,
            None,
            &MctsConfig {
                seed,
                ..config.clone()
            },
            6,
        )
        .await;
        differs |= notes(&other) != notes(&a);
    }
    assert!(differs);
}

#[tokio::test]
async fn primitive_mcts_solves_a_short_task() {
    // One of the four (all mono) that seed 0 solves within 2 x GT; see the measurement.
    let task = common::task("env0", 0);
    let e = episode(&task, None, &MctsConfig::default(), 2 * gt(&task)).await;
    let s = &e.summary;
    assert_eq!(s.status, Status::Success, "{:?}", chosen(&e));
    assert!(s.success && s.steps <= 2 * gt(&task));
    assert_eq!(s.llm_calls, 0, "no model in primitive MCTS");
    let last = e.rounds.last().expect("rounds");
    assert!(last.done);
    assert!(
        e.rounds
            .iter()
            .all(|r| r.calls.is_empty() && r.proposal.is_none())
    );
    for r in &e.rounds {
        let d = r.decision.as_ref().expect("a decision every round");
        let action = d.action.as_ref().expect("an action");
        let robot = d.robot.expect("the robot that acts");
        assert!(
            r.actions.contains(&action_line(&task, robot, action)),
            "the choice is one of the team actions"
        );
        assert_eq!(
            r.outcome,
            RoundOutcome::Executed,
            "the rules' own actions are feasible"
        );
    }
}

#[tokio::test]
async fn an_oracle_prior_solves_optimally_what_primitive_mcts_does_not() {
    let task = common::task("env1", 3);
    let optimum = planner::analyse(&task, &Limits::default())
        .plan
        .expect("solvable")
        .len() as u32;
    let budget = 2 * gt(&task);
    let config = MctsConfig::default();
    let primitive = episode(&task, None, &config, budget).await;
    let oracle = Oracle::default();
    let llm = episode(&task, Some(&oracle), &config, budget).await;
    assert_eq!(llm.summary.status, Status::Success);
    assert_eq!(llm.summary.steps, optimum);
    assert!(
        !primitive.summary.success,
        "primitive MCTS solved it in {} steps",
        primitive.summary.steps
    );
    // Five samples a step, each recorded with its prompt; tokens add up.
    assert_eq!(llm.summary.llm_calls, 5 * llm.summary.steps);
    assert_eq!(
        llm.summary.prompt_tokens,
        100 * u64::from(llm.summary.llm_calls)
    );
    assert_eq!(
        llm.summary.completion_tokens,
        10 * u64::from(llm.summary.llm_calls)
    );
    let first = &llm.rounds[0];
    assert_eq!(first.calls.len(), 5);
    let prompt = &first.calls[0]
        .messages
        .last()
        .expect("a user message")
        .content;
    assert!(prompt.contains(&task.meta.instruction));
    assert!(first.actions.iter().all(|a| prompt.contains(a.as_str())));
    assert!(prompt.contains("(none yet)"));
    let later = &llm.rounds[1].calls[0]
        .messages
        .last()
        .expect("a user message")
        .content;
    let done = chosen(&llm)[0].clone();
    assert!(
        later.contains(&done),
        "the last executed actions are recalled"
    );
}

#[tokio::test]
async fn unusable_answers_are_dropped_and_the_search_falls_back_to_uniform() {
    let task = common::task("env0", 1);
    let config = MctsConfig::default();
    let garbage = Garbage::default();
    let llm = episode(&task, Some(&garbage), &config, 4).await;
    let primitive = episode(&task, None, &config, 4).await;
    assert_eq!(llm.summary.llm_calls, 5 * llm.summary.steps);
    assert!(
        llm.rounds
            .iter()
            .flat_map(|r| &r.calls)
            .any(|c| c.error.is_some())
    );
    // No sample counted: the prior is uniform, so the search is primitive MCTS's.
    assert_eq!(chosen(&llm), chosen(&primitive));
    assert_ne!(llm.summary.status, Status::BackendError);
}

#[tokio::test]
async fn a_backend_gone_for_good_ends_the_episode() {
    #[derive(Debug)]
    struct Gone;
    impl Backend for Gone {
        fn info(&self) -> BackendInfo {
            BackendInfo {
                kind: BackendKind::OpenAi,
                model: "gone".into(),
                base_url: None,
            }
        }
        fn ask(&self, _q: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
            Box::pin(async { Err(LlmError::new(LlmErrorKind::Connect, "refused")) })
        }
    }
    let task = common::task("env0", 1);
    let e = episode(&task, Some(&Gone), &MctsConfig::default(), 8).await;
    assert_eq!(e.summary.status, Status::BackendError);
    assert_eq!(e.summary.steps, 1);
    assert!(matches!(
        e.rounds[0].outcome,
        RoundOutcome::BackendError { .. }
    ));
    assert!(
        e.summary
            .error
            .as_deref()
            .is_some_and(|m| m.contains("refused"))
    );
}

#[tokio::test]
async fn a_cancelled_episode_stops_before_its_next_step() {
    let task = common::task("env0", 1);
    let cancel = Cancel::default();
    let mut env = SymbolicEnv::new(Arc::clone(&task));
    let mut seen = 0;
    let mut method = Mcts::primitive(MctsConfig::default());
    let e = episode::play(
        &mut env,
        &task,
        &mut method,
        &BuiltinBackend::default(),
        sequential(20),
        &cancel,
        &mut |_| {
            seen += 1;
            if seen == 2 {
                cancel.cancel();
            }
            Ok(())
        },
    )
    .await
    .expect("runs");
    assert_eq!(e.summary.status, Status::Interrupted);
    assert_eq!(e.summary.steps, 2);
}

/// SR and AS by task type, the paper's Table I layout.
#[derive(Default)]
struct Row {
    tasks: u32,
    successes: u32,
    steps: u32,
    gt: u32,
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "the full measurement (81 tasks); run with --release -- --ignored --nocapture"]
async fn measure_primitive_mcts_on_every_original_task() {
    let config = MctsConfig::default();
    let mut rows: Vec<(&'static str, Row)> = ["mono", "dual", "trio", "unsolvable"]
        .into_iter()
        .map(|t| (t, Row::default()))
        .collect();
    let start = std::time::Instant::now();
    for task in common::released_tasks() {
        let kind = planner::analyse(&task, &Limits::default())
            .task_type
            .map_or("unsolvable", |t| t.name());
        let task = Arc::new(task);
        let gt = gt(&task);
        let e = episode(&task, None, &config, 2 * gt).await;
        let steps = if e.summary.success {
            e.summary.steps
        } else {
            2 * gt + 1
        };
        println!(
            "{} task {:>2} {:<10} gt {:>2} {} in {:>2} steps",
            task.meta.scene,
            task.meta.task_id,
            kind,
            gt,
            if e.summary.success {
                "solved"
            } else {
                "failed"
            },
            e.summary.steps
        );
        let row = &mut rows.iter_mut().find(|(k, _)| *k == kind).expect("a row").1;
        row.tasks += 1;
        row.successes += u32::from(e.summary.success);
        row.steps += steps;
        row.gt += gt;
    }
    let paper = [
        ("mono", 14.0),
        ("dual", 21.5),
        ("trio", 26.9),
        ("average", 21.7),
    ];
    println!(
        "\nPrimitive MCTS, authors' settings, seed {}, budget 2 x GT:",
        config.seed
    );
    println!("| type | tasks | SR | AS | mean GT | paper SR / AS (40 tasks) |");
    println!("|---|---|---|---|---|---|");
    let mut all = Row::default();
    for (kind, row) in &rows {
        all.tasks += row.tasks;
        all.successes += row.successes;
        all.steps += row.steps;
        all.gt += row.gt;
        if row.tasks == 0 {
            continue;
        }
        let paper = paper
            .iter()
            .find(|(k, _)| k == kind)
            .map_or("-".to_owned(), |(_, as_)| format!("0.000 / {as_:.1}"));
        println!(
            "| {kind} | {} | {:.3} | {:.1} | {:.1} | {paper} |",
            row.tasks,
            f64::from(row.successes) / f64::from(row.tasks),
            f64::from(row.steps) / f64::from(row.tasks),
            f64::from(row.gt) / f64::from(row.tasks)
        );
    }
    println!(
        "| all | {} | {:.3} | {:.1} | {:.1} | 0.000 / 21.7 |",
        all.tasks,
        f64::from(all.successes) / f64::from(all.tasks),
        f64::from(all.steps) / f64::from(all.tasks),
        f64::from(all.gt) / f64::from(all.tasks)
    );
    println!("wall {:.1} s", start.elapsed().as_secs_f64());
    assert_eq!(all.tasks, 81);
}
