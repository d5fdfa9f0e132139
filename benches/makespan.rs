//! The two proofs at team scale: `makespan/<task>` is the joint-step search alone (the
//! sequential optimum it starts from is found outside the measurement), on the median
//! and the slowest of the project's own benchmark; `team/<robots>/sequential` and
//! `team/<robots>/makespan` are both searches on generated tasks of teams of 3, 4 and 6
//! robots (`benches/tasks/`, written by `coherent generate`, see below). The makespan
//! search is most of the generator's time (`docs/planner.md`, "Team scale").

use std::hint::black_box;
use std::path::Path;

use coherent_core::planner::{self, Limits};
use coherent_core::{Task, benchmark, load_tasks, makespan};
use criterion::{
    BenchmarkGroup, Criterion, criterion_group, criterion_main, measurement::WallTime,
};

fn makespan_of(group: &mut BenchmarkGroup<'_, WallTime>, name: &str, task: &Task) {
    let limits = Limits::default();
    let sequential = planner::search(task, &task.robots, &task.goal, &limits);
    let plan = sequential.plan.expect("a solvable task");
    group.bench_function(name, |b| {
        b.iter(|| {
            black_box(makespan::search_with(
                task,
                &task.init,
                &task.robots,
                &task.goal,
                Some(&plan),
                &limits,
            ))
        })
    });
}

fn ours(c: &mut Criterion) {
    let mut group = c.benchmark_group("makespan");
    group.sample_size(10);
    // On 2026-11-29 (release build): s2-apartment task 7, a dual task of 12 steps and 10
    // joint steps, 26,217 states (0.57 s, the 90th percentile of the 100); s1-apartment
    // task 17, a trio task of 16 steps and 11 joint steps, 60,416 states (1.9 s, the
    // slowest).
    let tasks = benchmark::tasks().expect("the compiled-in benchmark reads");
    for (scene, id) in [("s2-apartment", 7), ("s1-apartment", 17)] {
        let task = tasks
            .iter()
            .find(|t| t.meta.scene == scene && t.meta.task_id == id)
            .expect("a benchmark task");
        makespan_of(&mut group, &format!("{scene}/{id}"), task);
    }
    group.finish();
}

/// Generated tasks, one a team size, each the first of its set whose makespan took a
/// measurable time (`coherent generate --tasks 6 --seed 1 --scenes 2 --team T
/// --predicates 2 --max-states 200000 --max-memory 256`):
/// - `team-3.json`: T `quadrotor=1,legged=1,arm=1`, scene-000 task 0: 23 steps, 15 joint
///   steps (1,892 and 1,792 states);
/// - `team-4.json`: T `quadrotor=1,legged=2,arm=1`, scene-001 task 0: 16 steps, 10 joint
///   steps (5,323 and 6,150 states);
/// - `team-6.json`: T `quadrotor=2,legged=2,arm=2`, scene-000 task 0: 9 steps, 6 joint
///   steps (681 and 7,829 states).
fn team(c: &mut Criterion) {
    let mut group = c.benchmark_group("team");
    group.sample_size(10);
    for robots in [3, 4, 6] {
        let file =
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("benches/tasks/team-{robots}.json"));
        let task = load_tasks(&file)
            .unwrap_or_else(|e| panic!("{e}"))
            .remove(0);
        assert_eq!(task.robots.len(), robots);
        let limits = Limits::default();
        group.bench_function(format!("{robots}/sequential"), |b| {
            b.iter(|| black_box(planner::search(&task, &task.robots, &task.goal, &limits)))
        });
        makespan_of(&mut group, &format!("{robots}/makespan"), &task);
    }
    group.finish();
}

criterion_group!(benches, ours, team);
criterion_main!(benches);
