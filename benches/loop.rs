//! `loop/pefa_round`: one PEFA round with a backend that answers at once, so that the
//! figure is the loop's own cost: rendering both prompts (every robot's observation as
//! facts, the action list), parsing both answers, the feasibility check and the
//! transition, and the round's record.

use std::hint::black_box;
use std::sync::Arc;

use coherent_agents::episode::{self, Course};
use coherent_agents::llm::{
    Answer, Backend, BackendInfo, BackendKind, BoxFuture, Finish, LlmError, OutputMode, Query,
    Role, Usage,
};
use coherent_agents::pefa::Pefa;
use coherent_agents::{Cancel, HISTORY_WINDOW, Prompts};
use coherent_core::Execution;
use coherent_core::SymbolicEnv;
use coherent_core::planner::{self, Limits};
use criterion::{Criterion, criterion_group, criterion_main};
use serde_json::json;

mod common;

/// Answers the assigner and the executor with fixed texts, as a model would.
struct Instant {
    proposal: String,
    decision: String,
}

impl Backend for Instant {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            // It stands for a model's server with instant answers.
            kind: BackendKind::OpenAi,
            model: "instant".into(),
            base_url: None,
        }
    }

    fn ask(&self, q: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        let text = match q.role {
            Role::Assigner => self.proposal.clone(),
            Role::Executor => self.decision.clone(),
        };
        Box::pin(async move {
            Ok(Answer {
                text,
                finish: Finish::Stop,
                usage: Usage::default(),
                latency_ms: 0.0,
                attempts: 1,
                mode: OutputMode::JsonSchema,
            })
        })
    }
}

fn pefa_round(c: &mut Criterion) {
    // env1 task 16, the largest original scene's hardest task: the first step of its
    // optimal plan, proposed and executed from the start.
    let task = Arc::new(common::task(1, 16));
    let plan = planner::search(&task, &task.robots, &task.goal, &Limits::default())
        .plan
        .expect("env1 task 16 is solvable");
    let first = plan[0];
    let backend = Instant {
        proposal: json!({
            "reasoning": "the first step",
            "robot": task.node(first.robot).label(),
            "subtask": first.action.render(&task),
        })
        .to_string(),
        decision: json!({
            "action": first.action.render(&task),
            "subtask_complete": true,
            "note": "",
        })
        .to_string(),
    };
    let mut pefa = Pefa::new(Prompts::builtin());
    let course = Course {
        execution: Execution::Sequential,
        max_steps: 1,
        history: HISTORY_WINDOW,
        max_states: Limits::DEFAULT_MAX_STATES,
        seed: 0,
    };
    let cancel = Cancel::default();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .build()
        .expect("a runtime");
    c.bench_function("loop/pefa_round", |b| {
        b.iter(|| {
            let mut env = SymbolicEnv::new(Arc::clone(&task));
            let episode = runtime
                .block_on(episode::play(
                    &mut env,
                    &task,
                    &mut pefa,
                    &backend,
                    course,
                    &cancel,
                    &mut |_| Ok(()),
                ))
                .expect("no I/O");
            assert_eq!(episode.rounds.len(), 1);
            black_box(episode)
        })
    });
}

criterion_group!(benches, pefa_round);
criterion_main!(benches);
