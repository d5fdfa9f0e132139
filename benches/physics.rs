//! `physics/plan/<scene>`: a whole optimal plan carried out in Rapier with the generated
//! layout, the relations read back and compared after every step; one task per scene,
//! the one whose plan moves the most robots (the pictures of `docs/render/`).

use std::hint::black_box;
use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn physics(c: &mut Criterion) {
    let mut group = c.benchmark_group("physics");
    group.sample_size(10);
    for (n, id) in [(0, 14), (1, 15), (2, 13), (3, 13)] {
        let task = Arc::new(common::task(n, id));
        let plan = planner::search(&task, &task.robots, &task.goal, &Limits::default())
            .plan
            .expect("the task is solvable");
        let report = coherent_sim::execute_plan(&task, &plan);
        assert!(report.physics_ok, "{:?}", report.physics_error);
        eprintln!(
            "physics/plan/env{n}: task {id}, {} steps, {:.1} s simulated",
            plan.len(),
            report.sim_seconds
        );
        group.bench_function(format!("plan/env{n}"), |b| {
            b.iter(|| black_box(coherent_sim::execute_plan(&task, black_box(&plan))))
        });
    }
    group.finish();
}

criterion_group!(benches, physics);
criterion_main!(benches);
