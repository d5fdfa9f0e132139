//! `rules/step/<scene>`: the action lists of every robot of a task plus one transition,
//! the work the rules do for one planning round.

use std::hint::black_box;

use coherent_core::rules;
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("rules/step");
    for n in 0..4 {
        // Task 0 of each scene, at its start.
        let task = common::task(n, 0);
        group.bench_function(format!("env{n}"), |b| {
            b.iter(|| {
                let s = black_box(&task.init);
                let mut first = None;
                for &robot in &task.robots {
                    let actions = rules::actions(&task, s, robot);
                    first = first.or_else(|| actions.first().map(|a| (robot, *a)));
                    black_box(actions);
                }
                let mut next = s.clone();
                if let Some((robot, action)) = first {
                    rules::apply(&task, &mut next, robot, action);
                }
                black_box(next)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
