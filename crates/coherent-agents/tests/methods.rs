//! Every method through `episode::run` on the built-in backend (the optimal planner in
//! every role, no mistakes) and on the simulated one (the same with seeded mistakes).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::transcript::{RoundOutcome, Status};
use coherent_agents::{Builtin, Settings};
use coherent_agents::{BuiltinBackend, Cancel, Episode, ErrorRates};
use coherent_core::Execution;
use coherent_core::planner::{self, Limits};
use coherent_core::{SymbolicEnv, Task, load_tasks};

mod common;

fn out(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("coherent-methods-{name}-{}", std::process::id()))
}

async fn run(task: &Arc<Task>, method: Builtin, backend: &BuiltinBackend) -> Episode {
    let budget =
        Budget::searched(task, Execution::Sequential, None, &Limits::default()).expect("a budget");
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let settings = Settings::new(method);
    let out = out(method.name());
    common::run(
        task,
        &mut env,
        backend,
        &settings,
        budget,
        &out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs")
    .0
}

/// One task per scene, mono to trio.
fn tasks() -> Vec<Arc<Task>> {
    vec![
        common::task("env0", 1),
        common::task("env1", 3),
        common::task("env2", 6),
        common::task("env3", 2),
    ]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_mistakes_every_method_that_asks_a_model_solves_and_the_direct_ones_optimally() {
    for task in tasks() {
        let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
        let optimum = planner::analyse(&task, &Limits::default())
            .plan
            .expect("solvable")
            .len() as u32;
        let robots = task.robots.len() as u32;
        for method in Builtin::ALL {
            if matches!(method, Builtin::Mcts | Builtin::Random) {
                continue; // no model and no plan: their own tests
            }
            let e = run(&task, method, &BuiltinBackend::new(Limits::default())).await;
            let s = &e.summary;
            assert_eq!(s.status, Status::Success, "{name} {}", method.name());
            let calls = match method {
                Builtin::Pefa | Builtin::PefaNoHistory => 2 * s.steps,
                Builtin::Cmrs => s.steps,
                Builtin::Dmrs1d => robots * s.steps,
                Builtin::Dmrs2d => 2 * robots * s.steps,
                Builtin::LlmMcts => 5 * s.steps,
                // The goal, written once.
                Builtin::LlmPddl => 1,
                Builtin::Mcts | Builtin::Optimal | Builtin::Random => 0,
            };
            assert_eq!(s.llm_calls, calls, "{name} {}", method.name());
            if method != Builtin::LlmMcts {
                // The others take the planner's step every round.
                assert_eq!(s.steps, optimum, "{name} {}", method.name());
            }
        }
    }
}

/// LLM+P on the built-in backend, which writes the true goal: every solvable released and
/// native task at its optimum (the ground truth), with the one model call for the goal.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn llm_pddl_solves_every_solvable_task_at_its_optimum_with_one_model_call() {
    let native = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../benchmark/tasks");
    let mut tasks = common::released_tasks();
    tasks.extend(load_tasks(&native).expect("the native tasks load"));
    let backend = BuiltinBackend::new(Limits::default());
    let mut solved = 0;
    for task in tasks {
        let task = Arc::new(task);
        let Some(plan) = planner::analyse(&task, &Limits::default()).plan else {
            continue;
        };
        let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
        let s = run(&task, Builtin::LlmPddl, &backend).await.summary;
        assert_eq!(s.status, Status::Success, "{name}");
        assert_eq!(s.steps, plan.len() as u32, "{name}");
        assert_eq!(s.llm_calls, 1, "{name}");
        solved += 1;
    }
    assert_eq!(
        solved, 180,
        "80 solvable released tasks and 100 native ones"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_simulated_backend_makes_its_mistakes_reproducibly() {
    let task = common::task("env1", 3);
    let rates = ErrorRates::all(0.2);
    let mut seen = Vec::new();
    for method in [Builtin::Pefa, Builtin::Cmrs, Builtin::Dmrs1d] {
        let once = run(
            &task,
            method,
            &BuiltinBackend::simulated(Limits::default(), rates, 7),
        )
        .await;
        let again = run(
            &task,
            method,
            &BuiltinBackend::simulated(Limits::default(), rates, 7),
        )
        .await;
        let strip = |e: &Episode| -> Vec<_> {
            e.rounds
                .iter()
                .map(|r| (r.decision.clone(), r.outcome.clone(), r.calls.len()))
                .collect()
        };
        assert_eq!(
            strip(&once),
            strip(&again),
            "{}: same seed, same episode",
            method.name()
        );
        seen.extend(once.rounds.iter().map(|r| r.outcome.clone()));
    }
    let kinds = |f: fn(&RoundOutcome) -> bool| seen.iter().filter(|o| f(o)).count();
    assert!(
        kinds(|o| matches!(o, RoundOutcome::Infeasible { .. })) > 0,
        "hallucinated actions are refused"
    );
    assert!(
        kinds(|o| matches!(
            o,
            RoundOutcome::NoProposal { .. } | RoundOutcome::NoDecision { .. }
        )) > 0,
        "malformed answers cost rounds"
    );
    assert!(kinds(|o| *o == RoundOutcome::Executed) > 0);
}

#[test]
fn error_rates_parse_and_refuse_what_they_should() {
    let r = ErrorRates::parse("hallucinate=0.1, wrong_robot=0.2").expect("valid");
    assert_eq!(
        (r.hallucinate, r.wrong_robot, r.malformed, r.suboptimal),
        (0.1, 0.2, 0.0, 0.0)
    );
    assert_eq!(
        ErrorRates::parse("all=0.25").expect("valid"),
        ErrorRates::all(0.25)
    );
    assert_eq!(ErrorRates::parse("all=0.3").expect("valid").suboptimal, 0.3);
    for bad in ["typo=0.1", "hallucinate", "malformed=2", "all=-0.1"] {
        assert!(ErrorRates::parse(bad).is_err(), "{bad}");
    }
}
