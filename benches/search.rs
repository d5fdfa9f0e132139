//! `search/<scene>/<task>`: the optimal planner (the whole team's shortest plan, no task
//! type) on small, medium and the hardest tasks of the released scenes and of the
//! project's own benchmark (compiled in).

use std::hint::black_box;

use coherent_core::Task;
use coherent_core::benchmark;
use coherent_core::planner::{self, Limits};
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn bench_one(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: String,
    task: &Task,
) {
    let limits = Limits::default();
    group.bench_function(name, |b| {
        b.iter(|| black_box(planner::search(task, &task.robots, &task.goal, &limits)))
    });
}

fn search(c: &mut Criterion) {
    let mut group = c.benchmark_group("search");
    group.sample_size(10);
    // Released (scene, task), states expanded on 2026-11-22: env0 task 1, 4 steps and 11
    // states; env2 task 6, 11 steps and 258; env1 task 16, 13 steps and 2,020 (the
    // hardest before the search's pruning, 278,000 states); env1 task 15, 16 steps and
    // 12,326, the most of the released tasks now.
    for (n, id) in [(0, 1), (2, 6), (1, 16), (1, 15)] {
        bench_one(&mut group, format!("env{n}/{id}"), &common::task(n, id));
    }
    // Our benchmark: s4-restaurant task 2, a mono task of 4 steps and 21 states (the
    // fewest); s4-restaurant task 10, a dual task of 12 steps and 1,002 states (the
    // median); s1-apartment task 17, a trio task of 16 steps and 31,964 states (the most).
    let tasks = benchmark::tasks().expect("the compiled-in benchmark reads");
    for (scene, id) in [
        ("s4-restaurant", 2),
        ("s4-restaurant", 10),
        ("s1-apartment", 17),
    ] {
        let task = tasks
            .iter()
            .find(|t| t.meta.scene == scene && t.meta.task_id == id)
            .expect("a benchmark task");
        bench_one(&mut group, format!("{scene}/{id}"), task);
    }
    group.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
