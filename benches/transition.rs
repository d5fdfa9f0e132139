//! `transition/apply/<scene>`: applying one action to a state; `transition/replay/<scene>`:
//! a whole optimal plan replayed through the rules (each step checked and applied).

use std::hint::black_box;

use coherent_core::planner::{self, Limits};
use coherent_core::rules;
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn transition(c: &mut Criterion) {
    let mut group = c.benchmark_group("transition");
    // Task 0 of each scene (env3's cannot be solved: its task 1), its optimal plan.
    for (n, id) in [(0, 0), (1, 0), (2, 0), (3, 1)] {
        let task = common::task(n, id);
        let plan = planner::search(&task, &task.robots, &task.goal, &Limits::default())
            .plan
            .expect("the task is solvable");
        let first = plan[0];
        let robot = *task.robot(first.robot).expect("a robot acts");
        group.bench_function(format!("apply/env{n}"), |b| {
            b.iter(|| {
                let mut s = black_box(&task.init).clone();
                rules::apply(&task, &mut s, robot, first.action);
                black_box(s)
            })
        });
        group.bench_function(format!("replay/env{n}"), |b| {
            b.iter(|| black_box(planner::replay(&task, black_box(&plan))))
        });
    }
    group.finish();
}

criterion_group!(benches, transition);
criterion_main!(benches);
