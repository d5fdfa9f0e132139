//! `search/<scene>/<task>`: the optimal planner (the whole team's shortest plan, no task
//! type) on a small, a medium and the hardest task of the released scenes.

use std::hint::black_box;

use coherent_core::planner::{self, Limits};
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn search(c: &mut Criterion) {
    let mut group = c.benchmark_group("search");
    group.sample_size(10);
    // (scene, task): 4 steps and 12 states expanded; 11 steps and about 1,100; env1
    // task 16, 13 steps and about 278,000, the most of the released tasks.
    for (n, id) in [(0, 1), (2, 6), (1, 16)] {
        let task = common::task(n, id);
        let limits = Limits::default();
        group.bench_function(format!("env{n}/{id}"), |b| {
            b.iter(|| black_box(planner::search(&task, &task.robots, &task.goal, &limits)))
        });
    }
    group.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
